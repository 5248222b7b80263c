"""Golden models: for every registered unit, its model, its vectors and its check.

``MODELS[name]`` has

- ``run(inputs, **params)``: output arrays in raw units (integers from a bit-exact model,
  reals from a float model);
- ``vectors(rng, n, **params)``: exactly ``n`` rows: the hard cases of
  ``design/math-notes.md`` §5 first, then random rows; ``n=None`` gives the full sweep
  (exhaustive where the input space allows);
- ``check(inputs, outputs, **params)``: ``{field: (error, bound)}`` per row, where ``error`` is
  ``|RTL - model|`` (or the distance to the set of allowed values) and ``bound`` the derived
  limit (0 for bit-exact fields);
- ``against_exact(inputs, outputs, **params)``: ``(error, what)``, the RTL's distance per row
  from the *exact* function the unit approximates (``make tradeoffs``' unit error), and
  ``exact_vectors(rng, n, **params)``: the rows it is measured on (by default ``vectors``).
"""
from dataclasses import dataclass
from typing import Callable

import numpy as np

from hdl.setup_unit.formats import EDGE, VALUE, edge_names, parse_groups, parse_precision

from . import angular, fenney, raster, shade

__all__ = ["MODELS", "Model", "TYPICAL_SIZE", "raster_bounds", "raster_hard_cases",
           "random_triangles"]


@dataclass(frozen=True)
class Model:
    run: Callable
    make_vectors: Callable     # hard cases first, then random rows; may give more than n
    check: Callable
    exact: bool              # every output bit-exact
    typical: int = 5000      # rows (triangles for raster) that make sim streams by default
    against_exact: Callable = None
    make_exact_vectors: Callable = None

    def vectors(self, rng, n, **params):
        out = self.make_vectors(rng, n, **params)
        return out if n is None else {k: np.asarray(v)[:n] for k, v in out.items()}

    def exact_vectors(self, rng, n, **params):
        return (self.make_exact_vectors or self.vectors)(rng, n, **params)


def _grid(*axes):
    mesh = np.meshgrid(*axes, indexing="ij")
    return [m.ravel().astype(np.int64) for m in mesh]


def _cat(*dicts):
    return {k: np.concatenate([np.asarray(d[k], np.int64) for d in dicts]) for k in dicts[0]}


def _random(rng, n, fmts):
    return {k: rng.integers(lo, hi + 1, size=n) for k, (lo, hi) in fmts.items()}


def _exact_check(model):
    def check(inputs, outputs, **params):
        want = model(inputs, **params)
        return {k: (np.abs(np.asarray(outputs[k], np.int64) - want[k]), 0) for k in want}
    return check


# ---- texel_decode ----------------------------------------------------------------------------

def _texel_run(inp, **_):
    return fenney.texel_decode(inp["texel_x"], inp["texel_z"])


def _texel_vectors(rng, n, **_):
    if n is None:                                                    # all 65,536 texels
        tx, tz = _grid(np.arange(256), np.arange(256))
        return {"texel_x": tx, "texel_z": tz}
    corners = [0, 1, 63, 64, 126, 127, 128, 191, 192, 253, 254, 255]
    tx, tz = _grid(corners, corners)
    return _cat({"texel_x": tx, "texel_z": tz},
                _random(rng, max(0, n - len(tx)), {"texel_x": (0, 255), "texel_z": (0, 255)}))


# ---- fenney_power ----------------------------------------------------------------------------

def _power_run(inp, **_):
    return {"p": fenney.power_int(inp["x"], inp["c"])}


def _power_vectors(rng, n, **_):
    if n is None:                                                    # all 262,144 inputs
        x, c = _grid(np.arange(1024), np.arange(256))
        return {"x": x, "c": c}
    x, c = _grid([0, 1, 2, 511, 512, 1021, 1022, 1023], [0, 1, 2, 127, 128, 254, 255])
    return _cat({"x": x, "c": c}, _random(rng, max(0, n - len(x)), {"x": (0, 1023), "c": (0, 255)}))


# ---- fenney_dot ------------------------------------------------------------------------------

def _flip(a):
    """-a within s8 (-128 flips to 127)."""
    return np.minimum(-np.asarray(a), 127)


def _unit_lights(rng, n):
    v = rng.normal(size=(n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    li = np.trunc(v * 127).astype(np.int64)
    return {"lx": li[:, 0], "ly": li[:, 1], "lz": li[:, 2]}


def _dot_vectors(rng, n, **_):
    n = 50_000 if n is None else n
    # hard cases: every corner of the input box (n2 up to 196,097, D at both extremes), the
    # light straight up and below the horizon, h = 0 and 255
    ends = [-256, -254, 0, 254, 255]
    x, y, z, lx, h = _grid(ends, [0, 1, 255], ends, [-128, -127, 0, 127], [0, 128, 255])
    hard = {"x": x, "y": y, "z": z, "lx": lx, "ly": _flip(lx), "lz": lx, "h": h}
    m = max(0, n - len(x))
    half = m // 2
    # decoded texels (valid and over-filtered) with unit lights ...
    tex = fenney.texel_decode(rng.integers(0, 256, half), rng.integers(0, 256, half))
    tex.pop("invalid")
    decoded = {**tex, **_unit_lights(rng, half), "h": rng.integers(0, 256, half)}
    # ... and anything the fields can hold
    anything = _random(rng, m - half, {"x": (-256, 255), "y": (0, 255), "z": (-256, 255),
                                       "lx": (-128, 127), "ly": (-128, 127),
                                       "lz": (-128, 127), "h": (0, 255)})
    return _cat(hard, decoded, anything)


def _dot_run(inp, normalize=False, rsqrt_bits=12):
    return {"x": fenney.dot_float(inp, normalize)}


def _dot_check(inp, out, normalize=False, rsqrt_bits=12):
    err = np.abs(np.asarray(out["x"], float) - fenney.dot_float(inp, normalize))
    return {"x": (err, fenney.dot_bound(inp, normalize, rsqrt_bits))}


# ---- fenney_xz -------------------------------------------------------------------------------

def _xz_dot_inputs(inp):
    dec = fenney.texel_decode(inp["texel_x"], inp["texel_z"])
    return {**dec, **{k: inp[k] for k in ("lx", "ly", "lz", "h")}}


def _xz_run(inp, normalize=False, rsqrt_bits=12):
    d = _xz_dot_inputs(inp)
    x = np.rint(fenney.dot_float(d, normalize))
    return {"p": fenney.power_int(x, inp["c"]), "invalid": d["invalid"]}


def _xz_check(inp, out, normalize=False, rsqrt_bits=12):
    """``p`` must be P(X, c) for an integer X within the dot product's bound of its float
    model; P is monotone in X, so the allowed set is every P(X) for X in [lo, hi]."""
    d = _xz_dot_inputs(inp)
    x = fenney.dot_float(d, normalize)
    b = fenney.dot_bound(d, normalize, rsqrt_bits)
    lo = np.clip(np.ceil(x - b), 0, 1023).astype(np.int64)
    hi = np.clip(np.floor(x + b), 0, 1023).astype(np.int64)
    p = np.asarray(out["p"], np.int64)
    span = int((hi - lo).max()) if len(lo) else 0
    cand = np.stack([fenney.power_int(np.minimum(lo + k, hi), inp["c"]) for k in range(span + 1)])
    dist = np.abs(cand - p[None, :]).min(axis=0)
    inv = np.abs(np.asarray(out["invalid"], np.int64) - d["invalid"])
    return {"p": (dist, 0), "invalid": (inv, 0)}


def _xz_vectors(rng, n, **_):
    n = 50_000 if n is None else n
    tx, tz, lx, c = _grid([0, 127, 254, 255], [0, 127, 254, 255], [-128, -127, 0, 127],
                          [0, 255])
    hard = {"texel_x": tx, "texel_z": tz, "lx": lx, "ly": _flip(lx), "lz": lx,
            "h": np.full(len(tx), 255), "c": c}
    m = max(0, n - len(tx))
    rnd = {**_random(rng, m, {"texel_x": (0, 255), "texel_z": (0, 255), "h": (0, 255),
                              "c": (0, 255)}), **_unit_lights(rng, m)}
    return _cat(hard, rnd)


# ---- fenney_polar ----------------------------------------------------------------------------

def _polar_run(inp, trig_bits=10):
    i = fenney.polar_float(inp)
    return {"intensity": i, "shade": fenney.power_int(fenney.expand8to10(np.rint(i)), inp["c"])}


def _polar_check(inp, out, trig_bits=10):
    i_rtl = np.asarray(out["intensity"], np.int64)
    shade = fenney.power_int(fenney.expand8to10(i_rtl), inp["c"])
    return {"intensity": (np.abs(i_rtl - fenney.polar_float(inp)), fenney.polar_bound(trig_bits)),
            "shade": (np.abs(np.asarray(out["shade"], np.int64) - shade), 0)}


def _polar_vectors(rng, n, **_):
    if n is None:        # every S against every R - Q, with random k and c
        s, r = _grid(np.arange(256), np.arange(256))
        m = len(s)
        rnd = _random(rng, m, {"k1": (0, 255), "k2": (0, 255), "k3": (0, 255), "q": (0, 255),
                               "c": (0, 255)})
        return {"s": s, "r": (r + rnd["q"]) % 256, **rnd}
    # hard cases: S at 0 and near 90 deg, R - Q at the quadrant edges (and wrapping), the k's
    # at their ends (the sum reaching -255 and 765), c at 0 and 255
    s, r, k, c = _grid([0, 1, 128, 254, 255], [0, 63, 64, 65, 127, 128, 129, 191, 192, 193, 255],
                       [0, 255], [0, 255])
    hard = {"s": s, "r": r, "k1": k, "k2": k, "k3": 255 - k, "q": np.zeros_like(s), "c": c}
    hard2 = dict(hard, k1=np.zeros_like(s), k2=np.zeros_like(s), k3=np.full_like(s, 255),
                 q=np.full_like(s, 128))
    m = max(0, n - 2 * len(s))
    rnd = _random(rng, m, {k: (0, 255) for k in ("s", "r", "k1", "k2", "k3", "q", "c")})
    return _cat(hard, hard2, rnd)


# ---- illum (seed 003) ------------------------------------------------------------------------

ILLUM_FIELDS = ("phi_l", "theta_l", "phi_h", "theta_h", "phi_n", "theta_n")


def _illum_run(inp, **params):
    return angular.illum_float(inp, **params)


def _illum_check(inp, out, **params):
    want = angular.illum_float(inp, **params)
    bounds = angular.illum_bounds(**params)
    return {k: (np.abs(np.asarray(out[k], float) - want[k]), bounds[k]) for k in want}


def _illum_vectors(rng, n, angle_bits=10, **_):
    n = 50_000 if n is None else n
    full, half, quarter = 1 << angle_bits, 1 << (angle_bits - 1), 1 << (angle_bits - 2)
    # hard cases: N' = A' (inner product 1), opposite (negative, clamps), theta sums past
    # 180 deg, theta = 0 (phi meaningless), phi wrapping at 0/360, quarter-turn edges
    edge = [0, 1, quarter - 1, quarter, quarter + 1, half - 1, half, full - 1]
    pa, ta, pn, tn = _grid(edge, edge[:7], [0, full - 1, half], [0, quarter, half])
    hard = {"phi_l": pa, "theta_l": ta, "phi_h": pn, "theta_h": tn, "phi_n": pn,
            "theta_n": tn}
    m = max(0, n - len(pa))
    rnd = _random(rng, m, {k: (0, full - 1) for k in ILLUM_FIELDS})
    for k in ILLUM_FIELDS:
        if k.startswith("theta"):
            rnd[k] = rnd[k] % (half + 1)                            # polar angle 0..180 deg
    # a quarter of the random rows light near the normal, where the specular table is steep
    near = rnd["phi_n"][: m // 4], rnd["theta_n"][: m // 4]
    for a in ("l", "h"):
        jitter = rng.integers(-8, 9, size=(2, len(near[0])))
        rnd[f"phi_{a}"][: m // 4] = (near[0] + jitter[0]) % full
        rnd[f"theta_{a}"][: m // 4] = np.clip(near[1] + jitter[1], 0, half)
    return _cat(hard, rnd)


# ---- rotation (seed 003) ---------------------------------------------------------------------

def _rotation_run(inp, **params):
    return angular.rotation_float(inp, **params)


def _rotation_check(inp, out, **params):
    """phi' compared around the circle; both within the interval bounds of
    golden.angular.rotation_bounds."""
    bits = params.get("angle_bits", 12)
    want = angular.rotation_float(inp, **params)
    bounds = angular.rotation_bounds(inp, **params)
    full = 2.0**bits
    dphi = np.abs(np.asarray(out["phi"], float) - want["phi"]) % full
    return {"phi": (np.minimum(dphi, full - dphi), bounds["phi"]),
            "theta": (np.abs(np.asarray(out["theta"], float) - want["theta"]), bounds["theta"])}


def _rotation_vectors(rng, n, angle_bits=12, **_):
    n = 50_000 if n is None else n
    full, half, quarter = 1 << angle_bits, 1 << (angle_bits - 1), 1 << (angle_bits - 2)
    # hard cases: theta_N = 0 with any phi_N; theta_A = 0; D = 0 and 180 deg (exact cases);
    # phi wrapping at 0/360; theta_A = theta_N (sin Z -> 0); A 90 deg from N (cos Z -> 0,
    # |yk| >= 1); theta at 90 deg (asin at +-1); results below the horizon; theta sums past
    # 180 deg
    edge_t = [0, 1, quarter // 2, quarter - 1, quarter, quarter + 1, half]
    edge_p = [0, 1, quarter, half, full - 1]
    pn, tn, pa, ta = _grid(edge_p, edge_t, edge_p, edge_t)
    hard = {"phi_n": pn, "theta_n": tn, "phi_a": pa, "theta_a": ta}
    m = max(0, n - len(pn))
    pn, pa = rng.integers(0, full, (2, m))
    tn, ta = rng.integers(0, quarter + 1, (2, m))                    # both on the hemisphere
    return _cat(hard, {"phi_n": pn, "theta_n": tn, "phi_a": pa, "theta_a": ta})


# ---- bump_polar (seed 003) -------------------------------------------------------------------

def _bump_run(inp, **params):
    return angular.bump_polar_float(inp, **params)


def _bump_check(inp, out, **params):
    want = angular.bump_polar_float(inp, **params)
    bounds = angular.bump_polar_bounds(inp, **params)
    return {k: (np.abs(np.asarray(out[k], float) - want[k]), bounds[k]) for k in want}


def _bump_vectors(rng, n, angle_bits=12, **_):
    n = 20_000 if n is None else n
    full, quarter = 1 << angle_bits, 1 << (angle_bits - 2)
    rot = _rotation_vectors(rng, n, angle_bits)               # N and L: the rotation's cases
    m = len(rot["phi_n"])
    return {"phi_n": rot["phi_n"], "theta_n": rot["theta_n"], "phi_l": rot["phi_a"],
            "theta_l": rot["theta_a"], "phi_h": rng.integers(0, full, m),
            "theta_h": rng.integers(0, quarter + 1, m), "phi_b": rng.integers(0, full, m),
            "theta_b": rng.integers(0, quarter * 2 // 3 + 1, m)}      # bumps within 60 deg


# ---- raster ---------------------------------------------------------------------------------

def _raster_run(inp, **params):
    out = raster.run(inp, **params)
    return {k: (v / VALUE.lsb if k.startswith("v") else v) for k, v in out.items()}


def _groups(channels, groups="0"):
    return max(parse_groups(groups, channels)) + 1


def _flat_words(rng, n, flat):
    """Random flat words (u32): the raster must carry each to its triangle's fragments."""
    return {f"f{k}": rng.integers(0, 1 << 32, n, dtype=np.int64) for k in range(flat)}


def raster_hard_cases(screen_bits=10, sub_bits=4, channels=2, groups="0", flat=0, **_):
    """math-notes §5's setup and span cases, as triangles (raw sub-pixel coordinates)."""
    S, W = 1 << sub_bits, 1 << screen_bits
    c = S // 2                                   # a pixel centre's offset
    big = 2 * W * S - 1                          # the coordinate format's largest value
    tris = {
        "omega=0 (collinear)": [(0, 0), (5 * S, 5 * S), (10 * S, 10 * S)],
        "omega=0 (one point)": [(3 * S, 3 * S)] * 3,
        "sliver |omega|=1": [(c, c), (c + 37 * S + 3, c + 1), (c + 37 * S + 2, c + 1)],
        "sliver |omega|=1 long": [(c, c + 2 * S), (c + (W - 2) * S, c + 2 * S + 1),
                                  (c + (W - 2) * S - 1, c + 2 * S + 1)],
        "x1=0": [(9 * S, 2 * S), (9 * S, 20 * S + 3), (30 * S, 40 * S)],
        "y1=0 (flat top)": [(4 * S + c, 6 * S + c), (40 * S + c, 6 * S + c), (20 * S, 50 * S)],
        "y1=y2 (flat bottom)": [(20 * S + 5, 3 * S), (2 * S, 33 * S + c), (50 * S, 33 * S + c)],
        "off screen": [(-W * S, -W * S // 2), (big, 5 * S), (W * S // 3, big)],
        "sub-pixel": [(3 * S + 1, 2 * S + 7), (27 * S + 13, 9 * S + 2), (11 * S + 5, 31 * S + 15)],
        "0- and 1-pixel spans": [(10 * S + c, 2 * S), (10 * S + c + 3, 40 * S), (10 * S + c - 4, 60 * S)],
        "1-pixel column": [(12 * S + 2, 0), (13 * S - 2, 0), (12 * S + 8, W * S)],
        "whole screen": [(-2 * W * S, W * S // 2), (W * S // 2, -2 * W * S), (big, big)],
        "whole screen, other way": [(big, big), (W * S // 2, -2 * W * S), (-2 * W * S, W * S // 2)],
        "longest span": [(W // 2 * S, 0), (-2 * W * S + S, 12 * S), (big - S, 12 * S + 3)],
    }
    n = len(tris)
    out = {f"{a}{k}": np.array([t[k][i] for t in tris.values()], np.int64)
           for k in range(3) for i, a in enumerate("xy")}
    # edge constants: normals 0, 90 and 180 deg apart and between (e = (cos - 1) / 2)
    e = (np.cos(np.radians([0, 30, 90, 120, 180, 45, 60, 90, 135, 10, 170, 100, 90, 20])) - 1) / 2
    raw = np.clip(np.round(e * 2 ** 15), EDGE.min, 0).astype(np.int64)
    for g in range(_groups(channels, groups)):           # each group's constants differ
        for k, name in enumerate(edge_names(g)):
            out[name] = np.roll(raw, k + 5 * g)[:n]
    vals = np.array([16384, -16384, 0, 8192, 16383, -7000, 12000, 3000, -16384, 9000, 16384,
                     -2000, 5000, 100, 16000], np.int64)
    for ch in range(channels):
        for k in range(3):
            out[f"v{ch}_{k}"] = np.roll(vals, 3 * ch + k)[:n]
    out.update(_flat_words(np.random.default_rng(n), n, flat))
    return out, list(tris)


def random_triangles(rng, n, screen_bits=10, sub_bits=4, channels=2, size=None, groups="0",
                     flat=0, **_):
    """Random triangles mostly on screen (some off it), values in [-1, 1], e in [-1, 0]."""
    S, W = 1 << sub_bits, 1 << screen_bits
    size = W if size is None else size
    centre = rng.integers(0, W * S, (n, 1, 2))
    extent = (size * S * rng.random((n, 1, 1)) ** 2).astype(np.int64) + 1
    pts = np.clip(centre + (rng.random((n, 3, 2)) * 2 - 1) * extent, -W * S, 2 * W * S - 1).astype(np.int64)
    out = {f"{a}{k}": pts[:, k, i] for k in range(3) for i, a in enumerate("xy")}
    for g in range(_groups(channels, groups)):
        for name in edge_names(g):
            out[name] = rng.integers(EDGE.min, 1, n)
    for ch in range(channels):
        for k in range(3):
            out[f"v{ch}_{k}"] = rng.integers(-16384, 16385, n)
    out.update(_flat_words(rng, n, flat))
    return out


TYPICAL_SIZE = 40    # random_triangles' size for about 100 pixels a triangle on average, as
                     # on the default torus scene


def _raster_vectors(rng, n, **params):
    """``n`` triangles: the hard cases, on a screen of at most 64 x 64 pixels (about 33,000
    fragments; the tests run them on the full screen too), then random triangles of typical
    size. The full sweep (``n=None``): the hard cases on the full screen (whole-screen
    triangles, the longest spans) and 1,000 typical triangles."""
    small = {**params, "screen_bits": min(params.get("screen_bits", 10), 6)}
    hard, _ = raster_hard_cases(**(params if n is None else small))
    more = 1000 if n is None else max(0, n - len(hard["x0"]))
    return _cat(hard, random_triangles(rng, more, **params, size=TYPICAL_SIZE))


def _raster_check(inp, out, **params):
    """Coverage and the flat words must match exactly (else every fragment counts as wrong);
    values within one LSB of the float model of the same method, at each channel's
    ``precision`` (docs/quadratic.md derives the widths)."""
    want = _raster_run(inp, **params)
    same = len(out["tri"]) == len(want["tri"]) and all(
        np.array_equal(np.asarray(out[k]), want[k]) for k in want if not k.startswith("v"))
    n = max(len(out["tri"]), 1)
    if not same:
        return {"coverage": (np.full(n, np.inf), np.zeros(n))}
    res = {"coverage": (np.zeros(n), np.zeros(n))}
    bounds = raster_bounds(params.get("channels", 2), params.get("precision", "14"))
    for k in want:
        if k.startswith("v"):
            res[k] = (np.abs(np.asarray(out[k], float) - want[k]),
                      np.full(len(want[k]), bounds[int(k[1:])][1]))
    return res


RASTER_INTERNAL = 2 ** -15.37   # the raster's error at FI, screens up to 1024 (docs/quadratic.md)


def raster_bounds(channels, precision="14"):
    """Each channel's LSB and its bound on |RTL - float model|, in VALUE's units (2**-14): half
    an LSB of its ``p`` fraction bits (the output's rounding), the internal error at FI and
    the floors to the channel's own FI, 2**-(p + 6) (``Widths.fi``; docs/quadratic.md "A
    channel's precision"). Below one LSB at every p: 0.90 LSB at 14, 0.52 at 8."""
    return [(2.0 ** (VALUE.frac_bits - p),
             (2.0 ** -(p + 1) + RASTER_INTERNAL + 2.0 ** -(p + 6)) / VALUE.lsb)
            for p in parse_precision(precision, channels)]


# ---- against the exact functions (make tradeoffs) ---------------------------------------------

SHININESS = 32.0     # the scene contract's default material: where the powers are measured


def _float_exact(name):
    """A float model is the exact function: its own check's error."""
    def err(inputs, outputs, **params):
        errs = MODELS[name].check(inputs, outputs, **params)
        return np.concatenate([e for e, _ in errs.values()]), "LSB of VALUE (2^-14)"
    return err


def _power_table_exact(inputs, outputs, **params):
    n = params.get("shininess", SHININESS)
    s = np.clip(np.asarray(inputs["s"]) / 2.0 ** 14, 0, 1)
    return np.abs(outputs["p"] - s ** n * 1024), "LSB of 1/1024"


def _fenney_power_exact(inputs, outputs, **_):
    x = np.asarray(inputs["x"]) / 1024.0
    return (np.abs(outputs["p"] - x ** SHININESS * 1024),
            f"LSB of 1/1024, against x^{SHININESS:g} (C = {int(inputs['c'][0])})")


def _fenney_power_exact_vectors(rng, n, **_):
    """Every X at the default material's concentration."""
    return {"x": np.arange(1024), "c": np.full(1024, fenney.concentration_for(SHININESS))}


def _dot_exact(inputs, outputs, **_):
    """Decoded texels (|x| + |y| + |z| = 255) and lights: against b/|b| . l/127."""
    b = np.stack([inputs[k] for k in "xyz"]).astype(float)
    lv = np.stack([inputs[f"l{k}"] for k in "xyz"]).astype(float)
    ok = (np.abs(b).sum(0) == 255) & (np.abs(lv).sum(0) > 0)
    b, lv, x = b[:, ok], lv[:, ok], np.asarray(outputs["x"])[ok]
    cos = (b * lv).sum(0) / (np.linalg.norm(b, axis=0) * 127)
    h = np.asarray(inputs["h"])[ok] / 255.0
    return (np.abs(x - np.clip(1024 * ((1 - h) + h * cos), 0, 1023)),
            "LSB of X (1/1024), against b/|b| . l/127 (the light as given)")


def _rotation_exact(inputs, outputs, **params):
    bits = params.get("angle_bits", 12)
    want = angular.rotation_float(inputs, angle_bits=bits, method="exact")
    t = lambda a: np.asarray(a, float) * 2 * np.pi / 2 ** bits
    got = angular.to_vector(t(outputs["phi"]), t(outputs["theta"]))
    ref = angular.to_vector(t(want["phi"]), t(want["theta"]))
    cos = np.clip((got * ref).sum(-1), -1, 1)
    return np.degrees(np.arccos(cos)), "degrees between the rotated vector and the exact one"


MODELS = {
    "texel_decode": Model(_texel_run, _texel_vectors, _exact_check(_texel_run), True),
    "fenney_power": Model(_power_run, _power_vectors, _exact_check(_power_run), True,
                          against_exact=_fenney_power_exact,
                          make_exact_vectors=_fenney_power_exact_vectors),
    "fenney_dot": Model(_dot_run, _dot_vectors, _dot_check, False, against_exact=_dot_exact),
    "fenney_xz": Model(_xz_run, _xz_vectors, _xz_check, False),
    "fenney_polar": Model(_polar_run, _polar_vectors, _polar_check, False),
    "illum": Model(_illum_run, _illum_vectors, _illum_check, False),
    "rotation": Model(_rotation_run, _rotation_vectors, _rotation_check, False,
                      against_exact=_rotation_exact),
    "bump_polar": Model(_bump_run, _bump_vectors, _bump_check, False),
    "raster": Model(_raster_run, _raster_vectors, _raster_check, False, typical=300,
                    against_exact=_float_exact("raster"),     # random triangles, no hard cases
                    make_exact_vectors=lambda rng, n, **q: random_triangles(
                        rng, n, **q, size=TYPICAL_SIZE)),
    "phong": Model(lambda inp, **q: shade.phong(inp, **q)[0], shade._phong_vectors,
                   shade.phong_check, False, against_exact=_float_exact("phong")),
    "peercy": Model(lambda inp, **q: shade.peercy(inp, **q)[0], shade._peercy_vectors,
                    shade.peercy_check, False, against_exact=_float_exact("peercy")),
    "power_table": Model(lambda inp, **q: {"p": shade.power_table(inp["s"], **q)},
                         shade._power_vectors,
                         _exact_check(lambda inp, **q: {"p": shade.power_table(inp["s"], **q)}),
                         True, against_exact=_power_table_exact),
    "colour": Model(lambda inp, **q: shade.colour(inp, **q), shade._colour_vectors,
                    _exact_check(shade.colour), True),
}
