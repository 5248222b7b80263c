"""The texture join proven (issue 51 §5): the texel cache (``hdl.texture_unit.cache``), the
real one, between a stream of fragments and a texture memory of any latency, with
backpressure on every stream.

The design under proof (``Join``) is ``texel_cache`` with two values riding through it: a
sequence tag ``seq`` and each bank's line number ``ln<k>``, which its output carries beside
the texel ``tex<k>``. The harness (``harness``) gives it free inputs and a memory model
(``flows.sby.memory_model``: takes a request when it likes, at most two outstanding, answers
in order with a fixed function of the address), and states:

- ``held``, ``held_payload``: a stalled output keeps its valid and payload;
- ``order``: the n-th fragment out is the n-th in (the inputs' ``seq`` counts them, modulo
  ``2**SEQ``, more than the fragments the cache can hold): none made, lost, repeated or
  reordered; ``no_extra``: at most ``capacity`` in flight;
- ``texel_k``: each fragment leaves with bank k's texel of its own line, the memory's word
  for that address: a response taken twice, or dropped, hands a later fragment the wrong
  line;
- ``drain`` (liveness): while the memory answers within ``MEM_WAIT`` clocks and ready is
  held high, a fragment leaves within ``drain_bound`` clocks of entering.

The safety properties are proven by k-induction with the memory's latency unbounded. Their
invariants tie the queue's words (Amaranth's ``SyncFIFOBuffered``: a memory of depth - 1
words and an output register) to the harness's counters, and the cache's tags and data
array to the memory's function (``_invariants``). ``drain`` is a bounded check (BMC) past
its bound. The mutants (``MUTANTS``) break the join and must be caught.

``python -m flows.texjoin [--only name] [--timeout s]``; ``make formal`` runs it too.
"""
import argparse
import json
from types import SimpleNamespace

from amaranth.back import verilog
from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.lib import stream

from hdl.fixed import layout
from hdl.texture_unit.cache import ADDR, request_fields, response_fields, texel_cache

from .sby import COUNT, OUT, keep_only, memory_model, run_sby

SEQ = 4                  # bits of the sequence tag: more than the cache holds (2**SEQ > capacity)
PROVE_DEPTH = 6          # k of the safety proofs
LN_BITS = 4              # a bank's line numbers (16 lines of one texel: the tags keep 3 bits)
MEM_WAIT = 1         # drain: the memory takes a request, and gives a response, within a clock
TEXEL_BITS = 8                  # a texel: wide enough that the memory's function (the address, bank
#                                 and line, with a pattern) is one to one

# the joins proven: one bank on its port (nearest), and four banks on one shared port
# (bilinear with ``bank_ports = False``, the widest join: one request and one response a
# clock among four banks)
JOINS = {"texjoin_nearest": {"banks": 1, "shared": False},
         "texjoin_shared": {"banks": 4, "shared": True}}
CACHE = {"lines": 2, "ways": 1, "line": 1, "depth": 4}      # make formal's SMALL

MUTANTS = {   # name: (what it breaks, the property that must catch it)
    "wrong_side": ("the join waits on the wrong side: a request goes out only beside a "
                   "response", "drain"),
    "dropped_resp": ("a response is taken from the memory but never reaches the cache",
                     "drain"),
    "resp_twice": ("a response is handed to the cache twice", "texel"),
}


class Join(Elaboratable):
    """``texel_cache`` with flat ports: ``i_*`` (valid, ready, seq, ln<k>), ``o_*`` (valid,
    ready, seq, ln<k>, tex<k>), and a memory port ``req<p>_*``/``resp<p>_*`` a bank (or one
    shared)."""

    def __init__(self, banks, shared):
        self.banks, self.shared = banks, shared
        self.nports = 1 if shared else banks
        self.i_valid, self.i_ready = Signal(name="i_valid"), Signal(name="i_ready")
        self.o_valid, self.o_ready = Signal(name="o_valid"), Signal(name="o_ready")
        self.i_seq, self.o_seq = Signal(SEQ, name="i_seq"), Signal(SEQ, name="o_seq")
        self.i_ln = [Signal(LN_BITS, name=f"i_ln{k}") for k in range(banks)]
        self.o_ln = [Signal(LN_BITS, name=f"o_ln{k}") for k in range(banks)]
        self.o_tex = [Signal(TEXEL_BITS, name=f"o_tex{k}") for k in range(banks)]
        # the memory ports, flat: (valid, ready, addr) and (valid, ready, data)
        self.req = [(Signal(name=f"req{p}_valid"), Signal(name=f"req{p}_ready"),
                     Signal(ADDR.width, name=f"req{p}_addr")) for p in range(self.nports)]
        self.resp = [(Signal(name=f"resp{p}_valid"), Signal(name=f"resp{p}_ready"),
                      Signal(TEXEL_BITS, name=f"resp{p}_data")) for p in range(self.nports)]

    def ports(self):
        return [self.i_valid, self.i_ready, self.o_valid, self.o_ready, self.i_seq, self.o_seq,
                *self.i_ln, *self.o_ln, *self.o_tex, *(x for r in self.req for x in r),
                *(x for r in self.resp for x in r)]

    def elaborate(self, platform):
        m = Module()
        i = SimpleNamespace(valid=self.i_valid, ready=self.i_ready)
        o = SimpleNamespace(valid=self.o_valid, ready=self.o_ready)
        v = {"seq": self.i_seq, **{f"ln{k}": x for k, x in enumerate(self.i_ln)},
             **{f"_ln{k}": x for k, x in enumerate(self.i_ln)}}
        reqs, resps = [], []
        for (valid, ready, addr), (rvalid, rready, data) in zip(self.req, self.resp):
            req = stream.Signature(layout(request_fields())).create()
            resp = stream.Signature(layout(response_fields(TEXEL_BITS))).flip().create()
            m.d.comb += [valid.eq(req.valid), req.ready.eq(ready), addr.eq(req.payload.addr),
                         resp.valid.eq(rvalid), rready.eq(resp.ready),
                         resp.payload.data.eq(data)]
            reqs.append(req)
            resps.append(resp)
        v, _ = texel_cache(m, i, v, o, reqs, resps, banks=self.banks,
                           texel_bits=TEXEL_BITS, bank_texels=1 << LN_BITS, **CACHE)
        m.d.comb += self.o_seq.eq(v["seq"])
        for k in range(self.banks):
            m.d.comb += [self.o_ln[k].eq(v[f"ln{k}"]), self.o_tex[k].eq(v[f"_tex{k}"])]
        return m


def capacity():
    """Fragments the cache holds once accepted: its queue and its output register."""
    return CACHE["depth"] + 1


def drain_bound(join):
    """Clocks from the watched fragment's offer to its leaving, with ready held high from the
    offer and every wait of the memory at most ``MEM_WAIT`` clocks (a request taken, or a
    response given, within ``MEM_WAIT`` + 1). A fragment's misses take R = one response a
    bank, all at once on their own ports, or ``banks`` one after another on a shared port:
    ``per`` = R (MEM_WAIT + 1) + 1 clocks at the head, with its move to the output register.

    - the tags' clearing after a reset: ``lines / ways`` clocks;
    - the fragments ahead (``capacity``, each accepted before the offer), one after another
      at the head, and the last one's clock in the output register: capacity ``per`` + 1;
    - then the cache holds nothing and the memory owes nothing: the watched fragment's
      requests, R (MEM_WAIT + 1), its clock at the head and in the output register
      (``per``), the queue's read (1)."""
    R = join["banks"] if join["shared"] else 1
    per = R * (MEM_WAIT + 1) + 1
    sets = CACHE["lines"] // CACHE["ways"]
    return sets + capacity() * per + 1 + R * (MEM_WAIT + 1) + per + 1


def export(join, module):
    """The Verilog of ``Join`` for these parameters, as ``module``."""
    dut = Join(**join)
    return verilog.convert(dut, name=module, ports=dut.ports(), emit_src=False)


def _texel(k, ln, shared):
    """The memory's word for bank k's line ``ln``: its address as the cache sends it (the
    bank above the line number where the banks share the memory), through ``memory_model``'s
    function."""
    addr = f"{{2'd{k}, {ln}}}" if shared or k else ln
    return f"(({{{ADDR.width - LN_BITS - (2 if shared or k else 0)}'d0, {addr}}}) ^ " \
        f"{TEXEL_BITS}'h{'5a' * (TEXEL_BITS // 8)})"


def harness(join, module, mutant=None, only=None, bounded=False):
    """The Verilog of ``formal_top``: ``Join`` as ``module``, the memory model on each port
    (its waits bounded by ``MEM_WAIT`` only with ``bounded``, for ``drain``), the properties
    (``only``: those whose labels start with one of these), the invariants, and ``mutant``
    between the cache and the memory on port 0."""
    banks, nports = join["banks"], 1 if join["shared"] else join["banks"]
    cap, D = capacity(), CACHE["depth"] - 1
    L = ["`default_nettype none", "module formal_top(input wire clk);",
         "  reg init = 1'b1;", "  always @(posedge clk) init <= 1'b0;", "  wire rst = init;",
         "  (* anyseq *) reg i_valid, o_ready;",
         *[f"  (* anyseq *) reg [{LN_BITS - 1}:0] i_ln{k};" for k in range(banks)],
         f"  wire [{SEQ - 1}:0] i_seq, o_seq;", "  wire i_ready, o_valid;",
         *[f"  wire [{LN_BITS - 1}:0] o_ln{k};" for k in range(banks)],
         *[f"  wire [{TEXEL_BITS - 1}:0] o_tex{k};" for k in range(banks)]]
    conn = ["clk", "rst", "i_valid", "i_ready", "o_valid", "o_ready", "i_seq", "o_seq",
            *[f"{d}_ln{k}" for d in "io" for k in range(banks)],
            *[f"o_tex{k}" for k in range(banks)]]
    core = {p: p for p in conn}
    for p in range(nports):
        L += [f"  wire req{p}_valid, req{p}_ready, resp{p}_valid, resp{p}_ready;",
              f"  wire [{ADDR.width - 1}:0] req{p}_addr;",
              f"  wire [{TEXEL_BITS - 1}:0] resp{p}_data;"]
        for n in ("req{p}_valid", "req{p}_ready", "req{p}_addr", "resp{p}_valid",
                  "resp{p}_ready", "resp{p}_data"):
            core[n.format(p=p)] = n.format(p=p)
    # the mutants, between the cache (its side: m_*) and the memory on port 0
    M = []
    if mutant == "wrong_side":        # a request offered, and taken, only beside a response
        core.update(req0_valid="m_req0_valid", req0_ready="m_req0_ready")
        M += ["  wire m_req0_valid, m_req0_ready;",
              "  assign req0_valid = m_req0_valid & resp0_valid;",
              "  assign m_req0_ready = req0_ready & resp0_valid;"]
    elif mutant == "dropped_resp":    # once, when the solver likes: the memory gives a
        #                               response and sees it taken; the cache never sees it
        core.update(resp0_valid="m_resp0_valid", resp0_ready="m_resp0_ready")
        M += ["  (* anyseq *) reg m_drop;", "  reg m_done = 1'b0;",
              "  wire m_now = m_drop & ~m_done;", "  wire m_resp0_ready;",
              "  assign m_resp0_valid = resp0_valid & ~m_now;",
              "  assign resp0_ready = m_resp0_ready | m_now;",
              "  always @(posedge clk) if (m_now & resp0_valid) m_done <= 1'b1;",
              "  wire m_resp0_valid;"]
    elif mutant == "resp_twice":      # once, when the solver likes: a response the cache
        #                               took is offered again the next clock
        core.update(resp0_valid="m_resp0_valid", resp0_ready="m_resp0_ready",
                    resp0_data="m_resp0_data")
        M += ["  (* anyseq *) reg m_pick;", "  reg m_again = 1'b0, m_used = 1'b0;",
              f"  reg [{TEXEL_BITS - 1}:0] m_last;", "  wire m_resp0_ready;",
              "  wire m_resp0_valid = m_again | resp0_valid;",
              "  wire [15:0] m_resp0_data = m_again ? m_last : resp0_data;",
              "  assign resp0_ready = m_resp0_ready & ~m_again;",
              "  always @(posedge clk) begin m_again <= 1'b0;",
              "    if (!m_used & m_pick & resp0_valid & resp0_ready) begin",
              "      m_again <= 1'b1; m_used <= 1'b1; m_last <= resp0_data; end end"]
    elif mutant is not None:
        raise ValueError(f"unknown mutant {mutant!r}; known: {', '.join(MUTANTS)}")
    L += M
    L += [f"  {module} dut (" + ", ".join(f".{p}({c})" for p, c in core.items()) + ");"]
    for p in range(nports):
        mem = memory_model(f"req{p}", f"resp{p}", [(f"req{p}_addr", ADDR.width)],
                      [(f"resp{p}_data", TEXEL_BITS)], wait=MEM_WAIT)
        L += mem if bounded else [ln for ln in mem if "mwait >=" not in ln]

    # the environment: sequence tags, held inputs; the counters
    L += ["  wire in_t = ~rst & i_valid & i_ready, out_t = ~rst & o_valid & o_ready;",
          f"  reg [{COUNT - 1}:0] n_in = 0, n_out = 0;",
          "  always @(posedge clk) if (!rst) begin n_in <= n_in + in_t; "
          "n_out <= n_out + out_t; end",
          f"  assign i_seq = n_in[{SEQ - 1}:0];",
          f"  wire [{LN_BITS * banks - 1}:0] i_lns = {{{', '.join(f'i_ln{k}' for k in range(banks))}}};",
          f"  reg [{LN_BITS * banks - 1}:0] past_in;", "  reg past_istall = 1'b0;",
          "  always @(posedge clk) begin past_istall <= ~rst & i_valid & ~i_ready; "
          "past_in <= i_lns; end",
          "  always @* if (past_istall) in_held: assume(i_valid && i_lns == past_in);",
          "  wire [" + str(SEQ + banks * (LN_BITS + TEXEL_BITS) - 1) + ":0] outs = {o_seq, "
          + ", ".join(f"o_ln{k}, o_tex{k}" for k in range(banks)) + "};",
          f"  reg [{SEQ + banks * (LN_BITS + TEXEL_BITS) - 1}:0] past_out;",
          "  reg past_ostall = 1'b0;",
          "  always @(posedge clk) begin past_ostall <= ~rst & o_valid & ~o_ready; "
          "past_out <= outs; end",
          f"  wire [{COUNT - 1}:0] in_flight = n_in - n_out;"]
    L += _invariants(join, cap, D)
    # drain: the watched fragment, ready held high from its offer (a join that waits on the
    # wrong side never takes it)
    L += [f"  (* anyconst *) reg [{COUNT - 1}:0] watch;",
          "  reg offered = 1'b0, done = 1'b0;", f"  reg [{COUNT - 1}:0] age = 0;",
          "  wire watch_offer = ~rst && i_valid && !offered && n_in == watch;",
          "  wire watch_out = out_t && offered && !done && n_out == watch;",
          "  always @(posedge clk) begin if (watch_offer) offered <= 1'b1; "
          "if (watch_out) done <= 1'b1;",
          "    if (watch_offer) age <= 1; else if (offered && !done && age != {"
          + str(COUNT) + "{1'b1}}) age <= age + 1; end",
          "  wire pending = offered && !done;"]
    if bounded:
        L += ["  always @* if (watch_offer || pending) assume(o_ready);"]
    L += ["  always @* if (!rst) begin",
          "    if (past_ostall) begin held: assert(o_valid);",
          "      held_payload: assert(outs == past_out); end",
          f"    no_extra: assert(in_flight <= {cap});",
          f"    if (out_t) order: assert(o_seq == n_out[{SEQ - 1}:0]);",
          *[f"    if (o_valid) texel_{k}: assert(o_tex{k} == {_texel(k, f'o_ln{k}', join['shared'])});"
            for k in range(banks)],
          f"    if (pending) drain: assert(age <= {drain_bound(join)});",
          "    c_three: cover(out_t && n_out == 2);",
          "    c_stall: cover(past_ostall && o_ready);",
          "    c_watch: cover(watch_out && watch == 2);",
          "  end", "endmodule"]
    return keep_only("\n".join(L) + "\n", only)


def _invariants(join, cap, D):
    """What makes the safety properties inductive: the queue's words and the harness's
    counters agree (each an equality of a few bits), read from the flattened design by
    ``sby_text``'s connects (``q_*``)."""
    banks = join["banks"]
    W = SEQ + banks * LN_BITS + banks * 2          # seq, the lines, each bank's slot and miss
    L = ["  (* keep *) wire [1:0] q_level, q_consume, q_produce;",
         "  (* keep *) wire q_rrdy;", f"  (* keep *) wire [{W - 1}:0] q_rdata;",
         *[f"  (* keep *) wire [{W - 1}:0] q_s{i};" for i in range(D)],
         f"  wire [{COUNT - 1}:0] at_r = n_out + o_valid;",
         f"  wire [{COUNT - 1}:0] at_s = at_r + q_rrdy;",
         "  always @* if (!rst) begin",
         f"    inv_queue: assert(q_level <= {D} && q_produce < {D} && q_consume < {D} && "
         f"q_produce == (q_consume + q_level) % {D});",
         "    inv_count: assert(in_flight == o_valid + q_rrdy + q_level);",
         f"    if (o_valid) inv_out: assert(o_seq == n_out[{SEQ - 1}:0]);",
         f"    if (q_rrdy) inv_r: assert(q_rdata[{SEQ - 1}:0] == at_r[{SEQ - 1}:0]);"]
    for i in range(D):
        j = f"((({i} + {D}) - q_consume) % {D})"
        L += [f"    if ({j} < q_level) inv_s{i}: assert(q_s{i}[{SEQ - 1}:0] == "
              f"at_{i}[{SEQ - 1}:0]);"]
    # slot i's place behind the head, and the count it should hold (wrapped as the tags)
    return [*L[:7], *[f"  wire [{COUNT - 1}:0] at_{i} = at_s + ((({i} + {D}) - q_consume) "
                      f"% {D});" for i in range(D)], *L[7:], "  end"]


def sby_text(module, join, mode, depth):
    """The SymbiYosys job: the design flattened, its memories as registers (so that the
    queue's words can be named), the invariants' wires connected."""
    D = CACHE["depth"] - 1
    q = "dut.tex_queue"
    wires = [("q_level", f"{q}.inner_level"), ("q_consume", f"{q}.consume"),
             ("q_produce", f"{q}.produce"), ("q_rrdy", f"{q}.r_rdy"),
             ("q_rdata", f"{q}.r_data"), *[(f"q_s{i}", f"{q}.storage[{i}]") for i in range(D)]]
    return "\n".join([
        "[options]", f"mode {mode}", f"depth {depth}", "multiclock off", "",
        "[engines]", "smtbmc yices", "",
        "[script]", "read_verilog -formal harness.v", f"read_verilog {module}.v",
        "hierarchy -top formal_top", "proc", "flatten", "memory_collect", "memory_map",
        "opt_clean", "cd formal_top", *[f"connect -set {w} {n}" for w, n in wires], "cd ..",
        "prep -top formal_top", "",
        "[files]", "harness.v", f"{module}.v", ""])


# check: (sby mode, the properties asserted, memory waits bounded)
CHECKS = {"prove": ("prove", ("held", "no_extra", "order", "inv_"), False),
          "drain": ("bmc", ("drain",), True),
          "texel": ("bmc", ("texel",), False),
          "cover": ("cover", None, True)}
# texel's BMC depth a join: each step costs more (one port: 2 s to 12 steps, 58 s to 16,
# past 120 s to 20; shared: 729 s to 16); the mutant's failure is at step 9
TEXEL_DEPTH = {"texjoin_nearest": 16, "texjoin_shared": 12}


def run(name, check, mutant=None, timeout=None):
    """One check of ``JOINS[name]`` (``CHECKS``): ``prove``, the safety properties by
    k-induction (k = ``PROVE_DEPTH``) at any memory latency; ``drain``, a BMC past the drain
    bound; ``texel``, a BMC to ``TEXEL_DEPTH``; ``cover``. A mutant runs with the check of
    the property it breaks. Returns ``{target, check, mutant, status, failed, seconds,
    depth}``."""
    join = JOINS[name]
    mode, only, bounded = CHECKS[check]
    depth = {"prove": PROVE_DEPTH, "texel": TEXEL_DEPTH[name]}.get(check, bmc_depth(join))
    tag = name + (f"_{mutant}" if mutant else "") + f"_{check}"
    work = OUT / tag
    module = f"f_{name}"
    status, failed, seconds = run_sby(work, {
        f"{module}.v": export(join, module),
        "harness.v": harness(join, module, mutant, only, bounded),
        "job.sby": sby_text(module, join, mode, depth)}, mode, timeout)
    out = {"target": name, "check": check, "mutant": mutant, "status": status,
           "failed": failed, "seconds": seconds, "depth": depth,
           "log": str(work / "run.log")}
    (work / "result.json").write_text(json.dumps(out, indent=2) + "\n")
    return out


def bmc_depth(join):
    """Deep enough for the watched fragment to be offered behind a full cache (two clocks a
    fragment) and to pass its drain bound, which holds the clearing."""
    return capacity() * 2 + drain_bound(join) + 2


def jobs(names):
    """``[(target, check, mutant)]``: each join's checks and covers, then the mutants on the
    one-port join, each with the check of the property it breaks."""
    out = [(n, c, None) for n in names for c in CHECKS]
    if "texjoin_nearest" in names:
        out += [("texjoin_nearest", prop, m) for m, (_, prop) in MUTANTS.items()]
    return out


def caught(r):
    return r["status"] == "fail" and any(f.startswith(MUTANTS[r["mutant"]][1])
                                         for f in r["failed"])


def table(results):
    """The markdown rows of the joins and their mutants."""
    rows = ["| join | proven by k-induction (latency unbounded) | k | s | drain (BMC, bound) "
            "| depth | s | texel (BMC) | depth | s | covers |",
            "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    by = {}
    for r in results:
        if not r["mutant"]:
            by.setdefault(r["target"], {})[r["check"]] = r
    word = lambda r: "holds" if r["status"] == "pass" else f"{r['status']} {' '.join(r['failed'])}"
    for name, c in by.items():
        p, d, t, v = (c.get(k) for k in ("prove", "drain", "texel", "cover"))
        proven = "**held, no_extra, order**" if p and p["status"] == "pass" else \
            (word(p) if p else "-")
        rows.append(
            f"| {name} | {proven} | {PROVE_DEPTH} | {p['seconds'] if p else 0:.0f} | "
            f"{word(d) + f' ({drain_bound(JOINS[name])})' if d else '-'} | "
            f"{d['depth'] if d else '-'} | {d['seconds'] if d else 0:.0f} | "
            f"{word(t) if t else '-'} | {TEXEL_DEPTH[name]} | {t['seconds'] if t else 0:.0f} | "
            f"{'all reached' if v and v['status'] == 'pass' else (word(v) if v else '-')} |")
    muts = [r for r in results if r["mutant"]]
    if muts:
        rows += ["", "| mutant | on | what it breaks | must fail | failed | caught | s |",
                 "| --- | --- | --- | --- | --- | --- | --- |"]
        rows += [f"| {r['mutant']} | {r['target']} | {MUTANTS[r['mutant']][0]} | "
                 f"{MUTANTS[r['mutant']][1]} | {', '.join(r['failed']) or '-'} | "
                 f"{'yes' if caught(r) else 'NO'} | {r['seconds']:.0f} |" for r in muts]
    return "\n".join(rows) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.texjoin",
                                 description=__doc__.split("\n")[0])
    ap.add_argument("--only", help="comma-separated joins: " + ", ".join(JOINS))
    ap.add_argument("--timeout", type=float, default=None, help="seconds a check may take")
    args = ap.parse_args(argv)
    names = args.only.split(",") if args.only else list(JOINS)
    bad = [n for n in names if n not in JOINS]
    if bad:
        ap.error(f"unknown join {bad[0]!r}; known: {', '.join(JOINS)}")
    results = run_all(names, args.timeout)
    print(table(results))
    bad = [r for r in results if (r["mutant"] and not caught(r))
           or (not r["mutant"] and r["status"] != "pass")]
    if bad:
        raise SystemExit(f"texjoin: {len(bad)} check(s) did not hold: "
                         + ", ".join(f"{r['target']} {r['check']} {r['mutant'] or ''}"
                                     for r in bad))


def run_all(names, timeout=None):
    """Every job of ``names``, one at a time, a line each as it finishes; the results also
    in build/formal/texjoin.json."""
    results = []
    for t in jobs(names):
        r = run(*t, timeout=timeout)
        print(f"texjoin {r['target']} {r['check']} {r['mutant'] or ''}: {r['status']} "
              f"{r['seconds']:.0f} s", flush=True)
        results.append(r)
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "texjoin.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()
