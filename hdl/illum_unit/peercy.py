"""``peercy``: the Cartesian bump-mapping baseline of seed 003's Table 1 (Peercy, Airey and
Cabral 1997; Ernst et al.): L and H into the tangent space by the per-pixel TBN matrix,
normalised, then dotted with the perturbed normal from the bump map.

    stage 1     the operands registered, beside the multipliers they feed
    stage 2-3   L_t = M L, H_t = M H        18 products, M's rows T, B, N (interpolated)
    stage 4     L_t, H_t rounded to VALUE
    stage 5-6   |L_t|^2, |H_t|^2, P.L_t, P.H_t     12 products (P: the bump normal)
    stage 7-8   |v|^2 in [1/16, 4) -> m in [1, 4) by an even shift 2e (as phong)
    stage 9-10  g = 1/sqrt(m) from a table of ``rsqrt_bits`` address bits (registered twice)
    stage 11-13 d = (P.L_t) g 2^e, s = (P.H_t) g 2^e: 2 products, rounded to VALUE, saturated

Seed 003 counts Peercy's front end at 27 multipliers, 9 dividers, 3 square roots and 18 adders:
two 3x3 matrix-vector products (18 multipliers) and a normalisation by division. Here the
normalisation is a reciprocal square root table and a multiply, which is cheaper than nine
dividers, so the baseline is not made to look worse than it is. 32 multipliers in all, each
alone in its stage on s16 operands: one MULT18X18D each.

|v| is floored at 1/4 and held below 2 (|v|^2 saturates at 4), as in phong; an interpolated
frame's rows are near unit length, so L_t is too.
"""
from amaranth.hdl import Mux

from .. import arith
from ..fixed import Field
from ..lut import rom
from ..setup_unit.formats import VALUE
from ..shade_unit.phong import (G_FRAC, Q_BITS, clamp_q, even_shift, round_dot, scale_lanes)
from ..unit import Unit

AXES = "xyz"
FRAME = ("t", "b", "n")          # M's rows: tangent, binormal, normal
VECTORS = (("l", "d"), ("h", "s"))


def round_value(x, frac=2 * VALUE.frac_bits):
    """A sum of VALUE products rounded to VALUE and saturated."""
    r = (x + (1 << frac - VALUE.frac_bits - 1)) >> frac - VALUE.frac_bits
    return Mux(r > VALUE.max, VALUE.max, Mux(r < VALUE.min, VALUE.min, r))[:VALUE.width] \
        .as_signed()


class Peercy(Unit):
    NAME = "peercy"
    DOC = ("Cartesian bump mapping (Peercy et al.): TBN . L and TBN . H per pixel, normalised, "
           "dotted with the bump normal: seed 003's baseline")
    PARAMS = {"rsqrt_bits": 10}
    RANGES = {"rsqrt_bits": (4, 14)}
    inputs = tuple(Field(f"{r}{a}", VALUE) for r in FRAME + ("l", "h", "p") for a in AXES)
    outputs = tuple(Field(o, VALUE) for _, o in VECTORS)
    latency = 13

    @property
    def lut(self):
        return arith.rsqrt_seed(self.params["rsqrt_bits"], G_FRAC)

    def datapath(self, p, v):
        v = p.stage(v)          # the operands registered, beside the DSPs they feed
        frame = [[v.pop(f"{r}{a}") for a in AXES] for r in FRAME]
        bump = [v.pop(f"p{a}") for a in AXES]
        prods = {}
        for vec, _ in VECTORS:
            w = [v.pop(f"{vec}{a}") for a in AXES]
            prods.update({f"_{vec}{r}{a}": frame[i][j] * w[j] for i, r in enumerate(FRAME)
                          for j, a in enumerate(AXES)})
        v = p.stage({**v, **{f"_p{a}": c for a, c in zip(AXES, bump)}}, **prods)
        v = p.stage(v, **{f"_{vec}{r}": sum(v.pop(f"_{vec}{r}{a}") for a in AXES)
                          for vec, _ in VECTORS for r in FRAME})
        v = p.stage(v, **{f"_{vec}{r}": round_value(v.pop(f"_{vec}{r}"))
                          for vec, _ in VECTORS for r in FRAME})
        prods = {}
        for vec, _ in VECTORS:
            t = [v.pop(f"_{vec}{r}") for r in FRAME]
            prods.update({f"_q{vec}{i}": t[i] * t[i] for i in range(3)})
            prods.update({f"_d{vec}{i}": v[f"_p{a}"] * t[i] for i, a in enumerate(AXES)})
        for a in AXES:
            v.pop(f"_p{a}")
        v = p.stage(v, **prods)
        v = p.stage(v, **{f"_{k}{vec}": sum(v.pop(f"_{k}{vec}{i}") for i in range(3))
                          for vec, _ in VECTORS for k in "qd"})
        v = p.stage(v, **{k: f(v.pop(k)) for k, f in (
            *((f"_q{vec}", clamp_q) for vec, _ in VECTORS),
            *((f"_d{vec}", round_dot) for vec, _ in VECTORS))})
        new = {}
        for vec, _ in VECTORS:
            q = v.pop(f"_q{vec}")
            e = even_shift(q)
            new.update({f"_m{vec}": (q << (2 * e))[:Q_BITS], f"_e{vec}": e})
        v = p.stage(v, **new)
        bits = self.params["rsqrt_bits"]
        v = p.stage(v, **{f"_g{vec}": rom(self.lut, arith.rsqrt_addr(v.pop(f"_m{vec}"), Q_BITS,
                                                                     bits), f"rsqrt_{vec}")
                          for vec, _ in VECTORS})
        v = p.stage(v)                                                  # the tables' output
        return scale_lanes(p, v, {f"_d{vec}": (v.pop(f"_g{vec}"), f"_e{vec}", out)
                                  for vec, out in VECTORS})
