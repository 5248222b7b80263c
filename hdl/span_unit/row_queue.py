"""The row queue: rows from the row engine to the stepper, with credits.

The row engine never stalls: a row starts only when ``space`` (a register) promises a place,
so no handshake runs back from the fragment stream into the engine or the walker. A row's
values are written into a few memories (distributed RAM, 16 words, 4-bit pointers that
wrap), each at its own time: what the engine only carries at the row's start, what it
computes at its end, or (the engine with its channels in turn) a channel's values as its job
ends. A memory is written at its own count of writes, or at the slot the engine gives
(``addr``). The engine keeps the rows' order, so the k-th row started is the k-th out, and
every memory is read at one pointer. ``space`` is high while fewer than ``depth`` rows are
started and not yet taken, so with ``depth`` < 16 no slot is written again before it is
read. Out: a stream of rows whose valid is a register (written and not taken), so the
stepper's load enable is one LUT from registers. ``flows/parts.py`` proves it alone.
"""
from amaranth.hdl import Module, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

__all__ = ["RowQueue", "ROW_QUEUE", "credits"]

# Rows the row queue holds (started, not yet taken): all but one of its memories' 16 words,
# so a row engine may run ahead of the stepper by 15 rows. Measured (batch Verilator, the
# default scene's pipeline): 8 gave 0.897 fragments per clock on the default torus, 15 gives
# 0.921; the short rows at triangles' tips drain a shallow queue while the engine's ~45
# clocks of latency refill it.
ROW_QUEUE = 15


class RowQueue(wiring.Component):
    """``memories``: ``{name: (fields, slotted)}``, ``fields`` a ``{field: shape}`` of the
    values the memory holds, ``slotted`` whether the engine gives the slot (``addr``). Each
    memory is a port ``name`` (``en``, ``data``, and ``addr`` if slotted); ``start``: a row
    takes a place; ``written``: a row's last write; ``o``: the rows, their fields in the
    memories' order."""

    def __init__(self, memories, depth=ROW_QUEUE):
        assert 0 < depth < 16
        self.memories, self.depth = memories, depth
        members = {"start": In(1), "written": In(1), "space": Out(1, init=1)}
        for name, (fields, slotted) in memories.items():
            port = {"en": Out(1), "data": Out(data.StructLayout(fields))}
            if slotted:
                port["addr"] = Out(4)
            members[name] = In(wiring.Signature(port))
        rows = {k: s for fields, _ in memories.values() for k, s in fields.items()}
        members["o"] = Out(stream.Signature(data.StructLayout(rows)))
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        take = Signal(name="rq_take")
        rptr = Signal(4, name="rq_rptr")
        m.d.comb += take.eq(self.o.valid & self.o.ready)
        valid, _, _ = credits(m, "rq", self.start, self.written, take, self.space, self.depth)
        m.d.comb += self.o.valid.eq(valid)
        for name, (fields, slotted) in self.memories.items():
            port = getattr(self, name)
            mem = Memory(shape=data.StructLayout(fields), depth=16, init=[])
            m.submodules[f"mem_{name}"] = mem
            wr, rd = mem.write_port(), mem.read_port(domain="comb")
            if slotted:
                addr = port.addr
            else:
                addr = Signal(4, name=f"{name}_wptr")
                m.d.sync += addr.eq(addr + port.en)
            m.d.comb += [wr.addr.eq(addr), wr.data.eq(port.data), wr.en.eq(port.en),
                         rd.addr.eq(rptr)]
            m.d.comb += [self.o.payload[k].eq(rd.data[k]) for k in fields]
        m.d.sync += rptr.eq(rptr + take)
        return m


def credits(m, name, started, written, take, space, depth):
    """A queue's flags from its handshakes: ``space`` (the caller's register) while fewer
    than ``depth`` items are started and not yet taken; ``valid`` (a register) while one is
    written and not taken. From compares of the registers and the handshakes, not from the
    sums: an item is left unless the one item goes; fewer than ``depth`` held unless a full
    queue grows. Returns ``(valid, valid_next, held)``."""
    level = Signal(range(depth + 1), name=f"{name}_level")    # written, not yet taken
    held = Signal(range(depth + 1), name=f"{name}_held")      # started, not yet taken
    valid = Signal(name=f"{name}_valid")
    valid_next = written | (level > 1) | (valid & ~take)
    m.d.sync += [held.eq(held + started - take), level.eq(level + written - take),
                 valid.eq(valid_next),
                 space.eq((held < depth - 1) | ((held == depth - 1) & ~(started & ~take))
                          | ((held == depth) & take & ~started))]
    return valid, valid_next, held
