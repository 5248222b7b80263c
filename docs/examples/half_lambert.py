"""A shading method the seeds do not have, registered from outside ``scene/``: Valve's
half-Lambert diffuse (README, "Adding an effect or a method"). The raster interpolates N.L
as X-shading does (seed 001), and each pixel's diffuse term becomes

    d' = ((d + 1) / 2)^2,

so the terminator's hard edge wraps round to the back of the mesh, which stays lit a little.
N.H and the power are the pipeline's as before.

The arithmetic, per light, with d in VALUE (14 fraction bits):

- h = clamp(floor((d + 1) / 2), 0, 1), the interpolated d may stray a little outside
  [-1, 1]; then its top ``hl_bits`` fraction bits (floor), so the product is
  (hl_bits + 1) x (hl_bits + 1) bits: 15 x 15 at the default 14, one MULT18X18D;
- d' = h^2 rounded to 14 fraction bits (round half up).

The model below is the same integer arithmetic, so the stage alone is bit-exact against it
(``tests/test_stages.py`` runs every one of VALUE's 65,536 codes). In a scene, the raster's
d is within one VALUE LSB of its float model, and |d d'/dd| = (d + 1) / 2 <= 1, so d' moves
by at most one truncation step of h (2^-hl_bits) times 2h <= 2, plus the rounding: within
one level of the colour, the default pipeline's bound.

Register it for every tool with ``SHADING_STAGES=docs/examples/half_lambert.py``, then
``python -m sim render docs/examples/half_lambert.toml``; or from Python with
``scene.registry.register(HalfLambert)``."""
import numpy as np
from amaranth.hdl import Mux

from hdl.dsp import Product
from hdl.setup_unit.formats import VALUE
from scene.stage import Stage, Sweep, raw

FRAC = VALUE.frac_bits
ONE = 1 << FRAC


class HalfLambert(Stage):
    name = "half_lambert"
    why = "shading.method = half_lambert"
    when = {"method": "half_lambert"}
    interpolates = "xshading"       # the raster's mode for N.L and N.H
    before = "colour"               # d' is the colour stage's d
    format_group = "shading"
    build_params = {"hl_bits": (14, (8, 14))}      # h's fraction bits into the product

    @classmethod
    def sweeps(cls):
        """h's bits: 14 (15 x 15 bits on a MULT18X18D) against 8 (9 x 9 bits)."""
        return [Sweep("half-Lambert h bits", str(b), scene="default", build="pipeline",
                      hardware={"method": "half_lambert", "hl_bits": b}) for b in (14, 8)]

    @property
    def params(self):
        return {"lights": self.q["lights"], "hl_bits": self.q["hl_bits"]}

    @property
    def latency(self):
        return 3                    # the product's input registers, its output, the rounding

    def rtl(self, p, v, uni):
        bits, lights = self.q["hl_bits"], range(self.q["lights"])
        shift = 2 * bits - FRAC     # h^2 has 2 bits fraction bits, d' FRAC

        def half(d):                # clamp(floor((d + 1) / 2), 0, 1), its top bits
            t = (d + ONE) >> 1
            return Mux(t < 0, 0, Mux(t > ONE, ONE, t))[FRAC - bits:FRAC + 1]
        hs = {f"_h{k}": half(v.pop(f"d{k}")) for k in lights}
        v = p.stage(v, **{f"_q{k}": Product(h, h) for k, h in enumerate(hs.values())})
        v = p.stage(v)
        return p.stage(v, **{f"d{k}": ((v.pop(f"_q{k}") + (1 << (shift - 1))) >> shift)
                             [:VALUE.width].as_signed() for k in lights})

    def half_lambert(self, d):
        """The RTL's arithmetic on VALUE codes ``d``: d' codes."""
        bits = self.q["hl_bits"]
        shift = 2 * bits - FRAC
        h = np.clip((np.asarray(d, np.int64) + ONE) >> 1, 0, ONE) >> (FRAC - bits)
        return (h * h + (1 << (shift - 1))) >> shift

    def model(self, prep, frag, ch, bound):
        ch = dict(ch)
        for k in range(self.q["lights"]):
            ch[f"d{k}"] = self.half_lambert(raw(ch[f"d{k}"])) * VALUE.lsb
        return ch

    def ideal(self, prep, frag, ch):
        """((d + 1) / 2)^2 on reals, d clamped to [-1, 1]."""
        ch = dict(ch)
        for k in range(self.q["lights"]):
            ch[f"d{k}"] = ((np.clip(ch[f"d{k}"], -1, 1) + 1) / 2) ** 2
        return ch
