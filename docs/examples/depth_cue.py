"""A new effect in one file: depth cueing, the colour dimmed with distance (README, "Adding an
effect or a method"). ``tests/test_stages.py`` registers it (``scene.registry``: after
the last stage, ``Colour``) and renders a scene through it, RTL against this model."""
import numpy as np

from hdl.fixed import Field, u
from hdl.shade_unit.formats import RGB
from scene.stage import Stage, raw

NEAR = Field("cue_near", u(8, 8))        # the gain at depth 1 (the nearest vertex), 8 bits


class DepthCue(Stage):
    name = "depth_cue"
    why = "an example: the colour times the gain the depth gives"
    uniforms = (NEAR,)
    when = {}                            # which scenes call for it: every one

    def uniform_values(self, scene, L, H):
        return {"cue_near": 255}

    @property
    def latency(self):
        return 2

    def rtl(self, p, v, uni):
        # gain = near * depth (depth in (0, 1] with 14 fraction bits: 8 of them and the one),
        # then each channel times the gain
        g = p.stage(v, _g=(uni["cue_near"] * v["depth"][6:15])[8:16])
        gain = g.pop("_g")
        return p.stage(g, **{c: (g.pop(c) * gain)[8:16] for c in RGB})

    def model(self, prep, frag, ch, bound):
        depth = (raw(ch["depth"]) >> 6) & 511
        gain = (prep["uniforms"]["cue_near"] * depth) >> 8
        return {**ch, **{c: (np.asarray(ch[c], np.int64) * gain) >> 8 for c in RGB}}

    def ideal(self, prep, frag, ch):
        """The colour times near * depth on reals, rounded to 8 bits."""
        gain = prep["uniforms"]["cue_near"] / 256 * np.asarray(ch["depth"], float)
        return {**ch, **{c: np.rint(np.asarray(ch[c], float) * gain).astype(np.int64)
                         for c in RGB}}
