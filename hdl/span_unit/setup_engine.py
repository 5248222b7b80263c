"""The setup as a component: ``Setup.program`` (hdl/setup_unit/setup.py, seed 001 §3) on a
schedule of shared multipliers, between the raster's triangles and the walker.

In: triangles, a stream (the raster's own input). Out: the walker's triangles, a valid/ready
handshake with a member per field (``Walker``'s input), whose valid is a register, with its
next value beside it (``o_valid_next``: the walker loads a clock early). Two forms:

- **One triangle at a time** (the default): the setup takes a triangle while idle and holds
  its results in the schedule's registers until the walker takes them; its ready is a
  register. With ``setup_serial`` the channels' jobs (``channel_engine``) follow the
  schedule on its first multiplier and write their constants into a memory of two slots
  (``consts``, read at ``consts_index`` and the slot the walker holds).
- **Overlapped** (``setup_ii``): the schedule (:class:`SetupSchedule`) takes a triangle every
  ``setup_ii`` clocks while the setup queue (a :class:`Queue`) promises a slot, and writes
  it into the queue's memories; the two are joined by the credit, as the row engine and the
  row queue are, and each is proven alone (flows/parts.py). The walker's constants are read
  in place at the slot last taken (``current``).

The fields' shapes and the setup's clocks come from a build of the same schedule on its own
(``_form``), before the component's signature is stated, so they are the elaborated ones.
``busy``: a triangle in the setup or in its queue.
"""
import functools

from amaranth.hdl import Const, Fragment, Module, Signal, Value, unsigned
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

from ..sched import Schedule, _or_tree
from ..term import Cat, Mux
from .queue import Queue
from .span import split_fields, turns
from .walker import walker_constants, walker_inputs

__all__ = ["SetupEngine", "SetupSchedule", "SETUP_QUEUE", "channel_engine", "queue_writes"]

SETUP_QUEUE = 15         # triangles the setup queue holds: all but its current slot


class SetupEngine(wiring.Component):
    """``plan``: the raster's :class:`RasterPlan`; ``layout``: the triangles' payload layout
    (the raster's input fields); ``flat``: the names of the flat words among them."""

    def __init__(self, plan, layout, flat=()):
        self.plan, self.layout, self.flat = plan, layout, tuple(flat)
        form = _form(plan, layout, self.flat)
        self.fields, self.current_fields, self.const_fields = form["shapes"]
        # the setup's clocks a triangle (its length, or the interval) and the offset of its
        # results' last register (or the queue's last write)
        self.end = form["end"]
        self.clocks = plan.setup_ii or self.end + 1
        triangle = wiring.Signature({"valid": Out(1), "ready": In(1),
                                     **{k: Out(s) for k, s in self.fields.items()}})
        members = {"i": In(stream.Signature(layout)), "o": Out(triangle),
                   "o_valid_next": Out(1), "busy": Out(1)}
        if self.current_fields:
            members["current"] = Out(data.StructLayout(self.current_fields))
        if self.const_fields:
            members["consts_index"] = In(form["index_bits"])
            members["consts"] = Out(data.StructLayout(self.const_fields))
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        out = _build(m, self.plan, self.i, self.o.ready, self.flat, platform,
                     self.consts_index if self.const_fields else None)
        m.d.comb += [getattr(self.o, k).eq(x) for k, x in out["fields"].items()]
        if self.current_fields:
            m.d.comb += [self.current[k].eq(x) for k, x in out["current"].items()]
        if self.const_fields:
            m.d.comb += [self.consts[k].eq(x) for k, x in out["consts"].items()]
        m.d.sync += self.o.valid.eq(out["valid_next"])   # the walker loads from the next
        m.d.comb += [self.o_valid_next.eq(out["valid_next"]), self.busy.eq(out["busy"])]
        return m


@functools.lru_cache(maxsize=None)
def _form_cached(plan, layout_items, flat):
    m = Module()
    i = stream.Signature(data.StructLayout(dict(layout_items))).flip().create()   # an input
    index = Signal(8)
    out = _build(m, plan, i, Signal(), flat, None, index)
    Fragment.get(m, None)                  # (its ROMs are used, for Amaranth's checks)
    shapes = lambda vals: {k: Value.cast(x).shape() for k, x in vals.items()}
    return {"shapes": (shapes(out["fields"]), out["current"] and shapes(out["current"]),
                       out["consts"] and shapes(out["consts"])),
            "end": out["end"], "index_bits": out["index_bits"]}


def _form(plan, layout, flat):
    """The setup's output shapes and its end, from a build of it on its own."""
    return _form_cached(plan, tuple((k, f.shape) for k, f in layout), flat)


def _build(m, plan, i, ready, flat, platform, consts_index):
    """The setup into ``m``: triangles from the stream ``i``, ``ready`` the walker's. Returns
    its outputs: ``fields`` (what the walker reads), ``valid_next``, ``busy``, ``end``, and
    ``current`` and ``consts`` (with ``index_bits``) when its form has them, else None."""
    ch, ii = len(plan.channels), plan.setup_ii
    # one triangle at a time, the setup's product copies keep their own registers: shared,
    # they saved 2.7k FF of the default raster's 15.5k, but a shared register feeds every
    # member's reader, and the routes from two of them set the clock (107.4, 110.9 and,
    # with alpha's saturation split, 118.9 MHz placed, against 134.3 and 133.6 unshared)
    out = {"current": None, "consts": None, "index_bits": 0}
    if ii:
        # overlapped: the schedule (``SetupSchedule``) writes each triangle into the setup
        # queue, joined as the row engine and the row queue are
        m.submodules.schedule = ss = SetupSchedule(plan, i.payload.shape(), flat)
        m.submodules.setup_queue = sq = Queue(ss.memories, SETUP_QUEUE, name="sq")
        wiring.connect(m, wiring.flipped(i), ss.i)
        m.d.comb += [sq.start.eq(ss.started), sq.written.eq(ss.written), ss.space.eq(sq.space),
                     sq.o.ready.eq(ready)]
        for name in ss.memories:
            wiring.connect(m, getattr(ss, name), getattr(sq, name))
        coef = {k: Const(*c) for k, c in ss.consts.items()}
        coef.update({k: sq.o.payload[k] for k, _ in sq.o.payload.shape()})
        coef.update({k: sq.current[k] for k, _ in sq.current.shape()})
        out.update(valid_next=sq.o_valid_next, busy=sq.pending, end=ss.offset,
                   current={k: coef[k] for k in walker_constants(ch, flat,
                                                                  narrow=bool(plan.row_narrow))})
    else:
        sc = Schedule(m, "su", Const(1), mults=plan.setup_mults, mux_groups=8,
                      platform=platform, narrow=plan.setup_narrow, share=False)
        coef, valid_next, busy, end, consts = _one_at_a_time(m, plan, sc, i, _inputs(m, i),
                                                             ready, flat, platform)
        out.update(valid_next=valid_next, busy=busy, end=end)
        if consts:
            mem, bits = consts
            m.d.comb += mem["index"].eq(consts_index[:bits])
            out.update(consts=mem["fields"], index_bits=bits)
    out["fields"] = walker_inputs(coef, ch, flat, out["consts"] is not None,
                                  out["current"] is not None, bool(plan.row_narrow))
    return out


def _inputs(m, i):
    """The setup's inputs: the triangle's fields and its index (``tri``, a count)."""
    count = Signal(32, name="su_tri")
    with m.If(i.valid & i.ready):
        m.d.sync += count.eq(count + 1)
    return {**{k: i.payload[k] for k, _ in i.payload.shape()}, "tri": count}


class SetupSchedule(wiring.Component):
    """The overlapped setup (``setup_ii``): a triangle every ``setup_ii`` clocks while the
    setup queue promises a slot (``space``), each written into the queue's memories at fixed
    offsets from its start (:func:`queue_writes`): the setup queue's producer, as the row
    engine is the row queue's, with the same ports (``started``, ``written``, a port per
    memory). It never stalls, and its ready, start and input captures come from registers
    (copies of ``aligned``). ``consts``: the results that are constants (``{name: (value,
    shape)}``), not written."""

    def __init__(self, plan, layout, flat=()):
        self.plan, self.layout, self.flat = plan, layout, tuple(flat)
        # its memories, constants, each memory's write offset, its length; a triangle every
        # ``ii``
        self.memories, self.consts, self.offsets, self.length = _schedule_form(
            plan, tuple((k, f.shape) for k, f in layout), self.flat)
        self.offset = max(self.offsets.values())         # the last write: ``written``
        self.ii = plan.setup_ii
        members = {"i": In(stream.Signature(layout)), "space": In(1), "started": Out(1),
                   "written": Out(1), "busy": Out(1)}
        for name, (fields, _, _) in self.memories.items():
            members[name] = Out(wiring.Signature({"en": Out(1), "addr": Out(4),
                                                  "data": Out(data.StructLayout(fields))}))
        super().__init__(members)

    def elaborate(self, platform):
        m = Module()
        writes, _, sc, _ = _schedule(m, self.plan, self.i, self.space, self.flat, platform)
        for name, vals, en, addr, _, _ in writes:
            port = getattr(self, name)
            m.d.comb += [port.en.eq(en), port.addr.eq(addr),
                         *[port.data[k].eq(x) for k, x in vals.items()]]
        m.d.comb += [self.started.eq(sc.start), self.written.eq(sc.at(self.offset)),
                     self.busy.eq(sc.busy())]
        return m


def _schedule(m, plan, i, space, flat, platform):
    """The overlapped setup's schedule into ``m``. Returns ``(writes, constants, schedule,
    last write's offset)``."""
    sc = Schedule(m, "su", Const(1), ii=plan.setup_ii, mults=plan.setup_mults, mux_groups=8,
                  platform=platform, narrow=plan.setup_narrow, share=True)
    m.d.comb += [sc.start.eq(i.valid & sc.aligned & space), i.ready.eq(sc.aligned & space)]
    v = sc.inputs(_inputs(m, i), copy=sc.aligned_copy)
    coef = plan.setup.program(sc, v)
    coef.update({k: v[k] for k in flat})
    writes, offset = queue_writes(sc, coef, walker_constants(len(plan.channels), flat,
                                                             narrow=bool(plan.row_narrow)))
    sc.finish()
    sc.check()
    consts = {k: (x.value, x.shape()) for k, x in coef.items() if isinstance(x, Const)}
    return writes, consts, sc, offset


@functools.lru_cache(maxsize=None)
def _schedule_form(plan, layout_items, flat):
    """The overlapped setup's memories (``{name: (fields, slotted, current)}``), its
    constants, each memory's write offset and its length, from a build of it on its own."""
    m = Module()
    i = stream.Signature(data.StructLayout(dict(layout_items))).create()
    writes, consts, sc, _ = _schedule(m, plan, i, Signal(), flat, None)
    Fragment.get(m, None)
    memories = {name: ({k: Value.cast(x).shape() for k, x in vals.items()}, True, now)
                for name, vals, _, _, now, _ in writes}
    offsets = {name: at for name, _, _, _, _, at in writes}
    return memories, consts, offsets, sc.length


def _one_at_a_time(m, plan, sc, i, inputs, ready, flat, platform):
    """The setup taking a triangle while idle; its results held in the schedule's registers
    until the walker takes them (``ready``). With ``setup_serial``, the channels' jobs
    (``channel_engine``) follow the schedule, reading its held registers, and write their
    constants into the slot of the channel-constant memory that the walker does not read: the
    walker's slot flips as it takes the triangle. Returns ``(values, valid_next, busy, end,
    consts)``, ``consts`` the memory's read port (``index`` and ``fields``) and its index
    bits, or None."""
    setup = plan.setup
    # ready from registers only: the next triangle starts a clock after the walker takes
    # this one. The inputs are captured while the setup is idle (its ready), from copies
    # of ready, each a state machine of its own (Schedule.aligned_copy says why)
    idle = []

    def idle_copy():
        idle.append(Signal(name=f"su_idle{len(idle)}", init=1))
        return idle[-1]
    first = idle_copy()
    m.d.comb += [sc.start.eq(i.valid & first), i.ready.eq(first)]
    v = sc.inputs(inputs, copy=idle_copy)
    in_turn = plan.setup_serial
    coef = setup.program(sc, v, in_turn=bool(in_turn))
    coef.update({k: v[k] for k in flat})          # held as tri is, in the input registers
    sc.keep(*coef.values())                       # the walker reads them after the job
    last, end, consts, busy = sc.at(sc.length - 1), sc.length - 1, None, Const(0)
    done = Signal()
    if in_turn:
        # the jobs share the setup's multiplier: they start once what they read is ready
        # (au, av) and the setup has issued its last product, beside the rest of its
        # schedule (the edges' divisions); the setup ends with the later
        rslot = Signal(name="cs_rslot")
        with m.If(done & ready):                  # the walker takes the triangle
            m.d.sync += rslot.eq(~rslot)
        go = max(sc.when(*(coef[k] for k in setup.job_inputs)), sc.last_issue + 1)
        mem, a2, written, t = channel_engine(m, setup, coef, sc.at(go), ~rslot, rslot,
                                             platform, in_turn, host=(sc, 0))
        coef.update(a2)
        consts, busy = (mem, mem["bits"]), t["busy"]
        if go + t["end"] > end:
            last, end = written, go + t["end"]
    sc.finish()                                   # after its guest's (channel_engine)
    done_n = last | (done & ~ready)
    m.d.sync += done.eq(done_n)
    running = []
    for k, r in enumerate(idle):
        running.append(Signal(name=f"su_running{k}"))
        run_n = (i.valid & r) | (running[k] & ~last)
        m.d.sync += [running[k].eq(run_n), r.eq(~run_n & ~done_n)]
    return coef, done_n, running[0] | done | busy, end, consts


def channel_engine(m, setup, src, go, wslot, rslot, platform=None, mults=1, host=None):
    """The setup's channels in turn: one datapath on ``mults`` wide multipliers computes one
    channel's constants per job (``Setup.channel_job``: a..f, Pu, Pv, P0 and 2A), a job every
    ``ii = ceil(11 / mults)`` clocks, the first at ``go`` (a pulse, with the engine idle), so a
    further channel costs ``ii`` clocks per triangle, not registers or multipliers. Each job
    captures its channel's inputs from the setup's held registers ``src`` (picked by a
    one-hot channel register) and writes a..f, Pu, Pv and P0 into the channel-constant memory
    (distributed RAM, a channel's constants a word: ``2 x 2**ceil(log2 channels)`` words, two
    triangles' worth), at slot ``wslot`` (the one the walker does not read, ``rslot``), and 2A
    into a register per channel (the walker holds it for the row queue). ``host``:
    ``(schedule, index)``, the setup's multiplier that is this engine's first (``Schedule``'s
    ``host``: the jobs then run after the setup's last product). Returns the memory's read
    side (``index``, the channel it reads, and its ``fields``), the registers of 2A, the last
    job's write (the setup's end) and the timing."""
    channels, modes = setup.channels, setup.modes
    ii = -(-11 // mults)
    sc = Schedule(m, "cs", Const(1), ii=ii, mults=mults, mux_groups=8, platform=platform,
                  host=host)
    sel, index, under = turns(m, sc, "cs", channels, go)
    pick = lambda key: _or_tree([Mux(sel[c], src[key(c)], 0) for c in range(channels)])
    quad = [c for c, mode in enumerate(modes) if mode != "linear"]
    s0 = setup.suffix(0)
    vals = {f"i0_{k}": pick(lambda c: f"i{c}_{k}") for k in range(3)}
    # a linear channel's edge constants are 0: its a, b, c come out 0, so its sums are linear
    vals.update({f"{e}{s0}": _or_tree([Mux(sel[c], src[f"{e}{setup.suffix(c)}"], 0)
                                        for c in quad] or [Const(0, 1)])
                 for e in ("e12", "e13", "e23")})
    vals.update(au=src["au"], av=src["av"], slot=wslot, index=index, sel=Cat(*sel))
    v = sc.inputs(vals, copy=sc.aligned_copy)
    out = setup.channel_job(sc, v)
    keys = ("a", "b", "c", "d", "e", "f", "pu", "pv", "p0")
    end = sc.when(*out.values())
    data_ = {k: sc.late_at(out[k], end) for k in (*keys, "a2")}
    slot, idx, chan = (sc.late(v[k], end) for k in ("slot", "index", "sel"))
    sc.read(end, *data_.values(), slot, idx, chan)
    en = sc.at(end)
    bits = max(1, (channels - 1).bit_length())
    words = {k: data_[k] for k in keys}
    mem = Memory(shape=unsigned(sum(len(x) for x in words.values())), depth=2 << bits, init=[])
    m.submodules["channel_consts"] = mem
    wr, rd = mem.write_port(), mem.read_port(domain="comb")
    read_index = Signal(bits, name="cs_read_index")
    m.d.comb += [wr.addr.eq(Cat(idx[:bits], slot)), wr.data.eq(Cat(*words.values())),
                 wr.en.eq(en), rd.addr.eq(Cat(read_index, rslot))]
    a2 = {}
    for c in range(channels):
        a2[f"c{c}_a2"] = r = Signal.like(Value.cast(data_["a2"]), name=f"cs_a2_{c}",
                                         reset_less=True)
        with m.If(en & chan[c]):
            m.d.sync += r.eq(data_["a2"])
    last = Signal(name="cs_written")
    m.d.comb += last.eq(en & chan[-1])
    sc.finish()
    sc.check()
    busy = Signal(name="cs_busy")
    m.d.comb += busy.eq(sc.busy() | under)
    consts = {"index": read_index, "bits": bits, "fields": split_fields(rd.data, words)}
    return consts, a2, last, {"ii": ii, "end": (channels - 1) * ii + end, "busy": busy}


def queue_writes(sc, values, current=()):
    """An overlapped setup's results (``values``, of the schedule ``sc``) as the setup queue's
    writes: the triangle's slot is counted at the start and travels with it (``sq_slot``
    and its late copies); each value is written as soon as it is ready, into one of a few
    memories that each take the values ready within an interval of each other, so no value
    is kept in a copy for this. ``current``: names of values read at the slot last taken
    (the walker's constants, read in place while it walks that triangle); constants are not
    written. Returns ``(writes, offset)``: ``(memory, values, enable, slot, current,
    offset)`` each, and the offset at which the last memory is written."""
    slots = Signal(4, name="sq_slots")                   # 4-bit pointers wrap at 16
    sc.m.d.sync += slots.eq(slots + sc.start)
    slot = sc.input("sq_slot", slots)
    keep = {k: x for k, x in values.items() if not isinstance(x, Const)}
    groups = []
    for k in sorted(keep, key=lambda k: (k in current, sc.when(keep[k]))):
        at = sc.when(keep[k])
        if not groups or k in current and not groups[-1][2] or at >= groups[-1][0] + sc.ii:
            groups.append([at, {}, k in current])
        groups[-1][1][k] = keep[k]
    offset, writes = 0, []
    for g, (_, vals, now) in enumerate(groups):
        at = max(sc.when(x) for x in vals.values())
        offset = max(offset, at)
        late = {k: sc.late_at(x, at) for k, x in vals.items()}
        addr = sc.late(slot, at)
        sc.read(at, *late.values(), addr)
        writes.append((f"g{g}", late, sc.at(at), addr, now, at))
    return writes, offset
