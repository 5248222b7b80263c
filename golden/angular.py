"""Models of seed 003 (Lee et al. 2003): the angular vector rotation and the law-of-cosines
illumination, in float (numpy, angles in radians). The seed's text is damaged; the equations
follow ``design/math-notes.md`` §2-3, and the decisions it leaves open are stated here.

Polar coordinates (phi, theta): phi is the angle from the x axis of the vector's projection
on the xy-plane, theta the angle from the z axis. The rotation takes A into the frame in which
N is the z axis: first -phi_N about z, then -theta_N about y.
"""
import numpy as np
from scipy.spatial.transform import Rotation

HALF_PI = np.pi / 2


def to_vector(phi, theta):
    phi, theta = np.asarray(phi, float), np.asarray(theta, float)
    return np.stack([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)],
                    axis=-1)


def to_polar(v):
    """(phi in [0, 2 pi), theta in [0, pi]) of vectors (..., 3); phi = 0 on the z axis."""
    v = np.asarray(v, float)
    phi = np.mod(np.arctan2(v[..., 1], v[..., 0]), 2 * np.pi)
    theta = np.arccos(np.clip(v[..., 2] / np.linalg.norm(v, axis=-1), -1.0, 1.0))
    return phi, theta


def rotate_exact(phi_n, theta_n, phi_a, theta_a):
    """A in the frame where N is the z axis: R = Ry(-theta_N) Rz(-phi_N), by scipy."""
    pn, tn, pa, ta = np.broadcast_arrays(*(np.asarray(v, float)
                                           for v in (phi_n, theta_n, phi_a, theta_a)))
    rot = Rotation.from_euler("zy", np.stack([-pn.ravel(), -tn.ravel()], axis=-1))  # extrinsic
    out = rot.apply(to_vector(pa.ravel(), ta.ravel()))
    return to_polar(out.reshape(pn.shape + (3,)))


def rotate_paper(phi_n, theta_n, phi_a, theta_a):
    """The published method (seed 003 eq 5-27), with the cases it leaves open decided.

    With D = phi_A - phi_N, X = theta_A + D, Y = theta_A - D:

    - theta_x = asin((sin X + sin Y) / 2)                  (eq 5-7) = asin(sin theta_A cos D)
    - Z = theta_x - theta_N
    - phi' = atan((cos Y - cos X) / (2 sin Z))             (eq 8-9)
    - yk = (cos Y - cos X) / (2 cos Z)                      (eq 27)
    - theta_prop = 1 - acos(yk) / 90 deg                    (eq 21, 26)
    - theta' = Z + (90 deg - Z) theta_prop                  (eq 19)

    Decisions (the paper is silent):

    - **Negative Z** (the vector falls on the -x side of N): phi' is taken with atan2 of the
      numerator and sin Z, which puts it in the right half-plane, and theta' uses |Z|, the
      angle from the z axis on that side. Z is first wrapped into (-180, 180] deg, so that a
      normal past the horizon (theta_N > 90 deg) still gives |Z| <= 180 deg.
    - **sin Z -> 0**: atan2 gives +-90 deg (the vector lies in the yz-plane), and 0 when the
      numerator is 0 as well.
    - **yk**: taken as |cos Y - cos X| / (2 |cos Z|), since the elevation does not depend on
      the side of y, and clamped to 1: |yk| >= 1 (cos Z -> 0 included) gives theta_prop = 1
      and theta' = 90 deg, the horizon.
    """
    phi_n, theta_n, phi_a, theta_a = (np.asarray(v, float) for v in
                                      (phi_n, theta_n, phi_a, theta_a))
    d = phi_a - phi_n
    x, y = theta_a + d, theta_a - d
    theta_x = np.arcsin(np.clip((np.sin(x) + np.sin(y)) / 2, -1.0, 1.0))
    z = np.angle(np.exp(1j * (theta_x - theta_n)))          # Z, wrapped into (-pi, pi]
    num = (np.cos(y) - np.cos(x)) / 2                       # sin theta_A sin D
    phi = np.mod(np.arctan2(num, np.sin(z)), 2 * np.pi)
    cos_z = np.abs(np.cos(z))
    yk = np.where(cos_z > 0, np.abs(num) / np.where(cos_z > 0, cos_z, 1.0), 1.0)
    prop = 1.0 - np.arccos(np.minimum(yk, 1.0)) / HALF_PI
    az = np.abs(z)
    return phi, az + (HALF_PI - az) * prop


def inner_product(phi_a, theta_a, phi_n, theta_n):
    """N'.A' by the law of cosines (seed 003 eq 22-25), exact:
    1/2 [cos(tA - tN) + cos(tA + tN)] + 1/2 [cos(tA - tN) - cos(tA + tN)] cos(phiA - phiN)."""
    c_minus, c_plus = np.cos(theta_a - theta_n), np.cos(theta_a + theta_n)
    return (c_minus + c_plus) / 2 + (c_minus - c_plus) / 2 * np.cos(phi_a - phi_n)


def random_hemisphere(rng, n):
    """Polar angles of n unit vectors uniform on the upper hemisphere (z >= 0)."""
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.abs(v[:, 2])
    return to_polar(v)


SEPARATION_BINS = ((0, 15), (15, 30), (30, 45), (45, 90))


def method_error(n=200_000, seed=0):
    """The published rotation against the exact one, fixed point aside.

    N and A uniform on the upper hemisphere. Returns rows per bin of the angle between N and
    A (degrees): ``(lo, hi, count, angle mean, p99, max (deg), |N'.A' error| mean, p99, max)``
    where the angle is between the two rotated vectors and N'.A' = cos theta' (N' is z)."""
    rng = np.random.default_rng(seed)
    pn, tn = random_hemisphere(rng, n)
    pa, ta = random_hemisphere(rng, n)
    ex = to_vector(*rotate_exact(pn, tn, pa, ta))
    pp = to_vector(*rotate_paper(pn, tn, pa, ta))
    angle = np.degrees(np.arccos(np.clip((ex * pp).sum(axis=-1), -1.0, 1.0)))
    dot_err = np.abs(pp[:, 2] - ex[:, 2])
    sep = np.degrees(np.arccos(np.clip((to_vector(pn, tn) * to_vector(pa, ta)).sum(-1), -1, 1)))
    rows = []
    for lo, hi in SEPARATION_BINS:
        m = (sep >= lo) & (sep < hi)
        a, e = angle[m], dot_err[m]
        rows.append((lo, hi, int(m.sum()), a.mean(), np.percentile(a, 99), a.max(),
                     e.mean(), np.percentile(e, 99), e.max()))
    return rows, sep, angle


# ---- the illumination unit's model and bounds (hdl/illum_unit/illum.py) ----------------------

def turns(raw, bits):
    return np.asarray(raw, float) * (2 * np.pi / 2**bits)


def illum_float(inp, angle_bits=10, trig_bits=14, table_bits=10, shininess=16):
    """Clamped inner products, diffuse d and specular d**shininess, in LSBs of 2**-15."""
    a = {k: turns(v, angle_bits) for k, v in inp.items()}
    out = {}
    for v in ("l", "h"):
        d = np.clip(inner_product(a[f"phi_{v}"], a[f"theta_{v}"], a["phi_n"], a["theta_n"]),
                    0.0, 1.0)
        out[f"dot_{v}"] = d * 2**15
        out[{"l": "diffuse", "h": "specular"}[v]] = d ** (1 if v == "l" else shininess) * 2**15
    return out


def illum_bounds(angle_bits=10, trig_bits=14, table_bits=10, shininess=16):
    """Bounds on |RTL - illum_float| in LSBs of 2**-15, per output.

    Each cosine entry is within e LSB of 2**-T (e = the table's measured error), so
    eps = e 2**-T. Then 1/2 (c- + c+) is within eps, and 1/2 (c- - c+) cf within
    eps |cf| + eps |c- - c+| / 2 + eps**2 <= 2 eps + eps**2: the inner product within
    3 eps + eps**2, plus half an LSB for the rounding (clamping is 1-Lipschitz).
    A table output is within the table's error of f(d_RTL) (the builder measures it over the
    whole bin d_RTL falls in) and f(d_RTL) within max|f'| |d_RTL - d| of f(d): max|f'| is 1
    for the diffuse table and the shininess for the specular one."""
    from hdl.illum_unit.illum import shade_lut
    from hdl.lut import quarter_cos_lut
    eps = quarter_cos_lut(trig_bits, 1 << (angle_bits - 2)).max_error * 2.0**-trig_bits
    dot = (3 * eps + eps * eps) * 2**15 + 0.5
    dot_value = dot * 2.0**-15
    return {"dot_l": dot, "dot_h": dot,
            "diffuse": shade_lut(table_bits, 1).max_error + dot_value * 2**15,
            "specular": shade_lut(table_bits, shininess).max_error
            + shininess * dot_value * 2**15}
