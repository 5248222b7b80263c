"""A second effect in one file, with a scene key and an interpolated channel of its own: fog by
distance (README, "Adding an effect or a method"). The scene's ``[fog]`` table gives ``near``, ``far``
(camera distances along the view axis) and ``color``; each vertex's fog factor
f = clamp((far - z) / (far - near), 0, 1) rides the raster as a linear channel, and each
pixel's colour is blended toward the fog's: c f + fog (1 - f).

``tests/test_stages.py`` registers ``Fog`` (``scene.registry``: after the last stage,
``Colour``) and renders a scene through it, RTL against this model. ``python docs/examples/fog.py OUT.png``
draws the default torus with and without it, through the RTL (Verilator's batch path)."""
import numpy as np
from amaranth.hdl import Mux

from hdl.fixed import Field, u
from hdl.setup_unit.formats import VALUE
from hdl.shade_unit.formats import RGB
from scene.stage import SceneError, Stage, raw

ONE = 1 << VALUE.frac_bits          # f = 1 as a channel's raw value
W = 8                               # the blend's weight: 8 fraction bits, 0..256


class Fog(Stage):
    name = "fog"
    why = "[fog]: the colour blended toward fog.color by the distance"
    when = {}                       # every scene: its [fog] table has defaults
    scene_keys = {"fog": {"near": (4.0, ("num", 0.0, 1e6)), "far": (6.0, ("num", 0.0, 1e6)),
                          "color": ([0.55, 0.6, 0.7], ("vec", 3, 0.0, 1.0))}}
    channels = (("fog", "linear", 0),)
    uniforms = tuple(Field(f"fog_{c}", u(8)) for c in RGB)

    def prepare(self, scene, view, data):
        fog = scene["fog"]
        if not fog["far"] > fog["near"]:
            raise SceneError(f"fog.far: must be beyond fog.near ({fog['near']:g}), not "
                             f"{fog['far']:g}")
        z = view.zc[view.drawn]                                   # (n, 3) camera depths
        return {"fog": np.clip((fog["far"] - z) / (fog["far"] - fog["near"]), 0.0, 1.0)}

    def vertex_values(self, data):
        return {"fog": data["fog"]}

    def uniform_values(self, scene, L, H):
        color = np.rint(np.array(scene["fog"]["color"]) * 255).astype(int)
        return {f"fog_{c}": int(color[k]) for k, c in enumerate(RGB)}

    @property
    def latency(self):
        return 2

    def rtl(self, p, v, uni):
        # the weight w = f in 8 fraction bits, clamped to [0, 256] (the interpolated f may
        # round a little outside [0, 1]); then fog + (c - fog) w / 256 per channel, rounded
        f = v.pop("fog")
        w = Mux(f < 0, 0, Mux(f >= ONE, 1 << W, f[VALUE.frac_bits - W:VALUE.frac_bits + 1]))
        v = p.stage(v, _w=w)
        w = v.pop("_w")
        blend = lambda c: ((uni[f"fog_{c}"] << W) + (v.pop(c) - uni[f"fog_{c}"]) * w
                           + (1 << (W - 1)))[W:W + 8]
        return p.stage(v, **{c: blend(c) for c in RGB})

    def weight(self, ch):
        return np.clip(raw(ch["fog"]) >> (VALUE.frac_bits - W), 0, 1 << W)

    def model(self, prep, frag, ch, bound):
        w, uni = self.weight(ch), prep["uniforms"]
        ch = {k: x for k, x in ch.items() if k != "fog"}
        return {**ch, **{c: ((uni[f"fog_{c}"] << W) + (np.asarray(ch[c], np.int64)
                                                      - uni[f"fog_{c}"]) * w
                             + (1 << (W - 1))) >> W for c in RGB}}

    def ideal(self, prep, frag, ch):
        f = np.clip(ch["fog"], 0.0, 1.0)
        fog = np.array(prep["scene"]["fog"]["color"]) * 255
        ch = {k: x for k, x in ch.items() if k != "fog"}
        return {**ch, **{c: np.rint(np.asarray(ch[c], float) * f + fog[k] * (1 - f))
                         .astype(np.int64) for k, c in enumerate(RGB)}}


if __name__ == "__main__":
    import sys
    from pathlib import Path

    from PIL import Image

    from scene import driver as S, pipeline
    from sim.render import run_rtl

    if len(sys.argv) != 2:
        sys.exit("usage: python docs/examples/fog.py OUT.png")
    image = {"width": 192, "height": 128}
    pictures = []
    for stages, data in (((), {"image": image}),
                         ((Fog,), {"image": image, "fog": {"near": 3.2, "far": 5.0}})):
        with pipeline.registered(*stages):
            prep = S.prepare(S.parse(data, "fog"))
            pictures.append(run_rtl(prep, "verilator")[0])
    Image.fromarray(np.concatenate(pictures, 1)).save(Path(sys.argv[1]))
    print(f"{sys.argv[1]}: the default torus through the RTL, without and with fog")
