"""The raster's parts proven alone (issue 49 §3): the setup, the walker, the row engines,
the queues and the stepper.

**The stepper** (``hdl/span_unit/stepper.py``): rows in, one fragment per clock out, both
streams.

The stepper under proof is the one the raster builds at make formal's size (a 16 x 16 screen,
one channel), taken from the raster's elaboration, so its row and fragment layouts are the
real ones. The harness gives it free rows (any span ``[xs, xe)`` on the screen, ``some``
and ``one`` as the row queue computes them, any row, Phi, d and 2A; each row's ``tri`` the
count of rows accepted before it, so that rows are told apart) and a free ``ready``, and
keeps a reference of its own: a queue of the rows accepted that have pixels, and how many
fragments of the first one are out. It states:

- ``held``: a stalled output keeps its valid and payload;
- ``no_extra``: a fragment goes out only while a row owes one;
- ``order``: each fragment is the next one owed: the first owing row's ``tri`` and row, at
  the column after the last one out, so none is made, lost, repeated or reordered, and each
  row gives exactly ``xe - xs`` fragments;
- ``drain``: while a row owes fragments and ready is high, the next one is out within
  ``DRAIN`` clocks (a row's first fragment waits two: its load, then the output register).

All four are proven by k-induction, with invariants that tie the stepper's state (its output
register, skid and current row) to the reference's next owed fragments (``_invariants``), so
drain holds on every run, not to a depth. The mutants (``MUTANTS``) sit between the part's
output and the harness and must be caught by a BMC of their own property.

**The queue** (``hdl/span_unit/queue.py``), as the raster builds it with each row engine
(``row_queue``: the engine of all channels at once, a memory written at a row's start and
one at its end; ``row_queue_serial``: the engine with its channels in turn, whose memories
are written at the slots it gives) and with an overlapped setup (``setup_queue``: the
walker's constants in memories read at the slot last taken). The harness is the engine: it starts a row only
while ``space`` is high, writes a row's last values (``written``) only after its start, in
order, and puts in the low bits of each memory's word the count of rows started (the early
memory) or written (the others) before it: a tag that tells the rows apart. Against the
counts of rows started, written and out:

- ``credit``: never more than ``depth`` rows started and not taken, so the engine's rows
  always find a place and no word is written again before it is read;
- ``held``, ``no_extra`` (a row goes out only once written), ``order`` (every memory's
  tag is the count of rows out: none made, lost, repeated or reordered, and every memory read
  at the same row);
- ``drain``: a written row is out within one clock while ready is high.

Its invariants tie the queue's counts, pointers and every word of its memories (mapped to
registers for the proof) to the counts.

**The walker** (``hdl/span_unit/walker.py``), as the raster builds it one triangle at a time.
The harness is the setup: free triangles, held until taken, each tagged with its count, with
rows ``j0 .. j0 + to_j1`` on the screen unless culled or empty (the setup's row range; the
columns of each row are free, so the DDA's exactness is left to the simulations against the
edge-function model). Against the triangle walked, the rows visited and the row owed:

- ``rows_visited``, ``rows_all``: each row of a triangle is visited once, in order, all of
  them before the next triangle is taken; ``culled_count``: the culled triangles counted;
- ``on_screen``: a row goes out only with a pixel on the screen;
- ``held``, ``no_extra``, ``order`` (each row out is the last row visited with a pixel, of
  the triangle walked; ``order_kept``: none is overtaken, so none is lost), ``drain``.
**The setup** (``hdl/span_unit/setup_engine.py``), one triangle at a time: free triangles
in, a free ready out, every product a free value; ``held``, ``no_extra``, ``order`` and
``order_in`` (one at a time: a triangle is taken only once the last is out), ``drain`` (its
schedule's length), ``valid_next``; the invariants tie the schedule's phase bits and its
copies of its flags to the counts.

**The row engines** (``hdl/span_unit/row_engine.py``), both forms, and **the overlapped
setup's schedule** (``SetupSchedule``, the setup queue's producer): items held until taken, a
free credit; ``handshake`` and ``credit`` (an item starts exactly when taken, only on a
credit), ``interval`` (while a job is in flight, only a multiple of ``ii`` after the last
start), ``early`` (the row engine's carried values written at the start), ``order`` and
``drain`` (its last write exactly D clocks after each start), and, for the two that give
the queue its slots (the setup and the serial row engine), ``slot_*`` (each memory written
at its offset, at its item's slot); the invariants tie the schedule's phase bits to the
starts delayed, its slot counts to the clocks since the last start, and the copies of an
item's slot to the starts counted.

``python -m flows.parts [--only row_queue]``; ``make formal`` runs it too.
"""
import argparse
import functools
import json
import re

from amaranth.back import verilog
from amaranth.hdl import Fragment
from amaranth.lib import data

from hdl.dsp import soft_as_mul

from .sby import COUNT, OUT, keep_only, run_sby

PROVE_DEPTH = 8          # k of the proofs
MUTANT_DEPTH = 12        # the mutants' BMC: each breaks its property within a few clocks
COVER_DEPTH = 22         # the covers: a row of 16 pixels out, behind two others
DRAIN = 2                # clocks a fragment owed may wait with ready high (above)
SLOTS = 4                # the reference's rows owing fragments: the row in the stepper and
#                          up to two whose last fragments sit in the output register and skid
RASTER = {"screen_bits": 4, "channels": 1}
TAG = 5                  # the queues' tags: counts modulo 32, twice their 16 words
SETUP_II = 48            # the setup queue's raster: a triangle every 48 clocks
NARROW = 21              # the narrow row engine's mantissa bits
# parts on a schedule of products (the setup, the row engines): the products are free
# values, since no property reads one; a mutant shows once an item has been through (the
# clocks given here, and 5 more), a cover of two items out after two
SCHEDULED = {"setup": lambda part: part.end + 1,
             "row_engine": lambda part: part.offset,
             "row_engine_serial": lambda part: part.offset,
             "row_engine_narrow": lambda part: part.offset,
             "setup_schedule": lambda part: part.offset}

MUTANTS = {   # name: (what it breaks, the property that must catch it)
    "dropped": ("a fragment offered is taken and lost on its way out", "order"),
    "extra": ("a fragment that went out is offered again", "order"),
    "unstable": ("a stalled fragment's column changes", "held"),
    "stuck": ("the output stops offering fragments", "drain"),
    "overrun": ("the queue's space stays high: the engine starts rows it has no place for",
                "credit"),
    "lost_write": ("a row's last write into the queue is left out once", "drain"),
    "extra_write": ("a write into the queue comes with no row for it", "order"),
    "wrong_slot": ("a write into the queue at the next item's slot, once", "slot_"),
}
CHECKS = {"prove": ("prove", ("held", "no_extra", "order", "drain", "credit", "on_screen",
                             "rows_", "culled", "pending_", "valid_next", "handshake",
                             "early", "interval", "slot_", "inv_")),
          "cover": ("cover", None)}


def _raster(**knobs):
    """The raster at ``RASTER``'s size, elaborated whole (its parts are taken from it, so
    their layouts are the real ones; nothing is left unelaborated)."""
    from hdl.units import make_unit
    m = make_unit("raster", **RASTER, **knobs).elaborate(None)
    Fragment.get(m, None)
    return m


def stepper():
    """The stepper as the raster builds it at ``RASTER``'s size."""
    return _raster().submodules.stepper


def row_queue(serial=False):
    """The row queue as the raster builds it with either row engine."""
    return _raster(**({"row_serial": 1} if serial else {})).submodules.row_queue


@functools.lru_cache(maxsize=8)
def export(part, module):
    """The part's Verilog (once per part and name: every check of a part runs on it); soft
    products (the narrow multipliers' low bits) as ``$mul``, so that they are cut too."""
    with soft_as_mul():
        return verilog.convert(part, name=module, emit_src=False)


def _fields(layout):
    return {k: (f.offset, f.shape.width, f.shape.signed) for k, f in layout}


def stepper_harness(part, module, mutant=None, only=None):
    """The Verilog of ``formal_top``: the stepper as ``module``, its environment, the
    reference, the properties (``only``: those whose labels start with one of these), and
    ``mutant`` between the stepper's output and the harness."""
    rows, frags = _fields(part.i.payload.shape()), _fields(part.o.payload.shape())
    W, F = part.i.payload.shape().size, part.o.payload.shape().size
    sb = part.w.screen_bits
    X = sb + 2                           # columns 0 .. 2**sb, and their sums, unsigned
    sl = lambda fields, bus, k: f"{bus}[{fields[k][0] + fields[k][1] - 1}:{fields[k][0]}]"
    L = ["`default_nettype none", "module formal_top(input wire clk);",
         "  reg init = 1'b1;", "  always @(posedge clk) init <= 1'b0;", "  wire rst = init;",
         "  (* anyseq *) reg i_valid, o_ready, stop;",
         f"  (* anyseq *) reg [{W - 1}:0] free;",
         f"  wire [{W - 1}:0] i_payload;", "  wire i_ready, busy;",
         "  wire d_valid, d_ready;", f"  wire [{F - 1}:0] d_payload;",
         "  wire o_valid;", f"  wire [{F - 1}:0] o_payload;",
         f"  {module} dut (.clk(clk), .rst(rst), .i__valid(i_valid), .i__ready(i_ready), "
         ".i__payload(i_payload), .o__valid(d_valid), .o__ready(d_ready), "
         ".o__payload(d_payload), .busy(busy));",
         f"  reg [{COUNT - 1}:0] n_in = 0;",
         "  wire in_t = ~rst & i_valid & i_ready;",
         "  always @(posedge clk) if (!rst) n_in <= n_in + in_t;"]
    # the row: its span on the screen (columns 0 .. 2**sb), some and one as the row queue's
    # ``_outputs`` make them, tri = the rows accepted before it; the rest free
    xs, xe = (f"{sl(rows, 'free', k)}" for k in ("xs", "xe"))
    parts = {k: sl(rows, "free", k) for k in rows}
    parts.update(some=f"($signed({xs}) < $signed({xe}))",
                 one=f"($signed({xs}) + 1 == $signed({xe}))",
                 tri=f"{{{rows['tri'][1] - COUNT}'d0, n_in}}")
    order = sorted(rows, key=lambda k: -rows[k][0])
    L += [f"  assign i_payload = {{{', '.join(parts[k] for k in order)}}};",
          f"  always @* if (!rst) valid_row: assume($signed({xs}) >= 0 && "
          f"$signed({xe}) <= {1 << sb});",
          f"  reg [{W - 1}:0] past_in;", "  reg past_istall = 1'b0;",
          "  always @(posedge clk) begin past_istall <= ~rst & i_valid & ~i_ready; "
          "past_in <= free; end",
          "  always @* if (past_istall) in_held: assume(i_valid && free == past_in);"]
    L += mutated(mutant, F, frags["x"][0])
    # the reference: rows that owe fragments (tri, row, first and end column), and k, the
    # fragments of the first one already out
    R = SLOTS
    tri_w = rows["tri"][1]
    L += ["  wire out_t = ~rst & o_valid & o_ready;",
          *[f"  reg [{tri_w - 1}:0] q_tri{s}; reg [{rows['j'][1] - 1}:0] q_y{s}; "
            f"reg [{X - 1}:0] q_xs{s}, q_xe{s};" for s in range(R)],
          "  reg [2:0] q_n = 0;", f"  reg [{X - 1}:0] k = 0;",
          f"  wire [{X - 1}:0] in_xs = {xs}, in_xe = {xe};",
          f"  wire push = in_t & $signed({xs}) < $signed({xe});",
          f"  wire [{X - 1}:0] next_x = q_xs0 + k;",
          "  wire pop = out_t && next_x + 1 == q_xe0;",
          f"  wire [{tri_w - 1}:0] o_tri = {sl(frags, 'o_payload', 'tri')};",
          f"  wire [{frags['x'][1] - 1}:0] o_x = {sl(frags, 'o_payload', 'x')};",
          f"  wire [{frags['y'][1] - 1}:0] o_y = {sl(frags, 'o_payload', 'y')};",
          "  always @(posedge clk) if (rst) begin q_n <= 0; k <= 0; end else begin",
          "    k <= pop ? 0 : k + out_t;",
          "    q_n <= q_n + push - pop;"]
    for s in range(R):                   # shift out at a pop, the new row behind the rest
        nxt = s + 1
        keep = (f"q_tri{nxt}, q_y{nxt}, q_xs{nxt}, q_xe{nxt}" if nxt < R else None)
        L += [f"    if (push && q_n - pop == {s}) begin q_tri{s} <= {{{tri_w - COUNT}'d0, n_in}}; "
              f"q_y{s} <= {sl(rows, 'free', 'j')}; q_xs{s} <= in_xs; q_xe{s} <= in_xe; end"]
        if keep:
            L += [f"    else if (pop) begin q_tri{s} <= q_tri{nxt}; q_y{s} <= q_y{nxt}; "
                  f"q_xs{s} <= q_xs{nxt}; q_xe{s} <= q_xe{nxt}; end"]
    L += ["  end"]
    L += _invariants(rows, frags, X, R)
    L += [f"  reg [{F - 1}:0] past_out;", "  reg past_ostall = 1'b0;",
          "  always @(posedge clk) begin past_ostall <= ~rst & o_valid & ~o_ready; "
          "past_out <= o_payload; end",
          "  reg [3:0] wait_n = 0;",
          "  always @(posedge clk) wait_n <= (~rst & q_n != 0 & o_ready & ~out_t) ? "
          "wait_n + 1 : 0;",
          "  always @* if (!rst) begin",
          "    if (past_ostall) begin held: assert(o_valid);",
          "      held_payload: assert(o_payload == past_out); end",
          f"    no_extra_slots: assert(q_n <= {R});",
          "    if (out_t) no_extra: assert(q_n != 0);",
          f"    if (out_t) order: assert(o_tri == q_tri0 && o_y == q_y0[{frags['y'][1] - 1}:0] "
          f"&& o_x == next_x[{frags['x'][1] - 1}:0]);",
          f"    drain: assert(wait_n <= {DRAIN});",
          "    c_row: cover(pop && q_tri0 == 2);",
          "    c_stall: cover(past_ostall && o_ready);",
          "    c_long: cover(pop && q_xe0 - q_xs0 == 16);",
          "  end", "endmodule"]
    return keep_only("\n".join(L) + "\n", only)


def mutated(mutant, F, flip):
    """The stream from the part (``d_*``) to the harness (``o_*``), with ``mutant`` between
    (``F``: the payload's width; ``flip``: the payload bit the unstable mutant flips)."""
    if mutant is None:
        return ["  assign o_valid = d_valid, o_payload = d_payload, d_ready = o_ready;"]
    if mutant == "dropped":            # once: an item taken from the part, not shown
        return ["  reg used = 1'b0;", "  wire now = stop & ~used & d_valid;",
                "  always @(posedge clk) if (now) used <= 1'b1;",
                "  assign o_valid = d_valid & ~now, o_payload = d_payload, "
                "d_ready = o_ready | now;"]
    if mutant == "extra":              # once: an item that went out is offered again
        return ["  reg used = 1'b0, again = 1'b0;", f"  reg [{F - 1}:0] last;",
                "  always @(posedge clk) begin again <= 1'b0;",
                "    if (!used & stop & d_valid & o_ready) begin again <= 1'b1; "
                "used <= 1'b1; last <= d_payload; end",
                "    if (again & ~o_ready) again <= 1'b1; end",
                "  assign o_valid = again | d_valid, o_payload = again ? last : d_payload, "
                "d_ready = o_ready & ~again;"]
    if mutant == "unstable":           # once: a stalled item's bit ``flip`` flips
        return [f"  assign o_valid = d_valid, o_payload = d_payload ^ "
                f"((stop & d_valid & ~o_ready) ? {F}'d{1 << flip} : {F}'d0), "
                "d_ready = o_ready;"]
    if mutant == "stuck":              # from a clock the solver picks, nothing goes out
        return ["  reg dead = 1'b0;", "  always @(posedge clk) if (stop) dead <= 1'b1;",
                "  assign o_valid = d_valid & ~dead, o_payload = d_payload, "
                "d_ready = o_ready & ~dead;"]
    raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")


def _invariants(rows, frags, X, R):
    """What makes the safety properties inductive: the stepper's state (its output register,
    skid and current row, read from the flattened design by ``sby_text``'s connects, ``s_*``)
    is the reference's next owed fragments, in order. F0 is the first owed (row 0 at column
    ``next_x``), F1 and F2 each the one after (the next column, or the next row's first)."""
    t, y = rows["tri"][1], frags["y"][1]
    row = lambda f, r: f"(({r}) == 0 ? q_{f}0 : ({r}) == 1 ? q_{f}1 : q_{f}2)"
    after = "r1 + 2'd1"
    L = ["  (* keep *) wire s_cur, s_last, s_skid;",
         f"  (* keep *) wire [{t - 1}:0] s_tri, s_skid_tri;",
         f"  (* keep *) wire [{X - 2}:0] s_x, s_xe;",
         f"  (* keep *) wire [{frags['x'][1] - 1}:0] s_skid_x;",
         f"  (* keep *) wire [{y - 1}:0] s_y, s_skid_y;",
         f"  wire [{X - 1}:0] c0 = next_x;", "  wire adv0 = c0 + 1 == q_xe0;",
         "  wire [1:0] r1 = adv0 ? 2'd1 : 2'd0;",
         f"  wire [{X - 1}:0] c1 = adv0 ? q_xs1 : c0 + 1;",
         f"  wire adv1 = c1 + 1 == {row('xe', 'r1')};",
         "  wire [1:0] r2 = adv1 ? r1 + 2'd1 : r1;",
         f"  wire [{X - 1}:0] c2 = adv1 ? {row('xs', after)} : c1 + 1;",
         "  wire [1:0] m = o_valid + s_skid;",
         "  wire [1:0] rm = m == 0 ? 2'd0 : m == 1 ? r1 : r2;",
         f"  wire [{X - 1}:0] cm = m == 0 ? c0 : m == 1 ? c1 : c2;",
         *[f"  wire [{w - 1}:0] {f}_{r} = {row(f, r)};" for f, w in
           (("tri", t), ("y", rows["j"][1]), ("xe", X)) for r in ("r1", "rm")],
         "  always @* if (!rst) begin",
         f"    inv_slots: assert(q_n <= 3 && (q_n == 0 ? k == 0 : k < q_xe0 - q_xs0));",
         *[f"    if (q_n > {s}) inv_row{s}: assert(q_xs{s} < q_xe{s} && q_xe{s} <= {1 << (X - 2)});"
           for s in range(R)],
         f"    if (o_valid) inv_o: assert(q_n != 0 && o_tri == q_tri0 && o_y == q_y0[{y - 1}:0] "
         f"&& o_x == c0[{frags['x'][1] - 1}:0]);",
         "    if (s_skid) inv_skid: assert(o_valid && (r1 < q_n) && "
         f"s_skid_tri == tri_r1 && s_skid_y == y_r1[{y - 1}:0] && "
         f"s_skid_x == c1[{frags['x'][1] - 1}:0]);",
         "    if (s_cur) inv_cur: assert(q_n == rm + 1 && "
         f"s_tri == tri_rm && s_y == y_rm[{y - 1}:0] && "
         f"s_x == cm[{X - 2}:0] && s_xe == xe_rm[{X - 2}:0] && s_last == (cm + 1 == xe_rm));",
         "    if (!s_cur) inv_idle: assert(q_n == (m == 0 ? 0 : m == 1 ? 1 : r1 + 1) && "
         "(m == 0 || (m == 1 ? adv0 : adv1)));",
         "    if (!o_valid) inv_empty: assert(!s_skid);",
         "  end"]
    return L


WIRES = [("s_cur", "st_cur"), ("s_last", "st_last"), ("s_skid", "st_skid_valid"),
         ("s_tri", "st_tri"), ("s_skid_tri", "st_skid_tri"), ("s_x", "st_x"),
         ("s_xe", "st_xe"), ("s_skid_x", "st_skid_x"), ("s_y", "st_y"),
         ("s_skid_y", "st_skid_y")]


class _Mem:
    """A memory of the queue under proof, as the harness writes and reads it: its name, the
    width of its word, whether the producer gives its slot, whether it is written at an
    item's start (the row engine's early memory) or with its last write, whether it is read
    at the slot last taken (``current``), and its offset in the stream or the current port."""

    def __init__(self, name, width, slotted, early, current, at):
        self.name, self.width, self.slotted, self.early = name, width, slotted, early
        self.current, self.at = current, at


def _queue_memories(part):
    out, at = [], {False: 0, True: 0}
    for name, (fields, slotted, current) in part.memories.items():
        width = data.StructLayout(fields).size
        out.append(_Mem(name, width, slotted, name == "early", current, at[current]))
        at[current] += width
    return out


def queue_harness(part, module, mutant=None, only=None):
    """The Verilog of ``formal_top``: the queue as ``module``, the producer that writes it
    (module docstring), the counts, the properties and their invariants, and ``mutant``
    between the queue's output and the harness."""
    F = part.o.payload.shape().size
    mems = _queue_memories(part)
    held = [x for x in mems if x.current]
    H = sum(x.width for x in held)
    D, T = part.depth, TAG
    ports = "".join(f", .{x.name}__en({x.name}_en), .{x.name}__data({x.name}_data)"
                    + (f", .{x.name}__addr({x.name}_addr)" if x.slotted else "")
                    for x in mems)
    ports += ", .current(current)" if held else ""
    L = ["`default_nettype none", "module formal_top(input wire clk);",
         "  reg init = 1'b1;", "  always @(posedge clk) init <= 1'b0;", "  wire rst = init;",
         "  (* anyseq *) reg start, written, o_ready, stop;",
         "  wire space, d_space, d_valid, d_ready, o_valid_next, pending;",
         f"  wire [{F - 1}:0] d_payload;",
         *([f"  wire [{H - 1}:0] current;"] if held else []),
         "  assign space = " + ("1'b1;" if mutant == "overrun" else "d_space;"),
         "  wire o_valid;", f"  wire [{F - 1}:0] o_payload;",
         f"  reg [{COUNT - 1}:0] n_st = 0, n_wr = 0, n_out = 0;", "  reg any_out = 1'b0;",
         "  wire st_t = ~rst & start, wr_t = ~rst & written;",
         "  wire out_t = ~rst & o_valid & o_ready;",
         # the producer: an item starts only on a credit; its last write follows its start
         "  always @* if (!rst) begin env_start: assume(!start || space); "
         "env_written: assume(!written || n_wr != n_st); end",
         "  always @(posedge clk) if (rst) begin n_st <= 0; n_wr <= 0; n_out <= 0; "
         "any_out <= 0; end else begin n_st <= n_st + st_t; n_wr <= n_wr + wr_t; "
         "n_out <= n_out + out_t; any_out <= any_out | out_t; end"]
    for x in mems:                      # the tag in a word's low bits, the rest free
        count = "n_st" if x.early else "n_wr"
        L += [f"  (* anyseq *) reg [{x.width - 1}:0] {x.name}_free;",
              f"  wire {x.name}_en = {'st_t' if x.early else 'wr_t'};",
              f"  wire [{x.width - 1}:0] {x.name}_data = {{{x.name}_free[{x.width - 1}:{T}], "
              f"{count}[{T - 1}:0]}};"]
        if x.slotted:
            L += [f"  wire [3:0] {x.name}_addr = {count}[3:0];"]
    L += [f"  {module} dut (.clk(clk), .rst(rst), .start(st_t), .written(wr_t), "
          f".space(d_space), .o_valid_next(o_valid_next), .pending(pending){ports}, "
          ".o__valid(d_valid), .o__ready(d_ready), .o__payload(d_payload));"]
    streamed = [x for x in mems if not x.current]
    L += mutated(None if mutant == "overrun" else mutant, F, streamed[0].at)
    L += [f"  reg [{F - 1}:0] past_out;", "  reg past_ostall = 1'b0, past_vn = 1'b0;",
          "  always @(posedge clk) begin past_ostall <= ~rst & o_valid & ~o_ready; "
          "past_out <= o_payload; past_vn <= ~rst & o_valid_next; end",
          f"  wire [{COUNT - 1}:0] n_held = n_st - n_out, n_level = n_wr - n_out;",
          "  reg [3:0] wait_n = 0;",
          "  always @(posedge clk) wait_n <= (~rst & n_level != 0 & o_ready & ~out_t) ? "
          "wait_n + 1 : 0;",
          "  always @* if (!rst) begin",
          "    if (past_ostall) begin held: assert(o_valid);",
          "      held_payload: assert(o_payload == past_out); end",
          f"    credit: assert(n_held <= {D});",
          "    pending_count: assert(pending == (n_held != 0));",
          "    valid_next: assert(d_valid == past_vn);",
          "    if (out_t) no_extra: assert(n_level != 0);",
          *[f"    if (out_t) order_{x.name}: assert(o_payload[{x.at + T - 1}:{x.at}] == "
            f"n_out[{T - 1}:0]);" for x in streamed],
          *[f"    if (any_out) order_current_{x.name}: assert(current[{x.at + T - 1}:{x.at}] "
            f"== n_out[{T - 1}:0] - 1'b1);" for x in held],
          "    drain: assert(wait_n <= 1);",
          f"    c_full: cover(n_held == {D});",
          "    c_wrap: cover(out_t && n_out == 17);",
          "    c_stall: cover(past_ostall && o_ready);",
          "  end"]
    # invariants: the queue's counts and pointers are the harness's; every word of a memory
    # that an item started (or written) and not taken owns holds that item's tag, and a
    # current memory's word at the slot last taken holds the tag of the item taken last
    L += [f"  (* keep *) wire [{D.bit_length() - 1}:0] s_level, s_held;",
          "  (* keep *) wire s_valid;",
          "  (* keep *) wire [3:0] s_rptr;",
          *(["  (* keep *) wire [3:0] s_cur;"] if held else []),
          *[f"  (* keep *) wire [3:0] s_wptr_{x.name};" for x in mems if not x.slotted],
          *[f"  (* keep *) wire [{x.width - 1}:0] s_{x.name}_{a};" for x in mems
            for a in range(16)],
          "  always @* if (!rst) begin",
          "    inv_counts: assert(s_level == n_level && s_held == n_held "
          "&& n_level <= n_held && s_rptr == n_out[3:0]);",
          f"    inv_flags: assert(s_valid == (n_level != 0) && space == (n_held < {D}));",
          *[f"    inv_wptr_{x.name}: assert(s_wptr_{x.name} == "
            f"{'n_st' if x.early else 'n_wr'}[3:0]);" for x in mems if not x.slotted]]
    if held:
        L += ["    if (any_out) inv_cur: assert(s_cur == n_out[3:0] - 1'b1);"]
    for x in mems:
        owned = "n_held" if x.early else "n_level"
        for a in range(16):
            i = f"4'd{a} - n_out[3:0]"
            L += [f"    if ({{{COUNT - 4}'d0, {i}}} < {owned}) inv_{x.name}_{a}: "
                  f"assert(s_{x.name}_{a}[{T - 1}:0] == n_out[{T - 1}:0] + {{1'b0, {i}}});"]
            if x.current:
                L += [f"    if (any_out && {i} == 4'd15) inv_{x.name}_{a}_cur: "
                      f"assert(s_{x.name}_{a}[{T - 1}:0] == n_out[{T - 1}:0] - 1'b1);"]
    L += ["  end", "endmodule"]
    return keep_only("\n".join(L) + "\n", only)


def queue_wires(part):
    """The queue's registers and memory words the invariants read (``s_*``)."""
    mems, n = _queue_memories(part), part.name
    return ([("s_level", f"{n}_level"), ("s_held", f"{n}_held"), ("s_valid", f"{n}_valid"),
             ("s_rptr", f"{n}_rptr")]
            + ([("s_cur", f"{n}_cur")] if any(x.current for x in mems) else [])
            + [(f"s_wptr_{x.name}", f"{x.name}_wptr") for x in mems if not x.slotted]
            + [(f"s_{x.name}_{a}", f"mem_{x.name}[{a}]") for x in mems for a in range(16)])


def setup_queue():
    """The setup queue as the raster builds it with an overlapped setup."""
    setup = _raster(setup_ii=SETUP_II).submodules.setup.elaborate(None)
    Fragment.get(setup, None)
    return setup.submodules.setup_queue


def walker():
    """The walker as the raster builds it at ``RASTER``'s size (one triangle at a time: it
    holds the triangle's constants)."""
    return _raster().submodules.walker


def _copies(part):
    """The walker's copies of its state machine (``control(k)`` in walker.py), from its
    Verilog."""
    text = export(part, "f_walker")
    return sorted(set(re.findall(r"\bw_full(\w+)\b", text)) - {"0"})


def _members(port, names):
    """The walker's fields of a triangle or a row, laid out one after another as a bus of
    the harness."""
    out, at = {}, 0
    for k in names:
        shape = getattr(port, k).shape()
        out[k] = (at, shape.width, shape.signed)
        at += shape.width
    return out


def walker_harness(part, module, mutant=None, only=None):
    """The Verilog of ``formal_top``: the walker as ``module``; free triangles from a setup
    that keeps its valid and payload until they are taken (the valid the register of the
    early one), each tagged ``tri`` with its count, with rows ``j0 .. j0 + to_j1`` on the
    screen unless culled or empty; the reference (the triangle walked, the rows visited, the
    row owed); the properties and their invariants; ``mutant`` on the rows' stream."""
    ins, rows = _members(part.i, part.inputs), _members(part.o, part.outputs)
    W, F = (sum(w for _, w, _ in x.values()) for x in (ins, rows))
    sl = lambda fields, bus, k: f"{bus}[{fields[k][0] + fields[k][1] - 1}:{fields[k][0]}]"
    size = 1 << part.w.screen_bits
    C = COUNT
    L = ["`default_nettype none", "module formal_top(input wire clk);",
         "  reg init = 1'b1;", "  always @(posedge clk) init <= 1'b0;", "  wire rst = init;",
         "  (* anyseq *) reg i_valid_next, o_ready, stop;",
         f"  (* anyseq *) reg [{W - 1}:0] free;",
         "  reg i_valid = 1'b0;", "  always @(posedge clk) i_valid <= ~rst & i_valid_next;",
         f"  wire [{W - 1}:0] i_payload;", "  wire i_ready, busy;", "  wire [31:0] culled;",
         "  wire d_valid, d_ready;", f"  wire [{F - 1}:0] d_payload;",
         "  wire o_valid;", f"  wire [{F - 1}:0] o_payload;",
         f"  {module} dut (.clk(clk), .rst(rst), .i__valid(i_valid), .i__ready(i_ready), "
         ".i_valid_next(i_valid_next), "
         + "".join(f".i__{k}({sl(ins, 'i_payload', k)}), " for k in ins)
         + "".join(f".o__{k}({sl(rows, 'd_payload', k)}), " for k in rows)
         + ".o__valid(d_valid), .o__ready(d_ready), .culled(culled), .busy(busy));",
         f"  reg [{C - 1}:0] n_in = 0, n_cull = 0;",
         "  wire in_t = ~rst & i_valid & i_ready;",
         f"  wire [{ins['to_j1'][1] - 1}:0] f_to_j1 = {sl(ins, 'free', 'to_j1')};",
         f"  wire [{ins['to_jm'][1] - 1}:0] f_to_jm = {sl(ins, 'free', 'to_jm')};",
         f"  wire [{ins['j0'][1] - 1}:0] f_j0 = {sl(ins, 'free', 'j0')};",
         f"  wire f_rows = {sl(ins, 'free', 'rows')}, f_cull = {sl(ins, 'free', 'cull')};"]
    parts = {k: sl(ins, "free", k) for k in ins}
    parts.update(tri=f"{{{ins['tri'][1] - C}'d0, n_in}}", last0="(f_to_j1 == 0)",
                 at_jm0="(f_to_jm == 0)")
    order = sorted(ins, key=lambda k: -ins[k][0])
    L += [f"  assign i_payload = {{{', '.join(parts[k] for k in order)}}};",
          # the setup's triangles: rows j0 .. j0 + to_j1 on the screen, none if culled
          "  always @* if (!rst && i_valid) valid_tri: assume(!f_rows || (!f_cull && "
          f"$signed(f_j0) >= 0 && $signed(f_to_j1) >= 0 && $signed(f_j0) + $signed(f_to_j1) "
          f"< {size + 1}));",
          f"  reg [{W - 1}:0] past_in;", "  reg past_istall = 1'b0;",
          "  always @(posedge clk) begin past_istall <= ~rst & i_valid & ~i_ready; "
          "past_in <= free; end",
          "  always @* if (past_istall) in_held: assume(i_valid && free == past_in);",
          "  always @(posedge clk) if (!rst) begin n_in <= n_in + in_t; "
          "n_cull <= n_cull + (in_t & f_cull); end"]
    L += mutated(mutant, F, rows["j"][0])
    # the reference: the triangle walked (its tag, rows, first row, rows - 1), the rows
    # visited (k, from the walker's accept), and the row owed: visited, with pixels on the
    # screen (the walker's own test, a clock after its visit), not yet out
    jw = rows["j"][1]
    L += ["  (* keep *) wire s_have, s_full, s_load, s_accept, s_last, s_some;",
          f"  (* keep *) wire [{jw - 1}:0] s_j, s_buf_j;",
          f"  (* keep *) wire [{jw}:0] s_to_j1;",
          f"  (* keep *) wire [{rows['xl'][1] - 1}:0] s_buf_xl, s_buf_xr;",
          f"  (* keep *) wire [{rows['tri'][1] - 1}:0] s_tri;",
          "  wire out_t = ~rst & o_valid & o_ready;",
          f"  reg [{C - 1}:0] r_tri = 0; reg r_rows = 1'b0, any_in = 1'b0;",
          f"  reg [{jw}:0] r_j0 = 0, r_n = 0, k = 0;",
          f"  reg owed = 1'b0, visited = 1'b0; reg [{jw - 1}:0] owed_j = 0;",
          "  wire push = visited & s_some, owing = owed | push;",
          f"  wire [{jw - 1}:0] owing_j = owed ? owed_j : s_buf_j;",
          "  always @(posedge clk) if (rst) begin r_rows <= 0; k <= 0; owed <= 0; "
          "visited <= 0; any_in <= 0; end else begin",
          "    visited <= s_accept; any_in <= any_in | in_t;",
          f"    if (in_t) begin r_tri <= n_in; r_rows <= f_rows; r_j0 <= f_j0[{jw}:0]; "
          f"r_n <= f_to_j1[{jw}:0]; k <= 0; end",
          "    else k <= k + s_accept;",
          "    if (out_t) owed <= 1'b0;",
          "    else if (push) begin owed <= 1'b1; owed_j <= s_buf_j; end",
          "  end",
          f"  reg [{F - 1}:0] past_out;", "  reg past_ostall = 1'b0;",
          "  always @(posedge clk) begin past_ostall <= ~rst & o_valid & ~o_ready; "
          "past_out <= o_payload; end",
          "  reg [3:0] wait_n = 0;",
          "  always @(posedge clk) wait_n <= (~rst & (owing | s_have) & o_ready & ~out_t & "
          "~s_accept) ? wait_n + 1 : 0;",
          f"  wire [{jw - 1}:0] o_j = {sl(rows, 'o_payload', 'j')};",
          f"  wire [{rows['xl'][1] - 1}:0] o_xl = {sl(rows, 'o_payload', 'xl')}, "
          f"o_xr = {sl(rows, 'o_payload', 'xr')};",
          f"  wire [{rows['tri'][1] - 1}:0] o_tri = {sl(rows, 'o_payload', 'tri')};",
          "  always @* if (!rst) begin",
          "    if (past_ostall) begin held: assert(o_valid);",
          "      held_payload: assert(o_payload == past_out); end",
          "    if (out_t) no_extra: assert(r_rows && any_in);",
          f"    if (out_t) order: assert(owing && o_j == owing_j && "
          f"o_tri == {{{rows['tri'][1] - C}'d0, r_tri}});",
          "    if (push) order_kept: assert(!owed);",
          f"    if (out_t) on_screen: assert($signed(o_xl) < $signed(o_xr) && $signed(o_xr) > 0 "
          f"&& $signed(o_xl) < {size});",
          "    if (s_accept) rows_visited: assert(r_rows && k <= r_n && s_j == r_j0 + k);",
          "    if (in_t && any_in) rows_all: assert(!r_rows || k == r_n + 1);",
          f"    culled_count: assert(culled[{C - 1}:0] == n_cull);",
          "    drain: assert(wait_n <= 2);",
          "    c_rows: cover(out_t && o_tri == 2 && o_j == r_j0 + 2);",
          "    c_stall: cover(past_ostall && o_ready);",
          "    c_skip: cover(visited && !s_some && s_have);",
          "  end"]
    # invariants: the copies agree; load and accept are the handshakes they stand for; the
    # walker's row counters are the reference's; the buffer holds the last row visited
    L += [f"  (* keep *) wire s_{x}_{c};" for c in _copies(part) for x in
          ("have", "full", "load", "accept")]
    L += ["  always @* if (!rst) begin",
          *[f"    inv_copy_{c}: assert(s_have_{c} == s_have && s_full_{c} == s_full && "
            f"s_load_{c} == s_load && s_accept_{c} == s_accept);" for c in _copies(part)],
          "    inv_load: assert(s_load == (i_valid & i_ready) && i_ready == (~s_have & ~s_full));",
          "    inv_accept: assert(s_accept == (s_have & ~s_full) && busy == s_have);",
          "    inv_visited: assert(visited == 0 || (s_full && k != 0));",
          "    if (s_have) inv_have: assert(r_rows && any_in && k <= r_n && s_j == r_j0 + k "
          "&& s_to_j1 == r_n - k && s_last == (k == r_n));",
          f"    if (r_rows) inv_rows: assert(any_in && r_j0 + r_n < {size + 1});",
          "    if (!s_have) inv_idle: assert(!any_in || !r_rows || k == r_n + 1);",
          "    if (s_full) inv_full: assert(r_rows && k != 0 && s_buf_j == r_j0 + k - 1 && "
          f"s_some == ($signed(s_buf_xl) < $signed(s_buf_xr) && $signed(s_buf_xr) > 0 && "
          f"$signed(s_buf_xl) < {size}) && s_tri == {{{rows['tri'][1] - C}'d0, r_tri}});",
          "    inv_owed: assert(owed == (s_full && s_some && !visited) && "
          "(!owed || owed_j == s_buf_j) && o_valid == (s_full && s_some));",
          "  end", "endmodule"]
    return keep_only("\n".join(L) + "\n", only)


def walker_wires(part):
    return ([("s_have", "busy"), ("s_full", "w_full0"), ("s_load", "w_load0"),
             ("s_accept", "w_accept0"), ("s_last", "w_last"), ("s_some", "wb_some"),
             ("s_j", "j"), ("s_buf_j", "wb_j"), ("s_to_j1", "w_to_j1"),
             ("s_buf_xl", "wb_xl"), ("s_buf_xr", "wb_xr"), ("s_tri", "w_tri")]
            + [(f"s_{x}_{c}", f"w_{x}{c}") for c in _copies(part)
               for x in ("have", "full", "load", "accept")])


def setup():
    """The setup as the raster builds it at ``RASTER``'s size, one triangle at a time."""
    return _raster().submodules.setup


def setup_harness(part, module, mutant=None, only=None):
    """The Verilog of ``formal_top``: the setup as ``module``, free triangles in (the setup
    captures a triangle as it starts, so they need not be held), a free ready out; against
    the counts of triangles in and out: ``held``, ``no_extra``, ``order`` (each triangle out
    has the index of the next one owed: ``tri``, the setup's own count of triangles in, so
    none is made, lost, repeated or reordered), ``drain`` (a triangle in is out within
    ``end + 1`` clocks of ready held high: its schedule, then its output register) and
    ``valid_next`` (the valid is the register of the early one). Invariants: at most one
    job's phase bit is set, and the job runs exactly while one is; the copies of the
    setup's state agree; a job in flight is the triangle owed, and has waited no longer than
    its phase."""
    outs = _members(part.o, part.fields)
    F = sum(w for _, w, _ in outs.values())
    P = part.i.payload.shape().size
    end, C = part.end, COUNT
    sl = lambda k: f"o_payload[{outs[k][0] + outs[k][1] - 1}:{outs[k][0]}]"
    n_idle, n_run = _state_copies(part)
    L = ["`default_nettype none", "module formal_top(input wire clk);",
         "  reg init = 1'b1;", "  always @(posedge clk) init <= 1'b0;", "  wire rst = init;",
         "  (* anyseq *) reg i_valid, o_ready, stop;", f"  (* anyseq *) reg [{P - 1}:0] free;",
         "  wire i_ready, busy, vn, d_valid, d_ready, o_valid;",
         f"  wire [{F - 1}:0] d_payload, o_payload;",
         f"  {module} dut (.clk(clk), .rst(rst), .i__valid(i_valid), .i__ready(i_ready), "
         ".i__payload(free), "
         + "".join(f".o__{k}(d_payload[{outs[k][0] + outs[k][1] - 1}:{outs[k][0]}]), "
                   for k in outs)
         + ".o__valid(d_valid), .o__ready(d_ready), .o_valid_next(vn), .busy(busy));"]
    L += mutated(mutant, F, outs["tri"][0])
    L += [f"  reg [{C - 1}:0] n_in = 0, n_out = 0;",
          "  wire in_t = ~rst & i_valid & i_ready, out_t = ~rst & o_valid & o_ready;",
          "  always @(posedge clk) if (!rst) begin n_in <= n_in + in_t; "
          "n_out <= n_out + out_t; end",
          f"  reg [{F - 1}:0] past_out;", "  reg past_ostall = 1'b0, past_vn = 1'b0;",
          "  always @(posedge clk) begin past_ostall <= ~rst & o_valid & ~o_ready; "
          "past_out <= o_payload; past_vn <= ~rst & vn; end",
          "  wire owed = n_in != n_out;",
          "  reg [7:0] wait_n = 0;",
          "  always @(posedge clk) wait_n <= (~rst & owed & o_ready & ~out_t) ? wait_n + 1 : 0;",
          f"  wire [{outs['tri'][1] - 1}:0] o_tri = {sl('tri')};",
          "  always @* if (!rst) begin",
          "    if (past_ostall) begin held: assert(o_valid);",
          "      held_payload: assert(o_payload == past_out); end",
          "    if (out_t) no_extra: assert(owed);",
          f"    if (out_t) order: assert(o_tri[{C - 1}:0] == n_out);",    # counts modulo 2^C
          # one at a time: a triangle is taken only once the last is out, so the next out
          # is the next owed (a triangle dropped on its way out shows here)
          "    if (in_t) order_in: assert(!owed);",
          f"    drain: assert(wait_n <= {end + 1});",
          "    valid_next: assert(d_valid == past_vn);",
          "    c_two: cover(out_t && n_out == 1);",          # a second triangle through
          "    c_stall: cover(past_ostall && o_ready);",
          "  end"]
    # invariants: the phase bits (one job at most, running while one is set), the copies,
    # the job in flight owed and its wait bounded by its phase
    ph = [f"s_ph{k}" for k in range(1, end + 1)]
    L += [f"  (* keep *) wire {', '.join(ph)};",
          "  (* keep *) wire s_done;",
          f"  (* keep *) wire [{outs['tri'][1] - 1}:0] s_count;",
          *[f"  (* keep *) wire s_idle{k};" for k in range(n_idle)],
          *[f"  (* keep *) wire s_running{k};" for k in range(n_run)],
          f"  wire [{end - 1}:0] phases = {{{', '.join(reversed(ph))}}};",
          "  wire job = |phases;",
          "  always @* if (!rst) begin",
          "    inv_one: assert((phases & (phases - 1)) == 0);",
          "    inv_run: assert(s_running0 == job && !(job && s_done));",
          *[f"    inv_run{k}: assert(s_running{k} == s_running0);" for k in range(1, n_run)],
          *[f"    inv_idle{k}: assert(s_idle{k} == (!job && !s_done));" for k in range(n_idle)],
          "    inv_done: assert(d_valid == s_done && busy == (job || s_done));",
          f"    inv_count: assert(s_count[{C - 1}:0] == n_in && "
          f"n_in - n_out == {{{C - 1}'d0, job || s_done}});",
          f"    if (job || s_done) inv_tri: assert(d_payload[{outs['tri'][0] + C - 1}:"
          f"{outs['tri'][0]}] == n_out);",
          "    if (!job && !s_done) inv_wait_idle: assert(wait_n == 0);",
          f"    if (s_done) inv_wait_done: assert(wait_n <= {end});",
          *[f"    if (s_ph{k}) inv_wait{k}: assert(wait_n <= {k - 1});"
            for k in range(1, end + 1)],
          "  end", "endmodule"]
    return keep_only("\n".join(L) + "\n", only)


def _state_copies(part):
    """How many copies of the setup's idle and running flags it has (its Verilog)."""
    text = export(part, "f_setup")
    return (len(set(re.findall(r"\bsu_idle(\d+)\b", text))),
            len(set(re.findall(r"\bsu_running(\d+)\b", text))))


def setup_wires(part):
    n_idle, n_run = _state_copies(part)
    return ([(f"s_ph{k}", f"su_ph{k}") for k in range(1, part.end + 1)]
            + [("s_done", "done"), ("s_count", "su_tri")]
            + [(f"s_idle{k}", f"su_idle{k}") for k in range(n_idle)]
            + [(f"s_running{k}", f"su_running{k}") for k in range(n_run)])


def row_engine(serial=False):
    """The row engine as the raster builds it at ``RASTER``'s size (one channel: the serial
    engine's row is then one job)."""
    return _raster(**({"row_serial": 1} if serial else {})).submodules.row_engine


def row_engine_narrow():
    """The narrow row engine (block floating point) as the raster builds it with
    ``row_narrow=NARROW``: the same schedule, on M-bit multipliers and their shifters."""
    return _raster(row_narrow=NARROW).submodules.row_engine.narrow


def setup_schedule():
    """The overlapped setup's schedule (``SetupSchedule``, the setup queue's producer) as the
    raster builds it with ``setup_ii=SETUP_II``."""
    setup = _raster(setup_ii=SETUP_II).submodules.setup.elaborate(None)
    Fragment.get(setup, None)
    return setup.submodules.schedule


def _module(part):
    """The name a scheduled part's Verilog is read under for its state's names."""
    return "f_setup_schedule" if hasattr(part, "consts") else "f_row_engine"


def _phases(part):
    """The prefix of a scheduled part's schedule (its phase bits ``<prefix>_ph<k>``)."""
    text = export(part, _module(part))
    return next(p for p in ("re", "rs", "su") if re.search(rf"\b{p}_ph1\b", text))


def _engine_ports(part):
    """The part's input port connections to ``free`` and their width: the walker's rows (a
    member per field) or the setup's triangles (a stream's payload)."""
    if not hasattr(part, "rows"):
        return [".i__payload(free)"], part.i.payload.shape().size
    at, conn = 0, []
    for k in part.rows:
        width = getattr(part.i, k).shape().width
        conn.append(f".i__{k}(free[{at + width - 1}:{at}])")
        at += width
    return conn, at


def row_engine_harness(part, module, mutant=None, only=None):
    """The Verilog of ``formal_top``: a scheduled producer of a queue as ``module``, the row
    engine (rows from the walker) or the overlapped setup (triangles), its items free but
    held until taken (the walker's ``held``, proven; the stream contract), the queue's
    credit (``space``) free. Against a reference of its starts delayed by its write's
    offset D:

    - ``handshake``: an item is started exactly when one is taken; ``credit``: only on a
      credit; ``interval``: while a job is in flight, only a multiple of ``ii`` clocks after
      the last start (so the jobs' products never collide);
    - ``early``: what a row only carries is written as it starts (the row engine);
    - ``order``: the last write comes only D clocks after a start; ``drain``: D clocks after
      each start, it comes. So each item started is written once, in order, and never late.

    The invariants: the schedule's phase bits are the starts delayed; its slot counts are
    the clocks since the last start modulo ``ii``; ``aligned`` and ``inflight`` follow."""
    conn, W = _engine_ports(part)
    D, C, ii, L = part.offset, COUNT, part.ii, part.length
    H = max(D, L - 1)                              # the starts remembered
    early = "early" in part.memories
    L_ = ["`default_nettype none", "module formal_top(input wire clk);",
          "  reg init = 1'b1;", "  always @(posedge clk) init <= 1'b0;", "  wire rst = init;",
          "  (* anyseq *) reg i_valid, space, stop;", f"  (* anyseq *) reg [{W - 1}:0] free;",
          "  wire i_ready, started, d_written, busy" + (", early_en;" if early else ";"),
          f"  reg [{W - 1}:0] past_in;", "  reg past_istall = 1'b0, dead = 1'b0, used = 1'b0;",
          "  always @(posedge clk) begin past_istall <= ~rst & i_valid & ~i_ready; "
          "past_in <= free; end",
          "  always @* if (past_istall) in_held: assume(i_valid && free == past_in);",
          "  always @(posedge clk) if (stop) dead <= 1'b1;"]
    # the mutants: the engine sees the queue's space high once stopped (overrun); a last
    # write left out, or one added, once
    dut_space = "space | dead" if mutant == "overrun" else "space"
    slotted = part.offsets                        # the memories written at a given slot
    conn += [(f".{g}__en({g}_en), " if g != "early" else "") + f".{g}__addr({g}_addr)"
             for g in slotted]
    L_ += [(f"  wire {g}_en;" if g != "early" else "") + f" wire [3:0] {g}_addr;"
           for g in slotted]
    if mutant == "wrong_slot":                    # the harness sees the first memory's
        g = next(iter(slotted))                   # write once at the slot after its own
        conn[-len(slotted)] = f".{g}__en({g}_en), .{g}__addr({g}_addr_d)"
        L_ += [f"  wire [3:0] {g}_addr_d; wire now = stop & ~used & {g}_en;",
               "  always @(posedge clk) if (now) used <= 1'b1;",
               f"  assign {g}_addr = {g}_addr_d + now;"]
    L_ += [f"  {module} dut (.clk(clk), .rst(rst), .i__valid(i_valid), .i__ready(i_ready), "
           + ", ".join(conn) + f", .space({dut_space}), .started(started), "
           ".written(d_written), .busy(busy)" + (", .early__en(early_en));" if early else ");")]
    if mutant == "lost_write":
        L_ += ["  wire now = stop & ~used & d_written;",
               "  always @(posedge clk) if (now) used <= 1'b1;",
               "  wire written = d_written & ~now;"]
    elif mutant == "extra_write":
        L_ += ["  wire now = stop & ~used & ~d_written;",
               "  always @(posedge clk) if (now) used <= 1'b1;",
               "  wire written = d_written | now;"]
    elif mutant in (None, "overrun", "wrong_slot"):
        L_ += ["  wire written = d_written;"]
    else:
        raise ValueError(f"the scheduled part has no mutant {mutant!r}")
    slot = max(ii - 1, 1).bit_length()
    L_ += [f"  reg [{H}:1] dl = 0;",
           f"  always @(posedge clk) dl <= rst ? {H}'d0 : "
           + (f"{{dl[{H - 1}:1], started}};" if H > 1 else "started;"),
           f"  reg [{C - 1}:0] n_w = 0;", f"  reg [{slot - 1}:0] since = 0;",
           "  always @(posedge clk) if (!rst) n_w <= n_w + written;",
           # a job's slot: the starts before it, modulo the queue's 16 words; the job at
           # offset k started k clocks ago, after n_s less the starts in dl[k:1]
           f"  reg [{C - 1}:0] n_s = 0;",
           "  always @(posedge clk) if (!rst) n_s <= n_s + started;",
           # (cum<k>: the starts in dl[k:1]; tag<k>: the slot of the job at offset k)
           "  wire [3:0] cum0 = 4'd0, tag0 = n_s[3:0];",
           *[f"  wire [3:0] cum{k} = cum{k - 1} + dl[{k}], tag{k} = n_s[3:0] - cum{k};"
             for k in range(1, H + 1)],
           # the clocks since the last start (since reset before any), modulo ii
           f"  always @(posedge clk) since <= rst ? 0 : started ? {1 % ii} : "
           f"since == {ii - 1} ? 0 : since + 1;",
           "  always @* if (!rst) begin",
           "    handshake: assert(started == (i_valid && i_ready));",
           "    if (started) credit: assert(space);",
           *([f"    if (started) interval: assert({_latest(0, ii, L, H)});"] if ii > 1 else []),
           *(["    early: assert(early_en == started);"] if early else []),
           f"    if (written) order: assert(dl[{D}]);",
           f"    if (dl[{D}]) drain: assert(written);",
           # every memory is written exactly at its offset, at its job's slot
           *[f"    slot_{g}: assert({g}_en == {f'dl[{k}]' if k else 'started'} && "
             f"(!{g}_en || {g}_addr == tag{k}));"
             for g, k in slotted.items()],
           "    c_two: cover(written && n_w == 1);",
           "    c_stall: cover(i_valid && !i_ready && space);",
           "  end"]
    ph, sel, counts = _engine_state(part)
    copies = _slot_copies(part)
    L_ += [f"  (* keep *) wire s_ph{k};" for k in ph] + [f"  (* keep *) wire s_sel{k};" for k in sel]
    L_ += ["  (* keep *) wire [3:0] s_slots;"] if slotted else []
    L_ += [f"  (* keep *) wire [3:0] s_slot_at{c};" for c in copies]
    L_ += [f"  (* keep *) wire [{slot - 1}:0] s_slot{n};" for n in range(counts)]
    L_ += [f"  (* keep *) wire s_aligned{n};" for n in range(counts)]
    L_ += ["  (* keep *) wire s_inflight;"] if counts else []
    L_ += ["  always @* if (!rst) begin",
           *[f"    inv_ph{k}: assert(s_ph{k} == dl[{k}]);" for k in ph],
           # one channel (RASTER): every job is its row's only one, so the serial engine's
           # channel select (``s_sel0``) is 1, and so is its capture at the start (read from
           # offset 1) and its copy made at offset k (read from k + 1) while a job is past it
           *[f"    inv_sel{k}: assert(s_sel0);" if k == 0 else
             f"    inv_sel{k}: assert(!(|dl[{D}:{k + (k > 1)}]) || s_sel{k});" for k in sel],
           # ``Schedule._align``: aligned next clock when the slot count is 0 or no job is
           # in flight (none started at 1 .. length - 1 clocks ago)
           *([f"    inv_since: assert(since < {ii});"] if counts else []),
           # the starts remembered keep the interval (``interval`` at each start)
           *[f"    inv_gap{j}: assert(!dl[{j}] || {_latest(j, ii, L, H)});"
             for j in range(1, H) if counts],
           # the clocks since the last start, where it is still remembered
           *[f"    inv_since{j}: assert(!dl[{j}] || " + (f"|dl[{j - 1}:1] || " if j > 1 else "")
             + f"since == {j % ii});" for j in range(1, H + 1) if counts],
           *[f"    inv_slot{n}: assert(s_slot{n} == since);" for n in range(counts)],
           *[f"    inv_aligned{n}: assert(s_aligned{n} == (since == 0 || !(|dl[{L - 1}:1])));"
             for n in range(counts)],
           *([f"    inv_inflight: assert(s_inflight == |dl[{L - 2}:1]);"] if counts else []),
           # the setup's slot count, and each copy of a job's slot, written at offset c and
           # read at c + 1 .. c + ii, holds the slot of the job there
           *(["    inv_slots: assert(s_slots == n_s[3:0]);"] if slotted else []),
           *[f"    inv_slot_at{c}_{k}: assert(!dl[{k}] || s_slot_at{c} == tag{k});"
             for c in copies for k in range(c + 1, min(c + ii, H) + 1)],
           "  end", "endmodule"]
    return keep_only("\n".join(L_) + "\n", only)


def _latest(j, ii, L, H):
    """Verilog: of the starts in ``dl`` older than position ``j``, the newest is a multiple
    of ``ii`` clocks before it, or more than ``L - 1`` (no job of it still in flight)."""
    terms = [f"!(dl[{j + d}]" + (f" && !(|dl[{j + d - 1}:{j + 1}])" if d > 1 else "") + ")"
             for d in range(1, L) if d % ii and j + d <= H]
    return " && ".join(terms) or "1"


def _engine_state(part):
    """The offsets of the scheduled part's phase bits up to its write's, of the serial
    engine's channel select (0), its capture (1) and its late copies, and how many slot
    counts (``aligned`` and its copies) its schedule keeps."""
    pre, text = _phases(part), export(part, _module(part))
    ph = [k for k in range(1, max(part.offset, part.length - 1) + 1)
          if re.search(rf"\b{pre}_ph{k}\b", text)]
    sel = sorted({int(k) for k in re.findall(r"\brs_sel_at(\d+)\b", text)})
    if sel:                                      # the select, and its capture at the start
        assert RASTER["channels"] == 1
        sel = [0, 1, *sel]
    # the slot counts behind ``aligned`` and its copies (each enables a share of the input
    # captures, among them the serial engine's slot)
    counts = len(set(re.findall(rf"\b{pre}_slot(\d+)\b", text)))
    return ph, sel, counts


# a slotted producer's count of the slots given (the next item's) and its job's capture of it
SLOTS_OF = {"su": ("sq_slots", "su_sq_slot"), "rs": ("rs_next_slot", "rs_slot")}


def _slot_copies(part):
    """The offsets at which a slotted producer writes its copies of a job's slot (0: the
    capture at the start), or none."""
    if not part.offsets:
        return []
    _, capture = SLOTS_OF[_phases(part)]
    text = export(part, _module(part))
    return [0, *sorted({int(c) for c in re.findall(rf"\b{capture}_at(\d+)\b", text)})]


def row_engine_wires(part):
    pre = _phases(part)
    ph, sel, counts = _engine_state(part)
    copies = _slot_copies(part)
    count, capture = SLOTS_OF.get(pre, (None, None))
    slots = ([("s_slots", count)] + [(f"s_slot_at{c}", f"{capture}_at{c}" if c else capture)
                                     for c in copies]) if copies else []
    names = {0: "rs_sel0", 1: "rs_sel"}
    return ([(f"s_ph{k}", f"{pre}_ph{k}") for k in ph]
            + [(f"s_sel{k}", names.get(k, f"rs_sel_at{k}")) for k in sel]
            + [(f"s_slot{n}", f"{pre}_slot{n}") for n in range(counts)]
            + [(f"s_aligned{n}", f"{pre}_aligned{n or ''}") for n in range(counts)]
            + ([("s_inflight", f"{pre}_inflight")] if counts else []) + slots)


ENGINE = ("lost_write", "extra_write", "overrun")

# the parts: name -> (the part, its harness, the wires its invariants read, its mutants)
STREAM = ("dropped", "extra", "unstable", "stuck")
PARTS = {
    "stepper": (stepper, stepper_harness, lambda part: WIRES, STREAM),
    "walker": (walker, walker_harness, walker_wires, STREAM),
    "row_queue": (row_queue, queue_harness, queue_wires, (*STREAM, "overrun")),
    "row_queue_serial": (lambda: row_queue(serial=True), queue_harness, queue_wires,
                         (*STREAM, "overrun")),
    "setup_queue": (setup_queue, queue_harness, queue_wires, (*STREAM, "overrun")),
    "setup": (setup, setup_harness, setup_wires, STREAM),
    "row_engine": (row_engine, row_engine_harness, row_engine_wires, ENGINE),
    "row_engine_serial": (lambda: row_engine(serial=True), row_engine_harness,
                          row_engine_wires, (*ENGINE, "wrong_slot")),
    "setup_schedule": (setup_schedule, row_engine_harness, row_engine_wires,
                       (*ENGINE, "wrong_slot")),
    "row_engine_narrow": (row_engine_narrow, row_engine_harness, row_engine_wires, ENGINE),
}


def sby_text(module, mode, depth, wires=(), cut=False, producer=False):
    """The SymbiYosys job: the design flattened, for the invariants their wires connected and
    its memories mapped to registers (a mutant's BMC asserts none of them, and the signals
    they read may be optimised away); ``cut``: each product a free value. A scheduled
    ``producer``'s invariants read no memory, and its wires are connected before
    ``opt_clean``, which would drop those no property reads (the copies of ``aligned`` that
    enable only input captures); the others' after it, where their names are the
    registers'."""
    connect = ("cd formal_top", *[f"connect -set {w} dut.{n}" for w, n in wires], "cd ..")
    return "\n".join([
        "[options]", f"mode {mode}", f"depth {depth}", "multiclock off", "",
        "[engines]", "smtbmc yices", "",
        "[script]", "read_verilog -formal harness.v", f"read_verilog {module}.v",
        "hierarchy -top formal_top", "proc", "flatten",
        *(("memory_map",) if wires and not producer else ()),
        *(("cutpoint t:$mul",) if cut else ()),
        *(connect if producer else ()),
        "opt_clean",
        *(() if producer else connect),
        "prep -top formal_top", "",
        "[files]", "harness.v", f"{module}.v", ""])


def run(name, check, mutant=None, timeout=None, part=None):
    """One check of part ``name`` (``CHECKS``), or a mutant with its property's check.
    Returns ``{target, check, mutant, status, failed, seconds, depth}``."""
    build, harness, wires, _ = PARTS[name]
    part = part or build()
    mode, only = CHECKS[check]
    depth = PROVE_DEPTH
    if mutant:                  # a BMC of the one property it breaks (an overrun: once the
        #                         queue is full, ``depth`` rows after the first start)
        mode, only = "bmc", (MUTANTS[mutant][1],)
        depth = (part.depth + 4 if mutant == "overrun" and hasattr(part, "depth") else
                 SCHEDULED[name](part) + 5 if name in SCHEDULED else MUTANT_DEPTH)
    elif mode == "cover":                  # a scheduled part: two items through (an
        #                                    interval apart, where it has one)
        depth = (COVER_DEPTH if name not in SCHEDULED else
                 part.offset + part.ii + 2 if getattr(part, "ii", None) else
                 2 * (SCHEDULED[name](part) + 2))
    tag = name + (f"_{mutant}" if mutant else "") + f"_{check}"
    work = OUT / tag
    module = f"f_{name}"
    status, failed, seconds = run_sby(work, {
        f"{module}.v": export(part, module), "harness.v": harness(part, module, mutant, only),
        "job.sby": sby_text(module, mode, depth, () if mutant else wires(part),
                            cut=name in SCHEDULED, producer=harness is row_engine_harness)},
        mode, timeout)
    out = {"target": name, "check": mode if mutant else check, "mutant": mutant,
           "status": status,
           "failed": failed, "seconds": seconds, "depth": depth,
           "log": str(work / "run.log")}
    (work / "result.json").write_text(json.dumps(out, indent=2) + "\n")
    return out


def caught(r):
    return r["status"] == "fail" and any(f.startswith(MUTANTS[r["mutant"]][1])
                                         for f in r["failed"])


def run_all(names=None, timeout=None):
    """Every check, then every mutant, of each part in ``names`` (None: all); a line each;
    build/formal/parts.json."""
    results = []
    for name in names or PARTS:
        part = PARTS[name][0]()
        for check, mutant in ([(c, None) for c in CHECKS]
                              + [("prove", m) for m in PARTS[name][3]]):
            r = run(name, check, mutant, timeout, part)
            print(f"parts {name} {r['check']} {r['mutant'] or ''}: {r['status']} "
                  f"{' '.join(r['failed'])} {r['seconds']:.0f} s", flush=True)
            results.append(r)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "parts.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


def table(results):
    rows = ["| part | check | mutant | must fail | status | failed | s |",
            "| --- | --- | --- | --- | --- | --- | --- |"]
    rows += [f"| {r['target']} | {r['check']} | {r['mutant'] or '-'} | "
             f"{MUTANTS[r['mutant']][1] if r['mutant'] else '-'} | "
             f"{('caught' if caught(r) else 'NOT CAUGHT') if r['mutant'] else r['status']} | "
             f"{', '.join(r['failed']) or '-'} | {r['seconds']:.0f} |" for r in results]
    return "\n".join(rows) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.parts",
                                 description=__doc__.split("\n")[0])
    ap.add_argument("--only", default=None, help=f"parts, comma-separated: {', '.join(PARTS)}")
    ap.add_argument("--timeout", type=float, default=None, help="seconds a check may take")
    args = ap.parse_args(argv)
    names = args.only.split(",") if args.only else None
    unknown = [n for n in names or () if n not in PARTS]
    if unknown:
        ap.error(f"unknown part(s) {', '.join(unknown)}; parts: {', '.join(PARTS)}")
    results = run_all(names, args.timeout)
    print(table(results))
    bad = [r for r in results if (r["mutant"] and not caught(r))
           or (not r["mutant"] and r["status"] != "pass")]
    if bad:
        raise SystemExit(f"parts: {len(bad)} check(s) did not hold: "
                         + ", ".join(f"{r['check']} {r['mutant'] or ''}" for r in bad))


if __name__ == "__main__":
    main()
