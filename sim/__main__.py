"""``python -m sim``: describe units, run them on the RTL, export Verilog, check against golden.

  units [--json]                      every unit's parameters and field formats
  run UNIT --in IN.npz --out OUT.npz [--simulator amaranth|icarus|verilator] [--param N=V]
  verilog [--out DIR]                 Verilog of every unit, each linted by Verilator
  check [--unit U] [--simulator S] [--vectors N|all] [--param N=V]
                                      golden vectors through the RTL, one verdict per unit,
                                      waveforms under build/sim/
"""
import argparse
import json
import sys
import time

import numpy as np

from hdl.units import UNITS, describe, make_unit, parse_params

from .cli_common import UsageError, read_inputs, user_errors, write_outputs

SIMS = ("amaranth", "icarus", "verilator")


def simulate(name, params, inputs, simulator, *, p_valid=1.0, p_ready=1.0, seed=0,
             waves=None, progress=False):
    """Run inputs through the RTL on any simulator; returns ``(outputs, info)``.

    With ``progress``, says what it starts, and (Amaranth) reports every tenth of the rows."""
    if progress:
        rows = len(next(iter(inputs.values())))
        how = "Amaranth's simulator" if simulator == "amaranth" else f"cocotb on {simulator}"
        print(f"{name}: streaming {rows} rows through {how}", file=sys.stderr, flush=True)
    if simulator == "amaranth":
        from .amaranth_run import run_amaranth
        out, traffic = run_amaranth(make_unit(name, **params), inputs, p_valid=p_valid,
                                    p_ready=p_ready, seed=seed, vcd=waves,
                                    progress=name if progress else None)
        return out, {"latency": traffic.latency, "cycles": traffic.cycles, "waves": waves,
                     **getattr(traffic, "status", {})}
    from .cocotb_run import SimulatorMissing, run_cocotb
    try:
        return run_cocotb(name, params, inputs, simulator, p_valid=p_valid, p_ready=p_ready,
                          seed=seed, waves=bool(waves))
    except SimulatorMissing as e:
        raise UsageError(f"{simulator}: {e}") from None


def cmd_units(args):
    units = [describe(n) for n in UNITS]
    if args.json:
        print(json.dumps({"units": units}, indent=2))
        return
    for u in units:
        params = ", ".join(f"{k}={v}" for k, v in u["params"].items()) or "no parameters"
        print(f"{u['name']}  ({params}; latency {u['latency']} at defaults)\n  {u['doc']}")
        for side in ("inputs", "outputs"):
            for f in u[side]:
                kind = "s" if f["signed"] else "u"
                scale = f" / 2^{f['frac_bits']}" if f["frac_bits"] else ""
                print(f"    {side[:-1]:6} {f['name']:10} {kind}{f['width']:<3} raw{scale} "
                      f"[{f['unit']}]")


def cmd_run(args):
    params = parse_params(args.unit, args.param)
    unit = make_unit(args.unit, spec=True, **params)
    inputs = read_inputs(unit, args.inp)
    n = len(next(iter(inputs.values())))
    t0 = time.time()
    out, info = simulate(args.unit, unit.params, inputs, args.simulator, progress=True)
    write_outputs(unit, args.out, out)
    print(f"{args.unit} on {args.simulator}: {n} rows in {info['cycles']} cycles "
          f"({time.time() - t0:.1f} s) -> {args.out}")


def cmd_verilog(args):
    from .verilog import BUILD, export, lint
    out_dir = args.out or BUILD / "verilog"
    for name in UNITS:
        path = export(name, None, out_dir)
        lint(path, name)
        print(f"{path}  lint clean (verilator -Wall, accepted: see sim/verilog.py)")


def cmd_check(args):
    from golden import MODELS
    from .verilog import BUILD
    names = [args.unit] if args.unit else list(UNITS)
    failed = 0
    for name in names:
        params = make_unit(name, spec=True, **parse_params(name, args.param)).params
        rng = np.random.default_rng(args.seed)
        n = None if args.vectors == "all" else int(args.vectors)
        inputs = MODELS[name].vectors(rng, n, **params)
        rows = len(next(iter(inputs.values())))
        waves = BUILD / "sim" / args.simulator / f"{name}.vcd"
        waves.parent.mkdir(parents=True, exist_ok=True)
        t0 = time.time()
        out, info = simulate(name, params, inputs, args.simulator, p_valid=args.p_valid,
                             p_ready=args.p_ready, seed=args.seed,
                             waves=waves if args.simulator == "amaranth" else True,
                             progress=True)
        result = MODELS[name].check(inputs, out, **params)
        bad = {k: int(np.sum(e > b + 1e-9)) for k, (e, b) in result.items()}
        errs = ", ".join(
            f"{k} {float(np.max(e)):.3g} (median bound {float(np.median(b)):.3g}, "
            f"worst error/bound {float(np.max(e / np.maximum(b, 1e-12))):.2f})"
            if np.max(b) > 0 else f"{k} {float(np.max(e)):.3g} (bit-exact)"
            for k, (e, b) in ((k, (e, np.broadcast_to(b, e.shape)))
                              for k, (e, b) in result.items()))
        ok = not any(bad.values())
        failed += not ok
        print(f"{'PASS' if ok else 'FAIL'}  {name:13} {args.simulator:9} {rows:7} vectors "
              f"{info['cycles']:8} cycles {time.time() - t0:6.1f} s  max error in LSB: "
              f"{errs}  waves: {info['waves']}", flush=True)
    return failed


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m sim", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="cmd", required=True)
    p = sub.add_parser("units", help="list units, parameters and field formats")
    p.add_argument("--json", action="store_true")
    p = sub.add_parser("run", help="stream an npz of raw inputs through a unit's RTL")
    p.add_argument("unit", choices=sorted(UNITS))
    p.add_argument("--in", dest="inp", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--simulator", choices=SIMS, default="amaranth")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE")
    p = sub.add_parser("verilog", help="export and lint the Verilog of every unit")
    p.add_argument("--out")
    p = sub.add_parser("check", help="golden vectors through the RTL; one verdict per unit")
    p.add_argument("--unit", choices=sorted(UNITS))
    p.add_argument("--simulator", choices=SIMS, default="icarus")
    p.add_argument("--vectors", default="5000", help="rows per unit, or 'all' (full sweep)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE")
    p.add_argument("--p-valid", type=float, default=0.8)
    p.add_argument("--p-ready", type=float, default=0.8)
    p.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    with user_errors():
        if args.cmd == "check" and args.vectors != "all" and not args.vectors.isdigit():
            raise UsageError(f"--vectors must be a number or 'all', not {args.vectors!r}")
        rc = {"units": cmd_units, "run": cmd_run, "verilog": cmd_verilog,
              "check": cmd_check}[args.cmd](args)
    sys.exit(1 if rc else 0)


if __name__ == "__main__":
    main()
