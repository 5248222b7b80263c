"""``python -m sim``: describe units, run them on the RTL, export Verilog, check against golden.

  units [--json]                      every unit's parameters (defaults, ranges, choices) and
                                      field formats, and the scene pipeline's (its choices:
                                      the registered stages')
  run UNIT --in IN.npz --out OUT.npz [--simulator S] [--param N=V]
                                      stream IN's rows through the unit's RTL into OUT
  verilog [--out DIR]                 Verilog of every unit with one port per field, and its
                                      field map (DIR/<unit>.json), each linted by Verilator
  check [UNIT] [--simulator S] [--vectors N|all] [--param N=V] [--waves]
                                      golden vectors through the RTL, one verdict per unit
  check UNIT --in IN.npz --out OUT.npz [--param N=V]
                                      your own outputs OUT for inputs IN against the golden
                                      model and its derived bounds
"""
import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from hdl.span_unit.plan import KNOBS
from hdl.units import UNITS, describe, make_unit, parse_params

from .cli_common import (UsageError, check_output_path, raster_knobs, read_fields,
                         read_inputs, rows, summary, user_errors, write_outputs)
from .run import simulate
from .simulators import SIMS, available

def cmd_units(args):
    from hdl.units import PIPELINES
    units = [describe(n) for n in UNITS]
    # the composed pipelines (a scene's: its choices and parameters are the registered
    # stages', scene.registry)
    pipelines = [describe(n) for n in PIPELINES]
    sims = {s: available(s) or "available" for s in SIMS}
    if args.json:
        print(json.dumps({"units": units, "pipelines": pipelines, "simulators": sims},
                         indent=2))
        return
    print("simulators: " + "; ".join(f"{s} ({why})" for s, why in sims.items()) + "\n")
    for u in units + pipelines:
        print(f"{u['name']}  (latency {u['latency']} at the defaults)\n  {u['doc']}")
        for k, v in u["params"].items():
            r = u["param_ranges"][k]
            allowed = (f"{r['min']}..{r['max']}" if "min" in r else r["string"]
                       if "string" in r else
                       " | ".join(map(str, r["choices"])) + (", one per channel"
                                                             if "per_channel" in r else ""))
            print(f"    param  {k:12} = {v!s:10} ({allowed})")
        for side in ("inputs", "outputs"):
            for f in u[side]:
                kind = "s" if f["signed"] else "u"
                scale = f" / 2^{f['frac_bits']}" if f["frac_bits"] else ""
                print(f"    {side[:-1]:6} {f['name']:12} {kind}{f['width']:<3} raw{scale} "
                      f"[{f['unit']}]")


def cmd_run(args):
    params = parse_params(args.unit, args.param)
    unit = make_unit(args.unit, spec=True, **params)
    inputs = read_inputs(unit, args.inp)
    check_output_path(args.out)
    waves, window = trace_args(args)
    t0 = time.time()
    if rows(inputs):
        out, info = simulate(args.unit, unit.params, inputs, args.simulator, progress=True,
                             waves=waves, window=window)
    else:
        out, info = {f.name: np.zeros(0, np.int64) for f in unit.outputs}, {"cycles": 0}
    write_outputs(unit, args.out, out)
    print(f"{args.unit} on {args.simulator}: {summary(unit, inputs, out, info.get('culled'))} "
          f"in {info['cycles']:,} cycles ({time.time() - t0:.1f} s) -> {args.out}"
          + (f"; waves: {info['waves']}" if info.get("waves") else ""))


def trace_args(args):
    """``--trace FILE`` and ``--trace-window FIRST:LAST`` -> (path without suffix, window)."""
    if args.trace_window and not args.trace:
        raise UsageError("--trace-window needs --trace FILE")
    if args.trace_window and args.simulator != "verilator":
        raise UsageError("--trace-window works on the batch path (--simulator verilator)")
    window = None
    if args.trace_window:
        first, sep, last = args.trace_window.partition(":")
        if not (sep and first.isdigit() and last.isdigit() and int(first) <= int(last)):
            raise UsageError(f"--trace-window must be FIRST:LAST cycles, not "
                             f"{args.trace_window!r}")
        window = (int(first), int(last))
    if args.trace:
        check_output_path(args.trace, "--trace")
        return Path(args.trace).with_suffix(""), window
    return None, window


def cmd_verilog(args):
    from .verilog import BUILD, export, lint
    out_dir = args.out or BUILD / "verilog"
    target = args.target
    if args.scene:
        from scene.driver import load, pipeline_params, prepare
        from scene.stages.texture import board_form
        scene = load(args.scene)
        module = f"scene_{scene['name']}"
        if not module.isidentifier():
            raise UsageError(f"{args.scene}: the scene's file name must make a Verilog "
                             f"module name ({module!r} is not one)")
        # an FPGA target takes the board form (make fpga's: the texture on chip by default)
        texture = args.texture or ("external" if target == "generic" else "onchip")
        params = board_form(pipeline_params(scene), texture) if target != "generic" else \
            prepare(scene, {"texture": texture})["params"]
        path = export("scene", params, out_dir, module=module, target=target)
        lint(path, module, target)
        print(f"{path}  lint clean (verilator -Wall), {target} form, texture {params['texture']};"
              f" ports: {path.with_suffix('.json')}")
        return
    for name in UNITS:
        path = export(name, None, out_dir, target=target)
        lint(path, name, target)
        print(f"{path}  lint clean (verilator -Wall, accepted: see sim/verilog.py); "
              f"ports: {path.with_suffix('.json')}")


def cmd_render(args):
    from .render import render
    size = None
    if args.size:
        w, sep, h = args.size.lower().partition("x")
        if not (sep and w.isdigit() and h.isdigit()):
            raise UsageError(f"--size must be WIDTHxHEIGHT, not {args.size!r}")
        size = (int(w), int(h))
    reason = available(args.simulator)
    if reason:
        raise UsageError(f"{args.simulator}: {reason}")
    out = Path(args.out) if args.out else None
    if out and (out.exists() and not out.is_dir() or not out.parent.is_dir()):
        raise UsageError(f"--out {out}: must be a directory, or a new one in an existing "
                         f"directory")
    if args.mem_latency < 1 or not 0 < args.mem_ready <= 1:
        raise UsageError(f"--mem-latency must be at least 1 and --mem-ready in (0, 1], not "
                         f"{args.mem_latency} and {args.mem_ready}")
    render(args.scene, args.out, args.simulator, size, mem_latency=args.mem_latency,
           mem_ready=args.mem_ready, hardware={"texture": args.texture,
                                               **raster_knobs(args.raster)})


def params_for(names, pairs, chosen):
    """Each unit's parameters from ``--param`` pairs. Without a chosen unit, a pair applies to
    the units that have that parameter; one that no unit has is an error."""
    if chosen:
        return {chosen: parse_params(chosen, pairs)}
    out = {n: {} for n in names}
    for pair in pairs:
        key = pair.partition("=")[0]
        takers = [n for n in names if key in UNITS[n].PARAMS]
        if not takers:
            raise UsageError(f"--param {pair}: no unit has a parameter {key!r}")
        for n in takers:
            out[n].update(parse_params(n, [pair]))
        print(f"note: --param {pair} applies to {', '.join(takers)}", file=sys.stderr)
    return out


def print_verdict(unit, label, inputs, out, info, seconds):
    from .verdict import judge
    ok, worst, lines = judge(unit, inputs, out)
    counts = summary(unit, inputs, out, info.get("culled"))
    cycles = f", {info['cycles']:,} cycles" if info.get("cycles") else ""
    took = f", {seconds:.1f} s" if seconds is not None else ""
    print(f"{'PASS' if ok else 'FAIL'}  {unit.NAME:13} {label}: {counts}{cycles}{took}; "
          f"worst error {worst:.2f} of its bound", flush=True)
    for line in lines:
        print(f"      {line}")
    if info.get("waves"):
        print(f"      waves: {info['waves']}")
    return ok


def cmd_check(args):
    from golden import MODELS
    from .verilog import BUILD
    chosen = args.unit or args.unit_opt
    if args.unit and args.unit_opt and args.unit != args.unit_opt:
        raise UsageError(f"two units named: {args.unit} and --unit {args.unit_opt}")
    if (args.inp is None) != (args.out is None):
        raise UsageError("check a file of outputs with both --in IN.npz and --out OUT.npz")
    if args.inp:
        if not chosen:
            raise UsageError("check --in/--out needs the unit: check UNIT --in ... --out ...")
        unit = make_unit(chosen, spec=True, **parse_params(chosen, args.param))
        inputs = read_inputs(unit, args.inp)
        out = read_fields(unit.outputs, args.out, unit.NAME, "output")
        if rows(out) != rows(inputs) and not unit.status_ports:
            raise UsageError(f"{args.out} has {rows(out):,} rows, {args.inp} has "
                             f"{rows(inputs):,}: one output row per input row")
        return not print_verdict(unit, f"{args.out} against golden", inputs, out, {}, None)
    names = [chosen] if chosen else list(UNITS)
    params = params_for(names, args.param, chosen)
    failed = 0
    for name in names:
        unit = make_unit(name, spec=True, **params[name])
        n = {"all": None, None: MODELS[name].typical}.get(args.vectors, args.vectors)
        n = n if n is None else int(n)
        inputs = MODELS[name].vectors(np.random.default_rng(args.seed), n, **unit.params)
        waves = BUILD / "sim" / args.simulator / name if args.waves else None
        t0 = time.time()
        out, info = simulate(name, unit.params, inputs, args.simulator, p_valid=args.p_valid,
                             p_ready=args.p_ready, seed=args.seed, waves=waves, progress=True)
        failed += not print_verdict(unit, args.simulator, inputs, out, info, time.time() - t0)
    return failed


def main(argv=None):
    with user_errors():            # a stage of one's own that cannot load: one line
        ap = parser()
        args = ap.parse_args(argv)
        if args.cmd == "check" and args.vectors not in (None, "all") \
                and not args.vectors.isdigit():
            raise UsageError(f"--vectors must be a number or 'all', not {args.vectors!r}")
        rc = {"units": cmd_units, "run": cmd_run, "verilog": cmd_verilog,
              "check": cmd_check, "render": cmd_render}[args.cmd](args)
    sys.exit(1 if rc else 0)


def parser():
    ap = argparse.ArgumentParser(prog="python -m sim", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("units", help="list units, parameters and field formats")
    p.add_argument("--json", action="store_true")
    p = sub.add_parser("run", help="stream an npz of raw inputs through a unit's RTL")
    p.add_argument("unit", choices=sorted(UNITS))
    p.add_argument("--in", dest="inp", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--simulator", choices=SIMS, default="amaranth",
                   help="amaranth | icarus | cocotb-verilator (cocotb benches) | verilator "
                        "(the fast batch path)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--trace", metavar="FILE",
                   help="write a waveform (FST from icarus, VCD from the others; the suffix "
                        "is the simulator's)")
    p.add_argument("--trace-window", metavar="FIRST:LAST",
                   help="only these cycles (batch path), to open a failure in a viewer")
    p = sub.add_parser("verilog", help="export and lint the Verilog of every unit, or of a "
                                       "scene's pipeline")
    p.add_argument("--out")
    p.add_argument("--scene", metavar="SCENE.toml",
                   help="the composed pipeline of this scene: build/verilog/scene_<name>.v")
    p.add_argument("--target", choices=("generic", "ecp5"), default="generic",
                   help="generic Verilog (default; the synthesiser infers multipliers), or an "
                        "FPGA family's form, which make fpga places (ecp5: MULT18X18D with "
                        "their registers)")
    p.add_argument("--texture", choices=("external", "onchip"),
                   help="a bump scene's texture: external (default for generic) or onchip "
                        "(default for an FPGA target)")
    from scene import registry
    p = sub.add_parser("render", help="render a scene through its pipeline's RTL, beside the "
                                      "float model and the reference",
                       epilog="the registered stages' choices (scene.registry; "
                              f"{registry.ENV} adds your own): shading.method: "
                              f"{', '.join(registry.methods())}; shading.power: "
                              f"{', '.join(registry.powers())}; bump.method: "
                              f"{', '.join(registry.bumps())}")
    p.add_argument("scene", metavar="SCENE.toml")
    p.add_argument("--out", metavar="DIR", help="default: build/render/<scene name>/")
    p.add_argument("--simulator", choices=SIMS, default="verilator",
                   help="verilator (the batch path, default) | amaranth | icarus | "
                        "cocotb-verilator")
    p.add_argument("--size", metavar="WxH", help="override the scene's image size")
    p.add_argument("--mem-latency", type=int, default=12, metavar="N",
                   help="the texture memory's latency in clocks (bump scenes; default 12)")
    p.add_argument("--mem-ready", type=float, default=1.0, metavar="P",
                   help="the chance each clock that the texture memory takes a request and "
                        "offers a response (default 1: no stalls)")
    p.add_argument("--texture", choices=("external", "onchip"), default="external",
                   help="bump scenes: the texels in external memory behind the texel cache "
                        "(default), or in an on-chip RAM that the host loads (maps up to "
                        "128 x 128)")
    p.add_argument("--raster", metavar="KNOB=N,...",
                   help="the raster's build knobs (hdl/span_unit/plan.py, docs/quadratic.md): "
                        + "; ".join(f"{k}: {what} ({lo}-{hi}, default {d})"
                                    for k, (d, (lo, hi), what) in KNOBS.items())
                        + "; recip, recip_iters: the setup's reciprocal; vector_bits: the "
                          "fraction bits of fenney_xz's vector channels, 4-14; e.g. "
                          "setup_ii=16,setup_mults=2,setup_narrow=2")
    p = sub.add_parser("check", help="golden vectors through the RTL, or your outputs against "
                                     "golden; one verdict per unit")
    p.add_argument("unit", nargs="?", choices=sorted(UNITS))
    p.add_argument("--unit", dest="unit_opt", choices=sorted(UNITS))
    p.add_argument("--in", dest="inp", help="inputs whose outputs --out holds")
    p.add_argument("--out", help="outputs to check (from sim run or your own simulation)")
    p.add_argument("--simulator", choices=SIMS, default="icarus",
                   help="amaranth | icarus | cocotb-verilator (cocotb benches) | verilator "
                        "(the fast batch path)")
    p.add_argument("--vectors", help="rows per unit (triangles for raster): hard cases first, "
                   "then random; 'all': the full sweep; default: 5,000 rows, 300 triangles")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--p-valid", type=float, default=0.8)
    p.add_argument("--p-ready", type=float, default=0.8)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--waves", action="store_true",
                   help="write a waveform per unit under build/sim/<simulator>/")
    return ap


if __name__ == "__main__":
    main()
