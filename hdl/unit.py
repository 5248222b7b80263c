# amaranth: UnusedElaboratable=no
"""The shape every unit has: ``i``/``o`` streams, a fully pipelined datapath, a ``latency``.

A unit subclasses :class:`Unit` and supplies

- ``NAME``, ``PARAMS`` (``{name: default}``), ``RANGES`` (``{name: (lo, hi)}`` for an
  integer, ``{name: ("a", "b")}`` for a choice; a float default takes a ``(lo, hi)`` range too;
  booleans need none), and the
  ``inputs``/``outputs`` field lists;
- ``latency``, the register stages from an accepted input to its output;
- ``datapath(p, v)``: given a :class:`Pipeline` and a dict of named values available at the
  current stage, add stages and return the dict at the last one.

The pipeline advances as a whole when its output is free (``en = ~o.valid | o.ready``), so one
item goes through per clock while ``o.ready`` is high, and under backpressure every stage holds:
nothing is lost, repeated or reordered. Composed units call their parts' ``datapath`` on one
pipeline; values a later stage needs ride along in the dict.
"""
from contextlib import contextmanager
import math
import operator

from amaranth.hdl import Module, Mux, Signal, Value
from amaranth.lib import stream, wiring
from amaranth.lib.wiring import In, Out

from .dsp import Product, mult18
from .fixed import layout
from .lut import RomRead, read_roms

__all__ = ["Pipeline", "Unit", "skid", "check_int", "check_bool", "check_float", "check_param",
           "param_range"]


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


def check_float(name, value, lo, hi):
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise TypeError(f"{name} must be a number, not {value!r}")
    if not (math.isfinite(value) and lo <= value <= hi):
        raise ValueError(f"{name} must be a finite number in {lo}..{hi}, not {value}")
    return float(value)


def check_param(name, value, default, allowed, per_channel=False):
    """One constructor parameter against its default's type and its ``RANGES`` entry."""
    if isinstance(default, bool):
        return check_bool(name, value)
    if isinstance(default, int):
        return check_int(name, value, *allowed)
    if isinstance(default, float):
        return check_float(name, value, *allowed)
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a string, not {value!r}")
    if allowed is None:                    # a free string (a file name, a map's name)
        return value
    parts = [v.strip() for v in value.split(",")] if per_channel else [value]
    for part in parts:
        if part not in allowed:
            each = " (one per channel)" if per_channel else ""
            raise ValueError(f"{name} must be one of {', '.join(map(repr, allowed))}{each}, "
                             f"not {part!r}")
    return value


def param_range(default, allowed, per_channel=False):
    """A parameter's range or choices, for ``sim units --json``."""
    if isinstance(default, bool):
        return {"choices": [False, True]}
    if isinstance(default, (int, float)):
        return {"min": allowed[0], "max": allowed[1]}
    if allowed is None:
        return {"string": ("one per channel, comma-separated" if per_channel else
                           "any string")}
    out = {"choices": list(allowed)}
    if per_channel:
        out["per_channel"] = "a comma-separated list, one per channel (one name applies to all)"
    return out


class _Pending:
    """A product (:class:`hdl.dsp.Product`) or a table read (:func:`hdl.lut.rom`) between its
    input and its output register."""

    def __init__(self, product):
        self.product = product


def skid(m, name, src, dst):
    """``src`` to ``dst`` (streams of one payload) through a register slice: ``dst.valid``
    and ``dst.payload`` are registers, and so is ``src.ready`` (a skid register of one item
    is empty), so a boundary between two stages is a clock with nothing combinational across
    it, neither the readies (which would otherwise ripple through every stage) nor the
    payload's multiplexer (its select a register, its output into one). One clock of latency;
    one item a clock. An item offered while the output is held goes into the skid register
    and out before anything newer. Returns the slice's busy bit (it holds an item)."""
    payload = Value.cast(src.payload)
    full = Signal(name=f"{name}_full")                  # the skid register holds an item
    held = Signal(len(payload), name=f"{name}_held", reset_less=True)
    valid = Signal(name=f"{name}_valid")                # the output register holds an item
    data = Signal(len(payload), name=f"{name}_data", reset_less=True)
    m.d.comb += [src.ready.eq(~full), dst.valid.eq(valid), dst.payload.eq(data)]
    with m.If(~valid | dst.ready):                      # the output register takes its next
        m.d.sync += [valid.eq(full | src.valid), full.eq(0),
                     data.eq(Mux(full, held, payload))]
    with m.Elif(src.valid & ~full):                     # held: the offered item into the skid
        m.d.sync += [full.eq(1), held.eq(payload)]
    return full | valid


class Pipeline:
    """Registers with one shared enable, and the ``valid`` bit that travels with them."""

    def __init__(self, m, i, o):
        self.m = m
        self.en = Signal()
        self.stages = 0
        self._valid = i.valid
        self.valids = []                   # every stage's valid bit: the pipeline is busy if any
        self.host = {}                     # the loaded tables' write buses (hdl.lut.rom's load)
        self.platform = None               # the FPGA flow's (hdl.dsp.Target): Product's form
        self._names = set()
        m.d.comb += [self.en.eq(~o.valid | o.ready), i.ready.eq(self.en)]

    def stage(self, v, **new):
        """Register every value of ``v`` and of ``new``; returns the dict of registers (the
        next stage). ``v`` is read after ``new`` is evaluated, so values a stage consumes can be
        popped from ``v`` in ``new``'s expressions and are not carried further."""
        self.stages += 1
        values = {**v, **new}
        # a table read's value is its output register: the next stage's (hdl.bram)
        out = {k: _Pending(q) for k, q in read_roms(
            self, {k: r for k, r in values.items() if isinstance(r, RomRead)}).items()}
        for name, value in values.items():
            if name in out:
                continue
            if isinstance(value, _Pending):        # a product's or a table's output register
                out[name] = value.product
                continue
            if isinstance(value, Product):         # its operands into the block's registers
                prod = mult18(self.m, self.unique(f"mul_{name}"), value.a, value.b, self.en,
                              self.platform)
                if not (value.a.shape().signed or value.b.shape().signed):
                    prod = prod[:len(value.a) + len(value.b)]       # unsigned: its own width
                out[name] = _Pending(prod)
                continue
            value = Value.cast(value)
            # data needs no reset (only the valid bits do): a DSP's or a block RAM's own
            # registers have none, so a reset would keep them out of it
            reg = Signal(value.shape(), name=f"s{self.stages}_{name}", reset_less=True)
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

    def finish(self, o, v, fields, stages, what):
        """Drive stream ``o`` from the last stage: its valid, and each of ``fields`` from
        ``v``; first check that the datapath has the ``stages`` its latency states."""
        if self.stages != stages:
            raise AssertionError(f"{what} has {self.stages} stages, its latency says {stages}")
        self.m.d.comb += o.valid.eq(self._valid)
        self.m.d.comb += [o.payload[f.name].eq(v[f.name]) for f in fields]

    @contextmanager
    def part(self, name):
        """Stages added inside go into a submodule ``name``, so a composed design keeps its
        units' names in its hierarchy (and in its Verilog)."""
        outer = self.m
        self.m = Module()
        outer.submodules[name] = self.m
        try:
            yield
        finally:
            self.m = outer


class Unit(wiring.Component):
    NAME = None
    PARAMS = {}
    RANGES = {}
    PER_CHANNEL = ()       # string parameters that list one choice per channel
    DOC = ""

    def __init__(self, **params):
        unknown = set(params) - set(self.PARAMS)
        self.params = {**self.PARAMS, **params}
        try:
            if unknown:
                raise TypeError(f"{self.NAME}: unknown parameter(s) "
                                f"{', '.join(sorted(unknown))}; "
                                f"known: {', '.join(self.PARAMS) or 'none'}")
            for name, default in self.PARAMS.items():
                check_param(name, self.params[name], default, self.RANGES.get(name),
                            name in self.PER_CHANNEL)
            self.validate(**self.params)
        except (TypeError, ValueError):      # never built, so never elaborated: made by
            raise                            # make_unit or spec, whose files say so (line 1)
        super().__init__({
            "i": In(stream.Signature(layout(self.inputs))),
            "o": Out(stream.Signature(layout(self.outputs))),
            **{f"u_{f.name}": In(f.fmt.shape) for f in self.uniforms},
            **self.status_ports,
            **{name: d(stream.Signature(layout(fields)))
               for name, (d, fields) in self.stream_ports.items()},
        })

    status_ports = {}   # extra outputs (a unit that emits many rows per input: busy, counters)
    # Streams beside ``i`` and ``o``: ``{name: (In or Out, fields)}`` (a memory port: its
    # requests out, its responses in)
    stream_ports = {}
    # Uniforms: inputs held for a whole run (a light's direction, a material's colour), the
    # registers a host writes before it streams triangles; ports ``u_<field>``.
    uniforms = ()

    @classmethod
    def spec(cls, **params):
        """An instance used for its formats, latency and datapath, never elaborated itself
        (the parts of a composed unit, the registry's descriptions)."""
        return cls(**params)      # never elaborated: this file's first line tells Amaranth

    def validate(self, **params):
        """Checks beyond ``RANGES`` (parameters that depend on each other); raise
        ``TypeError``/``ValueError`` naming the problem."""

    @classmethod
    def param_ranges(cls):
        return {name: param_range(default, cls.RANGES.get(name), name in cls.PER_CHANNEL)
                for name, default in cls.PARAMS.items()}

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
        p.platform = platform
        v = {f.name: self.i.payload[f.name] for f in self.inputs}
        v = self.datapath(p, v)
        p.finish(self.o, v, self.outputs, self.latency, f"{self.NAME}: datapath")
        return m


class NamedPorts(wiring.Component):
    """A unit with one port per field, for export: ``i_<field>`` and ``o_<field>`` beside
    ``i_valid``, ``i_ready``, ``o_valid`` and ``o_ready`` (and the unit's status ports), so a
    user wires it up without decoding a packed payload. The unit itself is the submodule
    ``core``."""

    def __init__(self, unit):
        self.unit = unit
        members = {"i_valid": In(1), "i_ready": Out(1)}
        members.update({f"i_{f.name}": In(f.fmt.shape) for f in unit.inputs})
        members.update({f"u_{f.name}": In(f.fmt.shape) for f in unit.uniforms})
        members.update({"o_valid": Out(1), "o_ready": In(1)})
        members.update({f"o_{f.name}": Out(f.fmt.shape) for f in unit.outputs})
        clash = set(members) & set(unit.status_ports)
        if clash:
            raise ValueError(f"{unit.NAME}: status port(s) {sorted(clash)} clash with fields")
        members.update(unit.status_ports)
        for name, (d, fields) in unit.stream_ports.items():    # name_valid, name_<field>...
            back = In if d is Out else Out
            members.update({f"{name}_valid": d(1), f"{name}_ready": back(1)})
            members.update({f"{name}_{f.name}": d(f.fmt.shape) for f in fields})
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        m.submodules.core = unit = self.unit
        m.d.comb += [unit.i.valid.eq(self.i_valid), self.i_ready.eq(unit.i.ready),
                     self.o_valid.eq(unit.o.valid), unit.o.ready.eq(self.o_ready)]
        m.d.comb += [unit.i.payload[f.name].eq(getattr(self, f"i_{f.name}"))
                     for f in unit.inputs]
        m.d.comb += [getattr(self, f"o_{f.name}").eq(unit.o.payload[f.name])
                     for f in unit.outputs]
        m.d.comb += [getattr(unit, f"u_{f.name}").eq(getattr(self, f"u_{f.name}"))
                     for f in unit.uniforms]
        m.d.comb += [getattr(self, name).eq(getattr(unit, name)) for name in unit.status_ports]
        for name, (d, fields) in unit.stream_ports.items():
            port = getattr(unit, name)
            pins = [(getattr(self, f"{name}_{f.name}"), port.payload[f.name]) for f in fields]
            pins.append((getattr(self, f"{name}_valid"), port.valid))
            ready = getattr(self, f"{name}_ready")
            if d is Out:                   # the unit's requests out, their ready in
                m.d.comb += [pin.eq(x) for pin, x in pins] + [port.ready.eq(ready)]
            else:                          # responses in, their ready out
                m.d.comb += [x.eq(pin) for pin, x in pins] + [ready.eq(port.ready)]
        return m
