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


def wrap(angle):
    """``angle`` modulo 2 pi into [0, 2 pi): ``np.mod`` of a tiny negative angle rounds to
    2 pi itself, which is 0."""
    w = np.mod(angle, 2 * np.pi)
    return np.where(w >= 2 * np.pi, 0.0, w)


def to_polar(v):
    """(phi in [0, 2 pi), theta in [0, pi]) of vectors (..., 3); phi = 0 on the z axis."""
    v = np.asarray(v, float)
    phi = wrap(np.arctan2(v[..., 1], v[..., 0]))
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
    phi = wrap(np.arctan2(num, np.sin(z)))
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


# ---- the rotation unit's model and bounds (hdl/rotation_unit/rotation.py) --------------------

def rotation_float(inp, angle_bits=12, method="paper", **_):
    """The published method (or the exact rotation) on the inputs' binary angles;
    (phi', theta') in raw LSBs."""
    a = {k: turns(v, angle_bits) for k, v in inp.items()}
    rotate = rotate_paper if method == "paper" else rotate_exact
    phi, theta = rotate(a["phi_n"], a["theta_n"], a["phi_a"], a["theta_a"])
    scale = 2**angle_bits / (2 * np.pi)
    return {"phi": phi * scale, "theta": theta * scale}


def _range_abs_sin(lo, hi):
    """min and max of |sin z| over [lo, hi] (hi - lo < pi)."""
    ends = np.abs(np.sin(np.stack([lo, hi])))
    mn, mx = ends.min(axis=0), ends.max(axis=0)
    k0 = np.ceil(lo / np.pi) <= np.floor(hi / np.pi)                     # a multiple of pi
    k1 = np.ceil(lo / np.pi - 0.5) <= np.floor(hi / np.pi - 0.5)         # pi/2 + k pi
    return np.where(k0, 0.0, mn), np.where(k1, 1.0, mx)


def _phi_arcs(phi_model, pm_lo, pm_hi, x_neg, x_pos, y_neg, y_pos):
    """The farthest phi' the RTL can give from the model: every quadrant the possible signs
    of x' and y' allow gives an arc of phi' from the interval [pm_lo, pm_hi] of its
    first-quadrant magnitude (half a turn if an arc holds the model's antipode)."""
    far = np.zeros_like(phi_model)
    for xn, x_ok in ((False, x_pos), (True, x_neg)):
        for yn, y_ok in ((False, y_pos), (True, y_neg)):
            b_lo, b_hi = (np.pi - pm_hi, np.pi - pm_lo) if xn else (pm_lo, pm_hi)
            lo, hi = (-b_hi, -b_lo) if yn else (b_lo, b_hi)
            d_lo = np.abs(np.angle(np.exp(1j * (lo - phi_model))))
            d_hi = np.abs(np.angle(np.exp(1j * (hi - phi_model))))
            holds_antipode = np.mod(phi_model + np.pi - lo, 2 * np.pi) <= hi - lo
            arc = np.where(holds_antipode, np.pi, np.maximum(d_lo, d_hi))
            far = np.where(x_ok & y_ok, np.maximum(far, arc), far)
    return far


def rotation_bounds(inp, method="paper", **params):
    """Per-row bounds on |RTL - rotation_float| in LSBs of the angle (see _paper_bounds)."""
    return (_paper_bounds if method == "paper" else _exact_bounds)(inp, **params)


def _paper_bounds(inp, angle_bits=12, trig_bits=14, asin_bits=12, atan_bits=8,
                  prop_bits=12, iterations=None):
    """Per-row bounds on |RTL - rotation_float| in LSBs of the angle, by interval arithmetic.

    Every intermediate value of the datapath is carried as an interval that must hold the
    RTL's value: a table output lies within the measured error of the entries its input
    interval can address (``Lut.error_over``, each over its whole bin) of the function, and asin, atan and
    Tprop are monotone; products of non-negative intervals multiply their ends; theta' is
    monotone in |Z| and in theta_prop, so its extremes are at the corners. The bound is the
    distance from the float model to the far end of the interval, plus half an LSB for
    theta's rounding. Where the sign of Z or of the numerator is not determined, phi' may lie
    in any quadrant those signs allow; next to N (where phi' is meaningless) that is any
    angle, and the bound is half a turn.
    """
    from hdl.rotation_unit.rotation import (PROP_FRAC, asin_lut, atan_lut,
                                            prop_lut, recip_sin_lut)
    from hdl.lut import quarter_cos_lut
    lsb = 2 * np.pi / 2**angle_bits
    a = {k: turns(v, angle_bits) for k, v in inp.items()}
    d = a["phi_a"] - a["phi_n"]
    x, y = a["theta_a"] + d, a["theta_a"] - d
    eps = quarter_cos_lut(trig_bits, 1 << (angle_bits - 2)).max_error * 2.0**-trig_bits
    s = (np.sin(x) + np.sin(y)) / 2
    num = (np.cos(y) - np.cos(x)) / 2
    e_asin = asin_lut(asin_bits, angle_bits).error_over(np.abs(s) - eps, np.abs(s) + eps) * lsb
    thx_lo = np.arcsin(np.clip(s - eps, -1, 1)) - e_asin
    thx_hi = np.arcsin(np.clip(s + eps, -1, 1)) + e_asin
    z_mid = np.angle(np.exp(1j * ((thx_lo + thx_hi) / 2 - a["theta_n"])))
    half_w = (thx_hi - thx_lo) / 2
    z_lo, z_hi = z_mid - half_w, z_mid + half_w
    az_lo = np.where((z_lo <= 0) & (z_hi >= 0), 0.0, np.minimum(np.abs(z_lo), np.abs(z_hi)))
    az_hi = np.minimum(np.maximum(np.abs(z_lo), np.abs(z_hi)), np.pi)
    recip = recip_sin_lut(angle_bits)
    r_top, e_r = recip.contents[0] * 2.0**-recip.fmt.frac_bits, recip.max_error * recip.fmt.lsb

    def recip_range(mn, mx):          # the table saturates at its first entry, r_top
        return (np.minimum(1 / (2 * np.maximum(mx, 1e-300)), r_top) - e_r,
                np.minimum(1 / (2 * np.maximum(mn, 1e-300)), r_top) + e_r)

    rs_lo, rs_hi = recip_range(*_range_abs_sin(z_lo, z_hi))
    rc_lo, rc_hi = recip_range(*_range_abs_sin(z_lo + np.pi / 2, z_hi + np.pi / 2))
    n_lo, n_hi = 2 * num - 2 * eps, 2 * num + 2 * eps                  # n2 = cos Y - cos X
    an_lo = np.where((n_lo <= 0) & (n_hi >= 0), 0.0, np.minimum(np.abs(n_lo), np.abs(n_hi)))
    an_hi = np.maximum(np.abs(n_lo), np.abs(n_hi))
    # phi': atan of |n2| / (2 |sin Z|) (floating-point addressed, saturating at the top)
    r_lo, r_hi = an_lo * np.maximum(rs_lo, 0), an_hi * rs_hi
    e_atan = atan_lut(atan_bits, angle_bits).error_over(r_lo, r_hi) * lsb
    r_max = 2.0 ** (angle_bits - 2)
    pm_lo = np.arctan(np.minimum(r_lo, r_max * (1 - 2.0**-atan_bits))) - e_atan
    pm_hi = np.arctan(r_hi) + e_atan
    want = rotation_float(inp, angle_bits)
    phi_model = want["phi"] * lsb
    # the RTL wraps Z into [-180, 180): values past either end change sign
    x_neg = ((z_lo < 0) & (z_hi >= -np.pi)) | (z_hi >= np.pi)
    x_pos = ((z_hi >= 0) & (z_lo < np.pi)) | (z_lo < -np.pi)
    phi_bound = _phi_arcs(phi_model, pm_lo, pm_hi, x_neg, x_pos, n_lo < 0, n_hi >= 0) / lsb
    # theta': |Z| + (90 - |Z|) Tprop(min(|n2| / (2 |cos Z|), 1))
    yk_lo, yk_hi = np.minimum(an_lo * np.maximum(rc_lo, 0), 1), np.minimum(an_hi * rc_hi, 1)
    e_prop = prop_lut(prop_bits).error_over(yk_lo, yk_hi) * 2.0**-PROP_FRAC
    tprop = lambda v: 1 - np.arccos(v) / (np.pi / 2)                          # noqa: E731
    p_lo, p_hi = tprop(yk_lo) - e_prop, tprop(yk_hi) + e_prop
    corners = np.stack([az + (np.pi / 2 - az) * pr for az in (az_lo, az_hi)
                        for pr in (p_lo, p_hi)])
    theta_model = want["theta"] * lsb
    theta_bound = np.maximum(corners.max(axis=0) - theta_model,
                             theta_model - corners.min(axis=0)) / lsb + 0.5
    return {"phi": phi_bound, "theta": theta_bound}


def _exact_bounds(inp, angle_bits=12, trig_bits=14, iterations=16, **_):
    """Bounds of the exact variant (hdl/rotation_unit: x', y', z' from the cosine table, then
    two vectoring CORDICs), in LSBs of the angle:

    - the Cartesian values: z' = cos theta' and x' within 3 eps + eps**2 (the law of cosines,
      as illum; s cos tN has 2 eps + eps**2, cos tA sin tN eps), y' within eps, eps the
      cosine table's error; |z'| cut to 17 fraction bits before it is scaled by K (K itself
      rounded to GAIN_FRAC bits: theta' moves by at most |K_q / K - 1| / 2);
    - a perturbation d of a 2-D vector of length l turns its angle by at most asin(d / l)
      (half a turn once d >= l): phi' = atan2(y', x') with l = r = sqrt(x'^2 + y'^2),
      theta' = atan2(r, z') with l = 1;
    - each CORDIC: the angle left after its last micro-rotation, atan(2**-(iterations - 1));
      the micro-rotations' angles, each rounded to half an accumulator LSB; the datapath's
      truncations, each shift below 2**-F in x and y, so the final vector within
      iterations * sqrt 2 * K * 2**-F of its exact value, an angle of that over K l (for
      CORDIC 1 it also lengthens r: theta's perturbation takes it);
    - the output rounded to half an LSB."""
    from hdl.lut import quarter_cos_lut
    from hdl.rotation_unit.rotation import (ANGLE_GUARD, CORDIC_FRAC, GAIN_FRAC, cordic_gain)
    lsb = 2 * np.pi / 2**angle_bits
    a = {k: turns(v, angle_bits) for k, v in inp.items()}
    pa, ta, pn, tn = a["phi_a"], a["theta_a"], a["phi_n"], a["theta_n"]
    eps = quarter_cos_lut(trig_bits, 1 << (angle_bits - 2)).max_error * 2.0**-trig_bits
    d = pa - pn
    x = np.sin(ta) * np.cos(d) * np.cos(tn) - np.cos(ta) * np.sin(tn)
    y = np.sin(ta) * np.sin(d)
    r = np.hypot(x, y)
    k = cordic_gain(iterations)
    e_x = e_z = 3 * eps + eps * eps
    e_y = eps
    datapath = iterations * np.sqrt(2) * k * 2.0**-CORDIC_FRAC     # a CORDIC's final vector
    own = np.arctan(2.0**(1 - iterations)) \
        + iterations * 0.5 * 2 * np.pi / 2**(angle_bits + ANGLE_GUARD)   # residual, table

    def turned(dev, length):
        return np.where(dev < length, np.arcsin(np.minimum(dev / np.maximum(length, 1e-300),
                                                           1.0)), np.pi)

    e_gain = abs(round(k * 2**GAIN_FRAC) / 2**GAIN_FRAC / k - 1) / 2
    dev_r = np.hypot(e_x, e_y) + datapath / k
    dev_z = e_z + 2.0**-17 + 2.0**-CORDIC_FRAC / k
    theta_bound = turned(dev_r + dev_z, 1.0) + e_gain + own + datapath / k + 0.5 * lsb
    phi_bound = np.minimum(turned(np.hypot(e_x, e_y), r) + own
                           + datapath / (k * np.maximum(r, 1e-300)), np.pi) + 0.5 * lsb
    return {"phi": np.minimum(phi_bound, np.pi) / lsb, "theta": theta_bound / lsb}


# ---- bump_polar: two rotations and the illumination ------------------------------------------

def _rotated(inp, vec, params):
    keep = {k: params[k] for k in ("method", "angle_bits", "trig_bits", "asin_bits", "atan_bits",
                                   "prop_bits", "iterations") if k in params}
    rows = {"phi_n": inp["phi_n"], "theta_n": inp["theta_n"], "phi_a": inp[f"phi_{vec}"],
            "theta_a": inp[f"theta_{vec}"]}
    return rotation_float(rows, **keep), rotation_bounds(rows, **keep)


def bump_polar_float(inp, **params):
    """illum_float on the float rotations of L and H (real angles, not rounded to steps)."""
    (l_rot, _), (h_rot, _) = _rotated(inp, "l", params), _rotated(inp, "h", params)
    rows = {"phi_l": l_rot["phi"], "theta_l": l_rot["theta"], "phi_h": h_rot["phi"],
            "theta_h": h_rot["theta"], "phi_n": inp["phi_b"], "theta_n": inp["theta_b"]}
    keep = {k: params[k] for k in ("angle_bits", "trig_bits", "table_bits", "shininess")
            if k in params}
    return illum_float(rows, **keep)


def bump_polar_bounds(inp, **params):
    """The illumination's bounds, plus what the rotations' errors do to the inner products.

    A rotated vector off by d_theta and d_phi (the rotation bounds, in radians) is off in
    direction by at most d_theta + sin(theta' + d_theta) d_phi, and an inner product of unit
    vectors changes by at most that angle. The diffuse table passes it on with slope 1, the
    specular table with slope ``shininess``."""
    bits = params.get("angle_bits", 12)
    lsb = 2 * np.pi / 2**bits
    keep = {k: params[k] for k in ("angle_bits", "trig_bits", "table_bits", "shininess")
            if k in params}
    base = illum_bounds(**keep)
    out = {}
    for vec, table, slope in (("l", "diffuse", 1), ("h", "specular",
                                                   params.get("shininess", 16))):
        rot, bound = _rotated(inp, vec, params)
        d_theta, d_phi = bound["theta"] * lsb, bound["phi"] * lsb
        reach = np.minimum(rot["theta"] * lsb + d_theta, np.pi / 2)
        angle = np.minimum(d_theta + np.sin(reach) * d_phi, np.pi)
        out[f"dot_{vec}"] = base[f"dot_{vec}"] + angle * 2**15
        out[table] = base[table] + slope * angle * 2**15
    return out
