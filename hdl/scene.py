"""The scene pipeline: one top-level composed from exactly the units a scene calls for
(``scenes.md``; the driver in ``golden/scene.py`` chooses the parameters).

    triangles -> raster (channels: depth, then N.L and N.H per light in the scene's mode; or
                 the normal's three components, linear, for phong)
              -> phong (method = "phong": normalise, dot with L and H)
              -> power (specular: power_table, or fenney_power with the fitted concentration)
              -> colour -> fragments (tri, x, y, depth, r, g, b)

The per-fragment units share one pipeline (one enable), each in a submodule named after it.
Lights and material colours are uniforms: ports ``u_<field>`` that a host sets before it
streams triangles. The depth test and the framebuffer are not here: they model external memory
(a 256 x 256 frame with depth is 2.6 Mbit, more than the 1 Mbit of block RAM of an ECP5-25F),
and the renderer (``sim/render.py``) keeps them.
"""
from amaranth.hdl import Const, Module, Mux
from amaranth.lib.wiring import Out

from .fixed import Field
from .illum_unit.fenney_power import power_lanes as fenney_lanes
from .setup_unit.formats import MODES, VALUE, triangle_fields
from .shade_unit.colour import colour_lanes
from .shade_unit.formats import LEVEL, RGB, colour_fields, light_fields
from .shade_unit.phong import Phong, phong_lanes
from .shade_unit.power import power_lanes
from .span_unit.raster import Raster
from .unit import Pipeline, Unit

__all__ = ["ScenePipeline", "METHODS"]

METHODS = MODES + ("phong",)
MAX_CHANNELS = Raster.RANGES["channels"][1]


class ScenePipeline(Unit):
    NAME = "scene"
    DOC = "A scene's pipeline: raster -> (phong) -> (power) -> colour, fragments out"
    PARAMS = {"screen_bits": 8, "sub_bits": 4, "method": "xshading", "lights": 1,
              "specular": True, "power": "table", "shininess": 32.0, "mant_bits": 6,
              "concentration": 64, "recip": "newton", "recip_iters": 2, "rsqrt_iters": 2}
    RANGES = {"screen_bits": (4, 10), "sub_bits": (1, 8), "method": METHODS, "lights": (1, 4),
              "power": ("table", "fenney"), "shininess": (1.0, 1e9), "mant_bits": (3, 8),
              "concentration": (0, 255), "recip": ("newton", "divide"), "recip_iters": (0, 3),
              "rsqrt_iters": (1, 3)}
    status_ports = {"busy": Out(1), "culled": Out(32)}

    def validate(self, **q):
        n = len(self.channels)
        if n > MAX_CHANNELS:
            raise ValueError(f"{q['lights']} lights with specular need {n} raster channels "
                             f"(depth, N.L and N.H per light); the raster has at most "
                             f"{MAX_CHANNELS}")

    @property
    def channels(self):
        """The raster's channels: ``(name, mode)``, depth first."""
        q = self.params
        if q["method"] == "phong":
            return [("depth", "linear")] + [(f"n{a}", "linear") for a in "xyz"]
        return [("depth", "linear")] + [(f.name, q["method"]) for f in
                                        light_fields(q["lights"], q["specular"], "d", "s")]

    def parts(self):
        """The units built, each with its parameters and the scene key that calls for it."""
        q = self.params
        out = [("raster", dict(screen_bits=q["screen_bits"], sub_bits=q["sub_bits"],
                               channels=len(self.channels),
                               modes=",".join(m for _, m in self.channels), recip=q["recip"],
                               recip_iters=q["recip_iters"]),
                f"shading.method = {q['method']}")]
        if q["method"] == "phong":
            out.append(("phong", dict(lights=q["lights"], specular=q["specular"],
                                      rsqrt_iters=q["rsqrt_iters"]),
                        "shading.method = phong"))
        if q["specular"]:
            if q["power"] == "table":
                out.append(("power_table", dict(shininess=float(q["shininess"]),
                                                mant_bits=q["mant_bits"]),
                            "shading.specular = true, shading.power = table"))
            else:
                out.append(("fenney_power", {}, "shading.specular = true, shading.power = "
                            f"fenney (C = {q['concentration']})"))
        out.append(("colour", dict(lights=q["lights"], specular=q["specular"]),
                    "material, lights"))
        return out

    @property
    def raster(self):
        return Raster.spec(**self.parts()[0][1])

    @property
    def inputs(self):
        q = self.params
        return triangle_fields(q["screen_bits"], q["sub_bits"], len(self.channels))

    @property
    def uniforms(self):
        q = self.params
        vec = ([Field(f"{t}{k}{a}", VALUE) for k in range(q["lights"])
                for t in ("l", "h") if q["specular"] or t == "l" for a in "xyz"]
               if q["method"] == "phong" else [])
        return vec + colour_fields(q["lights"], q["specular"])

    @property
    def outputs(self):
        frag = self.raster.outputs
        return ([f for f in frag if f.name in ("tri", "x", "y")] + [Field("depth", VALUE)]
                + [Field(c, LEVEL) for c in RGB])

    @property
    def shading_latency(self):
        from .units import UNITS
        return sum(UNITS[name].spec(**params).latency for name, params, _ in self.parts()[1:])

    @property
    def latency(self):
        """From a triangle in to its first fragment out, when nothing waits."""
        return self.raster.latency + self.shading_latency

    def elaborate(self, platform):
        q = self.params
        m = Module()
        m.submodules.raster = raster = Raster(**self.parts()[0][1])
        m.d.comb += [raster.i.valid.eq(self.i.valid), self.i.ready.eq(raster.i.ready),
                     raster.i.payload.eq(self.i.payload)]
        p = Pipeline(m, raster.o, self.o)
        frag = raster.o.payload
        v = {"tri": frag.tri, "x": frag.x, "y": frag.y}
        v.update({name: frag[f"v{k}"] for k, (name, _) in enumerate(self.channels)})
        uni = {f.name: getattr(self, f"u_{f.name}") for f in self.uniforms}
        lights = range(q["lights"])
        for name, params, _ in self.parts()[1:]:
            with p.part(name):
                if name == "phong":
                    spec = Phong.spec(**params)
                    v = phong_lanes(p, {**v, **{k: uni[k] for k in
                                                [f.name for f in spec.inputs[3:]]}},
                                    spec.vectors(), q["rsqrt_iters"])
                elif name == "power_table":
                    v = power_lanes(p, v, [(f"s{k}", f"p{k}") for k in lights],
                                    q["shininess"], q["mant_bits"])
                elif name == "fenney_power":
                    for k in lights:       # X: s as a 10-bit fraction, clamped
                        x = v.pop(f"s{k}") >> (VALUE.frac_bits - 10)
                        v[f"_fx{k}"] = Mux(x < 0, 0, Mux(x > 1023, 1023, x))[:10]
                        v[f"_fc{k}"] = Const(q["concentration"], 8)
                    v = fenney_lanes(p, v, [(f"_fx{k}", f"_fc{k}", f"p{k}") for k in lights])
                else:
                    v = colour_lanes(p, {**v, **{f.name: uni[f.name] for f in
                                                 colour_fields(q["lights"], q["specular"])}},
                                     q["lights"], q["specular"])
        p.finish(self.o, v, self.outputs, self.shading_latency, "scene: shading")
        busy = raster.busy
        for valid in p.valids:
            busy = busy | valid
        m.d.comb += [self.busy.eq(busy), self.culled.eq(raster.culled)]
        return m


def units_in(design):
    """The names of the units in an elaborated scene pipeline (its submodules')."""
    from amaranth.hdl import Fragment
    frag = Fragment.get(design, None)
    return sorted(name for _, name, *_ in frag.subfragments)
