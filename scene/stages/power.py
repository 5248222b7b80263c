"""The power stage: the specular power of each light's N.H per pixel, from the table
(``power_table``: max(0, s)^n in floating-point bins) or by the patent's quadratic
approximation (``fenney_power``, the concentration fitted to the shininess)."""
import numpy as np
from amaranth.hdl import Const, Mux

from golden import fenney, shade
from hdl.illum_unit.fenney_power import FenneyPower, power_lanes as fenney_lanes
from hdl.setup_unit.formats import VALUE
from hdl.shade_unit.power import PowerTable, power_lanes

from ..stage import Stage, raw


class Power(Stage):

    @classmethod
    def wanted(cls, q):
        return q["specular"] and q["bump"] != "angular"     # bump_polar has its own table

    @property
    def name(self):
        return "power_table" if self.q["power"] == "table" else "fenney_power"

    @property
    def params(self):
        q = self.q
        return dict(shininess=float(q["shininess"]), mant_bits=q["mant_bits"]) \
            if q["power"] == "table" else {}

    @property
    def why(self):
        q = self.q
        return "shading.specular = true, shading.power = " + (
            "table" if q["power"] == "table" else f"fenney (C = {q['concentration']})")

    @property
    def latency(self):
        unit = PowerTable if self.q["power"] == "table" else FenneyPower
        return unit.spec(**self.params).latency

    def rtl(self, p, v, uni):
        q, lights = self.q, range(self.q["lights"])
        if q["power"] == "table":
            return power_lanes(p, v, [(f"s{k}", f"p{k}") for k in lights], q["shininess"],
                               q["mant_bits"])
        for k in lights:                 # X: s as a 10-bit fraction, clamped
            x = v.pop(f"s{k}") >> (VALUE.frac_bits - 10)
            v[f"_fx{k}"] = Mux(x < 0, 0, Mux(x > 1023, 1023, x))[:10]
            v[f"_fc{k}"] = Const(q["concentration"], 8)
        return fenney_lanes(p, v, [(f"_fx{k}", f"_fc{k}", f"p{k}") for k in lights])

    def model(self, prep, frag, ch, bound):
        q, ch = self.q, dict(ch)
        for k in range(q["lights"]):
            s = raw(ch.pop(f"s{k}"))
            ch[f"p{k}"] = shade.power_table(s, q["shininess"], q["mant_bits"]) \
                if q["power"] == "table" else \
                fenney.power_int(np.clip(np.floor(s / 16), 0, 1023), q["concentration"])
        return ch
