"""Float models of quadratic shading over a triangle (seeds 000, 001, 002), vectorised numpy.

Conventions (math-notes §1, seed 001 §2.1.1): screen space, y down. Vertices are sorted by y
(then x); the top vertex is the origin, the middle one is (x1, y1), the bottom one (x2, y2),
all relative. Samples are ``I = [I1, I2, I3, I12, I13, I23]`` (top, middle, bottom, then the
mid-edge samples); a triangle's screen-space coefficients are ``[A, B, C, D, E, F]`` of
``Phi = A x^2 + B y^2 + C xy + D x + E y + F`` (eq 7). Ortho-normalised coordinates (eq 18-21):
u = 1 at the middle vertex, v = 1 at the bottom one. Seed 000 labels the ortho-normalised
vertices differently (p1 = (0,1), p2 = (0,0), p3 = (1,0)) but uses the same map and the same
a..f; we keep seed 001's labels, and ``test_quadratic_models`` holds them to the 6x6 solve.

Every function takes arrays of shape (n,) (or (n, 6) for samples) and returns arrays; where a
closed form divides by zero it returns inf or nan, which the tests use to show where it breaks.
"""
import numpy as np

from hdl.setup_unit.formats import EXACT_G_MAX

__all__ = ["sort_vertices", "omega", "solve6", "seiler", "abbas", "lee_jen", "ortho",
           "ortho_uv", "to_screen", "xshading_uv", "xshading_samples", "exact_samples",
           "linear_uv", "uv_of", "eval_uv", "eval_xy", "duff", "EXACT_G_MAX"]


def sort_vertices(x, y):
    """(n, 3) vertex coordinates -> the sort order (by y, then x) and x1, y1, x2, y2."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    order = np.lexsort((x, y), axis=-1)
    xs, ys = np.take_along_axis(x, order, -1), np.take_along_axis(y, order, -1)
    return order, xs[:, 1] - xs[:, 0], ys[:, 1] - ys[:, 0], xs[:, 2] - xs[:, 0], ys[:, 2] - ys[:, 0]


def omega(x1, y1, x2, y2):
    """Twice the signed area, seed 002 eq 47; its sign is the orientation, 0 degenerate."""
    return x1 * y2 - x2 * y1


def solve6(x1, y1, x2, y2, samples):
    """The reference: M c = Phi, seed 001 eq 8-11, by numpy.linalg.solve (singular -> nan)."""
    pts = [(0 * x1, 0 * y1), (x1, y1), (x2, y2), (x1 / 2, y1 / 2), (x2 / 2, y2 / 2),
           ((x1 + x2) / 2, (y1 + y2) / 2)]
    m = np.stack([np.stack([px * px, py * py, px * py, px, py, np.ones_like(px)], -1)
                  for px, py in pts], -2)
    out = np.full(np.shape(samples), np.nan)
    ok = np.linalg.cond(m) < 1e12
    out[ok] = np.linalg.solve(m[ok], np.asarray(samples, float)[ok][..., None])[..., 0]
    return out


def _seiler_terms(s):
    L, M, N, Q, R, S = np.moveaxis(np.asarray(s, float), -1, 0)
    T, U, V = L + M - 2 * Q, L + N - 2 * R, L + S - R - Q              # eq 16-18
    return L, T, U, V, 2 * Q - 2 * L - T, 2 * R - 2 * L - U             # eq 19-20


def seiler(x1, y1, x2, y2, samples):
    """Seiler, seed 002 eq 16-29 as printed: divides by x1 and y2."""
    with np.errstate(divide="ignore", invalid="ignore"):
        L, T, U, V, G, H = _seiler_terms(samples)
        i, j = x2 / x1, y1 / y2                                         # eq 21-22
        k = 1 - i * j                                                   # eq 23
        A = 2 * (T + U * j * j - 2 * V * j) / (k * k * x1 * x1)         # eq 24
        B = 2 * (U + T * i * i - 2 * V * i) / (k * k * y2 * y2)         # eq 25
        C = 4 * (2 * V - T * i - U * j - V * k) / (k * k * x1 * y2)     # eq 26
        D = (G - H * j) / (k * x1)                                      # eq 27
        E = (H - G * i) / (k * y2)                                      # eq 28
    return np.stack([A, B, C, D, E, L], -1)                            # eq 29: F = L


def abbas(x1, y1, x2, y2, samples):
    """Abbas et al. as simplified in seed 002 eq 30-62: divides by Omega and by y1.

    The seed prints the denominator of eq 35-36 as E32 D23 - E32 D32; with eq 57-60 that is not
    -2 Omega^3, while E32 D23 - E23 D32 is, and eq 62 (F2 = -F1^3 / 2) agrees with the latter:
    we use eq 62."""
    with np.errstate(divide="ignore", invalid="ignore"):
        L, M, N, Q, R, S = np.moveaxis(np.asarray(samples, float), -1, 0)
        T, U, V = M + L - 2 * Q, N + L - 2 * R, 4 * (L + S - Q - R)     # eq 30-32
        G, H = 4 * Q - 3 * L - M, 4 * R - 3 * L - N                     # eq 33-34
        w = omega(x1, y1, x2, y2)                                       # eq 47
        F1 = 1 / w                                                      # eq 61
        F2 = -F1 ** 3 / 2                                               # eq 62
        C1, C2 = 4 * T * y2 - V * y1, 4 * U * y1 - V * y2               # eq 55-56
        D23, D32, E23, E32 = 2 * x1 * w, -2 * x2 * w, y1 * w, -y2 * w   # eq 57-60
        A = (C1 * E32 - C2 * E23) * F2                                  # eq 49
        C = (C2 * D23 - C1 * D32) * F2                                  # eq 50
        B = (2 * T - A * x1 * x1 - C * x1 * y1) / (y1 * y1)             # eq 51
        D = (G * y2 - H * y1) * F1                                      # eq 52
        E = (H * x1 - G * x2) * F1                                      # eq 53
    return np.stack([A, B, C, D, E, L], -1)                            # eq 54


def lee_jen(x1, y1, x2, y2, samples):
    """Lee & Jen, seed 002 eq 63-76: divides by Omega only."""
    with np.errstate(divide="ignore", invalid="ignore"):
        L, T, U, V, G, H = _seiler_terms(samples)                       # eq 66-70
        w1, w2 = x1 * y2, x2 * y1                                       # eq 63-64
        w3 = w1 - w2                                                    # eq 65
        A = 2 * (T * y2 * y2 + U * y1 * y1 - 2 * V * y1 * y2) / w3 ** 2  # eq 71
        B = 2 * (U * x1 * x1 + T * x2 * x2 - 2 * V * x1 * x2) / w3 ** 2  # eq 72
        C = 4 * (V * (w1 + w2) - U * x1 * y1 - T * x2 * y2) / w3 ** 2   # eq 73
        D = (G * y2 - H * y1) / w3                                      # eq 74
        E = (H * x1 - G * x2) / w3                                      # eq 75
    return np.stack([A, B, C, D, E, L], -1)                            # eq 76


def ortho_uv(samples):
    """a..f over the ortho-normalised triangle from six samples, seed 001 eq 16."""
    I1, I2, I3, I12, I13, I23 = np.moveaxis(np.asarray(samples, float), -1, 0)
    a, b = 2 * (I1 + I2 - 2 * I12), 2 * (I1 + I3 - 2 * I13)
    c = 4 * (I1 + I23 - I13 - I12)
    return np.stack([a, b, c, I2 - I1 - a, I3 - I1 - b, I1], -1)


def uv_map(x1, y1, x2, y2):
    """(alpha_u, beta_u, alpha_v, beta_v), seed 001 eq 20-21 (inf where Omega = 0)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        w = 1 / omega(x1, y1, x2, y2)
    return y2 * w, -x2 * w, -y1 * w, x1 * w


def to_screen(x1, y1, x2, y2, uv):
    """Screen-space A..F from a..f, seed 001 eq 22."""
    au, bu, av, bv = uv_map(x1, y1, x2, y2)
    a, b, c, d, e, f = np.moveaxis(np.asarray(uv, float), -1, 0)
    with np.errstate(invalid="ignore"):
        return np.stack([a * au * au + b * av * av + c * au * av,
                         a * bu * bu + b * bv * bv + c * bu * bv,
                         2 * a * au * bu + 2 * b * av * bv + c * (au * bv + av * bu),
                         d * au + e * av, d * bu + e * bv, f], -1)


def ortho(x1, y1, x2, y2, samples):
    """The ortho-normalised setup, seed 001 eq 16-22: one reciprocal, Omega."""
    return to_screen(x1, y1, x2, y2, ortho_uv(samples))


def xshading_samples(I1, I2, I3, e12, e13, e23):
    """The six samples with the mid-edge approximation, seed 001 eq 29-31, where
    e_ij = (Ni.Nj - 1) / 2 is the per-edge constant (so (5 - Ni.Nj) / 8 = (2 - e_ij) / 4)."""
    return np.stack([I1, I2, I3, (I1 + I2) * (2 - e12) / 4, (I1 + I3) * (2 - e13) / 4,
                     (I2 + I3) * (2 - e23) / 4], -1)


def xshading_uv(I1, I2, I3, e12, e13, e23):
    """X-shading a..f, seed 001 eq 32: no square root, no division."""
    a, b = (I1 + I2) * e12, (I1 + I3) * e13
    c = a + b - (I2 + I3) * e23
    return np.stack([a, b, c, I2 - I1 - a, I3 - I1 - b, I1], -1)




def exact_mid(Ia, Ib, e, lo=-2.0, hi=2.0):
    """An exact mid-edge sample, seed 001 eq 4-6: (Ia + Ib) / ||Na + Nb||, with
    ||Na + Nb|| = 2 sqrt(1 + e) from the per-edge constant. Normals (almost) opposite make it
    0/0: the reciprocal is clamped to EXACT_G_MAX and the sample to the value range [lo, hi]."""
    with np.errstate(divide="ignore"):
        g = np.minimum(0.5 / np.sqrt(np.maximum(1 + np.asarray(e, float), 0)), EXACT_G_MAX)
    return np.clip((Ia + Ib) * g, lo, hi)


def exact_samples(I1, I2, I3, e12, e13, e23, lo=-2.0, hi=2.0):
    return np.stack([I1, I2, I3, exact_mid(I1, I2, e12, lo, hi), exact_mid(I1, I3, e13, lo, hi),
                     exact_mid(I2, I3, e23, lo, hi)], -1)


def linear_uv(I1, I2, I3):
    """Linear (Gouraud) over the same map, seed 000 eq 24-28: a = M - L, b = N - L, c = L,
    as u and v coefficients (our d, e, f)."""
    z = np.zeros_like(np.asarray(I1, float))
    return np.stack([z, z, z, I2 - I1, I3 - I1, np.asarray(I1, float)], -1)


def uv_of(x1, y1, x2, y2, X, Y):
    """(u, v) of points (X, Y) relative to the top vertex, eq 18-19 (per triangle row)."""
    w = 1 / omega(x1, y1, x2, y2)
    return (X * y2 - Y * x2) * w, (Y * x1 - X * y1) * w


def eval_uv(uv, u, v):
    """Phi(u, v) = a u^2 + b v^2 + c uv + d u + e v + f, eq 17."""
    a, b, c, d, e, f = np.moveaxis(np.asarray(uv, float), -1, 0)
    return a * u * u + b * v * v + c * u * v + d * u + e * v + f


def eval_xy(coef, X, Y):
    """Phi(x, y) = A x^2 + B y^2 + C xy + D x + E y + F, eq 7."""
    A, B, C, D, E, F = np.moveaxis(np.asarray(coef, float), -1, 0)
    return A * X * X + B * Y * Y + C * X * Y + D * X + E * Y + F


def duff(L1, L2, L3, N, u, v):
    """Phong with per-pixel normalisation (Duff), seed 000 eq 33-45: L' = A u + B v + C with
    A = L2 - L1, B = L3 - L1, C = L1 (eq 43-45), and ||L'||^2 the quadratic a = A.A, b = B.B,
    c = 2 A.B, d = 2 A.C, e = 2 B.C, f = C.C (eq 37-42; the seed prints f = C, it is C.C).
    Returns (L'.N / ||L'||, ||L'||^2 from the quadratic) at (u, v); vectors are (..., 3)."""
    A, B, C = L2 - L1, L3 - L1, L1
    dot = lambda p, q: (p * q).sum(-1)
    num = dot(A, N) * u + dot(B, N) * v + dot(C, N)
    q = eval_uv(np.stack([dot(A, A), dot(B, B), 2 * dot(A, B), 2 * dot(A, C), 2 * dot(B, C),
                          dot(C, C)], -1), u, v)
    return num / np.sqrt(q), q
