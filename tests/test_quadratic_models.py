"""The quadratic-shading float models (seeds 000-002) against the 6x6 solve and each other, the
hard cases each closed form breaks on, and the top-left coverage rule on meshes."""
import numpy as np
import pytest

from golden import quadratic as q
from golden import raster, torus

RNG = np.random.default_rng(3)


def random_triangles(n, rng=RNG):
    x = rng.uniform(-50, 50, (n, 3))
    y = rng.uniform(-50, 50, (n, 3))
    _, x1, y1, x2, y2 = q.sort_vertices(x, y)
    return x1, y1, x2, y2


def close(a, b, scale):
    return np.abs(a - b) <= 1e-7 * scale


def test_closed_forms_agree_with_the_6x6_solve():
    x1, y1, x2, y2 = random_triangles(2000)
    s = RNG.uniform(-1, 1, (2000, 6))
    ref = q.solve6(x1, y1, x2, y2, s)
    assert np.isfinite(ref).all()
    # coefficients scale like 1/size^2; compare values over the triangle instead of raw A..F
    pts = [(x1 * t, y1 * t) for t in (0.3, 0.7)] + [((x1 + x2) * 0.3, (y1 + y2) * 0.3)]
    for method in (q.seiler, q.abbas, q.lee_jen, q.ortho):
        got = method(x1, y1, x2, y2, s)
        for X, Y in pts:
            assert close(q.eval_xy(got, X, Y), q.eval_xy(ref, X, Y), 1e3).all(), method.__name__


def test_the_6x6_solve_interpolates_its_six_samples():
    x1, y1, x2, y2 = random_triangles(500)
    s = RNG.uniform(-1, 1, (500, 6))
    c = q.solve6(x1, y1, x2, y2, s)
    pts = [(0, 0), (x1, y1), (x2, y2), (x1 / 2, y1 / 2), (x2 / 2, y2 / 2),
           ((x1 + x2) / 2, (y1 + y2) / 2)]
    for k, (X, Y) in enumerate(pts):
        assert np.allclose(q.eval_xy(c, X, Y), s[:, k], atol=1e-9)


def hard(name):
    """(x1, y1, x2, y2) of one hard case, vertices sorted by y as the setup sorts them."""
    return {"x1=0": (0.0, 10.0, 7.0, 20.0), "y1=0": (12.0, 0.0, 5.0, 9.0),
            "y1=y2": (-6.0, 10.0, 8.0, 10.0), "omega=0": (4.0, 8.0, 8.0, 16.0)}[name]


# Which closed forms break where (seed 002 §3.1-3.3): Seiler divides by x1 (and y2), Abbas et
# al. by Omega and y1, Lee & Jen and the ortho-normalised setup by Omega only.
BREAKS = {"x1=0": {"seiler"}, "y1=0": {"abbas"}, "y1=y2": set(),
          "omega=0": {"seiler", "abbas", "lee_jen", "ortho", "solve6"}}


@pytest.mark.parametrize("case", sorted(BREAKS))
def test_which_setups_break_on_which_hard_case(case):
    x1, y1, x2, y2 = (np.array([v]) for v in hard(case))
    s = np.array([[0.2, 0.9, -0.4, 0.7, 0.1, 0.3]])
    ref = q.solve6(x1, y1, x2, y2, s)
    for method in (q.seiler, q.abbas, q.lee_jen, q.ortho, q.solve6):
        c = method(x1, y1, x2, y2, s)
        broken = not np.isfinite(c).all()
        assert broken == (method.__name__ in BREAKS[case]), (case, method.__name__, c)
        if not broken:
            assert np.allclose(c, ref, atol=1e-9)


def test_xshading_is_the_ortho_setup_of_the_approximate_mid_edges():
    I = RNG.uniform(-1, 1, (3, 1000))
    e = RNG.uniform(-1, 0, (3, 1000))
    assert np.allclose(q.xshading_uv(*I, *e), q.ortho_uv(q.xshading_samples(*I, *e)), atol=1e-12)


def unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def test_mid_edge_samples_exact_and_approximate():
    n1, n2, light = unit(RNG.normal(size=(3, 1000, 3)))
    I1, I2 = (n1 * light).sum(-1), (n2 * light).sum(-1)
    e = ((n1 * n2).sum(-1) - 1) / 2
    truth = (light * unit(n1 + n2)).sum(-1)                          # eq 4
    assert np.allclose(q.exact_mid(I1, I2, e, -9, 9)[np.abs(e + 1) > 1e-3],
                       truth[np.abs(e + 1) > 1e-3], atol=1e-9)
    # eq 27: the approximate mid-edge normal's length, 2 cos(phi/2) (5 - cos phi) / 8
    approx = (n1 + n2) * ((5 - (n1 * n2).sum(-1)) / 8)[:, None]
    phi = np.arccos(np.clip((n1 * n2).sum(-1), -1, 1))
    assert np.allclose(np.linalg.norm(approx, axis=-1), 2 * np.cos(phi / 2) * (5 - np.cos(phi)) / 8)
    small = phi < np.radians(45)
    assert (np.abs(np.linalg.norm(approx, axis=-1)[small] - 1) < 0.012).all()


def test_linear_and_quadratic_data_are_reproduced():
    x1, y1, x2, y2 = random_triangles(300)
    coef = RNG.uniform(-1, 1, (300, 6)) * [1e-3, 1e-3, 1e-3, 1e-2, 1e-2, 1]
    pts = [(0 * x1, 0 * y1), (x1, y1), (x2, y2), (x1 / 2, y1 / 2), (x2 / 2, y2 / 2),
           ((x1 + x2) / 2, (y1 + y2) / 2)]
    s = np.stack([q.eval_xy(coef, X, Y) for X, Y in pts], -1)
    assert np.allclose(q.ortho(x1, y1, x2, y2, s), coef, rtol=1e-6, atol=1e-12)
    lin = coef * [0, 0, 0, 1, 1, 1]
    s = np.stack([q.eval_xy(lin, X, Y) for X, Y in pts[:3]], -1)
    assert np.allclose(q.to_screen(x1, y1, x2, y2, q.linear_uv(*s.T)), lin, atol=1e-12)


def test_duff_is_the_normalised_linear_interpolation():
    L = unit(RNG.normal(size=(3, 400, 3)))
    N = unit(RNG.normal(size=(400, 3)))
    u, v = RNG.uniform(0, 0.5, (2, 400))
    val, qq = q.duff(L[0], L[1], L[2], N, u, v)
    lin = L[0] + (L[1] - L[0]) * u[:, None] + (L[2] - L[0]) * v[:, None]
    assert np.allclose(qq, (lin * lin).sum(-1))
    assert np.allclose(val, (unit(lin) * N).sum(-1))


# ---- rasterisation rule ------------------------------------------------------------------

def mesh(rng, cols, rows, size, sub_bits):
    """A jittered grid of vertices covering the whole screen (border vertices on it), each
    quad split along a random diagonal: triangles as raw (n, 3) x and y arrays."""
    one = 1 << sub_bits
    gx = np.linspace(0, size * one, cols + 1).round().astype(np.int64)
    gy = np.linspace(0, size * one, rows + 1).round().astype(np.int64)
    X, Y = np.meshgrid(gx, gy)
    jit = lambda n: rng.integers(-one * size // (3 * max(cols, rows)), one * size // (3 * max(cols, rows)) + 1, n)
    X[1:-1, 1:-1] += jit(X[1:-1, 1:-1].shape)
    Y[1:-1, 1:-1] += jit(Y[1:-1, 1:-1].shape)
    # snap some interior vertices to pixel centres and edges to hit the tie cases
    snap = rng.random(X.shape) < 0.3
    X[snap] = (X[snap] // one) * one + one // 2
    Y[snap] = (Y[snap] // one) * one + one // 2
    X[:, 0], X[:, -1], Y[0], Y[-1] = 0, size * one, 0, size * one
    tx, ty = [], []
    for r in range(rows):
        for c in range(cols):
            a, b, cc, d = (r, c), (r, c + 1), (r + 1, c), (r + 1, c + 1)
            quads = [(a, b, d), (a, d, cc)] if rng.random() < 0.5 else [(a, b, cc), (b, d, cc)]
            for t in quads:
                order = list(t) if rng.random() < 0.5 else list(t)[::-1]   # both windings
                tx.append([X[p] for p in order])
                ty.append([Y[p] for p in order])
    return np.array(tx), np.array(ty)


@pytest.mark.parametrize("seed", range(4))
def test_a_mesh_covers_every_pixel_exactly_once(seed):
    rng = np.random.default_rng(seed)
    size, sub = 64, 4
    x, y = mesh(rng, 5 + seed, 4 + seed, size, sub)
    tri, px, py = raster.coverage(x, y, sub, 6)
    counts = np.zeros((size, size), int)
    np.add.at(counts, (py, px), 1)
    assert (counts == 1).all(), f"{(counts == 0).sum()} gaps, {(counts > 1).sum()} overlaps"


def test_coverage_agrees_with_a_float_inside_test_away_from_edges():
    rng = np.random.default_rng(11)
    x = rng.integers(-200, 1300, (60, 3))
    y = rng.integers(-200, 1300, (60, 3))
    tri, px, py = raster.coverage(x, y, 4, 6)
    got = set(zip(tri.tolist(), px.tolist(), py.tolist()))
    for t in range(60):
        vx, vy = x[t] / 16, y[t] / 16
        cy, cx = np.mgrid[0:64, 0:64]
        cxf, cyf = cx + 0.5, cy + 0.5
        e = [(vx[b] - vx[a]) * (cyf - vy[a]) - (vy[b] - vy[a]) * (cxf - vx[a])
             for a, b in ((0, 1), (1, 2), (2, 0))]
        sign = np.sign((vx[1] - vx[0]) * (vy[2] - vy[0]) - (vx[2] - vx[0]) * (vy[1] - vy[0]))
        strictly = np.all([sign * k > 1e-9 for k in e], 0) if sign else np.zeros_like(cx, bool)
        outside = np.any([sign * k < -1e-9 for k in e], 0) if sign else np.ones_like(cx, bool)
        for j, i in zip(*np.nonzero(strictly)):
            assert (t, i, j) in got
        for j, i in zip(*np.nonzero(outside)):
            assert (t, i, j) not in got


def test_degenerate_triangles_cover_nothing():
    x = np.array([[0, 160, 320], [16, 16, 16]])
    y = np.array([[0, 160, 320], [0, 100, 700]])
    assert len(raster.coverage(x, y, 4, 6)[0]) == 0


# ---- quadratic vector interpolation on the torus (seed 000 §2) ------------------------------

def test_torus_vector_lengths_are_near_the_seeds_figures():
    r = torus.length_errors()
    assert r["triangles"] == 288
    assert abs(r["max_normal_angle_deg"] - 41.4) < 0.05          # seed 001 §5's torus
    # seed 000 reports mean 0.45 %, max 3.2 % for quadratic interpolation; ours (mid-edge
    # vectors as normalised averages) stays within those, far below linear interpolation's
    assert r["quadratic"]["mean"] < 0.45 and r["quadratic"]["max"] < 3.2
    assert r["linear"]["mean"] > 10 * r["quadratic"]["mean"]


def test_the_degree_measure_sees_flat_and_curved_meshes():
    """flows.degree (issue 49's per-triangle degree, measured): a plane's normals are all
    equal, so every edge constant is 0 and every X-shading term a, b, c is 0 (each triangle
    linear); the default torus's neighbouring normals differ by 30 degrees, so none is."""
    from flows.degree import worst_terms
    from scene import driver as S
    plane = S.prepare(S.parse({"mesh": {"shape": "plane", "segments": [4, 4]},
                               "camera": {"eye": [0.0, -2.0, 3.0]}}, "plane"))
    assert len(plane["inputs"]["x0"]) > 10 and (worst_terms(plane) == 0).all()
    torus = worst_terms(S.prepare(S.load("scenes/default.toml")))
    assert (torus > 2.0 ** -15).all()


@pytest.mark.parametrize("m, recip", [(14, False), (18, False), (22, False), (20, True)])
def test_the_block_floating_point_bound_holds(m, recip):
    """flows.bfp.bound (issue 49): the row start's error derived per triangle from its
    exponents and its widest chord must cover the emulated error (every product's operands
    rounded to m-bit mantissas, against the float model) at every fragment, slivers and
    screen-sized triangles included, and in the exact mode's larger terms; ``recip``: u and
    v made from mantissas of the numerator and the reciprocal (three roundings). Each term of the
    derivation is a worst case that the others seldom meet at once: the bound is 4-11 times
    the worst error (flows.bfp's table), and a bound 20 times over would be vacuous."""
    from flows.bfp import errors
    from golden import random_triangles, TYPICAL_SIZE
    rng = np.random.default_rng(7)
    for size in (TYPICAL_SIZE, None):                 # typical and screen-sized, at 256 x 256
        inputs = random_triangles(rng, 150, screen_bits=8, sub_bits=4, channels=2,
                                  **({"size": size} if size else {}))
        tri, err, width, bnd = errors(inputs, m, 8, 4, ("xshading", "exact"), recip)
        assert len(tri) > 1000 and (width[np.unique(tri)] < 1).any()      # slivers drawn
        assert (err <= bnd[tri]).all()
        assert (err / bnd[tri]).max() > 0.05                # the bound is not vacuous
