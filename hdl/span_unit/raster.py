"""``raster``: the setup unit and the span engine on one clock (seeds 000-002).

In: triangles (``x0 y0 x1 y1 x2 y2``, ``e01 e02 e12``, ``v{k}_0..2`` per channel, and ``flat``
words ``f{k}``); out: one fragment per clock, ``tri x y v{k} f{k}``, ``tri`` being the input
row's index. A flat word is a triangle's constant (fenney_polar's k1, k2, k3 and Q) that
travels with its triangle through the setup, the walker, the row engine and the row queue to
each of its fragments, unchanged: a triangle that covers no pixel takes its words with it, so
nothing beside the raster has to meet fragments with their triangles again.

Its parts, joined by streams: the setup (``SetupEngine``: ``Setup.program`` on a schedule of
``setup_mults`` shared multipliers, one triangle at a time or, with ``setup_ii``, one every
``setup_ii`` clocks through the setup queue), the walker (a row a clock), the row engine (a
schedule between the walker and the row queue, a row every ``row_ii`` clocks), the row queue
and the stepper (a fragment a clock). The setup works on the next triangle while the others
work on the current one.
Status outputs: ``busy`` (work in flight) and ``culled`` (degenerate triangles, Omega = 0,
dropped).
"""
from amaranth.hdl import Module
from amaranth.lib import wiring
from amaranth.lib.wiring import Out

from ..setup_unit.formats import (MODES, PRECISIONS, flat_fields, fragment_fields,
                                   triangle_fields)
from ..unit import Unit
from .plan import KNOBS, RANGES as PLAN_RANGES, RECIPS, RasterPlan
from .queue import Queue
from .setup_engine import SetupEngine
from .row_engine import RowEngine, const_fields, row_fields
from .row_pair import RowPair
from .walker import Walker
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
        """``(setup_clocks, row_ii, row_clocks)``: the plan's (``RasterPlan.timing``)."""
        return self.plan.timing[:3]

    @property
    def latency(self):
        return self.plan.latency

    def elaborate(self, platform):
        m = Module()
        ch, flat = len(self.plan.channels), [f.name for f in self.flat_fields]
        m.submodules.setup = su = SetupEngine(self.plan, self.i.payload.shape(), flat)
        wiring.connect(m, wiring.flipped(self.i), su.i)
        w = self.setup.w
        m.submodules.walker = wk = Walker(w, ch, su.fields, su.current_fields, flat,
                                          bool(su.const_fields), bool(self.plan.row_narrow))
        wiring.connect(m, su.o, wk.i)
        m.d.comb += wk.i_valid_next.eq(su.o_valid_next)
        if su.current_fields:
            m.d.comb += wk.current.eq(su.current)
        if self.plan.row_narrow:        # the narrow engine, and the wide one for the rest
            m.submodules.row_engine = re = RowPair(self.plan, row_fields(wk), flat)
        else:
            m.submodules.row_engine = re = RowEngine(self.plan, row_fields(wk), flat,
                                                     const_fields(su))
        wiring.connect(m, wk.o, re.i)
        if su.const_fields:
            m.d.comb += [su.consts_index.eq(re.consts_index), re.consts.eq(su.consts)]
        m.submodules.row_queue = rq = Queue({name: (fields, slotted, False)
                                             for name, (fields, slotted) in re.memories.items()})
        m.d.comb += [rq.start.eq(re.started), rq.written.eq(re.written), re.space.eq(rq.space)]
        for name in re.memories:
            wiring.connect(m, getattr(re, name), getattr(rq, name))
        m.submodules.stepper = st = Stepper(w, {k: f.shape for k, f in rq.o.payload.shape()},
                                            self.o.payload.shape(), self.precision, flat)
        wiring.connect(m, rq.o, st.i)
        wiring.connect(m, st.o, wiring.flipped(self.o))
        busy = (st.busy | self.o.valid | wk.busy | wk.o.valid | re.written | rq.o.valid
                | su.busy | re.busy)
        m.d.comb += [self.busy.eq(busy), self.culled.eq(wk.culled)]
        return m
