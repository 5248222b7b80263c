"""``raster``: the setup unit and the span engine on one clock (seeds 000-002).

In: triangles (``x0 y0 x1 y1 x2 y2``, ``e01 e02 e12``, ``v{k}_0..2`` per channel); out: one
fragment per clock, ``tri x y v{k}``, ``tri`` being the input row's index. The setup takes one
triangle per clock (a pipeline of ``Setup.latency`` stages) and works ahead of the span engine
while it walks the previous triangles. Status outputs: ``busy`` (work in flight) and
``culled`` (degenerate triangles, Omega = 0, dropped).
"""
from amaranth.hdl import Module, Signal
from amaranth.lib.wiring import Out

from ..setup_unit.formats import MODES, fragment_fields, parse_modes, triangle_fields
from ..setup_unit.setup import Setup, setup_fields
from ..unit import Pipeline, Unit
from .span import ROW_EVAL_STAGES, Link, row_eval, stepper, walker

__all__ = ["Raster"]


class Raster(Unit):
    NAME = "raster"
    DOC = ("Triangle setup (X-shading / exact mid-edge / linear, one reciprocal) and the "
           "forward-difference span engine; many fragments per triangle")
    PARAMS = {"screen_bits": 10, "sub_bits": 4, "channels": 2, "modes": "xshading",
              "recip": "newton", "recip_iters": 2}
    RANGES = {"screen_bits": (4, 12), "sub_bits": (1, 8), "channels": (1, 8), "modes": MODES,
              "recip": ("newton", "divide"), "recip_iters": (0, 3)}
    PER_CHANNEL = ("modes",)
    status_ports = {"busy": Out(1), "culled": Out(32)}

    def validate(self, screen_bits, sub_bits, channels, modes, recip, recip_iters):
        parse_modes(modes, channels)

    @property
    def setup(self):
        q = self.params
        return Setup(q["screen_bits"], q["sub_bits"], q["channels"], q["modes"], q["recip"],
                     q["recip_iters"])

    @property
    def inputs(self):
        q = self.params
        return triangle_fields(q["screen_bits"], q["sub_bits"], q["channels"])

    @property
    def outputs(self):
        return fragment_fields(self.params["screen_bits"], self.params["channels"])

    @property
    def latency(self):
        """From a triangle in to its first fragment out, when nothing waits: the setup, the
        walker's load, the row evaluation, the stepper's load."""
        return self.setup.latency + 1 + ROW_EVAL_STAGES + 1

    def elaborate(self, platform):
        m = Module()
        setup, ch = self.setup, self.params["channels"]
        w = setup.w
        count = Signal(32)
        with m.If(self.i.valid & self.i.ready):
            m.d.sync += count.eq(count + 1)
        coef = Link("coef")
        p = Pipeline(m, self.i, coef)
        v = {f.name: self.i.payload[f.name] for f in self.inputs}
        v = setup.datapath(p, {**v, "tri": count})
        if p.stages != setup.latency:
            raise AssertionError(f"setup has {p.stages} stages, latency says {setup.latency}")
        m.d.comb += coef.valid.eq(p.valid)
        missing = {f.name for f in setup_fields(w, ch)} - set(v)
        if missing:
            raise AssertionError(f"setup does not produce {sorted(missing)}")
        rows_in, rows_out = Link("rows_in"), Link("rows_out")
        culled = Signal(32)
        rows = walker(m, w, ch, v, coef.valid, coef.ready, rows_in, culled)
        q = Pipeline(m, rows_in, rows_out)
        rows = row_eval(q, w, ch, rows)
        assert q.stages == ROW_EVAL_STAGES
        m.d.comb += rows_out.valid.eq(q.valid)
        cur = stepper(m, w, ch, rows, rows_out, self.o)
        busy = cur | rows_in.valid
        for valid in p.valids + q.valids:
            busy = busy | valid
        m.d.comb += [self.busy.eq(busy), self.culled.eq(culled)]
        return m
