"""The colour stage (scenes.md "Lighting"): ambient + per light kd d colour + ks p, summed,
clamped, to 8-bit RGB; bit-exact. Its coefficients are uniforms."""
import numpy as np

from golden import shade
from hdl.shade_unit.colour import Colour as Unit, colour_lanes
from hdl.shade_unit.formats import COEF, RGB, colour_fields

from ..stage import Stage, raw


class Colour(Stage):
    name = "colour"
    format_group = "colour"
    why = "material, lights"

    @property
    def params(self):
        return dict(lights=self.q["lights"], specular=self.q["specular"])

    @property
    def uniforms(self):
        return colour_fields(self.q["lights"], self.q["specular"])

    def uniform_values(self, scene, L, H):
        """ambient colour, kd light colour and ks light per light: COEF."""
        mat, col = scene["material"], np.array(scene["material"]["color"])
        out = {}
        for ci, c in enumerate(RGB):
            out[f"amb_{c}"] = raw(mat["ambient"] * col[ci], COEF)
            for j, light in enumerate(scene["lights"]):
                out[f"kd{j}_{c}"] = raw(mat["diffuse"] * light["color"][ci] * col[ci], COEF)
                out[f"ks{j}_{c}"] = raw(mat["specular"] * light["color"][ci], COEF)
        return out

    @property
    def latency(self):
        return Unit.spec(**self.params).latency

    def ideal(self, prep, frag, ch):
        """The colour sum of scenes.md on reals (d clamped, p as given), rounded to 8 bits."""
        q = self.q
        d = [ch[f"d{k}"] for k in range(q["lights"])]
        p = [ch[f"p{k}"] if q["specular"] else np.zeros(len(d[0])) for k in range(q["lights"])]
        rgb = shade.colour_float(prep["scene"], d, p)
        return {**ch, **{c: rgb[:, k].astype(np.int64) for k, c in enumerate(RGB)}}

    def rtl(self, p, v, uni):
        return colour_lanes(p, {**v, **{f.name: uni[f.name] for f in self.uniforms}},
                            self.q["lights"], self.q["specular"])

    def model(self, prep, frag, ch, bound):
        q, ch = self.q, dict(ch)
        lights = range(q["lights"])
        inp = {f"d{k}": raw(ch.pop(f"d{k}")) for k in lights}
        inp.update({f"p{k}": ch.pop(f"p{k}") for k in lights if q["specular"]})
        inp.update(prep["uniforms"])
        rgb = shade.colour(inp, **self.params)
        return {**ch, **{c: np.asarray(rgb[c]) for c in RGB}}
