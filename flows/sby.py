"""What the SymbiYosys flows share (``formal.py``, ``texjoin.py``): where they write, the
harness's counters, the texture memory model and the tools' path."""
import os
import sys
from pathlib import Path

from sim.verilog import BUILD

OUT = BUILD / "formal"
MEM_WAIT = 3         # the memory model answers a request within this many clocks
COUNT = 10           # bits of the transfer counters (depths stay below 2**COUNT)


def memory_model(req, resp, req_fields, resp_fields, wait=MEM_WAIT):
    """A memory that takes requests when it likes, answers them in order after at most
    ``wait`` clocks each, with data from the address (a fixed function, so the order
    property can compare), two in flight at most."""
    (addr, aw), = req_fields
    (data, dw), = resp_fields
    reps = -(-dw // aw)
    return [
        f"  (* anyseq *) reg {req}_take, {resp}_give;",
        f"  reg [{aw - 1}:0] {req}_mq0, {req}_mq1;", f"  reg [1:0] {req}_mn = 0;",
        f"  reg [3:0] {req}_mwait = 0;",
        f"  assign {req}_ready = {req}_take & ({req}_mn != 2);",
        f"  assign {resp}_valid = ({req}_mn != 0) & {resp}_give;",
        f"  assign {data} = {{{reps}{{{req}_mq0}}}} ^ {dw}'h{'5a' * (-(-dw // 8))};".replace(
            f"{dw}'h{'5a' * (-(-dw // 8))}", f"{dw}'h{('5a' * 64)[:-(-dw // 4)]}"),
        f"  wire {req}_mreq = ~rst & {req}_valid & {req}_ready;",
        f"  wire {req}_mresp = ~rst & {resp}_valid & {resp}_ready;",
        f"  always @(posedge clk) if (rst) {req}_mn <= 0; else begin",
        f"    {req}_mn <= {req}_mn + {req}_mreq - {req}_mresp;",
        f"    if ({req}_mresp) {req}_mq0 <= {req}_mq1;",
        f"    if ({req}_mreq && ({req}_mn == 0 || ({req}_mn == 1 && {req}_mresp))) "
        f"{req}_mq0 <= {addr};",
        f"    if ({req}_mreq && ({req}_mn == 1 && !{req}_mresp || {req}_mn == 2)) "
        f"{req}_mq1 <= {addr};",
        f"    if ({req}_mreq && {req}_mn == 2 && {req}_mresp) {req}_mq1 <= {addr};",
        "  end",
        # bounded waits: a request or a response waits at most MEM_WAIT clocks for the memory
        f"  always @(posedge clk) {req}_mwait <= ((~rst & {req}_valid & ~{req}_ready) | "
        f"(~rst & {req}_mn != 0 & ~{resp}_valid)) ? {req}_mwait + 1 : 0;",
        f"  always @* if ({req}_mwait >= {wait}) assume({req}_take && {resp}_give);",
    ]


def tools_env():
    """sby finds the PyPI tools: ``yices-smt2`` from the venv's bin on PATH."""
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    return env
