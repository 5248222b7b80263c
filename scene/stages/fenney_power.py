"""The Fenney power stage (seed 004): the specular power of each light's N.H per pixel by the
patent's quadratic approximation, its concentration C fitted to the shininess. C is data, a
register the host writes; the hardware depends only on the lanes."""
import numpy as np
from amaranth.hdl import Mux

from golden import fenney
from hdl.fixed import Field, u
from hdl.illum_unit.fenney_power import FenneyPower as Unit, power_lanes
from hdl.setup_unit.formats import VALUE

from ..stage import Stage, Sweep, convert_powers, raw


def concentration(scene):
    """The Fenney concentration C fitted to the scene's shininess."""
    return fenney.concentration_for(float(scene["material"]["shininess"]))


class FenneyPower(Stage):
    name = "fenney_power"
    why = "shading.specular = true, shading.power = fenney (C a register)"

    @classmethod
    def sweeps(cls):
        """The patent's approximation, beside the power table's rows."""
        return [Sweep("power", cls.when["power"], cls.name, scene="fenney_power", rows=None,
                      quick=True)]
    when = {"specular": True, "power": "fenney"}
    gives = ("powers",)
    defers = True                 # bump_polar gives its own
    uniforms = (Field("conc", u(8)),)

    def uniform_values(self, scene, L, H):
        return {"conc": concentration(scene)}

    @property
    def latency(self):
        return Unit.spec().latency

    def rtl(self, p, v, uni):
        lights = range(self.q["lights"])
        for k in lights:                 # X: s as a 10-bit fraction, clamped
            x = v.pop(f"s{k}") >> (VALUE.frac_bits - 10)
            v[f"_fx{k}"] = Mux(x < 0, 0, Mux(x > 1023, 1023, x))[:10]
            v[f"_fc{k}"] = uni["conc"]
        return power_lanes(p, v, [(f"_fx{k}", f"_fc{k}", f"p{k}") for k in lights])

    def convert(self, ch, ideal):
        return convert_powers(ch, ideal)

    def ideal(self, prep, frag, ch):
        """The patent's approximation on reals, with its concentration."""
        ch = dict(ch)
        for k in range(self.q["lights"]):
            ch[f"p{k}"] = fenney.power_float(np.clip(ch.pop(f"s{k}"), 0, 1),
                                             concentration(prep["scene"]))
        return ch

    def model(self, prep, frag, ch, bound):
        """X = floor(s / 16) of s's raw value; ``bound``: ``s_offset`` ``{k: LSBs}`` added to
        s_k first (``candidates``)."""
        ch, nudge = dict(ch), bound.get("s_offset", {})
        for k in range(self.q["lights"]):
            s = raw(ch.pop(f"s{k}") + nudge.get(k, 0) * VALUE.lsb)
            ch[f"p{k}"] = fenney.power_int(np.clip(np.floor(s / 16), 0, 1023),
                                           prep["uniforms"]["conc"])
        return ch

    slack = 1

    def candidates(self, prep, frag, ch):
        """Where a stage before it gives s within a derived bound b of the float s the model
        rounds (phong's), every colour the RTL may give, ``(choices, n, 3)``, each within a
        level. The power takes X = floor(s / 16), so where s lies within b of a multiple of
        16 the RTL's X may be the next one either way, and at high concentrations one step
        of X is up to 63/1024 of the power (C = 255, X 1021: 10 levels at ks 0.5 and a
        light of 1.3). Each light's s is tried at -b, 0 and +b (the ends of the interval
        reach every X in it). None where s is the raster's (exact to the model)."""
        from hdl.shade_unit.formats import RGB
        from ..models import run_models
        stages = prep["pipeline"].stages[1:]
        b = {}
        for stage in stages[:stages.index(self)]:
            b.update(stage.bounds(prep, ch))
        lights = self.q["lights"]
        if not all(f"s{k}" in b for k in range(lights)):
            return None
        out = []
        for signs in np.ndindex(*(3,) * lights):
            off = {k: (signs[k] - 1) * b[f"s{k}"] for k in range(lights)}
            c = run_models(prep, frag, ch, stages, s_offset=off)
            out.append(np.stack([c[x] for x in RGB], -1))
        return np.stack(out).astype(np.int64)
