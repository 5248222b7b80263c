"""The scene pipeline: one top-level composed from exactly the units a scene calls for
(``scenes.md``; the driver in ``golden/scene.py`` chooses the parameters).

    triangles -> raster (channels: depth, then N.L and N.H per light in the scene's mode; or
                 the normal's three components, linear, for phong)
              -> phong (method = "phong": normalise, dot with L and H)
              -> power (specular: power_table, or fenney_power with the fitted concentration)
              -> colour -> fragments (tri, x, y, depth, r, g, b)

    bump = "fenney_xz" (seed 004, second embodiment):
    triangles -> raster (depth, s, t linear; L' and H' in the tangent frame per light, three
                 channels each, in the scene's mode: quadratic with each vector's own
                 per-edge constants (seed 000 section 2), or linear)
              -> texture ROM (X/Z texels, nearest or bilinear) -> texel_decode
              -> fenney_dot (one lane per light and vector, the texel shared) -> power -> colour

    bump = "angular" (seed 003):
    triangles -> raster (depth, s, t; the normal's angles phi_N, theta_N and the twist psi
                 of the texture's frame about N, all linear, unwrapped per triangle)
              -> texture ROM ((phi, theta) texels, nearest) -> phi_B + psi
              -> bump_polar (rotation of L and of H into N's frame, paper or exact; illum
                 with its diffuse and specular tables) -> colour

    bump = "fenney_polar" (seed 004, first embodiment):
    triangles -> raster (depth, and the texture coordinates s, t, linear; the per-triangle
                 constants k1, k2, k3, Q of L and of H per light as flat words, carried to
                 every fragment of their triangle)
              -> texture ROM (S/R texels, nearest, wrapping) -> fenney_polar (FIG. 3, one lane
                 per light and vector, the texel's sin S and cos S shared)
              -> power (of the H lanes) -> colour -> fragments

The per-fragment units share one pipeline (one enable), each in a submodule named after it.
Lights and material colours are uniforms: ports ``u_<field>`` that a host sets before it
streams triangles. The depth test and the framebuffer are not here: they model external memory
(a 256 x 256 frame with depth is 2.6 Mbit, more than the 1 Mbit of block RAM of an ECP5-25F),
and the renderer (``sim/render.py``) keeps them.
"""
from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib.wiring import Out

from .fixed import Field, binary_angle, u
from .illum_unit.fenney_dot import FenneyDot, dot_lanes
from .illum_unit.fenney_polar import polar_lanes
from .illum_unit.bump_polar import BumpPolar
from .illum_unit.fenney_power import power_lanes as fenney_lanes
from .illum_unit.texel_decode import TexelDecode
from .setup_unit.formats import MODES, VALUE
from .shade_unit.colour import colour_lanes
from .shade_unit.formats import LEVEL, RGB, colour_fields, light_fields
from .shade_unit.phong import Phong, phong_lanes
from .shade_unit.power import power_lanes
from .span_unit.raster import Raster
from .texture_unit import FILTERS, MAX_TEXTURE, fetch
from .unit import Pipeline, Unit

__all__ = ["ScenePipeline", "METHODS", "BUMPS"]

METHODS = MODES + ("phong",)
BUMPS = ("none", "fenney_xz", "fenney_polar", "angular")
ANGLE_BITS = 12               # angular: every angle in turns * 2**12 (the rotation's default)
MAX_CHANNELS = Raster.RANGES["channels"][1]


class ScenePipeline(Unit):
    NAME = "scene"
    DOC = "A scene's pipeline: raster -> (phong) -> (power) -> colour, fragments out"
    PARAMS = {"screen_bits": 8, "sub_bits": 4, "method": "xshading", "lights": 1,
              "specular": True, "power": "table", "shininess": 32.0, "mant_bits": 6,
              "concentration": 64, "recip": "newton", "recip_iters": 2, "rsqrt_iters": 2,
              "bump": "none", "bump_map": "bricks", "bump_size": 256, "bump_depth": 1.0,
              "filter": "nearest", "trig_bits": 10, "rotation": "paper", "normalize": False,
              "rsqrt_bits": 12}
    RANGES = {"screen_bits": (4, 10), "sub_bits": (1, 8), "method": METHODS, "lights": (1, 4),
              "power": ("table", "fenney"), "shininess": (1.0, 1e9), "mant_bits": (3, 8),
              "concentration": (0, 255), "recip": ("newton", "divide"), "recip_iters": (0, 3),
              "rsqrt_iters": (1, 3), "bump": BUMPS, "bump_map": None,
              "bump_size": (16, MAX_TEXTURE), "bump_depth": (0.0, 1e9), "filter": FILTERS,
              "trig_bits": (4, 16), "rotation": ("paper", "exact"),
              "rsqrt_bits": FenneyDot.RANGES["rsqrt_bits"]}
    status_ports = {"busy": Out(1), "culled": Out(32)}

    def validate(self, **q):
        if q["bump"] != "none":
            size = q["bump_size"]
            if size & (size - 1):
                raise ValueError(f"bump_size must be a power of two (the texture coordinates "
                                 f"wrap by their bits), not {size}")
            if q["method"] == "phong":
                raise ValueError(f"bump = {q['bump']} shades from its texels: method must not "
                                 f"be phong")
            if q["bump"] in ("fenney_polar", "angular") and q["filter"] != "nearest":
                raise ValueError(f"bump = {q['bump']} filters nearest only (its texels are "
                                 f"angles, which do not interpolate across their wrap)")
            if q["bump"] == "angular" and q["lights"] != 1:
                raise ValueError("bump = angular shades one light (bump_polar rotates one L "
                                 "and one H)")
        n = len(self.channels)
        if n > MAX_CHANNELS:
            raise ValueError(f"{q['lights']} lights with specular need {n} raster channels "
                             f"(depth, N.L and N.H per light; or depth, s, t and three per "
                             f"light and vector); the raster has at most "
                             f"{MAX_CHANNELS}")

    @property
    def channels(self):
        """The raster's channels: ``(name, mode)``, depth first."""
        q = self.params
        if q["bump"] != "none":
            tex = [("depth", "linear"), ("s", "linear"), ("t", "linear")]
            if q["bump"] == "fenney_polar":
                return tex
            if q["bump"] == "angular":
                return tex + [("phin", "linear"), ("thetan", "linear"), ("psi", "linear")]
            return tex + [(f"{t}{k}{a}", q["method"]) for t, k in self.lanes for a in "xyz"]
        if q["method"] == "phong":
            return [("depth", "linear")] + [(f"n{a}", "linear") for a in "xyz"]
        return [("depth", "linear")] + [(f.name, q["method"]) for f in
                                        light_fields(q["lights"], q["specular"], "d", "s")]

    def parts(self):
        """The units built, each with its parameters and the scene key that calls for it."""
        q = self.params
        raster = dict(screen_bits=q["screen_bits"], sub_bits=q["sub_bits"],
                      channels=len(self.channels), modes=",".join(m for _, m in self.channels),
                      recip=q["recip"], recip_iters=q["recip_iters"])
        vectors = f"L{' and H' if q['specular'] else ''} per light"
        if q["bump"] == "none":
            out = [("raster", raster, f"shading.method = {q['method']}")]
        elif q["bump"] == "fenney_polar":
            raster["flat"] = len(self.lanes)
            out = [("raster", raster, "bump.method = fenney_polar: depth and texture "
                    "coordinates, linear; each lane's k1, k2, k3 and Q as a flat word")]
        elif q["bump"] == "angular":
            out = [("raster", raster, "bump.method = angular: depth, texture coordinates, "
                    "the normal's angles and the frame's twist, linear")]
        else:                     # each vector's components: a group of edge constants
            raster["groups"] = ",".join(["0"] * 3 + [str(1 + n) for n in range(len(self.lanes))
                                                     for _ in "xyz"])
            out = [("raster", raster, f"bump.method = fenney_xz: depth, s, t linear; {vectors}"
                    f" in the tangent frame, shading.method = {q['method']}")]
        if q["bump"] != "none":
            kind = {"fenney_polar": "sr", "fenney_xz": "xz", "angular": "polar"}[q["bump"]]
            tex = dict(kind=kind, bump_map=q["bump_map"], bump_size=q["bump_size"],
                       bump_depth=q["bump_depth"], filter=q["filter"])
            if kind == "polar":
                tex["bits"] = ANGLE_BITS
            out.append(("texture", tex, f"bump.map = {q['bump_map']}: {kind} texels, "
                        f"{q['filter']}"))
        if q["bump"] == "angular":
            out.append(("bump_polar", self.bump_polar_params, "bump.method = angular, "
                        f"bump.rotation = {q['rotation']}: rotation x 2, illum"))
            out.append(("colour", dict(lights=q["lights"], specular=q["specular"]),
                        "material, lights"))
            return out
        if q["bump"] == "fenney_polar":
            out.append(("fenney_polar", dict(trig_bits=q["trig_bits"]),
                        f"bump.method = fenney_polar: {len(self.lanes)} lanes ({vectors})"))
        elif q["bump"] == "fenney_xz":
            out.append(("texel_decode", {}, "bump.method = fenney_xz"))
            out.append(("fenney_dot", self.dot_params, f"bump.method = fenney_xz: "
                        f"{len(self.lanes)} lanes ({vectors})"))
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
    def dot_params(self):
        """fenney_dot's: the patent's plain dot product, or the bump vector renormalised (a
        hardware choice, not a scene key: ``make tradeoffs`` sweeps it)."""
        return dict(normalize=self.params["normalize"], rsqrt_bits=self.params["rsqrt_bits"])

    @property
    def bump_polar_params(self):
        q = self.params
        return dict(method=q["rotation"], angle_bits=ANGLE_BITS,
                    shininess=max(1, min(1024, round(q["shininess"]))))

    @property
    def lanes(self):
        """A bump unit's lanes: ``(vector, light)``, L per light and, with specular, H."""
        q = self.params
        return [(t, k) for k in range(q["lights"]) for t in ("l", "h")
                if q["specular"] or t == "l"]


    def part_latency(self, name, params):
        """A part's stages in this pipeline: a unit's latency, or (the texture ROM, and
        fenney_polar's lanes, whose power unit is the pipeline's power part) their own."""
        from .units import UNITS
        if name == "texture":
            return 2 if params["filter"] == "nearest" else 7
        if name == "fenney_polar":
            return 6
        extra = {"fenney_dot": 1,       # the light's conversion to s8
                 "bump_polar": 1}       # the angles from the channels, phi_B + psi
        return UNITS[name].spec(**params).latency + extra.get(name, 0)

    @property
    def raster(self):
        return Raster.spec(**self.parts()[0][1])

    @property
    def inputs(self):
        return list(self.raster.inputs)

    @property
    def uniforms(self):
        q = self.params
        vec = ([Field(f"{t}{k}{a}", VALUE) for k in range(q["lights"])
                for t in ("l", "h") if q["specular"] or t == "l" for a in "xyz"]
               if q["method"] == "phong" else [])
        if q["bump"] == "angular":           # L and H in polar form, world frame
            vec = [Field(n, binary_angle(ANGLE_BITS)) for n in
                   ("phi_l", "theta_l", "phi_h", "theta_h")]
        return vec + colour_fields(q["lights"], q["specular"])

    @property
    def outputs(self):
        frag = self.raster.outputs
        return ([f for f in frag if f.name in ("tri", "x", "y")] + [Field("depth", VALUE)]
                + [Field(c, LEVEL) for c in RGB])

    @property
    def shading_latency(self):
        return sum(self.part_latency(name, params) for name, params, _ in self.parts()[1:])

    @property
    def latency(self):
        """From a triangle in to its first fragment out, when nothing waits."""
        return self.raster.latency + self.shading_latency

    def elaborate(self, platform):
        q = self.params
        m = Module()
        m.submodules.raster = raster = Raster(**self.parts()[0][1])
        m.d.comb += [raster.i.payload[f.name].eq(self.i.payload[f.name])
                     for f in raster.inputs]
        m.d.comb += [raster.i.valid.eq(self.i.valid), self.i.ready.eq(raster.i.ready)]
        p = Pipeline(m, raster.o, self.o)
        frag = raster.o.payload
        const = {}
        for n, (t, k) in enumerate(self.lanes if q["bump"] == "fenney_polar" else ()):
            word = frag[f"f{n}"]          # a lane's constants, packed k1 k2 k3 Q from the top
            const.update({f"{t}{k}_{c}": word[8 * (3 - j):8 * (4 - j)]
                          for j, c in enumerate(("k1", "k2", "k3", "q"))})
        # the pixel's coordinates ride along as _pix_x, _pix_y (x, y, z are the bump units')
        v = {"tri": frag.tri, "_pix_x": frag.x, "_pix_y": frag.y, **const}
        v.update({name: frag[f"v{k}"] for k, (name, _) in enumerate(self.channels)})
        uni = {f.name: getattr(self, f"u_{f.name}") for f in self.uniforms}
        lights = range(q["lights"])
        for name, params, _ in self.parts()[1:]:
            with p.part(name):
                if name == "texture":
                    v = fetch(p, v, "s", "t", **params)
                elif name == "fenney_polar":
                    lanes = [tuple(f"{t}{k}_{c}" for c in ("k1", "k2", "k3", "q"))
                             + (f"_i{t}{k}", None) for t, k in self.lanes]
                    v = polar_lanes(p, v, "_hi", "_lo", lanes, q["trig_bits"])   # S, R
                    for t, k in self.lanes:
                        # N.L (d) and N.H (s) as values: i / 255 by bit replication,
                        # (i << 6) | (i >> 2), within 2**-14 (s >> 4 is then the unit's X)
                        i = v.pop(f"_i{t}{k}")
                        v[f"{'d' if t == 'l' else 's'}{k}"] = \
                            Cat(i[2:8], i, Const(0, 2)).as_signed()
                elif name == "bump_polar":
                    top, ab = VALUE.frac_bits, ANGLE_BITS    # turns: the top fraction bits
                    ang = lambda key: v.pop(key)[top - ab:top]
                    theta_b, phi_b = v.pop("_hi"), v.pop("_lo")
                    v = p.stage(v, phi_n=ang("phin"), theta_n=ang("thetan"),
                                phi_b=(phi_b + ang("psi"))[:ab], theta_b=theta_b,
                                **{k: uni[k] for k in ("phi_l", "theta_l", "phi_h",
                                                       "theta_h")})
                    v = BumpPolar.spec(**params).datapath(p, v)
                    v.pop("dot_l"), v.pop("dot_h")
                    # diffuse (u16, 15 fraction bits) >> 1 is a value; specular >> 5 a power
                    v["d0"] = Cat(v.pop("diffuse")[1:], Const(0, 1)).as_signed()
                    v["p0"] = v.pop("specular")[5:]
                elif name == "texel_decode":
                    v["texel_x"], v["texel_z"] = v.pop("_hi"), v.pop("_lo")
                    v = TexelDecode.spec().datapath(p, v)
                    v.pop("invalid")         # decoded by the guard's rule (docs/bump.md)
                elif name == "fenney_dot":
                    # the interpolated vector as the patent's s8: round(127 v), clamped
                    conv = {}
                    for t, k in self.lanes:
                        for a in "xyz":
                            c = v.pop(f"{t}{k}{a}")
                            r = ((c << 7) - c + (1 << (VALUE.frac_bits - 1))) >> VALUE.frac_bits
                            conv[f"_{t}{k}{a}"] = Mux(r > 127, 127, Mux(r < -127, -127, r))[:8]\
                                .as_signed()
                    v = p.stage(v, **conv)
                    lanes = [tuple(f"_{t}{k}{a}" for a in "xyz") + (f"_h{t}{k}", f"_x{t}{k}")
                             for t, k in self.lanes]
                    v.update({f"_h{t}{k}": Const(255, 8) for t, k in self.lanes})   # h = 1
                    v = dot_lanes(p, v, "x", "y", "z", lanes, **self.dot_params)
                    for t, k in self.lanes:     # X / 1024 as a value: X << 4
                        v[f"{'d' if t == 'l' else 's'}{k}"] = \
                            Cat(Const(0, 4), v.pop(f"_x{t}{k}"), Const(0, 2)).as_signed()
                elif name == "phong":
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
        v["x"], v["y"] = v.pop("_pix_x"), v.pop("_pix_y")
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

