"""A scene stage: one object that says everything about one step of a scene's pipeline.

A stage subclasses :class:`Stage` and supplies

- ``when`` (the parameters' values that call for it), or ``wanted(q)``: whether a scene
  (the pipeline's parameters ``q``) calls for it; ``gives``: kinds of value only one stage
  gives (``"lighting"``, ``"powers"``), and ``defers``: it is left out where a stage before
  it gives them;
- ``name``: its submodule's name in the composed top, and its unit's in ``metrics.json``;
- ``channels``: the raster channels it reads, ``(name, mode, group)``; ``channel_bits``:
  the fraction bits it needs of some of them (``{name: bits}``; the rest keep VALUE's 14),
  the raster's ``precision``;
  ``flat``: the names of the flat words (a triangle's constants) it reads from the raster;
- ``uniforms``: the registers it reads (the host writes them: ``scene/host.py``), and
  ``uniform_values(scene, L, H)``: their raw values for a scene (``L``, ``H``: each light's
  unit vectors, world frame);
- ``tables``: the RAMs the host loads (``{key: lut}``, the lut giving depth and format; the
  key ``texture`` is the on-chip texture), and ``table_values(scene)``: their contents;
- ``params``: its unit's parameters, from the scene's; ``why``: the scene key that calls for it;
- ``build_params``: the pipeline's parameters it owns, ``{name: (default, range)}`` (a
  range as ``hdl.unit``'s ``RANGES``; None for a bool): ``scene.pipeline`` gathers them;
- ``sweeps()``: its rows of ``make tradeoffs`` (:class:`Sweep`), what accuracy costs in it;
- ``validate(q)``: its checks on the scene, raising ``ValueError`` that names the scene key;
- ``latency``: its register stages, from its units;
- ``rtl(p, v, uni)``: its stages on the :class:`hdl.unit.Pipeline` ``p``, from the values
  ``v`` of the stage before it (named as the stages name them); returns the values after it.
  A stage whose latency varies (a memory read) has ``build`` instead, with handshakes of its
  own, and ``ports``: the streams it adds to the top (its memory port); ``host``: the loaded
  tables' write buses (``hdl.lut.WriteBus``), by key;
- ``model(prep, frag, ch, bound)``: the same step in the float or integer model, on numpy
  arrays per fragment; ``bound``: the tests' offsets, each stage takes the ones it knows;
  ``candidates``, ``interval`` and ``bounds``: how far the RTL may be from it (the tests'
  and ``make fuzz``'s checks, ``scene.models.within``);
  ``ideal(prep, frag, ch)``: its algorithm on reals; ``format_group``: the group of formats
  it belongs to (``scene.models.ideal``); ``convert(ch, ideal)``: the values it gives, from
  its model's formats to its ideal's reals (or back), for the stage after it;

and, for the scene driver (``scene/prepare.py``), which never names a stage:

- ``scene_keys``: its own keys of the scene file, ``{table: {key: (default, rule)}}`` (the
  rules of ``scene/parse.py``), a table of its own or keys in a shared one;
- ``scene_params(scene)``: the build parameters its scene keys set, and
  ``check_scene(scene)``: its keys' checks on any scene (classmethods);
- ``prepare(scene, view, data)``: its data for a scene (encodings, per-triangle constants),
  given the view (``scene.prepare.view``) and the data of the stages before it; it may set
  a size the data decides in ``self.q``; ``prep["data"]`` holds them all for its models;
- ``vertex_values(data)``: its channels' values at the drawn triangles' vertices,
  ``{name: (n, 3)}``; ``triangle_values(data)``: raster inputs of its own per triangle (edge
  constants), raw and unrounded; ``flat_values(data)``: its flat words, ``{name: (n,)}``;
- ``memory_image(data)``: the texture memory's words, where it has a texture.

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

__all__ = ["Stage", "StageUnit", "Sweep", "Link", "SceneError", "convert_powers", "lanes", "lane_key",
           "raw"]


class SceneError(ValueError):
    """A scene file that cannot be rendered: the message names the key."""


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


class Stage:
    name = None
    bump = False           # a bump stage: texel fetch to N.L and N.H
    channels = ()
    channel_bits = {}
    flat = ()
    uniforms = ()
    params = {}
    build_params = {}
    why = ""
    scene_keys = {}
    gives = ()             # kinds of value it gives that one stage gives at most ("powers")
    defers = False         # left out where a stage before it gives the same

    def __init__(self, q):
        self.q = q

    when = {}              # the parameters' values that call for the stage (all of them)

    @classmethod
    def wanted(cls, q):
        """Whether a scene (the pipeline's parameters ``q``) calls for the stage."""
        return all(q[k] == v for k, v in cls.when.items())

    @property
    def lanes(self):
        """The bump stages' lanes: ``(vector, light)``, L per light and, with specular, H."""
        return lanes(self.q)

    def validate(self, q):
        """Checks on the scene beyond the parameters' ranges."""

    def uniform_values(self, scene, L, H):
        return {}

    tables = {}            # key: lut (its shape): the RAMs the host loads

    def table_values(self, scene):
        """The loaded tables' contents for a scene: ``{key: raw integers}``."""
        return {}

    @property
    def latency(self):
        raise NotImplementedError

    ports = {}             # name: (In or Out, fields): streams of the stage's own

    def rtl(self, p, v, uni):
        raise NotImplementedError

    def ideal(self, prep, frag, ch):
        """The stage's algorithm in float64 with no format: exact functions for its tables,
        no rounding or saturation (``scene.models.ideal``); values by name, reals."""
        raise NotImplementedError(f"{self.name}: no ideal model")

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

    def model(self, prep, frag, ch, bound):
        raise NotImplementedError

    format_group = "power"

    def convert(self, ch, ideal):
        """The values it gives, its model's formats to reals (``ideal``) or back."""
        return ch

    @classmethod
    def check_scene(cls, scene):
        """Checks of its scene keys on every scene, wanted or not (a key set for nothing)."""

    @classmethod
    def scene_params(cls, scene):
        return {}

    def prepare(self, scene, view, data):
        return {}

    def vertex_values(self, data):
        return {}

    def triangle_values(self, data):
        return {}, {}

    def flat_values(self, data):
        return {}

    def memory_image(self, data):
        return None

    slack = 0              # levels the RTL may be from the nearest of its candidates

    @property
    def label(self):
        """A few words on its form for the gallery (the last bump stage's names a bump
        pipeline there), or None."""
        return None

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

    def bounds(self, prep, ch):
        """Per value it gives and fragment, how far (VALUE LSBs) the RTL may be from its
        model; none: exact."""
        return {}

    @classmethod
    def sweeps(cls):
        """Its rows of ``make tradeoffs``: :class:`Sweep` each."""
        return ()

    def describe(self):
        """The stage in ``metrics.json``: its unit, why, its parameters and latency."""
        return {"name": self.name, "why": self.why, "params": self.params,
                "latency": self.latency}


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
