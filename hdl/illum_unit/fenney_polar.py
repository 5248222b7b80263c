"""Fenney's first embodiment, FIG. 3: polar bump texels shaded with k1, k2, k3 and Q.

    intensity = clamp(k1 + k2 sin S + k3 cos S cos(R - Q), 0, 255)        (eq 3)
    shade     = fenney_power(intensity expanded to 10 bits, c)

Formats: ``s`` u8 is S/90 deg * 256 (the texel's bits 15:8), ``r`` and ``q`` u8 are R and Q in
turns * 256 (bits 7:0 for r); ``k1 k2 k3`` u8 are k * 255; ``c`` u8 the concentration.
The 8-bit intensity is widened to the power unit's 10-bit X by bit replication
(``i << 2 | i >> 6``), so 0 -> 0 and 255 -> 1023.

Datapath of FIG. 3: a sin/cos unit on S and one on R - Q (wrapping mod 256), the latter giving
a magnitude and a sign bit, all three from one quarter-wave cosine table of ``trig_bits``
fraction bits; multipliers 12 and 14 (k2 sin S, k3 cos S), multiplier 20 (by |cos(R-Q)|),
adder 22 (k1 + k2 sin S), add/subtract unit 24 steered by the sign, a signed 11-bit sum, a
clamp to 0..255, and the power unit 30.

Each table entry is within ``e`` (<= 0.5) LSB of 2**-trig_bits, so the sum before rounding is
within ``255 * (3e + e**2 * 2**-trig_bits) * 2**-trig_bits`` of the real one, plus 0.5 for the
rounding: 0.874 LSB of intensity at trig_bits = 10 (golden.fenney.polar_bound).
"""
from amaranth.hdl import Mux

from ..dsp import Product, soft_halves
from ..fixed import Field, u
from ..lut import quarter_cos_lut, rom
from ..trig import cos_lookup
from ..unit import Unit
from .fenney_power import FenneyPower


class FenneyPolar(Unit):
    """S/R texel and k1, k2, k3, Q, c to intensity and shade, one per clock."""
    NAME = "fenney_polar"
    DOC = "Fenney polar S/R bump shading, FIG. 3 (US 6,819,319, first embodiment)"
    PARAMS = {"trig_bits": 10}
    inputs = (Field("s", u(8, 8, "90deg")), Field("r", u(8, 8, "turn")),
              Field("k1", u(8, unit="1/255")), Field("k2", u(8, unit="1/255")),
              Field("k3", u(8, unit="1/255")), Field("q", u(8, 8, "turn")),
              Field("c", u(8, 8)))
    outputs = (Field("intensity", u(8, unit="1/255")), Field("shade", u(10, 10)))

    RANGES = {"trig_bits": (4, 16)}

    def validate(self, trig_bits):
        self.power = FenneyPower.spec()

    @property
    def lut(self):
        return quarter_cos_lut(self.params["trig_bits"])

    @property
    def latency(self):
        return POLAR_STAGES + self.power.latency

    def datapath(self, p, v):
        v = polar_lanes(p, v, "s", "r", [("k1", "k2", "k3", "q", "intensity", "x")],
                        self.params["trig_bits"])
        v = self.power.datapath(p, v)                                # power unit 30
        v["shade"] = v.pop("p")
        return v


POLAR_STAGES = 7


def polar_lanes(p, v, s, r, lanes, trig_bits):
    """Eq 3 for one texel (``s``, ``r`` keys) against several lights side by side (7 stages):
    ``lanes`` of ``(k1, k2, k3, q, intensity, x)`` keys, each giving the clamped 8-bit
    intensity and the power unit's 10-bit X (``x`` None: not wanted). The texel's sin S and
    cos S are read once for every lane; each lane has its own R - Q, its three multipliers
    and its adders. The tables' outputs are registered, then each multiplier is alone in
    its stage. ``s``, ``r`` and the lanes' constants are consumed."""
    t = trig_bits
    v = dict(v)
    lut = quarter_cos_lut(t)
    s, r = v.pop(s), v.pop(r)
    new = {"_sin_s": rom(lut, 256 - s, "sin_s"),                    # sin S = cos(90 - S)
           "_cos_s": rom(lut, s, "cos_s")}
    for k, (_, _, _, q, _, _) in enumerate(lanes):
        cos_d, neg = cos_lookup(lut, r - v.pop(q), 8, f"cos_d{k}")   # subtractor 16, unit 18
        new.update({f"_cos_d{k}": cos_d, f"_neg{k}": neg})           # sign bit 26
    v = p.stage(v, **new)
    v = p.stage(v)                                                   # the tables' outputs
    sin_s, cos_s = v.pop("_sin_s"), v.pop("_cos_s")
    n = range(len(lanes))
    # k3 cos S <= 255 * 2**t: t + 8 bits (one MULT18X18D port at the default t = 10). The
    # two 8 x (t + 1) products are logic: a lane then takes one MULT18X18D, not 3, with its
    # own registers (Product). Each is two 4 x (t + 1) halves (soft_mult) in one clock, summed
    # in the next: 8 partial products in one clock were its critical path (117 MHz)
    new = {}
    for k, (_, k2, k3, _, _, _) in enumerate(lanes):
        for key, c, x in (("m12", v.pop(k2), sin_s), ("m14", v.pop(k3), cos_s)):
            lo, hi, half = soft_halves(c, x)
            new.update({f"_{key}lo_{k}": lo, f"_{key}hi_{k}": hi})
    v = p.stage(v, **new)
    whole = lambda key, k: v.pop(f"_{key}lo_{k}") + (v.pop(f"_{key}hi_{k}") << half)
    v = p.stage(v, **{f"_m20_{k}": Product(whole("m14", k)[:t + 8], v.pop(f"_cos_d{k}"))
                      for k in n},
                **{f"_a22_{k}": (v.pop(k1) << (2 * t)) + (whole("m12", k) << t)
                   for k, (k1, _, _, _, _, _) in enumerate(lanes)})
    v = p.stage(v)                                                   # the products
    v = p.stage(v, **{f"_total{k}": Mux(v.pop(f"_neg{k}"), v[f"_a22_{k}"] - v[f"_m20_{k}"],
                                        v[f"_a22_{k}"] + v[f"_m20_{k}"]) for k in n})  # unit 24
    for k in n:
        v.pop(f"_a22_{k}"), v.pop(f"_m20_{k}")
    out = {}
    for k, (_, _, _, _, key, x) in enumerate(lanes):
        s11 = ((v.pop(f"_total{k}") + (1 << (2 * t - 1))) >> (2 * t))[:11].as_signed()
        i8 = Mux(s11 < 0, 0, Mux(s11 > 255, 255, s11))[:8]          # clamp 28
        out[key] = i8
        if x is not None:
            out[x] = (i8 << 2) | (i8 >> 6)
    return p.stage(v, **out)
