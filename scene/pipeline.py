"""A scene's pipeline: the stages the scene calls for, in order, each a component joined to the
next by an ``amaranth.lib.stream`` (``wiring.connect``).

    triangles -> raster -> [texture -> texel_decode -> fenney_dot]   a bump method's
                           [texture -> fenney_polar]                  stages, each wanted
                           [texture -> bump_polar]                    for its ``when``
                           [phong]                                    a shading method's
                        -> [power_table | fenney_power]               specular (and no
                                                                      stage gives powers)
                        -> colour -> fragments (tri, x, y, depth, r, g, b)

The registered stages (``scene.registry``: the project's own in ``scene/stages/``, one file
each, and any registered from outside; README "Adding an effect or a method") are the one
place where the stages are chosen: each says itself whether a scene wants it. The raster's
channels are the ones its stages read, in the order of the list, depth first; its flat words
are theirs too. A scene's data is written at run time through the host port, rows of the
input stream beside the triangles (``scene/host.py``): lights, material colours and the
concentration into registers, the power tables and the on-chip texture into RAMs. So the
hardware depends only on the effects and the sizes, never on the data. The depth test and
the framebuffer are not here: they model
external memory (a 256 x 256 frame with depth is 2.6 Mbit, more than the 1 Mbit of block RAM
of an ECP5-25F), and the renderer keeps them.
"""
from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import Out

from hdl.fixed import Field
from hdl.setup_unit.formats import VALUE
from hdl.shade_unit.formats import LEVEL, RGB
from hdl.span_unit import Raster as RasterUnit
from hdl.unit import Unit, skid
from hdl.units import PIPELINES

from . import host, registry
from .registry import register, registered, stages, unregister
from .stage import StageUnit

__all__ = ["ScenePipeline", "register", "registered", "unregister", "stages", "wanted",
           "choose", "units_in"]

MAX_CHANNELS = RasterUnit.RANGES["channels"][1]
SOURCE = {"x": "_pix_x", "y": "_pix_y"}          # the fragment's pixel, as the stages carry it


class _FromStages:
    """A class attribute computed from the registered stages each time it is read, so a stage
    registered after import is seen (``scene.registry``)."""

    def __init__(self, fn):
        self.fn = fn

    def __get__(self, obj, owner=None):
        return self.fn()


def _params():
    own = registry.build_params()
    return {"screen_bits": 8, "sub_bits": 4, "lights": 1, "specular": True,
            **{k: v[0] for k, v in registry.choices().items()},
            **{k: d for k, (d, _) in own.items()}}


def _ranges():
    own = registry.build_params()
    return {"screen_bits": (4, 10), "sub_bits": (1, 8), "lights": (1, 4), **registry.choices(),
            **{k: r for k, (_, r) in own.items() if r is not None}}


class ScenePipeline(Unit):
    NAME = "scene"
    DOC = "A scene's pipeline: raster -> (bump stages) -> (phong) -> (power) -> colour"
    # Its parameters are the effects and the sizes; a scene's data (lights, material, tables,
    # the bump map) is loaded through the host port, so two scenes that differ only in their
    # data share one Verilog and one model. Beside the sizes and the choices, each stage's
    # own parameters, all read from the registered stages when asked.
    PARAMS = _FromStages(_params)
    RANGES = _FromStages(_ranges)

    def validate(self, **q):
        self.stages = choose(q)
        self.stream_ports = {name: port for s in self.stages for name, port in s.ports.items()}
        # held: a bit per stage (the raster's first), set while it holds data; a hang's
        # message names the stages that held it. loading: clocks with a write at the head
        self.status_ports = {"busy": Out(1), "culled": Out(32), "held": Out(len(self.stages)),
                             "loading": Out(32)}
        self.table_bases = {(s.name, key): base
                            for base, s, key, _ in host.tables(self.stages)}

    @property
    def raster(self):
        return self.stages[0]

    @property
    def channels(self):
        """The raster's channels: ``(name, mode)``, depth first."""
        return [(n, m) for n, m, _ in self.raster.all_channels]

    def parts(self):
        """The stages built: ``(name, params, why)``."""
        return [(s.name, s.params, s.why) for s in self.stages]

    def part_latency(self, name, params=None):
        return next(s.latency for s in self.stages if s.name == name)

    @property
    def inputs(self):
        """A triangle's fields and a write's (``scene/host.py``), one row."""
        return list(self.raster.unit.inputs) + list(host.FIELDS)

    uniforms = ()          # no ports: the stages' uniforms are registers behind the host port

    @property
    def registers(self):
        """The registers the host writes, in address order: every stage's uniforms."""
        seen, out = set(), []
        for stage in self.stages:
            out += [f for f in stage.uniforms if f.name not in seen]
            seen |= {f.name for f in stage.uniforms}
        return out

    @property
    def outputs(self):
        frag = self.raster.unit.outputs
        return ([f for f in frag if f.name in ("tri", "x", "y")] + [Field("depth", VALUE)]
                + [Field(c, LEVEL) for c in RGB])

    @property
    def shading_latency(self):
        """The shading stages' own, and a clock for each register slice between two."""
        rest = self.stages[1:]
        return sum(s.latency for s in rest) + max(len(rest) - 1, 0)

    @property
    def latency(self):
        """From a triangle in to its first fragment out, when nothing waits."""
        return self.raster.latency + self.shading_latency

    def stage_units(self, layout, platform=None):
        """The shading stages as components, in order, each made for the layout the one before
        it gives (``layout``: the raster's fragment), the last giving the fragment's fields:
        ``[(stage, StageUnit)]``."""
        out, rename, rest = [], self.raster.rename(), self.stages[1:]
        for stage in rest:
            unit = StageUnit(stage, layout, self.outputs if stage is rest[-1] else None,
                             rename, source=SOURCE,
                             bases={key: base for (name, key), base in self.table_bases.items()
                                    if name == stage.name}, platform=platform)
            out.append((stage, unit))
            layout, rename = unit.o.payload.shape(), None
        return out

    def elaborate(self, platform):
        m = Module()
        m.submodules.raster = raster = RasterUnit(**self.raster.params)
        # the host port (scene/host.py): a write waits at the head until the pipeline is
        # empty, then is registered; triangles go on to the raster
        drained, write = Signal(init=1), self.i.payload.cmd    # empty at reset
        m.d.comb += [raster.i.valid.eq(self.i.valid & ~write),
                     self.i.ready.eq(Mux(write, drained, raster.i.ready))]
        m.d.comb += [raster.i.payload[f.name].eq(self.i.payload[f.name])
                     for f in raster.inputs]
        w = w_en, w_addr, w_data = host.write_signals()
        m.d.sync += [w_en.eq(self.i.valid & write & drained), w_addr.eq(self.i.payload.addr),
                     w_data.eq(self.i.payload.data)]
        with m.If(self.i.valid & write):
            m.d.sync += self.loading.eq(self.loading + 1)
        regs = {}
        for k, f in enumerate(self.registers):
            regs[f.name] = reg = Signal(f.fmt.shape, name=f"r_{f.name}")
            with m.If(w_en & host.equals(w_addr, host.REGISTERS + k)):
                m.d.sync += reg.eq(w_data[:f.fmt.width])
        last, busy = raster.o, raster.busy
        held = [raster.busy]
        for k, (stage, unit) in enumerate(self.stage_units(raster.o.payload.shape(), platform)):
            m.submodules[stage.name] = unit
            if k:                # between two stages: a register slice (hdl.unit.skid)
                full = skid(m, f"skid_{stage.name}", last, unit.i)
                busy, held[-1] = busy | full, held[-1] | full
            else:                # the raster's output is a register beside a skid buffer
                wiring.connect(m, last, unit.i)
            m.d.comb += [getattr(unit, f"u_{f.name}").eq(regs[f.name]) for f in stage.uniforms]
            if stage.tables:
                m.d.comb += [getattr(unit, s.name).eq(s) for s in w]
            for name in stage.ports:                    # the memory port, the top's own
                wiring.connect(m, wiring.flipped(getattr(self, name)), getattr(unit, name))
            busy = busy | unit.busy
            held.append(unit.busy)
            last = unit.o
        wiring.connect(m, last, wiring.flipped(self.o))
        # ``drained`` a register: nothing in flight a clock ago and no triangle taken then
        # (a write at the head lets none pass, so it stays true). The OR of every stage's
        # busy bit, from across the chip, then never reaches the input's ready in the same
        # clock (placed, that path set the default pipeline's clock at 122.8 MHz)
        m.d.sync += drained.eq(~busy & ~(raster.i.valid & raster.i.ready))
        m.d.comb += [self.busy.eq(busy | w_en),
                     self.culled.eq(raster.culled), self.held.eq(Cat(*held))]
        return m


PIPELINES[ScenePipeline.NAME] = ScenePipeline


def wanted(q):
    """The stages that the pipeline's parameters ``q`` call for, as they are, unchecked. A
    stage that steps aside (``defers``) where a stage before it gives the same values is left
    out: bump_polar gives the powers from its own table, so no power stage follows it."""
    out, given = [], set()
    for cls in stages():
        if cls.wanted(q) and not (cls.defers and set(cls.gives) <= given):
            out.append(cls(q))
            given |= set(cls.gives)
    return out


def choose(q):
    """The stages that the pipeline's parameters ``q`` call for, each validated, the raster
    joined to the channels and flat words they read. A ``ValueError`` names the scene key."""
    stages = wanted(q)
    raster = stages[0]
    raster.given = {g for stage in stages[1:] for g in stage.gives}
    mode = registry.methods().get(q["method"])
    for stage in stages:
        stage.lighting_mode = mode
    for stage in stages:
        stage.validate(q)
    channels = [c for stage in stages for c in stage.channels]
    if len(channels) > MAX_CHANNELS:
        raise ValueError(f"lights: {q['lights']} lights need {len(channels)} raster channels "
                         f"({', '.join(n for n, _, _ in channels)}); the raster has at most "
                         f"{MAX_CHANNELS}")
    bits = {n: b for stage in stages for n, b in stage.channel_bits.items()}
    stages[0].join(channels, [w for stage in stages for w in stage.flat], bits)
    return stages


def units_in(design):
    """The names of the stages in an elaborated scene pipeline (its submodules')."""
    from amaranth.hdl import Fragment
    frag = Fragment.get(design, None)
    return sorted(name for _, name, *_ in frag.subfragments)
