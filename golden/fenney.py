"""Models of Fenney's bump shading (US 6,819,319), independent of the RTL.

- Bit-exact integer models where the patent defines integer arithmetic: the texel decode and
  the power approximation.
- Float models (numpy, real sin/cos/sqrt) where it does not: the dot product and the polar
  shading. Their outputs are real numbers in raw units (LSBs of the output field).
- The bounds the RTL must meet against the float models, derived from its fraction bits and
  its tables (``hdl.lut`` reports each table's error).
"""
import math

import numpy as np

from hdl.illum_unit import fenney_dot as dot_hw
from hdl.lut import quarter_cos_lut

# ---- texel decode (second embodiment) --------------------------------------------------------


def texel_decode(texel_x, texel_z):
    """The patent's decode, with the invalid-texel policy of hdl/illum_unit/texel_decode.py."""
    tx, tz = np.asarray(texel_x, np.int64), np.asarray(texel_z, np.int64)
    bx = (np.minimum(tx, 254) - 127) * 2
    bz = (np.minimum(tz, 254) - 127) * 2
    l1 = np.abs(bx) + np.abs(bz)
    return {"x": bx, "y": np.maximum(0, 255 - l1), "z": bz,
            "invalid": ((tx == 255) | (tz == 255) | (l1 > 255)).astype(np.int64)}


def texel_encode(v):
    """Unit vectors (..., 3), y up, to (texel_x, texel_z): scale to |x|+|y|+|z| = 1, then
    ``TexelX = int(xs * 127) + 127`` (C truncation; the patent's "- 127" for Z is a misprint)."""
    v = np.asarray(v, float)
    vs = v / np.abs(v).sum(axis=-1, keepdims=True)
    return np.trunc(vs[..., 0] * 127).astype(np.int64) + 127, \
        np.trunc(vs[..., 2] * 127).astype(np.int64) + 127


# ---- power approximation ---------------------------------------------------------------------


def power_int(x, c):
    """P(X, C), bit-exact to the patent (see hdl/illum_unit/fenney_power.py)."""
    x, c = np.asarray(x, np.int64), np.asarray(c, np.int64)
    lum = np.maximum(0, 1023 - (((c + 8) * (1023 - x)) >> 3))
    q = (lum * lum) >> 10
    return lum + ((c * (q - lum)) >> 8)


def power_float(x, c):
    """P(X, C) on reals, X in [0, 1]: the patent's quadratic without its integer steps,
    lum = max(0, 1 - (C + 8) (1 - X) / 8), P = lum + C (lum^2 - lum) / 256."""
    lum = np.maximum(0.0, 1 - (np.asarray(c, float) + 8) * (1 - np.asarray(x, float)) / 8)
    return lum + np.asarray(c, float) * (lum * lum - lum) / 256


def power_exponent(c, x=np.arange(1, 1024)):
    """Which power x**n the approximation with concentration c stands for.

    Returns ``(n_fit, max_err, n_half)``: the exponent of the least-squares fit over
    X = 1..1023 (searched on a log grid from 1 to 1024), the largest error of that fit in LSBs
    of the 10-bit fraction, and the exponent whose curve falls to 1/2 where P does."""
    p = power_int(x, c) / 1023.0
    t = x / 1023.0
    ns = np.geomspace(1.0, 1024.0, 4001)
    err = p[None, :] - t[None, :] ** ns[:, None]
    k = int(np.argmin((err ** 2).sum(axis=1)))
    x_half = t[np.argmax(p >= 0.5)]
    return float(ns[k]), float(np.abs(err[k]).max() * 1023), float(np.log(0.5) / np.log(x_half))


# ---- dot product -----------------------------------------------------------------------------


def _dot_terms(inp, normalize):
    b = np.stack([inp["x"], inp["y"], inp["z"]]).astype(float)
    light = np.stack([inp["lx"], inp["ly"], inp["lz"]]).astype(float)
    dot = (b * light).sum(axis=0)
    if normalize:
        length = np.maximum(np.sqrt((b * b).sum(axis=0)), dot_hw.MIN_LEN)
        return dot, dot / (127.0 * length)
    return dot, dot / (255.0 * 127.0)


def dot_float(inp, normalize=False, rsqrt_bits=None):
    """(1-h) + h*d as a 10-bit fraction (value * 1024), saturated to 0..1023."""
    _, d = _dot_terms(inp, normalize)
    h = np.asarray(inp["h"], float) / 255.0
    return np.clip(1024.0 * ((1.0 - h) + h * d), 0.0, 1023.0)


def dot_bound(inp, normalize=False, rsqrt_bits=12):
    """Per-row bound on |RTL - dot_float| in output LSBs.

    - 0.5 for the final rounding (``M * K + 2**35 >> 36`` is round-half-up);
    - ``h/4080 * E_dq``: the error of ``dq`` (d * 2**14) carried through ``M / 4080``, where
      ``E_dq = 0.5 + |D| * E_g / 2**15``, ``E_g`` the error of g in its LSBs (the table's
      ``max_error``; or, for n2 >= 65536, shifted two bits down, ``E_g + 1.01`` over ``2**16``:
      the truncated n2 >> 2 can sit one step past its bin, where g moves by at most
      2**29 / (127 * 128) / (2 * 16384) = 1.01 LSB);
    - ``|M| * |K / 2**36 - 1/4080|``: the constant divider.
    """
    dot, _ = _dot_terms(inp, normalize)
    h = np.asarray(inp["h"], float)
    if normalize:
        e_g = dot_hw.rsqrt_lut(rsqrt_bits).max_error
        n2 = sum(np.asarray(inp[k], float) ** 2 for k in "xyz")
        e_dq = np.where(n2 >= 65536, 0.5 + np.abs(dot) * (e_g + 1.01) / 2**16,
                        0.5 + np.abs(dot) * e_g / 2**15)
    else:
        e_g = abs(dot_hw.G_PLAIN - 2**dot_hw.G_FRAC / (127 * 255))
        e_dq = 0.5 + np.abs(dot) * e_g / 2**15
    m_max = 255 * 2**14 + h * (np.abs(dot) * 2**14 / (127 * 128) + 1)
    divider = m_max * abs(dot_hw.DIV_K / 2**dot_hw.DIV_SHIFT - 1 / 4080)
    return 0.5 + h / 4080 * e_dq + divider


def true_cosine_error(n=200_000, rng=None):
    """What the dot product costs against the true cosine, fixed point aside.

    Random unit bump normals on the upper hemisphere and unit lights (any direction) are
    encoded as the hardware sees them (texels; lights as int(l * 127)), decoded, and dotted
    (h = 1). Returns ``{normalize: (max, rms)}`` of ``1024 * (d - cos)``, in LSBs of X."""
    rng = np.random.default_rng(1) if rng is None else rng
    nrm = rng.normal(size=(n, 3))
    nrm[:, 1] = np.abs(nrm[:, 1])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True)
    lgt = rng.normal(size=(n, 3))
    lgt /= np.linalg.norm(lgt, axis=1, keepdims=True)
    cos = (nrm * lgt).sum(axis=1)
    inp = texel_decode(*texel_encode(nrm))
    li = np.trunc(lgt * 127).astype(np.int64)
    inp.update(lx=li[:, 0], ly=li[:, 1], lz=li[:, 2], h=np.full(n, 255))
    out = {}
    for normalize in (False, True):
        _, d = _dot_terms(inp, normalize)
        e = 1024 * (d - cos)
        out[normalize] = (float(np.abs(e).max()), float(np.sqrt((e ** 2).mean())))
    return out


# ---- polar shading (first embodiment) --------------------------------------------------------


def polar_float(inp):
    """k1 + k2 sin S + k3 cos S cos(R - Q), in LSBs of the u8 intensity, clamped to 0..255."""
    s_ang = np.asarray(inp["s"], float) / 256 * (np.pi / 2)
    d_ang = (np.asarray(inp["r"], float) - np.asarray(inp["q"], float)) / 256 * (2 * np.pi)
    k1, k2, k3 = (np.asarray(inp[k], float) for k in ("k1", "k2", "k3"))
    return np.clip(k1 + k2 * np.sin(s_ang) + k3 * np.cos(s_ang) * np.cos(d_ang), 0.0, 255.0)


def polar_bound(trig_bits=10):
    """0.5 for rounding, plus the three table entries' error e through the products:
    (k2 + 2 k3) e 2**-T + k3 e**2 2**-2T <= 255 (3e + e**2 2**-T) 2**-T."""
    e = quarter_cos_lut(trig_bits).max_error
    return 0.5 + 255 * (3 * e + e * e * 2.0**-trig_bits) * 2.0**-trig_bits


def expand8to10(i):
    """The 8-bit intensity widened to the power unit's X by bit replication."""
    i = np.asarray(i, np.int64)
    return (i << 2) | (i >> 6)


def concentration_for(n):
    """The concentration C whose fitted exponent (``power_exponent``, least
    squares over X = 1..1023) is nearest to n on a log scale. The fitted exponent grows with C,
    so a bisection finds it; C = 0..255 covers n of about 1 to 300, and n beyond the ends
    takes the end."""
    fit = lambda c: math.log(power_exponent(c)[0])
    lo, hi, target = 0, 255, math.log(n)
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if fit(mid) < target else (lo, mid)
    return min((lo, hi), key=lambda c: abs(fit(c) - target))
