"""The power table stage: the specular power of each light's N.H per pixel, max(0, s)^n from a
table in floating-point bins (``hdl.shade_unit.power``). The shininess is data: the table is
a RAM that the host loads; the hardware depends only on ``mant_bits`` and the lanes."""
import numpy as np

from golden import shade
from hdl.shade_unit.power import PowerTable as Unit, power_lanes, power_lut
from hdl.setup_unit.formats import VALUE

from ..stage import Stage, Sweep, convert_powers, raw

SHAPE = Unit.PARAMS["shininess"]          # the table's shape only: its contents are loaded


class PowerTable(Stage):
    name = "power_table"
    why = "shading.specular = true, shading.power = table (loaded)"
    when = {"specular": True, "power": "table"}
    gives = ("powers",)
    defers = True                 # bump_polar gives its own
    build_params = {"mant_bits": (6, (3, 8))}

    @classmethod
    def sweeps(cls):
        """The table's mantissa bits (``make tradeoffs``' power rows, beside Fenney's)."""
        default = cls.build_params["mant_bits"][0]
        return [Sweep("power", f"table {b}", cls.name, {} if b == default else {"mant_bits": b},
                      "default", {} if b == default else {"mant_bits": b}, rows=None,
                      default=b == default, quick=b == default) for b in (4, 6, 8)]

    @property
    def params(self):
        return dict(mant_bits=self.q["mant_bits"])

    @property
    def tables(self):
        return {"power": power_lut(SHAPE, self.q["mant_bits"])}

    def table_values(self, scene):
        return {"power": power_lut(scene["material"]["shininess"], self.q["mant_bits"]).contents}

    @property
    def latency(self):
        return Unit.spec(**self.params).latency

    def rtl(self, p, v, uni):
        return power_lanes(p, v, [(f"s{k}", f"p{k}") for k in range(self.q["lights"])], SHAPE,
                           self.q["mant_bits"])

    def convert(self, ch, ideal):
        return convert_powers(ch, ideal)

    def ideal(self, prep, frag, ch):
        """max(0, s)^n exactly."""
        ch = dict(ch)
        for k in range(self.q["lights"]):
            ch[f"p{k}"] = np.clip(ch.pop(f"s{k}"), 0, 1) ** prep["scene"]["material"]["shininess"]
        return ch

    def model(self, prep, frag, ch, bound):
        ch = dict(ch)
        for k in range(self.q["lights"]):
            ch[f"p{k}"] = shade.power_table(raw(ch.pop(f"s{k}")),
                                            prep["scene"]["material"]["shininess"],
                                            self.q["mant_bits"])
        return ch
