"""``raster``: the setup unit and the span engine on one clock (seeds 000-002).

In: triangles (``x0 y0 x1 y1 x2 y2``, ``e01 e02 e12``, ``v{k}_0..2`` per channel, and ``flat``
words ``f{k}``); out: one fragment per clock, ``tri x y v{k} f{k}``, ``tri`` being the input
row's index. A flat word is a triangle's constant (fenney_polar's k1, k2, k3 and Q) that
travels with its triangle through the setup, the walker, the row engine and the row queue to
each of its fragments, unchanged: a triangle that covers no pixel takes its words with it, so
nothing beside the raster has to meet fragments with their triangles again. The setup is a
schedule on shared multipliers (``Setup.program``, ``setup_mults`` of them); it works on the
next triangle while the walker and the row engine (``channels + 1`` multipliers, a row every
``row_ii`` clocks) and the stepper (one fragment per clock) work on the current one. By
default the setup takes one triangle at a time (its schedule's length per triangle); with
``setup_ii`` it overlaps triangles, starting one every ``setup_ii`` clocks, its results going
through a queue with credits (``span.setup_queue``) to the walker.
Status outputs: ``busy`` (work in flight) and ``culled`` (degenerate triangles, Omega = 0,
dropped).
"""
import functools

from amaranth.hdl import Const, Fragment, Module, Signal, Value
from amaranth.lib import wiring
from amaranth.lib.wiring import Out

from ..sched import Schedule
from ..setup_unit.formats import (MODES, PRECISIONS, flat_fields, fragment_fields,
                                   triangle_fields)
from ..unit import Unit
from .plan import KNOBS, RANGES as PLAN_RANGES, RECIPS, RasterPlan
from .queue import Queue
from .span import channel_engine, row_engine, row_engine_serial, setup_queue
from .walker import Walker, walker_constants, walker_inputs
from .stepper import Stepper

__all__ = ["Raster"]


class Raster(Unit):
    NAME = "raster"
    DOC = ("Triangle setup (X-shading / exact mid-edge / linear, one reciprocal) and the "
           "forward-difference span engine; many fragments per triangle")
    # its parameters: the plan's (``hdl.span_unit.plan``), per channel as strings
    PARAMS = {"screen_bits": 10, "sub_bits": 4, "channels": 2, "modes": "xshading",
              "recip": "newton", "recip_iters": 2, "groups": "0", "flat": 0,
              **{k: d for k, (d, _, _) in KNOBS.items()}, "precision": "14"}
    RANGES = {**PLAN_RANGES, "modes": MODES, "recip": RECIPS,
              "groups": None,     # a string: the plan checks it
              **{k: r for k, (_, r, _) in KNOBS.items()},
              "precision": PRECISIONS}   # each channel's fraction bits out (VALUE's 14 or fewer)
    PER_CHANNEL = ("modes", "groups", "precision")
    status_ports = {"busy": Out(1), "culled": Out(32)}

    def validate(self, **params):
        self.plan = RasterPlan.from_params(**params)
        self.precision, self.groups = self.plan.precision, self.plan.groups

    @property
    def setup(self):
        return self.plan.setup

    @property
    def inputs(self):
        q = self.plan
        return (triangle_fields(q.screen_bits, q.sub_bits, len(q.channels), q.groups)
                + self.flat_fields)

    @property
    def outputs(self):
        return fragment_fields(self.plan.screen_bits, len(self.plan.channels)) \
            + self.flat_fields

    @property
    def flat_fields(self):
        return flat_fields(self.plan.flat)

    @property
    def timing(self):
        """``(setup_clocks, row_ii, row_clocks)``: the setup's clocks per triangle (its
        length, or ``setup_ii``), the row engine's clocks per row and its latency (from the
        schedules themselves)."""
        return _timing(tuple(sorted(self.params.items())))[:3]

    @property
    def latency(self):
        """From a triangle in to its first fragment out, when nothing waits: the setup (to
        its results' last register, or last queue write), the walker's load and its row
        buffer, the row engine, the row queue, the stepper's load, the output register."""
        _, _, row_clocks, setup_end = _timing(tuple(sorted(self.params.items())))
        return setup_end + 1 + 2 + row_clocks + 3

    def elaborate(self, platform):
        m = Module()
        setup, ch = self.setup, len(self.plan.channels)
        w = setup.w
        count = Signal(32)
        with m.If(self.i.valid & self.i.ready):
            m.d.sync += count.eq(count + 1)
        ii = self.plan.setup_ii or None
        # one triangle at a time, the setup's product copies keep their own registers: shared,
        # they saved 2.7k FF of the default raster's 15.5k, but a shared register feeds every
        # member's reader, and the routes from two of them set the clock (107.4, 110.9 and,
        # with alpha's saturation split, 118.9 MHz placed, against 134.3 and 133.6 unshared)
        sc = Schedule(m, "su", Const(1), ii=ii, mults=self.plan.setup_mults, mux_groups=8,
                      platform=platform, narrow=self.plan.setup_narrow, share=bool(ii))
        flat = [f.name for f in self.flat_fields]
        src_ready = Signal()
        inputs = {**{f.name: self.i.payload[f.name] for f in self.inputs}, "tri": count}
        if ii:
            # overlapped: a triangle every ii clocks while the queue promises a slot; ready,
            # the start and the input captures from registers (copies of ``aligned``)
            space = Signal(name="sq_space", init=1)
            m.d.comb += [sc.start.eq(self.i.valid & sc.aligned & space),
                         self.i.ready.eq(sc.aligned & space)]
            v = sc.inputs(inputs, copy=sc.aligned_copy)
            coef = setup.program(sc, v)
            coef.update({k: v[k] for k in flat})
            current = walker_constants(ch, flat)
            coef, sq, end = setup_queue(m, sc, coef, current)
            current = {k: coef[k] for k in current}
            sc.finish()
            sc.check()
            m.d.comb += [space.eq(sq.space), sq.o.ready.eq(src_ready)]
            done_n, pending, consts = sq.o_valid_next, sq.pending, None
        else:
            coef, done_n, pending, end, consts = self._one_at_a_time(m, sc, inputs, src_ready,
                                                                    flat, platform)
            current = None
        space = Signal(name="rq_space", init=1)
        in_memory = consts is not None
        ins = walker_inputs(coef, ch, flat, in_memory, current is not None)
        shapes = lambda vals: {k: Value.cast(x).shape() for k, x in vals.items()}
        m.submodules.walker = wk = Walker(w, ch, shapes(ins), current and shapes(current), flat,
                                          in_memory)
        src_valid = Signal()               # the stream's valid: the register of done_n (the
        m.d.sync += src_valid.eq(done_n)   # walker loads from done_n, a clock early)
        m.d.comb += [wk.i.valid.eq(src_valid), wk.i_valid_next.eq(done_n),
                     src_ready.eq(wk.i.ready)]
        m.d.comb += [getattr(wk.i, k).eq(x) for k, x in ins.items()]
        if current:
            m.d.comb += [wk.current[k].eq(x) for k, x in current.items()]
        rows, rows_in = {k: getattr(wk.o, k) for k in wk.outputs}, wk.o
        # the row engine: every channel a job, or one channel a job (``row_serial``)
        engine = row_engine_serial if self.plan.row_serial else row_engine
        writes, started, written, re = engine(
            m, w, setup.modes, rows, rows_in, space, platform, flat,
            self.plan.row_serial or self.plan.row_mults or ch + 1, consts, self.precision)
        re_ii, re_length, re_busy = re["ii"], re["length"], re["busy"]
        m.submodules.row_queue = rq = Queue({
            name: ({k: Value.cast(x).shape() for k, x in vals.items()}, slot is not None, False)
            for name, vals, _, slot in writes})
        m.d.comb += [rq.start.eq(started), rq.written.eq(written), space.eq(rq.space)]
        for name, vals, en, slot in writes:
            port = getattr(rq, name)
            m.d.comb += [port.en.eq(en)] + [port.data[k].eq(x) for k, x in vals.items()]
            if slot is not None:
                m.d.comb += port.addr.eq(slot)
        m.submodules.stepper = st = Stepper(w, {k: f.shape for k, f in rq.o.payload.shape()},
                                            self.o.payload.shape(), self.precision, flat)
        wiring.connect(m, rq.o, st.i)
        wiring.connect(m, st.o, wiring.flipped(self.o))
        cur = st.busy
        busy = (cur | self.o.valid | wk.busy | wk.o.valid | written | rq.o.valid | pending
                | re_busy)
        m.d.comb += [self.busy.eq(busy), self.culled.eq(wk.culled)]
        self._timing = (ii or end + 1, re_ii, re_length, end)
        return m

    def _one_at_a_time(self, m, sc, inputs, src_ready, flat, platform):
        """The setup taking a triangle while idle; its results held in the schedule's
        registers until the walker takes them. With ``setup_serial``, the channels' jobs
        (``channel_engine``) follow the schedule, reading its held registers, and write their
        constants into the slot of the channel-constant memory that the walker does not
        read: the walker's slot flips as it takes the triangle. Returns ``(values,
        valid_next, busy, end, consts)``, ``consts`` the memory and the walker's slot."""
        # ready from registers only: the next triangle starts a clock after the walker takes
        # this one. The inputs are captured while the setup is idle (its ready), from copies
        # of ready, each a state machine of its own (Schedule.aligned_copy says why)
        idle = []

        def idle_copy():
            idle.append(Signal(name=f"su_idle{len(idle)}", init=1))
            return idle[-1]
        ready = idle_copy()
        m.d.comb += [sc.start.eq(self.i.valid & ready), self.i.ready.eq(ready)]
        v = sc.inputs(inputs, copy=idle_copy)
        in_turn = self.plan.setup_serial
        coef = self.setup.program(sc, v, in_turn=bool(in_turn))
        coef.update({k: v[k] for k in flat})          # held as tri is, in the input registers
        sc.keep(*coef.values())                       # the walker reads them after the job
        last, end, consts, busy = sc.at(sc.length - 1), sc.length - 1, None, Const(0)
        done = Signal()
        if in_turn:
            # the jobs share the setup's multiplier: they start once what they read is ready
            # (au, av) and the setup has issued its last product, beside the rest of its
            # schedule (the edges' divisions); the setup ends with the later
            rslot = Signal(name="cs_rslot")
            with m.If(done & src_ready):              # the walker takes the triangle
                m.d.sync += rslot.eq(~rslot)
            go = max(sc.when(*(coef[k] for k in self.setup.job_inputs)), sc.last_issue + 1)
            mem, a2, written, t = channel_engine(m, self.setup, coef, sc.at(go), ~rslot,
                                                 platform, in_turn, host=(sc, 0))
            coef.update(a2)
            consts, busy = (mem, rslot), t["busy"]
            if go + t["end"] > end:
                last, end = written, go + t["end"]
        sc.finish()                                   # after its guest's (channel_engine)
        done_n = last | (done & ~src_ready)
        m.d.sync += done.eq(done_n)
        running = []
        for k, r in enumerate(idle):
            running.append(Signal(name=f"su_running{k}"))
            run_n = (self.i.valid & r) | (running[k] & ~last)
            m.d.sync += [running[k].eq(run_n), r.eq(~run_n & ~done_n)]
        return coef, done_n, running[0] | done | busy, end, consts


@functools.lru_cache(maxsize=None)
def _timing(items):
    unit = Raster(**dict(items))
    Fragment.get(unit, None)                     # elaborated whole: nothing left unused
    return unit._timing
