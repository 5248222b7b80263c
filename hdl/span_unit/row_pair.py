"""The row engine with block floating point (issue 49): the narrow engine for the triangles
whose derived bound it holds, the wide engine for the others, behind one row engine's ports.

The setup chooses per triangle (``Setup._narrow_channel``, ``golden.bfp.choice``) and the
walker carries its ``narrow`` bit on every row. Rows go to the narrow engine
(``span.row_engine(narrow=M)``, every product one MULT18X18D) or to the wide one (today's,
on one wide multiplier: ``row_mults=1``). Both write the same row queue: a row may start on
one engine only when the other has no row in flight (``busy``), so rows are written in the
order they start, and no memory has two writers in a clock. ``started``, ``written`` and
each memory's port are the ORs and the multiplexers of the two engines'; the row values
(``late``) are multiplexed a clock before their one register, so the pair has one set.
"""
import dataclasses

from amaranth.hdl import Module, Mux, Signal, signed, unsigned
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from .row_engine import RowEngine
from .span import narrow_row_fields
from .walker import NARROW_KEYS

__all__ = ["RowPair"]


class RowPair(wiring.Component):
    """``plan``: the raster's plan (``row_narrow`` > 0); ``rows``: the walker's row fields;
    ``flat``: the flat words' names."""

    def __init__(self, plan, rows, flat=()):
        self.plan, self.flat = plan, tuple(flat)
        M, ch = plan.row_narrow, len(plan.channels)
        narrow_only = {"rsm", "narrow", *(f"c{c}_{k}" for c in range(ch) for k in NARROW_KEYS)}
        want = narrow_row_fields(plan.setup.w, M, plan.modes, flat)
        self.rows = dict(rows)
        self.narrow = RowEngine(plan, {k: rows[k] for k in want}, flat, narrow=M,
                                registered=False)
        self.wide = RowEngine(dataclasses.replace(plan, row_mults=1, row_narrow=0),
                              {k: s for k, s in rows.items() if k not in narrow_only}, flat,
                              registered=False)
        self.memories = {}
        for name, (fields, slotted) in self.narrow.memories.items():
            other, _ = self.wide.memories[name]
            self.memories[name] = ({k: _wider(s, other[k]) for k, s in fields.items()},
                                   slotted)
        # the narrow engine's interval (the other takes the few rows it cannot hold), the
        # longer length (and the row values' register) and last write
        self.ii = self.narrow.ii
        self.length = max(self.narrow.length, self.wide.length) + 1
        self.offset = max(self.narrow.offset, self.wide.offset)
        self.offsets = {}
        members = {"i": In(wiring.Signature({"valid": Out(1), "ready": In(1),
                                             **{k: Out(s) for k, s in self.rows.items()}})),
                   "space": In(1), "started": Out(1), "written": Out(1), "busy": Out(1)}
        for name, (fields, _) in self.memories.items():
            members[name] = Out(wiring.Signature({"en": Out(1),
                                                  "data": Out(data.StructLayout(fields))}))
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        m.submodules.narrow = n = self.narrow
        m.submodules.wide = w = self.wide
        for eng in (n, w):
            for k in eng.rows:
                m.d.comb += getattr(eng.i, k).eq(getattr(self.i, k))
            m.d.comb += eng.space.eq(self.space)
        # the engine that took the last row; a row for the other waits until it has none
        # in flight (its busy, a register, covers every offset after the start's)
        on_narrow = Signal(init=1)
        with m.If(n.started):
            m.d.sync += on_narrow.eq(1)
        with m.If(w.started):
            m.d.sync += on_narrow.eq(0)
        go_n = on_narrow | ~w.busy
        go_w = ~on_narrow | ~n.busy
        want = self.i.narrow
        m.d.comb += [n.i.valid.eq(self.i.valid & want & go_n),
                     w.i.valid.eq(self.i.valid & ~want & go_w),
                     self.i.ready.eq(Mux(want, n.i.ready & go_n, w.i.ready & go_w)),
                     self.started.eq(n.started | w.started),
                     self.busy.eq(n.busy | w.busy | self.written)]
        m.d.sync += self.written.eq(n.written | w.written)
        for name, (fields, _) in self.memories.items():
            port, pn, pw = getattr(self, name), getattr(n, name), getattr(w, name)
            d = m.d.sync if name == "late" else m.d.comb
            d += port.en.eq(pn.en | pw.en)
            for k in fields:
                d += port.data[k].eq(Mux(pn.en, pn.data[k], pw.data[k]))
        return m


def _wider(a, b):
    """A shape that holds every value of shapes ``a`` and ``b``."""
    if not (a.signed or b.signed):
        return unsigned(max(a.width, b.width))
    grow = lambda s: s.width + (0 if s.signed else 1)
    return signed(max(grow(a), grow(b)))
