"""Streaming vectors through a unit's exported Verilog with cocotb, on Icarus or Verilator.

A model is built once and kept under ``build/cocotb/<simulator>/``, keyed by the hash of its
Verilog, the build arguments and the tool versions: an unchanged unit is not built again, in
this process or the next. A lock file keeps two processes from building the same model at once.
"""
import hashlib
import json
import os
import shutil
import sys
import tempfile
import time
from contextlib import contextmanager
from importlib.metadata import version
from pathlib import Path

import numpy as np

from hdl.units import make_unit

from .progress import watch
from .simulators import COCOTB, available
from .verilog import BUILD, ROOT, build_lock, design_key, export, prune_objects, verilator_env

VERILATOR_ARGS = ["-Wno-fatal", "-Wno-WIDTHEXPAND", "-Wno-PROCASSINIT", "-O2"]
_built = {}


class SimulatorMissing(RuntimeError):
    pass


def _env(simulator):
    env = verilator_env() if COCOTB[simulator] == "verilator" else dict(os.environ)
    if COCOTB[simulator] == "verilator":
        # Python runs every clock here, so the model's C++ needs no optimisation: -O0 builds
        # about a third faster (raster: 42 s against 61 s). The batch path builds with -O2.
        env["MAKEFLAGS"] += " OPT_FAST=-O0 OPT_SLOW=-O0 OPT_GLOBAL=-O0"
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return env


@contextmanager
def _environ(env):
    saved = dict(os.environ)
    os.environ.update(env)
    try:
        yield
    finally:
        os.environ.clear()
        os.environ.update(saved)


def build(name, params, simulator, *, waves=False):
    """Build (or find in the cache) and return ``(runner, build_dir)``."""
    reason = available(simulator)
    if reason:
        raise SimulatorMissing(reason)
    design, tag = design_key(name, params)
    key = (name, design, simulator, waves)
    if key in _built:
        return _built[key]
    from cocotb_tools.runner import get_runner
    base = BUILD / "cocotb" / COCOTB[simulator] / (f"{name}-{tag}" + ("-waves" if waves else ""))
    build_dir = base / "obj"
    args = VERILATOR_ARGS if COCOTB[simulator] == "verilator" else []
    with build_lock(base.parent / f"{base.name}.lock"):
        src = export(name, params, base)
        tools = [version("cocotb")] + ([version("verilator")] if args else [])
        stamp = hashlib.sha1(json.dumps([src.read_text(), args, tools]).encode()).hexdigest()
        with _environ(_env(simulator)):
            runner = get_runner(COCOTB[simulator])
            if (build_dir / "stamp").exists() and (build_dir / "stamp").read_text() == stamp:
                pass                                     # built before, from the same Verilog
            else:
                t0 = time.time()
                print(f"{name}: building the {simulator} model (once; cached under {base})",
                      file=sys.stderr, flush=True)
                runner.build(sources=[src], hdl_toplevel=name, build_dir=build_dir,
                             build_args=args, timescale=("1ns", "1ps"), waves=waves,
                             always=True, clean=True, log_file=base / "build.log")
                if COCOTB[simulator] == "verilator":
                    prune_objects(build_dir)
                (build_dir / "stamp").write_text(stamp)
                (build_dir / "build_seconds").write_text(f"{time.time() - t0:.1f}")
                print(f"{name}: {simulator} model built in {time.time() - t0:.1f} s",
                      file=sys.stderr, flush=True)
    _built[key] = (runner, build_dir)
    return _built[key]


def _log_tail(path):
    return path.read_text()[-3000:] if path.exists() else ""


def run_cocotb(name, params, inputs, simulator, *, p_valid=1.0, p_ready=1.0, seed=0,
               waves=None, progress=None, uniforms=None, memory=None):
    """Run every row of ``inputs`` through the Verilog of unit ``name``.

    ``waves``: a path without suffix; the simulator's trace (FST from Icarus, VCD from
    Verilator) is moved there. ``progress``: called as ``progress(sent, outputs)``.
    ``memory``: the texture memory behind a memory port (:class:`sim.stream.Memory`).
    Returns ``(outputs, info)`` with ``info = {"latency", "cycles", "waves"}``.
    """
    runner, build_dir = build(name, params, simulator, waves=bool(waves))
    unit = make_unit(name, spec=True, **params)
    spec = {"inputs": [f.describe() for f in unit.inputs],
            "outputs": [f.describe() for f in unit.outputs],
            "p_valid": p_valid, "p_ready": p_ready, "seed": seed,
            "many": bool(unit.status_ports), "status": list(unit.status_ports),
            "uniforms": [{**f.describe(), "value": int(uniforms[f.name])} for f in unit.uniforms]}
    if memory is not None:
        from .stream import memory_ports
        spec["memory"] = {"line": memory.line, "latency": memory.latency,
                          "p_ready": memory.p_ready, "seed": seed}
        spec["memory_ports"] = memory_ports(unit)
    with tempfile.TemporaryDirectory(dir=build_dir.parent) as tmp:
        tmp = Path(tmp)
        (tmp / "spec.json").write_text(json.dumps(spec))
        np.savez(tmp / "in.npz", **{f["name"]: np.asarray(inputs[f["name"]], np.int64)
                                    for f in spec["inputs"]})
        if memory is not None:
            np.savez(tmp / "mem.npz", words=memory.words)
        env = {"SHADE_SPEC": str(tmp / "spec.json"), "SHADE_IN": str(tmp / "in.npz"),
               "SHADE_MEM": str(tmp / "mem.npz"),
               "SHADE_OUT": str(tmp / "out.npz"), "SHADE_PROGRESS": str(tmp / "progress"),
               "PYTHONPATH": _env(simulator)["PYTHONPATH"]}
        with _environ(_env(simulator)), watch(tmp / "progress", progress or (lambda *_: None)):
            try:
                runner.test(test_module="sim.cocotb_bench", hdl_toplevel=name,
                            hdl_toplevel_lang="verilog",
                            build_dir=build_dir, test_dir=tmp, extra_env=env,
                            waves=bool(waves), results_xml=str(tmp / "results.xml"),
                            log_file=tmp / "sim.log", timescale=("1ns", "1ps"))
            except SystemExit:         # the runner exits when the bench fails: say why
                raise RuntimeError(f"cocotb run of {name} on {simulator} failed:\n"
                                   f"{_log_tail(tmp / 'sim.log')}") from None
        if not (tmp / "out.npz").exists():
            raise RuntimeError(f"cocotb run of {name} on {simulator} produced no output:\n"
                               f"{_log_tail(tmp / 'sim.log')}")
        got = dict(np.load(tmp / "out.npz"))
        wave = None
        if waves:
            found = [f for pattern in ("*.fst", "*.vcd")
                     for f in sorted(tmp.glob(pattern)) + sorted(build_dir.glob(pattern))]
            if found:
                wave = Path(waves).with_suffix(found[0].suffix)
                wave.parent.mkdir(parents=True, exist_ok=True)
                shutil.move(found[0], wave)
    info = {"latency": int(got.pop("latency")), "cycles": int(got.pop("cycles")), "waves": wave}
    for k in ("culled", "loading", "memory_reads"):
        if k in got:
            info[k] = int(got.pop(k))
    return got, info
