"""Models of the per-fragment shading units (``hdl/shade_unit``), independent of the RTL.

- ``power_table``: bit-exact. The table's format is part of its definition: t = 1 - s binned
  as ``hdl.lut.float_bins`` states, each bin holding round(1024 (1 - t_centre)^n). Its error
  against the exact power is ``power_error`` (tested separately against ``Lut.max_error``).
- ``colour``: bit-exact, from the real-valued sum (every term is a dyadic rational that float64
  holds exactly), rounded half up.
- ``phong`` and ``peercy``: float (numpy sqrt), with the bound derived from the RTL's fraction
  bits and its table.
"""
import numpy as np

from hdl.lut import float_bins
from hdl.setup_unit.formats import VALUE
from hdl.shade_unit.formats import COEF, POWER, RGB
from hdl.shade_unit.phong import DOT_FRAC, G_FRAC

ONE = 2.0 ** VALUE.frac_bits


def _value(raw):
    return np.asarray(raw, np.int64) / ONE


# ---- power_table -----------------------------------------------------------------------------

def power_centres(mant_bits):
    """The value of s each table entry stands for: the centre of its bin of t = 1 - s."""
    edges = float_bins(VALUE.frac_bits - mant_bits, 1, mant_bits)
    return edges, 1.0 - (edges[:-1] + edges[1:]) / 2


def power_table(s, shininess=32.0, mant_bits=6):
    """p (raw POWER) for raw VALUE ``s``."""
    edges, centre = power_centres(mant_bits)
    t = 1.0 - np.clip(_value(s), 0.0, 1.0)
    a = np.searchsorted(edges, t, "right") - 1
    return np.rint(np.maximum(0.0, centre[a]) ** shininess * 2 ** POWER.frac_bits).astype(np.int64)


def power_error(shininess=32.0, mant_bits=6):
    """The table's largest error against max(0, s)^n over every s in [0, 1] (in POWER LSBs)."""
    s = np.arange(0, int(ONE) + 1)
    return float(np.abs(power_table(s, shininess, mant_bits)
                        - (s / ONE) ** shininess * 2 ** POWER.frac_bits).max())


def _power_vectors(rng, n, shininess=32.0, mant_bits=6):
    if n is None:                                                     # every s: 65,536
        return {"s": np.arange(VALUE.min, VALUE.max + 1)}
    one = int(ONE)
    octaves = [one - (1 << k) + d for k in range(15) for d in (-1, 0, 1)]
    hard = np.array([VALUE.min, -1, 0, 1, one - 1, one, one + 1, VALUE.max] + octaves)
    return {"s": np.concatenate([hard, rng.integers(-one // 4, one + 1, max(0, n - len(hard)))])}


# ---- colour ----------------------------------------------------------------------------------

def colour(inp, lights=1, specular=True):
    """r, g, b (raw levels): ambient + sum_k kd d_k + ks p_k, clamped, round(255 x)."""
    cf = 2.0 ** -COEF.frac_bits
    out = {}
    for c in RGB:
        total = np.asarray(inp[f"amb_{c}"], np.int64) * cf
        for k in range(lights):
            total = total + inp[f"kd{k}_{c}"] * cf * np.clip(_value(inp[f"d{k}"]), 0.0, 1.0)
            if specular:
                total = total + inp[f"ks{k}_{c}"] * cf * (np.asarray(inp[f"p{k}"]) *
                                                           2.0 ** -POWER.frac_bits)
        out[c] = np.minimum(np.floor(255.0 * total + 0.5), 255).astype(np.int64)
    return out


def _colour_vectors(rng, n, lights=1, specular=True):
    from hdl.shade_unit.colour import Colour
    fields = Colour.spec(lights=lights, specular=specular).inputs
    n = 50_000 if n is None else n
    lo = {"d": [VALUE.min, -1, 0, 1, 8192, 16383, 16384, 16385, VALUE.max],
          "p": [0, 1, 512, 1023, 1024, POWER.max], "c": [0, 1, 1024, 2048, COEF.max]}
    kinds = {f.name: "d" if f.name.startswith("d") else "p" if f.name.startswith("p") else "c"
             for f in fields}
    m = max(len(v) for v in lo.values())
    hard = {name: np.array(lo[kind] * m)[:m] for name, kind in kinds.items()}
    # every input at its extremes together: sums that clamp at 255 and that stay at 0
    hard = {k: np.concatenate([v, [lo[kinds[k]][-1], 0, lo[kinds[k]][-2]]]) for k, v in hard.items()}
    r = max(0, n - len(hard["amb_r"]))
    rnd = {}
    for f in fields:
        kind = kinds[f.name]
        if kind == "d":
            rnd[f.name] = rng.integers(-4096, 16385 + 1024, r)
        elif kind == "p":
            rnd[f.name] = rng.integers(0, 1025, r)
        else:                              # the colours a scene gives: mostly below 1
            rnd[f.name] = rng.integers(0, 1200, r)
    return {k: np.concatenate([hard[k], rnd[k]]).astype(np.int64) for k in hard}


# ---- phong -----------------------------------------------------------------------------------

def _phong_vectors_of(params):
    from hdl.shade_unit.phong import Phong
    return Phong.spec(**params).vectors()


def phong(inp, lights=1, specular=True, rsqrt_iters=2):
    """d_k = n.L_k / |n|, s_k = n.H_k / |n| (raw VALUE, saturated), |n| held in [1/4, 2]."""
    n = np.stack([_value(inp[f"n{a}"]) for a in "xyz"])
    length = np.clip(np.sqrt((n * n).sum(0)), 0.25, 2.0)
    out = {}
    for *keys, o in _phong_vectors_of(dict(lights=lights, specular=specular)):
        vec = np.stack([_value(inp[k]) for k in keys])
        out[o] = np.clip((n * vec).sum(0) / length * ONE, VALUE.min, VALUE.max)
    return out, length


def phong_check(inp, out, **params):
    """Per output, in LSBs of VALUE: 1/2 for the last rounding; the dot product's rounding to
    DOT_FRAC bits (1/2 LSB there) scaled by 1/|n| (<= 4); and |d| times the relative error of
    1/|n|: rsqrt's truncations (three per Newton-Raphson step, at most one LSB of G_FRAC each
    with g >= 1/2: 6 x 2^-G_FRAC) and n.n's truncation to 20 fraction bits (2^-20 / |n|^2,
    halved by the square root)."""
    want, length = phong(inp, **params)
    rel_g = 6 * 2.0 ** -G_FRAC + 2.0 ** -21 / length ** 2
    res = {}
    for k, w in want.items():
        bound = 0.5 + 0.5 * 2.0 ** (VALUE.frac_bits - DOT_FRAC) / length \
            + np.abs(w) * rel_g
        res[k] = (np.abs(np.asarray(out[k], float) - w), bound)
    return res


def _phong_vectors(rng, n, lights=1, specular=True, rsqrt_iters=2):
    n = 20_000 if n is None else n
    names = [k for *keys, _ in _phong_vectors_of(dict(lights=lights, specular=specular))
             for k in keys]
    one = int(ONE)
    axes = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, 0, -1]])
    # hard cases: the normal along each axis, at length 1 and at the floor (1/4) and below it
    # (0 and 1/8: interpolated between opposite normals), 90 deg between normal and light,
    # N.L < 0, and the normal halfway between two normals 90 deg apart (|n| = 0.707)
    normals = np.concatenate([axes * one, axes * (one // 4), axes * (one // 8), [[0, 0, 0]],
                              [[one // 2, one // 2, 0]], [[11585, 11585, 0]]])
    na, la = np.meshgrid(np.arange(len(normals)), np.arange(len(axes)), indexing="ij")
    hard = {f"n{a}": normals[na.ravel(), i] for i, a in enumerate("xyz")}
    for name in names:
        hard[name] = axes[la.ravel(), "xyz".index(name[-1])] * (one - 1)
    m = max(0, n - len(na.ravel()))
    # random: a unit normal shortened to 0.7..1 (interpolation), unit lights
    nv = rng.normal(size=(m, 3))
    nv *= rng.uniform(0.7, 1.0, (m, 1)) / np.linalg.norm(nv, axis=1, keepdims=True)
    rnd = {f"n{a}": np.rint(nv[:, i] * one) for i, a in enumerate("xyz")}
    for *keys, _ in _phong_vectors_of(dict(lights=lights, specular=specular)):
        lv = rng.normal(size=(m, 3))
        lv /= np.linalg.norm(lv, axis=1, keepdims=True)
        for i, k in enumerate(keys):
            rnd[k] = np.rint(lv[:, i] * (one - 1))
    return {k: np.concatenate([hard[k], rnd[k]]).astype(np.int64) for k in hard}


# ---- peercy ----------------------------------------------------------------------------------

def _peercy_tangent(inp, vec):
    """M v (float), each component saturated to VALUE as the RTL's L_t and H_t are."""
    m = np.stack([np.stack([_value(inp[f"{r}{a}"]) for a in "xyz"]) for r in "tbn"])
    w = np.stack([_value(inp[f"{vec}{a}"]) for a in "xyz"])
    return np.clip(np.einsum("ijk,jk->ik", m, w), VALUE.min / ONE, VALUE.max / ONE)


def peercy(inp, rsqrt_bits=10):
    """d = P.(M L) / |M L|, s = P.(M H) / |M H| (raw VALUE, saturated), |.| held in
    [1/4, 2]; and each vector's length."""
    p = np.stack([_value(inp[f"p{a}"]) for a in "xyz"])
    out, length = {}, {}
    for vec, o in (("l", "d"), ("h", "s")):
        x = _peercy_tangent(inp, vec)
        length[o] = np.clip(np.sqrt((x * x).sum(0)), 0.25, 2.0)
        out[o] = np.clip((p * x).sum(0) / length[o] * ONE, VALUE.min, VALUE.max)
    return out, length


def peercy_check(inp, out, rsqrt_bits=10):
    """Per output, in LSBs of VALUE, with ``len`` the vector's length less the rounding below
    (floored at 1/4): 1/2 for the last rounding; L_t's rounding to VALUE (1/2 LSB a component,
    sqrt(3)/2 LSB in all) moves P.x/|x| by at most |P| sqrt(3)/2 / len (its gradient is at most
    |P|/|x|); the dot product's rounding to DOT_FRAC bits, 2^(14 - DOT_FRAC)/2 / len; and |d|
    times the relative error of g: the table's own (its max_error over g >= 1/2) and |x|^2's
    truncation to 20 fraction bits (2^-20 / len^2, halved by the square root)."""
    from hdl.arith import rsqrt_seed
    want, length = peercy(inp, rsqrt_bits)
    p = np.sqrt(sum(_value(inp[f"p{a}"]) ** 2 for a in "xyz"))
    rel_g = rsqrt_seed(rsqrt_bits, G_FRAC).max_error * 2.0 ** (1 - G_FRAC)
    res = {}
    for k, w in want.items():
        ln = np.maximum(length[k] - np.sqrt(3) * 2.0 ** -(VALUE.frac_bits + 1), 0.25)
        bound = (0.5 + p * np.sqrt(3) / 2 / ln + 0.5 * 2.0 ** (VALUE.frac_bits - DOT_FRAC) / ln
                 + np.abs(w) * (rel_g + 2.0 ** -21 / ln ** 2))
        res[k] = (np.abs(np.asarray(out[k], float) - w), bound)
    return res


def _peercy_vectors(rng, n, rsqrt_bits=10):
    """Hard cases first: the identity frame and its axis permutations with L, H and P along
    every axis (P.L < 0 and P perpendicular among them); the frame shrunk to 1/8 and to 0 (L_t
    at and below the floor, from frames interpolated between opposite ones); rows near 2 (|L_t|
    past the cap, L_t's components saturated). Then random frames: a rotation with each row
    shortened to 0.8..1 (interpolation), unit L and H, a unit bump normal with z > 0."""
    n = 20_000 if n is None else n
    one = int(ONE)
    axes = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, 0, -1]])
    frames = [np.eye(3), np.eye(3)[[1, 2, 0]], np.eye(3)[[2, 0, 1]] * [[1], [-1], [1]],
              np.eye(3) / 8, np.zeros((3, 3)), np.full((3, 3), 1.99)]
    f, l, b = np.meshgrid(np.arange(len(frames)), np.arange(len(axes)), np.arange(len(axes)),
                          indexing="ij")
    f, l, b = f.ravel(), l.ravel(), b.ravel()
    hard = {}
    for i, r in enumerate("tbn"):
        for j, a in enumerate("xyz"):
            hard[f"{r}{a}"] = np.rint(np.array([fr[i, j] for fr in frames])[f] * one)
    for j, a in enumerate("xyz"):
        hard[f"l{a}"] = axes[l, j] * (one - 1)
        hard[f"h{a}"] = axes[(l + 1) % len(axes), j] * (one - 1)
        hard[f"p{a}"] = axes[b, j] * (one - 1)
    m = max(0, n - len(f))
    q, _ = np.linalg.qr(rng.normal(size=(m, 3, 3)))
    q *= rng.uniform(0.8, 1.0, (m, 3, 1))
    rnd = {f"{r}{a}": np.rint(q[:, i, j] * one) for i, r in enumerate("tbn")
           for j, a in enumerate("xyz")}
    for name in "lhp":
        v = rng.normal(size=(m, 3))
        if name == "p":
            v[:, 2] = np.abs(v[:, 2])
        v /= np.linalg.norm(v, axis=1, keepdims=True)
        rnd.update({f"{name}{a}": np.rint(v[:, j] * (one - 1)) for j, a in enumerate("xyz")})
    return {k: np.concatenate([hard[k], rnd[k]]).astype(np.int64) for k in hard}


def colour_float(scene, d, p):
    """The colour sum of scenes.md in float: d (lights, n) clamped, p (lights, n) powers."""
    mat = scene["material"]
    col = np.array(mat["color"])
    out = mat["ambient"] * col[None, :] + 0 * d[0][:, None]
    for j, l in enumerate(scene["lights"]):
        lc = np.array(l["color"])
        out = out + lc * (mat["diffuse"] * np.clip(d[j], 0, 1)[:, None] * col
                          + mat["specular"] * p[j][:, None])
    return np.rint(255 * np.clip(out, 0, 1)).astype(np.uint8)
