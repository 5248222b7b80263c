"""The walker (seed 001's triangle, walked row by row): rows from triangles.

It holds one triangle from the setup unit and emits one row per clock, from the first row
whose centre is at or below the top vertex to the last one above the bottom vertex
(clipped to the screen). Each edge is a DDA in exact integers: column ``i = ceil(x / S -
1/2)`` of the edge's crossing and the remainder ``r = i den - num``; a row step adds the
quotient and remainder of ``2 S dx / (2 S dy)`` and carries once. The long edge runs top to
bottom; the short one top to middle, then middle to bottom from the middle vertex's row.
Columns ``[left, right)`` are the pixels whose centres lie inside (top-left rule); a row
with none on screen goes no further (two clocks in the walker's buffer, not a row engine's
interval, so sliver and off-screen rows cost little). Beside them, the exact numerators
nu = X y2 - Y x2, nv = Y x1 - X y1 (eq 18-20, sub-pixel units) of the left edge's first
pixel and of column 0, stepped with additions.

In: the setup's triangles, a valid/ready handshake with each field a member of its own,
whose valid is the register of ``i_valid_next`` (the walker registers its load a clock
early). Out: rows, likewise (the edges' columns ``xl``,
``xr`` of row ``j``, unclamped, the numerator tracks of the left edge's first pixel E and of
column 0 B, and the triangle's constants). ``culled``: triangles with Omega = 0 dropped;
``busy``: rows left.
"""
from amaranth.hdl import Module, Mux, Signal, Value, signed
from amaranth.lib import data, wiring
from amaranth.lib.wiring import In, Out

from ..sched import CAPTURE_SHARE as SHARE

__all__ = ["Walker", "walker_constants", "walker_inputs", "NARROW_KEYS"]

EDGE = ("i", "r0", "q", "d", "n")             # an edge's DDA as the setup gives it
TRACKS = ("s0", "s1", "e1", "t0", "t1", "bs", "e0", "b0")   # the numerator tracks' starts, steps
CONTROL = ("rows", "j0", "to_j1", "to_jm", "left_long", "last0", "at_jm0", "first_short",
           "cull")


def _step(i, r, q, d, n):
    """One row of an edge DDA, with the remainder held as ``r - d`` and ``n - d`` beside it, so
    the carry is a register's sign bit: (i + q + carry, r - d + n if carry else r - d)."""
    carry = r[-1]
    return i + q + carry, Mux(carry, r + n, r - d)


NARROW_KEYS = ("na", "nb", "nc", "nd", "ne", "npu", "npv", "sphi", "sd")


def walker_constants(channels, flat=(), in_memory=False, narrow=False):
    """The triangle's values the walker holds for its rows, unchanged while it walks
    (``in_memory``: a channel's but 2A are in ``channel_engine``'s memory; ``narrow``: and
    the narrow row engine's, ``Setup._narrow_channel``)."""
    keys = ("a2",) if in_memory else ("a", "b", "c", "d", "e", "f", "pu", "pv", "p0", "a2")
    keys += NARROW_KEYS if narrow else ()
    return (["tri", *flat, "rs", "sh", *(("rsm", "narrow") if narrow else ())]
            + [f"c{ch}_{k}" for ch in range(channels) for k in keys])


def walker_inputs(src, channels, flat=(), in_memory=False, current=False, narrow=False):
    """What the walker reads of the setup's values ``src``: its control, the edges' DDAs (an
    edge's ``n`` the setup's ``n0`` at the width of its ``n``), the tracks and (unless the
    setup queue holds them, ``current``) the triangle's constants."""
    out = {k: src[k] for k in CONTROL}
    for e in "lst":
        out.update({f"{e}_{k}": src[f"{e}_{k}"] for k in EDGE[:-1]})
        n = Value.cast(src[f"{e}_n"])
        out[f"{e}_n"] = Value.cast(src[f"{e}_n0"])[:len(n)]
        if n.shape().signed:
            out[f"{e}_n"] = out[f"{e}_n"].as_signed()
    out.update({f"{k}_{a}": src[f"{k}_{a}"] for a in "uv" for k in TRACKS})
    if not current:
        out.update({k: src[k] for k in walker_constants(channels, flat, in_memory, narrow)})
    return out


class Walker(wiring.Component):
    """``w``: the raster's ``Widths``; ``inputs``: the triangle's fields (``{name: shape}``,
    ``walker_inputs``); ``current``: the fields of the triangle's constants when the setup
    queue holds them, read in place while the walker walks that triangle (a port of that
    name), else None: the walker holds them; ``in_memory``: a channel's constants but 2A are
    in ``channel_engine``'s memory."""

    def __init__(self, w, channels, inputs, current=None, flat=(), in_memory=False,
                 narrow=False):
        self.w, self.channels, self.flat, self.in_memory = w, channels, tuple(flat), in_memory
        self.narrow = narrow
        self.in_queue = current is not None
        consts = current or {k: inputs[k] for k in walker_constants(channels, flat, in_memory,
                                                                    narrow)}
        col = Mux(Signal(), Signal(inputs["l_i"]), Signal(inputs["s_i"])).shape()
        row = {"j": Signal(w.wrow).shape(), "xl": col, "xr": col,
               **{k: Signal(w.wn).shape() for k in ("E_u", "E_v", "B_u", "B_v")}, **consts}
        # the fields of a triangle and of a row are members of their own, not one payload:
        # one wide bus of them woke every reader of it in an event-driven simulator at each
        # change of any (Icarus ran the default scene 2.3 times slower, the input's bus
        # changing while the setup computes)
        self.inputs, self.outputs = tuple(inputs), tuple(row)
        triangle = wiring.Signature({"valid": Out(1), "ready": In(1),
                                     **{k: Out(s) for k, s in inputs.items()}})
        members = {"i": In(triangle), "i_valid_next": In(1),
                   "o": Out(wiring.Signature({"valid": Out(1), "ready": In(1),
                                              **{k: Out(s) for k, s in row.items()}})),
                   "culled": Out(32), "busy": Out(1)}
        if current:
            members["current"] = In(data.StructLayout(current))
        super().__init__(members)

    def elaborate(self, platform):
        m, w, channels, flat, in_memory = Module(), self.w, self.channels, self.flat, \
            self.in_memory
        src = {k: getattr(self.i, k) for k in self.inputs}
        j = Signal(w.wrow)
        to_j1, to_jm = (Signal(signed(w.wrow + 1), name=f"w_{k}") for k in ("to_j1", "to_jm"))
        left_long = Signal()
        keep = [] if self.in_queue else walker_constants(channels, flat, in_memory,
                                                         self.narrow)
        held = ({k: self.current[k] for k, _ in self.current.shape()} if self.in_queue else
                {k: Signal.like(src[k], name=f"w_{k}") for k in keep})
        edge = {}
        for e in ("l", "s", "t"):
            edge[e] = {k: Signal.like(src[f"{e}_{k}"], name=f"w_{e}_{k}")
                       for k in "iqdn"}
            edge[e]["r"] = Signal(signed(len(src[f"{e}_n"]) + 1), name=f"w_{e}_r",   # r - d
                                  reset_less=True)
        # numerator tracks: the left edge's first pixel (E), column 0 (B); their steps
        tr = {k: Signal(w.wn, name=f"w_{k}", reset_less=True) for k in
              ("E_u", "E_v", "B_u", "B_v", "s0_u", "s0_v", "s1_u", "s1_v", "e1_u", "e1_v",
               "t0_u", "t0_v", "t1_u", "t1_v", "bs_u", "bs_v")}
        # A row goes into a one-row buffer when it is empty (``full``, a register), so every
        # enable here comes from registers. The next triangle loads once the buffer's row (which
        # reads ``held``) has gone; with a row every ``ii`` >= 3 clocks that costs no throughput.
        # ``load`` and ``accept`` are registers too, computed a clock early from the next state.
        # They drive about two thousand enables, so the state machine is copied: each copy drives
        # a share (Schedule.aligned_copy says why copies must be state machines of their own).
        last, at_jm = Signal(name="w_last"), Signal(name="w_at_jm")   # to_j1, to_jm == 0
        rows = src["rows"]                         # not culled, j0 < j1 (the setup's register)

        some = Signal(name="wb_some")              # the buffer's row has a pixel on screen

        def control(k):
            """A copy of the walker's state: (have, full, load, accept)."""
            have, full = Signal(name=f"w_have{k}"), Signal(name=f"w_full{k}")
            load, accept = Signal(name=f"w_load{k}"), Signal(name=f"w_accept{k}")
            have_n = Mux(load, rows, have & ~(accept & last))
            full_n = accept | (full & some & ~self.o.ready)       # a row of no pixel is dropped
            m.d.sync += [have.eq(have_n), full.eq(full_n), accept.eq(have_n & ~full_n),
                         load.eq(self.i_valid_next & ~have_n & ~full_n)]
            return have, full, load, accept

        have, full, load, accept = control(0)
        m.d.comb += [self.i.ready.eq(~have & ~full), self.o.valid.eq(full & some)]

        def init(e):     # the walker's remainder i den - num from the setup's floor remainder,
            # held less d (and n as n - d): see _step; the setup computes both (r0, n0)
            return {"i": src[f"{e}_i"], "r": src[f"{e}_r0"], "q": src[f"{e}_q"],
                    "d": src[f"{e}_d"], "n": src[f"{e}_n"]}

        with m.If(load):                           # the rows and the edges: copy 0
            m.d.sync += [j.eq(src["j0"]), to_j1.eq(src["to_j1"]), to_jm.eq(src["to_jm"]),
                         left_long.eq(src["left_long"]), last.eq(src["last0"]),
                         at_jm.eq(src["at_jm0"])]
            first_short = src["first_short"]
            for e in ("l", "t"):
                m.d.sync += [edge[e][k].eq(val) for k, val in init(e).items()]
            s_init, t_init = init("s"), init("t")
            m.d.sync += [edge["s"][k].eq(Mux(first_short, t_init[k], s_init[k])) for k in "irqdn"]
            with m.If(src["cull"]):
                m.d.sync += self.culled.eq(self.culled + 1)
        with m.Elif(accept):
            m.d.sync += [j.eq(j + 1), to_j1.eq(to_j1 - 1), to_jm.eq(to_jm - 1),
                         last.eq(to_j1 == 1), at_jm.eq(to_jm == 1)]     # compares, not sums
            li, lr = _step(*(edge["l"][k] for k in "irqdn"))
            m.d.sync += [edge["l"]["i"].eq(li), edge["l"]["r"].eq(lr)]
            si, sr = _step(*(edge["s"][k] for k in "irqdn"))
            with m.If(at_jm):
                m.d.sync += [edge["s"][k].eq(edge["t"][k]) for k in "irqdn"]
            with m.Else():
                m.d.sync += [edge["s"]["i"].eq(si), edge["s"]["r"].eq(sr)]
        carry = Mux(left_long, edge["l"]["r"][-1], edge["s"]["r"][-1])     # r < d
        switch = ~left_long & at_jm
        for n, a in enumerate("uv"):               # the tracks: a copy for each of u, v
            _, _, load_a, accept_a = control(1 + n)
            with m.If(load_a):
                m.d.sync += [tr[k].eq(src[k]) for k in tr if k[0] not in "EB" and k[-1] == a]
                m.d.sync += [tr[f"{t}_{a}"].eq(src[f"{t.lower()}0_{a}"]) for t in "EB"]
            with m.Elif(accept_a):
                m.d.sync += tr[f"B_{a}"].eq(tr[f"B_{a}"] + tr[f"bs_{a}"])
                with m.If(switch):
                    m.d.sync += [tr[f"E_{a}"].eq(tr[f"e1_{a}"]), tr[f"s0_{a}"].eq(tr[f"t0_{a}"]),
                                 tr[f"s1_{a}"].eq(tr[f"t1_{a}"])]
                with m.Else():
                    m.d.sync += tr[f"E_{a}"].eq(Mux(carry, tr[f"E_{a}"] + tr[f"s1_{a}"],   # both
                                                    tr[f"E_{a}"] + tr[f"s0_{a}"]))  # sums, then pick
        bits = 3 * SHARE
        for k in keep:                             # the triangle's constants: a copy per share
            if bits >= SHARE:
                _, _, load_k, _ = control(f"_{k}")
                bits = 0
            with m.If(load_k):
                m.d.sync += held[k].eq(src[k])
            bits += len(held[k])
        row = {"j": j, "xl": Mux(left_long, edge["l"]["i"], edge["s"]["i"]),
               "xr": Mux(left_long, edge["s"]["i"], edge["l"]["i"]),
               **{k: tr[k] for k in ("E_u", "E_v", "B_u", "B_v")}}
        buf = {k: Signal.like(Value.cast(x), name=f"wb_{k}", reset_less=True)
               for k, x in row.items()}
        _, _, _, accept_b = control("_buf")
        size = 1 << w.screen_bits                  # [xl, xr) clamped to the screen is not empty
        with m.If(accept_b):
            m.d.sync += [buf[k].eq(x) for k, x in row.items()]
            m.d.sync += some.eq((row["xl"] < row["xr"]) & (row["xr"] > 0) & (row["xl"] < size))
        # the row engine clamps the span and picks the track (its first clock, not this one's)
        m.d.comb += [getattr(self.o, k).eq(x) for k, x in {**buf, **held}.items()]
        m.d.comb += self.busy.eq(have)
        return m


