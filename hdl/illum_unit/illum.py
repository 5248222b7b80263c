"""Law-of-cosines illumination (seed 003 §3.2, eq 22-25).

For A in (L', H') and the bump normal N', all in polar form (binary angles)::

    N'.A' = 1/2 [cos(tA - tN) + cos(tA + tN)] + 1/2 [cos(tA - tN) - cos(tA + tN)] cos(pA - pN)

three cosine look-ups and one multiplier per vector (six and two in all), halvings by shift.
Negative inner products clamp to 0; ``diffuse`` and ``specular`` are tables indexed by the
top ``table_bits`` bits of the clamped inner products: ``d`` and ``d ** shininess``.

Formats: angles u``angle_bits`` in turns (``raw / 2**angle_bits``); ``dot_l dot_h diffuse
specular`` u16 with 15 fraction bits (1.0 = 32768). The cosine tables hold ``trig_bits``
fraction bits. Bounds against the float model: ``golden.illum.bounds``.
"""
import functools

from amaranth.hdl import Mux

from ..fixed import Field, binary_angle, u
from ..lut import build_lut, quarter_cos_lut, rom
from ..trig import cos_address, signed_cos
from ..unit import Unit

OUT_FRAC = 15                          # dot, diffuse and specular: 1.0 = 2**15


@functools.lru_cache(maxsize=None)
def shade_lut(table_bits, exponent):
    """d ** exponent over d in [0, 1] (exponent 1: the diffuse table)."""
    return build_lut(lambda d: d ** exponent, table_bits, u(16, OUT_FRAC), domain=(0.0, 1.0))


class Illum(Unit):
    """Two inner products by the law of cosines, then diffuse and specular tables; latency 11."""
    NAME = "illum"
    DOC = "Law-of-cosines illumination with diffuse and specular tables (seed 003 eq 22-25)"
    PARAMS = {"angle_bits": 10, "trig_bits": 14, "table_bits": 10, "shininess": 16}
    latency = 11

    RANGES = {"angle_bits": (4, 16), "trig_bits": (8, 16), "table_bits": (4, 14),
              "shininess": (1, 1024)}

    def angle(self, name):
        return Field(name, binary_angle(self.params["angle_bits"]))

    @property
    def inputs(self):
        return tuple(self.angle(n) for n in ("phi_l", "theta_l", "phi_h", "theta_h",
                                             "phi_n", "theta_n"))

    @property
    def outputs(self):
        return tuple(Field(n, u(16, OUT_FRAC)) for n in ("dot_l", "dot_h", "diffuse",
                                                        "specular"))

    @property
    def cos_lut(self):
        return quarter_cos_lut(self.params["trig_bits"], 1 << (self.params["angle_bits"] - 2))

    @property
    def tables(self):
        return (shade_lut(self.params["table_bits"], 1),
                shade_lut(self.params["table_bits"], self.params["shininess"]))

    def datapath(self, p, v):
        bits, t = self.params["angle_bits"], self.params["trig_bits"]
        v = dict(v)
        p_n, t_n = v.pop("phi_n"), v.pop("theta_n")
        addrs = {}
        for a in ("l", "h"):
            p_a, t_a = v.pop(f"phi_{a}"), v.pop(f"theta_{a}")
            for key, angle in (("cm", t_a - t_n), ("cp", t_a + t_n), ("cf", p_a - p_n)):
                addrs[f"{key}_{a}"], addrs[f"{key}_{a}_neg"] = cos_address(self.cos_lut,
                                                                           angle, bits)
        v = p.stage(v, **addrs)                                       # the tables' addresses
        for key in [k for k in addrs if not k.endswith("_neg")]:
            v[key] = rom(self.cos_lut, v[key], key)
        v = p.stage(v)                                                # six cosine look-ups
        v = p.stage(v)                                                # the tables' outputs
        for a in ("l", "h"):
            cm, cp, cf = (signed_cos(v.pop(f"{k}_{a}"), v.pop(f"{k}_{a}_neg"))
                          for k in ("cm", "cp", "cf"))
            v[f"sum_{a}"], v[f"diff_{a}"], v[f"cf_{a}"] = cm + cp, cm - cp, cf
        v = p.stage(v)
        for a in ("l", "h"):                                          # the two multipliers
            v[f"prod_{a}"] = v.pop(f"diff_{a}") * v.pop(f"cf_{a}")
        v = p.stage(v)
        shift = 2 * t + 1 - OUT_FRAC                                  # 2 N.A at 2t bits
        for a in ("l", "h"):
            v[f"twice_{a}"] = (v.pop(f"sum_{a}") << t) + v.pop(f"prod_{a}")
        v = p.stage(v)
        for a in ("l", "h"):
            v[f"twice_{a}"] = v[f"twice_{a}"] + (1 << (shift - 1))
        v = p.stage(v)                                                # rounded
        for a in ("l", "h"):
            dot = v.pop(f"twice_{a}") >> shift
            v[f"dot_{a}"] = Mux(dot < 0, 0, Mux(dot > 1 << OUT_FRAC, 1 << OUT_FRAC, dot))[:16]
        v = p.stage(v)                                                # clamped at 0
        top = (1 << self.params["table_bits"]) - 1
        diffuse, specular = self.tables
        addr = {a: Mux(v[f"dot_{a}"] >> (OUT_FRAC - self.params["table_bits"]) > top, top,
                       v[f"dot_{a}"] >> (OUT_FRAC - self.params["table_bits"]))
                for a in ("l", "h")}
        v = p.stage(v, **{f"_a{a}": addr[a] for a in ("l", "h")})
        v = p.stage(v, diffuse=rom(diffuse, v.pop("_al"), "diffuse"),
                    specular=rom(specular, v.pop("_ah"), "specular", load="specular"))
        return p.stage(v)                                             # the tables' outputs
