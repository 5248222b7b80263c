"""The raster stage (seeds 000-002): triangles in, fragments out, with the channels the later
stages read and their flat words. Its unit is ``hdl.span_unit.Raster``; the composed top
instantiates it and names its outputs for the stages after it (``rename``)."""
import numpy as np

from golden import raster as raster_model
from hdl.setup_unit.formats import MODES, VALUE
from hdl.shade_unit.formats import light_fields
from hdl.span_unit import Raster as RasterUnit
from hdl.span_unit.plan import KNOBS, RANGES, RECIPS, Channel, RasterPlan

from ..stage import Stage


class Raster(Stage):
    name = "raster"
    format_group = "raster"

    methods = MODES       # its own shading methods: N.L and N.H interpolated in that mode
    given = ()            # what the stages after it give (``scene.pipeline.choose``)
    build_params = {"recip": (RECIPS[0], RECIPS),
                    "recip_iters": (2, RANGES["recip_iters"]),
                    **{k: (d, r) for k, (d, r, _) in KNOBS.items()}}   # the plan's knobs

    @property
    def channels(self):
        """Its own: depth, and N.L and N.H per light interpolated in the mode the shading
        method's stage chooses (seed 001; the raster's own methods: their mode), unless a
        stage after it gives the lighting (a bump method, phong's normal)."""
        q = self.q
        own = [("depth", "linear", 0)]
        if "lighting" not in self.given:
            own += [(f.name, self.lighting_mode, 0)
                    for f in light_fields(q["lights"], q["specular"], "d", "s")]
        return own

    def join(self, channels, flat, bits=None):
        """The channels of every stage (``(name, mode, group)``, this one's first), their
        flat words and the fraction bits some of them need (``{name: bits}``, the rest 14):
        the raster's parameters."""
        q = self.q
        self.all_channels, self.flat_names = channels, flat
        # the raster's plan, checked here (a knob's setting), not at build; its parameters
        # leave out the defaults, so that the Verilog's name does not change with a knob's
        self.plan = RasterPlan(
            q["screen_bits"], q["sub_bits"],
            tuple(Channel(m, g, (bits or {}).get(n, VALUE.frac_bits)) for n, m, g in channels),
            q["recip"], q["recip_iters"], len(flat), **{k: q[k] for k in KNOBS})
        self.params = self.plan.params(defaults=False)
        names = [n for n, _, _ in channels]
        self.why = (f"shading.method = {q['method']}" if q["bump"] == "none" else
                    f"bump.method = {q['bump']}") + f": channels {', '.join(names)}" + \
            (f"; {len(flat)} flat word(s)" if flat else "")
        return self

    @property
    def unit(self):
        return RasterUnit.spec(**self.params)

    @property
    def latency(self):
        return self.unit.latency

    def rename(self):
        """The fragment's fields as the stages name them: the pixel's coordinates ride along
        as ``_pix_x``, ``_pix_y`` (x, y, z are texel_decode's)."""
        out = {"x": "_pix_x", "y": "_pix_y"}
        out.update({f"v{k}": name for k, (name, _, _) in enumerate(self.all_channels)})
        out.update({f"f{k}": name for k, name in enumerate(self.flat_names)})
        return out

    def model(self, prep, frag=None, ch=None, bound=None, real=None):
        """The raster's float model on the scene: its fragments, and the values by name (the
        channels, reals; the flat words, integers). ``real``: from the unrounded inputs."""
        frag = raster_model.run(prep["inputs"], **self.params, real=real)
        ch = {name: frag[f"v{k}"] for k, (name, _, _) in enumerate(self.all_channels)}
        bits = self.plan.precision
        for (name, _, _), p in zip(self.all_channels, bits):
            if real is None and p < VALUE.frac_bits:     # the RTL's format: p bits, rounded
                ch[name] = np.floor(ch[name] * 2.0 ** p + 0.5) / 2.0 ** p
        ch.update({name: np.asarray(frag[f"f{k}"]) for k, name in enumerate(self.flat_names)})
        return frag, ch

    def ideal(self, prep, frag=None, ch=None):
        """The same pixels, each channel's interpolation (linear, X-shading's or exact
        mid-edges) from the unrounded positions, vertex values and edge constants."""
        return self.model(prep, real=prep["real"])
