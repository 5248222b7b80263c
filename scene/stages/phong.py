"""The phong stage (seed 000 eq 33-45, Duff): the interpolated normal (three linear channels)
normalised at every pixel and dotted with each L and H: the quality reference in hardware."""
import numpy as np

from golden import shade
from hdl.fixed import Field
from hdl.setup_unit.formats import VALUE
from hdl.shade_unit.phong import Phong as Unit, phong_lanes

from ..stage import Stage, raw


class Phong(Stage):
    name = "phong"
    format_group = "shading"
    channels = tuple((f"n{a}", "linear", 0) for a in "xyz")
    why = "shading.method = phong"
    when = {"method": "phong"}
    gives = ("lighting",)           # N.L and N.H: the raster interpolates none
    build_params = {"rsqrt_iters": (2, (1, 3))}

    @property
    def params(self):
        q = self.q
        return dict(lights=q["lights"], specular=q["specular"], rsqrt_iters=q["rsqrt_iters"])

    @property
    def uniforms(self):
        return [Field(f.name, VALUE) for f in Unit.spec(**self.params).inputs[3:]]   # L, H

    def uniform_values(self, scene, L, H):
        """Each light's L and H, world frame: VALUE."""
        out = {}
        for j, (lv, hv) in enumerate(zip(L, H)):
            for a in range(3):
                out[f"l{j}{'xyz'[a]}"], out[f"h{j}{'xyz'[a]}"] = raw(lv[a], VALUE), \
                    raw(hv[a], VALUE)
        return out

    def validate(self, q):
        if q["bump"] != "none":
            raise ValueError(f"shading.method: phong interpolates the normal, which "
                             f"bump.method = {q['bump']} replaces; use none of them together")

    @property
    def latency(self):
        return Unit.spec(**self.params).latency

    def rtl(self, p, v, uni):
        unit = Unit.spec(**self.params)
        return phong_lanes(p, {**v, **{f.name: uni[f.name] for f in self.uniforms}},
                           unit.vectors(), self.q["rsqrt_iters"])

    def ideal(self, prep, frag, ch):
        """The interpolated normal normalised exactly, dotted with L and H (seed 000 eq 33)."""
        ch = dict(ch)
        n = np.stack([ch.pop(k) for k in ("nx", "ny", "nz")], -1)
        n = n / np.linalg.norm(n, axis=-1, keepdims=True)
        for j, (L, H) in enumerate(zip(prep["float"]["L"], prep["float"]["H"])):
            ch[f"d{j}"] = n @ L
            if self.q["specular"]:
                ch[f"s{j}"] = n @ H
        return ch

    def _inputs(self, prep, ch):
        inp = {k: raw(ch[k]) for k in ("nx", "ny", "nz")}
        inp.update({f.name: np.full(len(inp["nx"]), prep["uniforms"][f.name])
                    for f in self.uniforms})
        return inp

    def model(self, prep, frag, ch, bound):
        out, _ = shade.phong(self._inputs(prep, ch), lights=self.q["lights"],
                             specular=self.q["specular"])
        ch = {k: v for k, v in ch.items() if k not in ("nx", "ny", "nz")}
        return {**ch, **{k: x * VALUE.lsb for k, x in out.items()}}

    def bounds(self, prep, ch):
        """Per output and fragment, how far (VALUE LSBs) the RTL may be from this model: the
        unit's derived bound (``golden.shade.phong_check``)."""
        inp = self._inputs(prep, ch)
        want, _ = shade.phong(inp, lights=self.q["lights"], specular=self.q["specular"])
        return {k: b for k, (_, b) in shade.phong_check(inp, want, lights=self.q["lights"],
                                                         specular=self.q["specular"]).items()}
