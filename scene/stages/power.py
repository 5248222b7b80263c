"""The power stage: the specular power of each light's N.H per pixel, from the table
(``power_table``: max(0, s)^n in floating-point bins) or by the patent's quadratic
approximation (``fenney_power``, the concentration fitted to the shininess).

The shininess is data: the power table is a RAM that the host loads (``tables``), and the
concentration a register; the hardware depends only on ``mant_bits`` and the lanes."""
import numpy as np
from amaranth.hdl import Mux

from golden import fenney, shade
from hdl.fixed import Field, u
from hdl.illum_unit.fenney_power import FenneyPower, power_lanes as fenney_lanes
from hdl.setup_unit.formats import VALUE
from hdl.shade_unit.power import PowerTable, power_lut, power_lanes

from ..stage import Stage, convert_powers, raw

SHAPE = PowerTable.PARAMS["shininess"]    # the table's shape only: its contents are loaded


def shininess(scene):
    return float(scene["material"]["shininess"])


def concentration(scene):
    """The Fenney concentration C fitted to the scene's shininess."""
    return fenney.concentration_for(shininess(scene))


class Power(Stage):

    @classmethod
    def wanted(cls, q):
        return q["specular"] and q["bump"] != "angular"     # bump_polar has its own table

    def convert(self, ch, ideal):
        return convert_powers(ch, ideal)

    @property
    def name(self):
        return "power_table" if self.q["power"] == "table" else "fenney_power"

    @property
    def params(self):
        return dict(mant_bits=self.q["mant_bits"]) if self.q["power"] == "table" else {}

    @property
    def why(self):
        return "shading.specular = true, shading.power = " + (
            "table (loaded)" if self.q["power"] == "table" else "fenney (C a register)")

    @property
    def uniforms(self):
        return [] if self.q["power"] == "table" else [Field("conc", u(8))]

    def uniform_values(self, scene, L, H):
        return {} if self.q["power"] == "table" else {"conc": concentration(scene)}

    @property
    def tables(self):
        return {"power": power_lut(SHAPE, self.q["mant_bits"])} \
            if self.q["power"] == "table" else {}

    def table_values(self, scene):
        return {"power": power_lut(shininess(scene), self.q["mant_bits"]).contents} \
            if self.q["power"] == "table" else {}

    @property
    def latency(self):
        unit = PowerTable if self.q["power"] == "table" else FenneyPower
        return unit.spec(**self.params).latency

    def rtl(self, p, v, uni):
        q, lights = self.q, range(self.q["lights"])
        if q["power"] == "table":
            return power_lanes(p, v, [(f"s{k}", f"p{k}") for k in lights], SHAPE,
                               q["mant_bits"])
        for k in lights:                 # X: s as a 10-bit fraction, clamped
            x = v.pop(f"s{k}") >> (VALUE.frac_bits - 10)
            v[f"_fx{k}"] = Mux(x < 0, 0, Mux(x > 1023, 1023, x))[:10]
            v[f"_fc{k}"] = uni["conc"]
        return fenney_lanes(p, v, [(f"_fx{k}", f"_fc{k}", f"p{k}") for k in lights])

    def ideal(self, prep, frag, ch):
        """max(0, s)^n exactly, or the patent's approximation on reals (its concentration)."""
        ch = dict(ch)
        for k in range(self.q["lights"]):
            s = np.clip(ch.pop(f"s{k}"), 0, 1)
            ch[f"p{k}"] = s ** shininess(prep["scene"]) if self.q["power"] == "table" else \
                fenney.power_float(s, concentration(prep["scene"]))
        return ch

    def model(self, prep, frag, ch, bound):
        q, ch = self.q, dict(ch)
        nudge = bound.get("s_offset", {})      # LSBs added to s_k first (fenney_candidates)
        for k in range(q["lights"]):
            s = raw(ch.pop(f"s{k}") + nudge.get(k, 0) * VALUE.lsb)
            ch[f"p{k}"] = shade.power_table(s, shininess(prep["scene"]), q["mant_bits"]) \
                if q["power"] == "table" else \
                fenney.power_int(np.clip(np.floor(s / 16), 0, 1023), prep["uniforms"]["conc"])
        return ch
