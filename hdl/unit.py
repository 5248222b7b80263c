"""The shape every unit has: ``i``/``o`` streams, a fully pipelined datapath, a ``latency``.

A unit subclasses :class:`Unit` and supplies

- ``NAME``, ``PARAMS`` (``{name: default}``), and the ``inputs``/``outputs`` field lists;
- ``latency``, the register stages from an accepted input to its output;
- ``datapath(p, v)``: given a :class:`Pipeline` and a dict of named values available at the
  current stage, add stages and return the dict at the last one.

The pipeline advances as a whole when its output is free (``en = ~o.valid | o.ready``), so one
item goes through per clock while ``o.ready`` is high, and under backpressure every stage holds:
nothing is lost, repeated or reordered. Composed units call their parts' ``datapath`` on one
pipeline; values a later stage needs ride along in the dict.
"""
import operator

from amaranth.hdl import Module, Signal, Value
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from .fixed import layout

__all__ = ["Pipeline", "Unit", "check_int", "check_bool"]


def check_int(name, value, lo, hi):
    try:
        value = operator.index(value)
    except TypeError:
        raise TypeError(f"{name} must be an integer, not {value!r}") from None
    if not lo <= value <= hi:
        raise ValueError(f"{name} must be in {lo}..{hi}, not {value}")
    return value


def check_bool(name, value):
    if not isinstance(value, bool):
        raise TypeError(f"{name} must be True or False, not {value!r}")
    return value


class Pipeline:
    """Registers with one shared enable, and the ``valid`` bit that travels with them."""

    def __init__(self, m, i, o):
        self.m = m
        self.en = Signal()
        self.stages = 0
        self._valid = i.valid
        self.valids = []                   # every stage's valid bit: the pipeline is busy if any
        self._names = set()
        m.d.comb += [self.en.eq(~o.valid | o.ready), i.ready.eq(self.en)]

    def stage(self, v, **new):
        """Register every value of ``v`` and of ``new``; returns the dict of registers (the
        next stage). ``v`` is read after ``new`` is evaluated, so values a stage consumes can be
        popped from ``v`` in ``new``'s expressions and are not carried further."""
        self.stages += 1
        out = {}
        for name, value in {**v, **new}.items():
            value = Value.cast(value)
            reg = Signal(value.shape(), name=f"s{self.stages}_{name}")
            with self.m.If(self.en):
                self.m.d.sync += reg.eq(value)
            out[name] = reg
        valid = Signal(name=f"s{self.stages}_valid")
        with self.m.If(self.en):
            self.m.d.sync += valid.eq(self._valid)
        self._valid = valid
        self.valids.append(valid)
        return out

    def unique(self, name):
        """``name``, or ``name_2``, ``name_3``... if a part used it already (composed units)."""
        k, out = 1, name
        while out in self._names:
            k += 1
            out = f"{name}_{k}"
        self._names.add(out)
        return out

    @property
    def valid(self):
        return self._valid


class Unit(wiring.Component):
    NAME = None
    PARAMS = {}
    DOC = ""

    def __init__(self, **params):
        unknown = set(params) - set(self.PARAMS)
        self.params = {**self.PARAMS, **params}
        try:
            if unknown:
                raise TypeError(f"{self.NAME}: unknown parameter(s) "
                                f"{', '.join(sorted(unknown))}; "
                                f"known: {', '.join(self.PARAMS) or 'none'}")
            self.validate(**self.params)
        except (TypeError, ValueError):
            self._MustUse__silence = True      # never built, so never to be elaborated
            raise
        super().__init__({
            "i": In(stream.Signature(layout(self.inputs))),
            "o": Out(stream.Signature(layout(self.outputs))),
            **self.status_ports,
        })

    status_ports = {}   # extra outputs (a unit that emits many rows per input: busy, counters)

    @classmethod
    def spec(cls, **params):
        """An instance used for its formats, latency and datapath, never elaborated itself
        (the parts of a composed unit, the registry's descriptions)."""
        unit = cls(**params)
        unit._MustUse__used = True
        return unit

    def validate(self, **params):
        """Check constructor parameters; raise ``TypeError``/``ValueError`` naming the problem."""

    inputs = ()
    outputs = ()

    @property
    def latency(self):
        raise NotImplementedError

    def datapath(self, p, v):
        raise NotImplementedError

    def elaborate(self, platform):
        m = Module()
        p = Pipeline(m, self.i, self.o)
        v = {f.name: self.i.payload[f.name] for f in self.inputs}
        v = self.datapath(p, v)
        if p.stages != self.latency:
            raise AssertionError(f"{self.NAME}: datapath has {p.stages} stages, "
                                 f"latency says {self.latency}")
        m.d.comb += self.o.valid.eq(p.valid)
        for f in self.outputs:
            m.d.comb += self.o.payload[f.name].eq(v[f.name])
        return m
