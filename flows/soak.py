"""``make soak``: long streams on the batch path with random stalls on both sides, against the
golden model. Every one-row-in-one-row-out unit streams ``--rows`` rows (hard cases, then
random) in one run, with valid gaps and ready stalls; ``raster`` streams ``--triangles``
triangles of typical size. Bit-exact units must match exactly, the others stay within their
derived bounds; the row count and the row-by-row comparison show that nothing was lost,
repeated or reordered, and the harness checks that every stalled output held its payload.

    make soak      (python -m flows.soak [--rows N] [--triangles N] [--units U,U])
"""
import argparse
import sys
import time

import numpy as np

from golden import MODELS
from hdl.units import UNITS, make_unit

from sim.run import simulate
from sim.cli_common import unit_names, user_errors

CHUNK = 1_000_000            # rows checked against golden at a time (memory)
TRAFFIC = {"p_valid": 0.8, "p_ready": 0.7, "seed": 17}


def _slice(arrays, lo, hi):
    return {k: v[lo:hi] for k, v in arrays.items()}


def soak_rows(name, n, seed=0):
    """``n`` rows through the unit; returns the verdict and the counts."""
    unit = make_unit(name, spec=True)
    inputs = MODELS[name].vectors(np.random.default_rng(seed), n, **unit.params)
    n = len(next(iter(inputs.values())))
    t0 = time.time()
    out, info = simulate(name, unit.params, inputs, "verilator", progress=True, **TRAFFIC)
    sim_s = time.time() - t0
    got = len(next(iter(out.values())))
    if got != n:
        return False, f"{got:,} rows out for {n:,} in"
    worst, over = 0.0, 0
    for lo in range(0, n, CHUNK):
        part = MODELS[name].check(_slice(inputs, lo, lo + CHUNK),
                                  _slice(out, lo, lo + CHUNK), **unit.params)
        for err, bound in part.values():
            err = np.asarray(err, float)
            bound = np.broadcast_to(np.asarray(bound, float), err.shape)
            over += int(np.sum(err > bound + 1e-9))
            pos = bound > 0
            if pos.any():
                worst = max(worst, float(np.max(err[pos] / bound[pos])))
    kind = "bit-exact" if MODELS[name].exact else f"worst error {worst:.2f} of its bound"
    return over == 0, (f"{n:,} rows in, {got:,} out, {info['cycles']:,} cycles, "
                       f"{sim_s:.1f} s; {kind}; {over:,} rows beyond their bound")


def soak_raster(triangles, seed=0, chunk=5000):
    unit = make_unit("raster", spec=True)
    inputs = MODELS["raster"].vectors(np.random.default_rng(seed), triangles, **unit.params)
    t0 = time.time()
    out, info = simulate("raster", unit.params, inputs, "verilator", progress=True, **TRAFFIC)
    sim_s = time.time() - t0
    bad, frags = 0, 0
    for lo in range(0, triangles, chunk):
        part = _slice(inputs, lo, lo + chunk)
        sel = (out["tri"] >= lo) & (out["tri"] < lo + chunk)
        mine = {k: v[sel] for k, v in out.items()}
        mine["tri"] = mine["tri"] - lo
        frags += int(sel.sum())
        for err, bound in MODELS["raster"].check(part, mine, **unit.params).values():
            bad += int(np.sum(np.asarray(err, float) > np.asarray(bound, float) + 1e-9))
    order = bool(np.all(np.diff(out["tri"]) >= 0))
    ok = bad == 0 and order and frags == len(out["tri"])
    return ok, (f"{triangles:,} triangles in ({info['culled']:,} culled), {len(out['tri']):,} "
                f"fragments out, {info['cycles']:,} cycles, {sim_s:.1f} s; coverage and values "
                f"{'within bounds' if bad == 0 else f'off in {bad:,} places'}, "
                f"{'in triangle order' if order else 'OUT OF ORDER'}")


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.soak", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rows", type=int, default=10_000_000)
    ap.add_argument("--triangles", type=int, default=100_000)
    ap.add_argument("--units", help="comma-separated units (default: all)")
    args = ap.parse_args(argv)
    with user_errors():
        names = unit_names(args.units, UNITS)
        failed = 0
        for name in names:
            ok, text = soak_raster(args.triangles) if name == "raster" else \
                soak_rows(name, args.rows)
            failed += not ok
            print(f"{'PASS' if ok else 'FAIL'}  {name:13} {text}", flush=True)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
