"""The stepper (seed 000 eq 29-32 along a span): rows in, one fragment per clock out.

A row (from the row queue) holds its span ``[xs, xe)`` (``some``: not empty; ``one``: one
pixel), its row ``j``, its triangle ``tri`` and flat words, and per channel Phi and its first
difference d at the span's first pixel and the triangle's 2A, each at the channel's FI
(``Widths.fi`` of its precision, Phi with its rounding half in it). Per pixel and channel
Phi += d, d += 2A (a linear channel's 2A is 0); the fragment is rounded, saturated and
registered on its way out.

Both sides are streams (``amaranth.lib.stream``): a row is taken in the clock of the current
row's last pixel, and beside the output register a one-fragment skid buffer takes the fragment
emitted while the output is held, so the stepper's few hundred enables wait on a register
(the skid is empty), not on the output's ready; the skid goes out before anything newer.
``busy``: a row or a skidded fragment in the stepper.
"""
from amaranth.hdl import Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

from ..setup_unit.formats import VALUE

__all__ = ["Stepper"]


class Stepper(wiring.Component):
    """``w``: the raster's ``Widths``; ``rows``: the row's fields (``{name: shape}``);
    ``fragment``: the output's layout (the raster's ``o``); ``precision``: each channel's
    fraction bits out."""

    def __init__(self, w, rows, fragment, precision, flat=()):
        self.w, self.precision, self.flat = w, tuple(precision), tuple(flat)
        super().__init__({"i": In(stream.Signature(data.StructLayout(rows))),
                          "o": Out(stream.Signature(fragment)), "busy": Out(1)})

    def elaborate(self, platform):
        m, w, rows, o = Module(), self.w, self.i.payload, self.o
        channels = len(self.precision)
        acc_bits = [w.acc(p) for p in self.precision]    # Phi, d wrap modulo 2**acc_bits
        cur, last = Signal(name="st_cur"), Signal(name="st_last")
        reg = lambda shape, name: Signal(shape, name=name, reset_less=True)   # no reset:
        x, xe = reg(w.screen_bits + 1, "st_x"), reg(w.screen_bits + 1, "st_xe")  # valid bits
        y, tri = reg(w.screen_bits, "st_y"), reg(len(rows.tri), "st_tri")        # have it
        const = {k: reg(len(rows[k]), f"st_{k}") for k in self.flat}   # the flat words
        phi = [reg(acc_bits[ch], f"st_phi{ch}") for ch in range(channels)]
        d = [reg(acc_bits[ch], f"st_d{ch}") for ch in range(channels)]
        a2 = [reg(acc_bits[ch], f"st_a2_{ch}") for ch in range(channels)]
        skid_valid = Signal(name="st_skid_valid")
        room = ~skid_valid
        m.d.comb += self.i.ready.eq(~cur | (room & last))
        with m.If(self.i.valid & self.i.ready):
            m.d.sync += [cur.eq(rows.some), last.eq(rows.one),
                         x.eq(rows.xs), xe.eq(rows.xe), y.eq(rows.j), tri.eq(rows.tri)]
            m.d.sync += [r.eq(rows[k]) for k, r in const.items()]
            for ch in range(channels):             # Phi arrives with the rounding half in it
                m.d.sync += [phi[ch].eq(rows[f"phi{ch}"]),
                             d[ch].eq(rows[f"d{ch}"]), a2[ch].eq(rows[f"c{ch}_a2"])]
        with m.Elif(cur & room):
            with m.If(last):
                m.d.sync += cur.eq(0)
            m.d.sync += [x.eq(x + 1), last.eq(x + 2 == xe)]
            for ch in range(channels):
                m.d.sync += [phi[ch].eq(phi[ch] + d[ch]), d[ch].eq(d[ch] + a2[ch])]
        emit = cur & room
        frag = {"tri": tri, "x": x, "y": y, **const}
        for ch, p in enumerate(self.precision):     # saturated to [-2, 2) at p fraction bits
            val = phi[ch].as_signed() >> (w.fi(p) - p)
            top, low = (1 << (p + 1)) - 1, -(1 << (p + 1))
            frag[f"v{ch}"] = Mux(val > top, top, Mux(val < low, low, val)) << (VALUE.frac_bits - p)
        skid = {k: Signal.like(o.payload[k], name=f"st_skid_{k}", reset_less=True)
                for k in frag}
        free = ~o.valid | o.ready                   # the output register is free
        with m.If(free):
            m.d.sync += [o.valid.eq(skid_valid | emit), skid_valid.eq(0)]
            m.d.sync += [o.payload[k].eq(Mux(skid_valid, skid[k], v)) for k, v in frag.items()]
        with m.Elif(emit):
            m.d.sync += [skid_valid.eq(1)] + [skid[k].eq(v) for k, v in frag.items()]
        m.d.comb += self.busy.eq(cur | skid_valid)
        return m
