"""``colour``: ambient + sum over lights of (kd x max(0, d) x colour + ks x p), to 8-bit RGB
(scenes.md, "Lighting").

Per channel c, with the coefficients the driver folds (``COEF``: ambient x colour_c,
kd x light_c x colour_c, ks x light_c)::

    S = amb_c << 14 + sum_k kd_k,c x clamp(d_k, 0, 1) + (ks_k,c x p_k) << 4     (2^-24 units)
    level = min(255, (255 S + 2^23) >> 24)                                      round half up

Exact integer arithmetic: the golden model is bit-exact. 255 S is (S << 8) - S, no multiplier.
Multipliers: 3 per light for diffuse, 3 more for specular (12 x 15 and 12 x 11 bits), their
products registered on both sides. Latency ``colour_stages``: clamp, products, a pairwise
adder tree, 255 S, the level.
"""
from amaranth.hdl import Mux

from ..dsp import Product
from ..fixed import Field
from ..unit import Unit
from ..setup_unit.formats import VALUE
from .formats import COEF, LEVEL, ONE, POWER, RGB, colour_fields, light_fields

FRAC = COEF.frac_bits + VALUE.frac_bits   # the sum's fraction bits


def colour_terms(lights, specular):
    return 1 + lights * (2 if specular else 1)


def colour_stages(lights, specular):
    """Clamp, products, a pairwise adder tree, 255 S, the level."""
    return 4 + (colour_terms(lights, specular) - 1).bit_length()


def colour_lanes(p, v, lights, specular):
    """Consumes ``d<k>``, ``p<k>`` and the coefficient fields; gives ``r``, ``g``, ``b``."""
    v = dict(v)
    # clamp(d, 0, 1) into the products' input registers (Product: a MULT18X18D with its own
    # registers), the products a clock later
    prods = {}
    for k in range(lights):
        dk = (lambda d: Mux(d < 0, 0, Mux(d > ONE, ONE, d))[:15])(v.pop(f"d{k}"))
        pk = v.pop(f"p{k}") if specular else None
        for c in RGB:
            prods[f"_d{k}{c}"] = Product(v.pop(f"kd{k}_{c}"), dk)
            if specular:
                prods[f"_s{k}{c}"] = Product(v.pop(f"ks{k}_{c}"), pk)
    v = p.stage(v, **prods)
    v = p.stage(v, **{f"_a{c}": v.pop(f"amb_{c}") << FRAC - COEF.frac_bits for c in RGB})
    shift = FRAC - COEF.frac_bits - POWER.frac_bits
    terms = {c: [v.pop(f"_a{c}")] + [v.pop(f"_{t}{k}{c}") << (shift if t == "s" else 0)
                                     for k in range(lights) for t in ("d", "s")
                                     if specular or t == "d"] for c in RGB}
    for _ in range((colour_terms(lights, specular) - 1).bit_length()):   # adder tree
        new = {}
        for c in RGB:
            ts = terms[c]
            for j in range(0, len(ts), 2):
                new[f"_t{c}{j // 2}"] = ts[j] + ts[j + 1] if j + 1 < len(ts) else ts[j]
        v = p.stage(v, **new)
        terms = {c: [v.pop(f"_t{c}{j}") for j in range((len(terms[c]) + 1) // 2)] for c in RGB}
    v = p.stage(v, **{f"_l{c}": ((s << 8) - s + (1 << FRAC - 1)) >> FRAC
                      for c, (s,) in terms.items()})                   # 255 S, rounded
    out = {}
    for c in RGB:
        level = v.pop(f"_l{c}")
        out[c] = Mux(level > LEVEL.max, LEVEL.max, level)[:LEVEL.width]
    return p.stage(v, **out)


class Colour(Unit):
    NAME = "colour"
    DOC = "Ambient + per light kd d colour + ks p, summed and clamped, to 8-bit RGB"
    PARAMS = {"lights": 1, "specular": True}
    RANGES = {"lights": (1, 4)}
    @property
    def latency(self):
        return colour_stages(self.params["lights"], self.params["specular"])

    @property
    def inputs(self):
        q = self.params
        return (light_fields(q["lights"], True, "d")
                + [Field(f"p{k}", POWER) for k in range(q["lights"]) if q["specular"]]
                + colour_fields(q["lights"], q["specular"]))

    outputs = tuple(Field(c, LEVEL) for c in RGB)

    def datapath(self, p, v):
        return colour_lanes(p, v, self.params["lights"], self.params["specular"])
