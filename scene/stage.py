"""A scene stage: one object that says everything about one step of a scene's pipeline.

A stage subclasses :class:`Stage`, whose hooks come in groups, one class each, by role:

====================  =====================================  ==============================
group                 required                               optional
====================  =====================================  ==============================
:class:`Choosing`     ``name``                               ``when``/``wanted``, ``gives``,
                                                             ``defers``, ``before``,
                                                             ``interpolates``, ``why``
:class:`SceneKeys`                                           ``scene_keys``,
                                                             ``check_scene``, ``scene_params``
:class:`DriverData`                                          ``prepare``, ``vertex_values``,
                                                             ``triangle_values``,
                                                             ``flat_values``, ``memory_image``,
                                                             ``uniform_values``,
                                                             ``table_values``
:class:`Hardware`     ``latency``, ``rtl`` (or ``build``)    ``channels``, ``channel_bits``,
                                                             ``flat``, ``uniforms``,
                                                             ``tables``, ``params``,
                                                             ``build_params``, ``ports``
:class:`Models`       ``model``, ``ideal``                   ``format_group``, ``convert``,
                                                             ``bounds``, ``candidates``,
                                                             ``interval``, ``slack``
:class:`BumpHooks`                                           ``bump``, ``lanes``, ``label``
:class:`Tools`                                               ``sweeps``, ``describe``
====================  =====================================  ==============================

A stage joins the pipeline by ``scene.registry.register`` (or its entry point, or
``SHADING_STAGES``), which checks the required hooks and names the one missing.

:class:`StageUnit` makes a stage a component with ``i`` and ``o`` streams, so the composed top
joins stages with ``wiring.connect``. Inside a stage the units share one enable (the
:class:`hdl.unit.Pipeline`), which is cheap; between stages the handshake is the stream's.
"""
from dataclasses import dataclass, field

import numpy as np
from amaranth.hdl import Const, Module, Shape, Signal, Value
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from hdl.fixed import layout
from hdl.setup_unit.formats import VALUE
from hdl.shade_unit.formats import POWER
from hdl.unit import Pipeline

from . import host as hostport

__all__ = ["Stage", "Choosing", "SceneKeys", "DriverData", "Hardware", "Models",
           "BumpHooks", "Tools", "StageUnit", "StageError", "Sweep", "Link", "SceneError", "convert_powers", "lanes", "lane_key",
           "raw"]


class SceneError(ValueError):
    """A scene file that cannot be rendered: the message names the key."""


class StageError(ValueError):
    """A stage that cannot join the pipeline: the message names the stage and the hook."""


@dataclass(frozen=True)
class Sweep:
    """A row of ``make tradeoffs`` that a stage asks for: a knob at one setting, the rest at
    their defaults, and what is built and measured for it."""
    knob: str
    setting: str
    unit: str = None           # the unit synthesised (``build = "unit"``) and tested alone
    params: dict = field(default_factory=dict)      # its parameters
    scene: str = None          # scenes/<scene>.toml rendered: accuracy and cycles
    hardware: dict = field(default_factory=dict)    # the scene pipeline's parameters set
    build: str = "unit"        # what is synthesised: the unit, the scene's "raster" or its
    #                            whole "pipeline"
    rows: object = False       # the unit's golden rows run against its exact function (an
    #                            int; None: its own sweep; False: not run)
    default: bool = False
    quick: bool = False        # in ``make tradeoffs --quick`` (no raster: a few minutes)

    def __post_init__(self):
        if self.build not in ("unit", "raster", "pipeline"):
            raise ValueError(f"Sweep.build: unit, raster or pipeline, not {self.build!r}")
        if self.build != "unit" and not self.scene:
            raise ValueError(f"Sweep {self.knob} {self.setting}: build = {self.build!r} "
                             f"needs a scene")


class Choosing:
    """Whether a scene calls for the stage, what it gives and where it goes.

    - ``name`` (required): its submodule's name in the composed top, and its unit's in
      ``metrics.json``;
    - ``when``: the pipeline parameters' values that call for it (all of them; ``{}``: every
      scene), or ``wanted(q)``. A value of ``method``, ``power`` or ``bump`` named here is a
      new choice of that scene key (``scene.registry``);
    - ``gives``: kinds of value only one stage gives (``"lighting"``: N.L and N.H, which the
      raster then does not interpolate; ``"powers"``), and ``defers``: it is left out where
      a stage before it gives them;
    - ``interpolates``: a shading method's stage that lets the raster interpolate N.L and
      N.H says in which of the raster's modes (``hdl.setup_unit.formats.MODES``);
    - ``before``: the name of the stage it goes before (None: after the last);
    - ``why``: the scene key that calls for it, for ``metrics.json``."""
    name = None
    why = ""
    when = {}
    gives = ()
    defers = False
    before = None
    interpolates = None

    @classmethod
    def wanted(cls, q):
        """Whether a scene (the pipeline's parameters ``q``) calls for the stage."""
        return all(q[k] == v for k, v in cls.when.items())

    def validate(self, q):
        """Checks on the scene beyond the parameters' ranges, raising ``ValueError`` that
        names the scene key."""


class SceneKeys:
    """Its own keys of the scene file (``scene/parse.py``)."""
    scene_keys = {}        # {table: {key: (default, rule)}}: a table of its own or keys in
    #                        a shared one, with the rules of scene/parse.py

    @classmethod
    def check_scene(cls, scene):
        """Checks of its scene keys on every scene, wanted or not (a key set for nothing)."""

    @classmethod
    def scene_params(cls, scene):
        """The build parameters its scene keys set."""
        return {}


class DriverData:
    """Its data for a scene (``scene/prepare.py``, which never names a stage)."""

    def prepare(self, scene, view, data):
        """Its data (encodings, per-triangle constants), given the view (``scene.prepare
        .view``) and the data of the stages before it; it may set a size the data decides in
        ``self.q``; ``prep["data"]`` holds them all for its models."""
        return {}

    def vertex_values(self, data):
        """Its channels' values at the drawn triangles' vertices, ``{name: (n, 3)}``."""
        return {}

    def triangle_values(self, data):
        """Raster inputs of its own per triangle (edge constants), raw and unrounded."""
        return {}, {}

    def flat_values(self, data):
        """Its flat words, ``{name: (n,)}``."""
        return {}

    def memory_image(self, data):
        """The texture memory's words, where it has a texture."""
        return None

    def uniform_values(self, scene, L, H):
        """Its registers' raw values for a scene (``L``, ``H``: each light's unit vectors,
        world frame)."""
        return {}

    def table_values(self, scene):
        """The loaded tables' contents for a scene: ``{key: raw integers}``."""
        return {}


class Hardware:
    """Its RTL.

    - ``latency`` (required): its register stages, from its units;
    - ``rtl(p, v, uni)`` (required, or ``build``): its stages on the
      :class:`hdl.unit.Pipeline` ``p``, from the values ``v`` of the stage before it (named
      as the stages name them) and its uniforms ``uni``; returns the values after it;
    - ``build``: instead of ``rtl``, for a stage whose latency varies (a memory read), with
      handshakes of its own, and ``ports``: the streams it adds to the top;
    - ``channels``: the raster channels it reads, ``(name, mode, group)``, each mode one of
      the raster's; ``channel_bits``: the fraction bits it needs of some (``{name: bits}``;
      the rest keep VALUE's 14); ``flat``: the flat words (a triangle's constants) it reads;
    - ``uniforms``: the registers it reads (the host writes them: ``scene/host.py``);
      ``tables``: the RAMs the host loads (``{key: lut}``; ``texture``: the on-chip texture);
    - ``params``: its unit's parameters; ``build_params``: the pipeline's parameters it owns,
      ``{name: (default, range)}`` (a range as ``hdl.unit``'s ``RANGES``; None for a bool)."""
    channels = ()
    channel_bits = {}
    flat = ()
    uniforms = ()
    tables = {}
    params = {}
    build_params = {}
    ports = {}             # name: (In or Out, fields): streams of the stage's own

    # the raster's mode for the lighting's channels (N.L, N.H, or a bump method's L' and H')
    # under the scene's shading method: the method's own (``scene.registry.methods``: the
    # raster's modes, or a method stage's ``interpolates``), never its name; set by
    # ``scene.pipeline.choose``
    lighting_mode = None

    @property
    def latency(self):
        raise NotImplementedError

    def rtl(self, p, v, uni):
        raise NotImplementedError

    def build(self, m, i, o, v, uni, ports, host, platform=None):
        """The stage's logic between the handshakes ``i`` and ``o`` (``Link``s); returns
        ``(values, busy)``. By default its ``rtl`` on one shared-enable pipeline, whose
        stages must be its ``latency``, its tables loaded from ``host``, its products in the
        form of ``platform`` (``hdl.dsp.Product``)."""
        p = Pipeline(m, i, o)
        p.host, p.platform = host, platform
        v = self.rtl(p, v, uni)
        if p.stages != self.latency:
            raise AssertionError(f"stage {self.name} has {p.stages} stages, its latency says "
                                 f"{self.latency}")
        m.d.comb += o.valid.eq(p.valid)
        busy = Const(0)
        for valid in p.valids:
            busy = busy | valid
        return v, busy


class Models:
    """The same step in the models, and how far the RTL may be from them.

    - ``model(prep, frag, ch, bound)`` (required): with the RTL's formats, on numpy arrays per
      fragment; ``bound``: the tests' offsets, each stage takes the ones it knows;
    - ``ideal(prep, frag, ch)`` (required): its algorithm on reals (``ideal.png``);
      ``format_group``: its group of formats (``scene.models.ideal``); ``convert``: the values
      it gives, from its model's formats to its ideal's reals or back;
    - ``bounds``, ``candidates``, ``interval``, ``slack``: how far the RTL may be from its
      model (the tests' and ``make fuzz``'s checks, ``scene.models.within``)."""
    format_group = "power"
    slack = 0              # levels the RTL may be from the nearest of its candidates

    def model(self, prep, frag, ch, bound):
        raise NotImplementedError

    def ideal(self, prep, frag, ch):
        """The stage's algorithm in float64 with no format: exact functions for its tables,
        no rounding or saturation (``scene.models.ideal``); values by name, reals."""
        raise NotImplementedError(f"{self.name}: no ideal model")

    def convert(self, ch, ideal):
        """The values it gives, its model's formats to reals (``ideal``) or back."""
        return ch

    def bounds(self, prep, ch):
        """Per value it gives and fragment, how far (VALUE LSBs) the RTL may be from its
        model; none: exact."""
        return {}

    def candidates(self, prep, frag, ch):
        """Where its bound is wider than a level of the model's colour: every colour the RTL
        may give, ``(choices, n, 3)``, each within ``slack`` levels (``scene.models
        .candidates``). None: the model's colour, within a level."""
        return None

    def interval(self, prep, frag, ch, before):
        """Where the colour is monotone in the values it gives, and its bound is offsets of
        its inputs: the least and largest of each value per fragment, ``({key: lo}, {key:
        hi})`` (``scene.models.within``); None: no such bound. ``before(**offsets)``: the
        stages before it on ``ch``, their models with the offsets (the texture's ``ds``,
        ``dt``), the values as it takes them."""
        return None


class BumpHooks:
    """Only for the bump stages (texel fetch to N.L and N.H)."""
    bump = False

    @property
    def lanes(self):
        """The bump stages' lanes: ``(vector, light)``, L per light and, with specular, H."""
        return lanes(self.q)

    @property
    def label(self):
        """A few words on its form for the gallery (the last bump stage's names a bump
        pipeline there), or None."""
        return None


class Tools:
    """What the tools ask of it."""

    @classmethod
    def sweeps(cls):
        """Its rows of ``make tradeoffs``: :class:`Sweep` each."""
        return ()

    def describe(self):
        """The stage in ``metrics.json``: its unit, why, its parameters and latency."""
        return {"name": self.name, "why": self.why, "params": self.params,
                "latency": self.latency}


class Stage(Choosing, SceneKeys, DriverData, Hardware, Models, BumpHooks, Tools):
    """A stage of a scene's pipeline, made for the pipeline's parameters ``q``."""
    # the hooks a stage must give, each a tuple of alternatives (scene.registry checks them)
    REQUIRED = (("latency",), ("rtl", "build"), ("model",), ("ideal",))

    def __init__(self, q):
        self.q = q


class Link:
    """A handshake inside a stage's pipeline, joined to its ports when it is elaborated."""

    def __init__(self):
        self.valid, self.ready = Signal(), Signal()


class StageUnit(wiring.Component):
    """A stage as a component: ``i`` (the layout ``layout_in``, its fields renamed by
    ``rename`` on the way in: the raster's ``v<k>`` are the channels' names) and ``o`` (the
    values the stage gives; where it is the last one, ``out_fields`` in their order, each
    from the value ``source`` names), a port ``u_<name>`` per uniform (the top's register) and,
    for a stage with loaded tables, the host's registered write ``w_en``, ``w_addr``,
    ``w_data`` (``scene/host.py``; ``bases``: each table's address). The datapath is built
    here, so the output layout is known; ``elaborate`` joins it to the ports.
    ``busy``: data in the stage."""

    def __init__(self, stage, layout_in, out_fields=None, rename=None, source=None,
                 bases=None, platform=None):
        self.stage = stage
        self.rename = rename or {}
        self._m = m = Module()
        self._in = {name: Signal(f.shape, name=f"i_{name}") for name, f in layout_in}
        self._uni = {f.name: Signal(f.fmt.shape, name=f"u_{f.name}") for f in stage.uniforms}
        self._w = hostport.write_signals() if stage.tables else ()
        buses = {}
        if self._w:
            buses = hostport.table_buses(*self._w, {k: b for k, b in (bases or {}).items()})
            if "texture" in stage.tables:
                buses["texture"] = hostport.texture_bus(*self._w)
        self._li, self._lo = Link(), Link()
        self._ports = {name: (stream.Signature(layout(fields)) if d is Out else
                              stream.Signature(layout(fields)).flip()).create(path=(name,))
                       for name, (d, fields) in stage.ports.items()}
        v, self.busy = stage.build(m, self._li, self._lo,
                                   {(rename or {}).get(k, k): x for k, x in self._in.items()},
                                   self._uni, self._ports, buses, platform)
        if out_fields is not None:
            source = source or {}
            v = {f.name: Value.cast(v[source.get(f.name, f.name)]) for f in out_fields}
            v = {f.name: x[:f.fmt.width].as_signed() if f.fmt.signed else x[:f.fmt.width]
                 for f, x in zip(out_fields, v.values())}
        self._out = {k: Value.cast(x) for k, x in v.items()}
        layout_out = data.StructLayout({k: Shape.cast(x.shape()) for k, x in self._out.items()})
        super().__init__({"i": In(stream.Signature(layout_in)),
                          "o": Out(stream.Signature(layout_out)),
                          **{f"u_{k}": In(s.shape()) for k, s in self._uni.items()},
                          **{s.name: In(s.shape()) for s in self._w},
                          **{name: d(stream.Signature(layout(fields)))
                             for name, (d, fields) in stage.ports.items()}})

    def elaborate(self, platform):
        m = self._m
        m.d.comb += [self._li.valid.eq(self.i.valid), self.i.ready.eq(self._li.ready),
                     self.o.valid.eq(self._lo.valid), self._lo.ready.eq(self.o.ready)]
        for name, inner in self._ports.items():
            wiring.connect(m, wiring.flipped(getattr(self, name)), inner)
        m.d.comb += [s.eq(self.i.payload[k]) for k, s in self._in.items()]
        m.d.comb += [self.o.payload[k].eq(x) for k, x in self._out.items()]
        m.d.comb += [s.eq(getattr(self, f"u_{k}")) for k, s in self._uni.items()]
        m.d.comb += [s.eq(getattr(self, s.name)) for s in self._w]
        return m


def raw(x, fmt=VALUE):
    """A real value as a format's raw integer (a channel's: ``VALUE``), rounded, saturated."""
    return np.clip(np.rint(np.asarray(x) * 2.0 ** fmt.frac_bits), fmt.min,
                   fmt.max).astype(np.int64)


def convert_powers(ch, ideal):
    """A stage's powers ``p<k>``: POWER LSBs to reals (``ideal``) or back."""
    ch = dict(ch)
    for k in [k for k in ch if k[0] == "p" and k[1:].isdigit()]:
        ch[k] = ch[k] * POWER.lsb if ideal else np.rint(ch[k] / POWER.lsb).astype(np.int64)
    return ch


def lanes(q):
    """A bump stage's lanes: ``(vector, light)``, L per light and, with specular, H."""
    return [(t, k) for k in range(q["lights"]) for t in ("l", "h") if q["specular"] or t == "l"]


def lane_key(t, k):
    """The value a lane gives: d (N.L) for an L lane, s (N.H) for an H lane."""
    return f"{'d' if t == 'l' else 's'}{k}"
