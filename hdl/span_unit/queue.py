"""A queue with credits between a schedule that never stalls and a stream: the row queue
(the row engine's rows to the stepper) and the setup queue (an overlapped setup's
triangles to the walker).

The producer never stalls: an item starts only when ``space`` (a register) promises a place,
so no handshake runs back from the stream into the producer. An item's values are written
into a few memories (distributed RAM, 16 words, 4-bit pointers that wrap), each at its own
time: what the row engine only carries at a row's start, what it computes at its end, a
channel's values as its job ends, or the setup's values as each group of them is ready. A
memory is written at its own count of writes, or at the slot the producer gives (``addr``).
The producer keeps the items' order, so the k-th started is the k-th out, and every memory
is read at one pointer; a ``current`` memory is read instead at the slot last taken, for as
long as it is the last (the walker's constants, read in place while it walks that
triangle). ``space`` is high while fewer than ``depth`` items are started and not yet
taken, so with ``depth`` < 16 (15 with a current memory: its slot stays in use) no slot is
written again before it is read. Out: a stream whose valid is a register (written and not
taken), with that register's next value beside it (``o_valid_next``, for the walker's load
a clock early). ``flows/parts.py`` proves it alone in the three forms the raster builds.
"""
from amaranth.hdl import Module, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

__all__ = ["Queue", "ROW_QUEUE", "credits"]

# Rows the row queue holds (started, not yet taken): all but one of its memories' 16 words,
# so a row engine may run ahead of the stepper by 15 rows. Measured (batch Verilator, the
# default scene's pipeline, a row every 5 clocks): 8 gave 0.897 fragments per clock on the
# default torus, 15 gave 0.921; the short rows at triangles' tips drain a shallow queue while
# the engine's ~45 clocks of latency refill it.
ROW_QUEUE = 15


class Queue(wiring.Component):
    """``memories``: ``{name: (fields, slotted, current)}``, ``fields`` a ``{field: shape}``
    of the values the memory holds, ``slotted`` whether the producer gives the slot
    (``addr``), ``current`` whether it is read at the slot last taken (its fields then on
    the port ``current``, not in the stream). Each memory is a port ``name`` (``en``,
    ``data``, and ``addr`` if slotted); ``start``: an item takes a place; ``written``: an
    item's last write; ``o``: the items, their fields in the memories' order; ``pending``:
    items started and not taken. ``name``: the prefix of its registers' names."""

    def __init__(self, memories, depth=ROW_QUEUE, name="rq"):
        assert 0 < depth < 16          # with a current memory, its slot is the 16th
        self.memories, self.depth, self.name = memories, depth, name
        members = {"start": In(1), "written": In(1), "space": Out(1, init=1),
                   "o_valid_next": Out(1), "pending": Out(1)}
        for mem, (fields, slotted, _) in memories.items():
            port = {"en": Out(1), "data": Out(data.StructLayout(fields))}
            if slotted:
                port["addr"] = Out(4)
            members[mem] = In(wiring.Signature(port))
        streamed = {k: s for f, _, c in memories.values() if not c for k, s in f.items()}
        members["o"] = Out(stream.Signature(data.StructLayout(streamed)))
        held = {k: s for f, _, c in memories.values() if c for k, s in f.items()}
        if held:
            members["current"] = Out(data.StructLayout(held))
        super().__init__(members)

    def elaborate(self, platform):
        m, n = Module(), self.name
        take = Signal(name=f"{n}_take")
        rptr, cur = Signal(4, name=f"{n}_rptr"), Signal(4, name=f"{n}_cur")   # cur: the slot
        #                                                                  last taken
        m.d.comb += take.eq(self.o.valid & self.o.ready)
        valid, valid_next, held = credits(m, n, self.start, self.written, take, self.space,
                                          self.depth)
        m.d.comb += [self.o.valid.eq(valid), self.o_valid_next.eq(valid_next),
                     self.pending.eq(held.any())]
        for name, (fields, slotted, current) in self.memories.items():
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
                         rd.addr.eq(cur if current else rptr)]
            out = self.current if current else self.o.payload
            m.d.comb += [out[k].eq(rd.data[k]) for k in fields]
        m.d.sync += rptr.eq(rptr + take)
        if any(c for _, _, c in self.memories.values()):
            with m.If(take):
                m.d.sync += cur.eq(rptr)
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
