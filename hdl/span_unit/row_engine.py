"""The row engine as a component (``span.plan_row_engine``: every channel a job, or one
channel a job with ``row_serial``), between the walker and the row queue.

In: rows, on the walker's row signature (a valid/ready handshake, a member per field), and
the row queue's credit (``space``). Out: the row queue's writes, a port per memory on the
queue's own signature (``en``, ``data``, and ``addr`` where the engine gives the slot);
``started``, a row's start (the credit it takes), and ``written``, a row's last write.
It never stalls: a row starts only when ``space`` promises it a place, and each write comes
at a fixed offset from its row's start. With the setup's channels in turn
(``setup_serial``), the channel-constant memory is read through ``consts_index`` and
``consts``.

The ports' shapes and the engine's clocks come from a build of the same schedule on its own
(``_form``), before the signature is stated.
"""
import functools
from types import SimpleNamespace

from amaranth.hdl import Fragment, Module, Signal, Value
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .span import plan_row_engine

__all__ = ["RowEngine", "const_fields", "row_fields"]


def row_fields(walker):
    """The walker's row fields, ``{name: shape}``: a row engine's input."""
    return {k: getattr(walker.o, k).shape() for k in walker.outputs}


def const_fields(setup):
    """The setup's channel-constant memory as a row engine reads it (``(fields, index
    bits)``), or None."""
    if not setup.const_fields:
        return None
    return dict(setup.const_fields), len(setup.consts_index)


class RowEngine(wiring.Component):
    """``plan``: the raster's plan; ``rows``: the walker's row fields (``{name: shape}``);
    ``flat``: the flat words' names; ``consts``: the channel-constant memory's fields
    (``{name: shape}``) and its index bits, or None; ``narrow``: the mantissa bits of the
    narrow engine (``span.row_engine``; its rows ``span.narrow_row_fields``), or None;
    ``registered=False``: the ``late`` writes a clock early, for the caller to register."""

    def __init__(self, plan, rows, flat=(), consts=None, narrow=None, registered=True):
        self.plan, self.rows, self.flat = plan, dict(rows), tuple(flat)
        self.const_fields, self.index_bits = consts or (None, 0)
        self.narrow, self.registered = narrow, registered
        form = _form(plan, tuple(self.rows.items()), self.flat,
                     consts and (tuple(consts[0].items()), consts[1]), narrow, registered)
        # its memories, its row interval and length, and its last write's offset from the start
        self.memories, self.ii, self.length, self.offset = form
        # the memories written at the slot the engine gives (the serial engine's): what a row
        # only carries as it starts, the rest at its last write
        self.offsets = {name: 0 if name == "early" else self.offset
                        for name, (_, slotted) in self.memories.items() if slotted}
        members = {"i": In(wiring.Signature({"valid": Out(1), "ready": In(1),
                                             **{k: Out(s) for k, s in self.rows.items()}})),
                   "space": In(1), "started": Out(1), "written": Out(1), "busy": Out(1)}
        for name, (fields, slotted) in self.memories.items():
            port = {"en": Out(1), "data": Out(data.StructLayout(fields))}
            if slotted:
                port["addr"] = Out(4)
            members[name] = Out(wiring.Signature(port))
        if self.const_fields:
            members["consts_index"] = Out(self.index_bits)
            members["consts"] = In(data.StructLayout(self.const_fields))
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        consts = ((self.consts_index, {k: self.consts[k] for k in self.const_fields},
                   self.index_bits) if self.const_fields else None)
        rows = {k: getattr(self.i, k) for k in self.rows}
        writes, started, written, t = plan_row_engine(m, self.plan, self.plan.setup.w, rows,
                                                      self.i, self.space, platform,
                                                      self.flat, consts, self.narrow,
                                                      self.registered)
        for name, vals, en, slot in writes:
            port = getattr(self, name)
            m.d.comb += [port.en.eq(en)] + [port.data[k].eq(x) for k, x in vals.items()]
            if slot is not None:
                m.d.comb += port.addr.eq(slot)
        m.d.comb += [self.started.eq(started), self.written.eq(written),
                     self.busy.eq(t["busy"])]
        return m


@functools.lru_cache(maxsize=None)
def _form(plan, rows, flat, consts, narrow=None, registered=True):
    """The engine's memories (``{name: ({field: shape}, slotted)}``), its row interval, its
    length and the offset of a row's last write from its start, from a build of it on its
    own."""
    m = Module()
    rows = {k: Signal(s, name=k) for k, s in rows}
    link = SimpleNamespace(valid=Signal(), ready=Signal())
    if consts:
        fields, bits = consts
        consts = (Signal(bits), {k: Signal(s, name=k) for k, s in fields}, bits)
    writes, _, _, t = plan_row_engine(m, plan, plan.setup.w, rows, link, Signal(), None, flat,
                                      consts, narrow, registered)
    Fragment.get(m, None)                        # (its memories used, for Amaranth's checks)
    memories = {name: ({k: Value.cast(x).shape() for k, x in vals.items()}, slot is not None)
                for name, vals, _, slot in writes}
    return memories, t["ii"], t["length"], t["written"]
