"""``phong``: per-pixel Phong shading's normalisation (seed 000 eq 33-45; Duff): the
interpolated normal n in, d = n.L / |n| and s = n.H / |n| out, for each light.

    stage 1        q = n.n, and each n.L, n.H, exactly (products of s16 values)
    stage 2        q -> m in [1, 4) by an even left shift 2e (a leading-one search)
    rsqrt          g ~ 2^15 / sqrt(m): a table seed and Newton-Raphson steps (hdl.arith)
    final          d = (n.L) g 2^e, rounded to VALUE and saturated

1/|n| = 2^e / sqrt(m). |n|^2 is floored at 1/16 (|n| >= 1/4): an interpolated normal that short
comes only from vertex normals more than 150 deg apart, and the floor keeps the shift to
e in 0..2. The dot products are rounded to 17 bits (15 fraction bits) before the last multiply,
so it fits one 18 x 18 multiplier.

Multipliers: 3 for n.n, 3 per vector (L, and H with specular), 3 per Newton-Raphson step, one
per output.
"""
from amaranth.hdl import Mux

from .. import arith
from ..fixed import Field
from ..setup_unit.formats import VALUE
from ..unit import Unit
from .formats import light_fields

Q_BITS = 22         # n.n with 20 fraction bits: [1/16, 4) -> bits 16..21
Q_FRAC = 20
Q_FLOOR = 1 << (Q_FRAC - 4)             # |n|^2 >= 1/16
G_FRAC = 15                             # 1/sqrt(m) in (1/2, 1], 15 fraction bits
DOT_FRAC = 15                           # n.L before the last multiply: s17, [-2, 2)


def phong_stages(iters):
    return 5 + arith.rsqrt_stages(iters) + 3


def phong_lanes(p, v, vectors, iters, seed_bits=8):
    """Normalise ``nx, ny, nz`` against each of ``vectors`` (``(vx, vy, vz, out)`` keys);
    consumes the normal and the vectors, gives each ``out``. Every multiplier alone in its
    stage (s16 operands: one DSP each)."""
    v = p.stage(v)          # the operands registered here, beside the 19 DSPs they feed
    n = [v.pop(k) for k in ("nx", "ny", "nz")]
    prods = {f"_q{a}": n[a] * n[a] for a in range(3)}
    for *keys, out in vectors:
        prods.update({f"_p{a}_{out}": n[a] * v.pop(k) for a, k in enumerate(keys)})
    v = p.stage(v, **prods)
    sums = {"_q": v.pop("_q0") + v.pop("_q1") + v.pop("_q2")}
    for *_, out in vectors:
        sums[f"_dot_{out}"] = v.pop(f"_p0_{out}") + v.pop(f"_p1_{out}") + v.pop(f"_p2_{out}")
    v = p.stage(v, **sums)
    q = v.pop("_q")
    v = p.stage(v, _q=clamp_q(q), **{f"_dot_{out}": round_dot(v.pop(f"_dot_{out}"))
                                     for *_, out in vectors})
    q = v.pop("_q")
    e = even_shift(q)
    v = p.stage(v, _m=(q << (2 * e))[:Q_BITS], _e=e)
    v = arith.rsqrt(p, v, "_m", Q_BITS, G_FRAC, iters, seed_bits, out="_g")
    v.pop("_m")
    g = v.pop("_g")
    return scale_lanes(p, v, {f"_dot_{key}": (g, "_e", key) for *_, key in vectors})


def round_dot(d, frac=2 * VALUE.frac_bits):
    """A dot product of VALUEs (``frac`` fraction bits) rounded to DOT_FRAC bits, saturated
    to s17."""
    lim = (1 << DOT_FRAC + 1) - 1
    d = (d + (1 << frac - DOT_FRAC - 1)) >> frac - DOT_FRAC
    return Mux(d > lim, lim, Mux(d < -lim - 1, -lim - 1, d))[:DOT_FRAC + 2].as_signed()


def clamp_q(q, frac=2 * VALUE.frac_bits):
    """|v|^2 (``frac`` fraction bits) truncated to Q_FRAC bits and held in [1/16, 4)."""
    q = q >> frac - Q_FRAC
    return Mux(q < Q_FLOOR, Q_FLOOR, Mux(q >= 1 << Q_BITS, (1 << Q_BITS) - 1, q))[:Q_BITS]


def even_shift(q):
    """e with q 4^e in [1, 4): leading one at bit 20 or 21 -> 0; 18-19 -> 1; 16-17 -> 2."""
    return Mux(q[Q_BITS - 2:].any(), 0, Mux(q[Q_BITS - 4:Q_BITS - 2].any(), 1, 2))


def scale_lanes(p, v, lanes):
    """``out = dot g 2^e`` rounded to VALUE and saturated, for ``{dot: (g, e, out)}`` (``g``
    a value, the other two keys): the product alone in its stage, then the round, then the
    saturation (three stages). Consumes the dots and the shifts."""
    v = p.stage(v, **{f"_pr_{key}": v.pop(dot) * g for dot, (g, _, key) in lanes.items()})
    shift = DOT_FRAC + G_FRAC - VALUE.frac_bits
    es = {e: v.pop(e) for _, e, _ in lanes.values() if e in v}
    v = p.stage(v, **{f"_r_{key}": ((v.pop(f"_pr_{key}") << es[e]) + (1 << shift - 1)) >> shift
                      for g, e, key in lanes.values()})
    out = {}
    for _, _, key in lanes.values():
        r = v.pop(f"_r_{key}")
        out[key] = Mux(r > VALUE.max, VALUE.max, Mux(r < VALUE.min, VALUE.min, r))[:VALUE.width] \
            .as_signed()
    return p.stage(v, **out)


class Phong(Unit):
    NAME = "phong"
    DOC = "Per-pixel Phong: the interpolated normal normalised, dotted with each L and H"
    PARAMS = {"lights": 1, "specular": True, "rsqrt_iters": 2}
    RANGES = {"lights": (1, 4), "rsqrt_iters": (1, 3)}

    @property
    def inputs(self):
        q = self.params
        return ([Field(f"n{a}", VALUE) for a in "xyz"]
                + [Field(f"{t}{k}{a}", VALUE) for k in range(q["lights"])
                   for t in ("l", "h") if q["specular"] or t == "l" for a in "xyz"])

    @property
    def outputs(self):
        return light_fields(self.params["lights"], self.params["specular"], "d", "s")

    @property
    def latency(self):
        return phong_stages(self.params["rsqrt_iters"])

    def vectors(self):
        q = self.params
        return [(f"{t}{k}x", f"{t}{k}y", f"{t}{k}z", f"{o}{k}") for k in range(q["lights"])
                for t, o in (("l", "d"), ("h", "s")) if q["specular"] or t == "l"]

    def datapath(self, p, v):
        return phong_lanes(p, v, self.vectors(), self.params["rsqrt_iters"])
