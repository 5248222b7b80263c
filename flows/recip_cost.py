"""What the setup's reciprocal costs in time and buys in accuracy: for each way of computing
it (Newton-Raphson with 0-3 steps from a 256-entry seed, or the restoring divider), the setup's
clocks per triangle (its schedule's length), the largest relative error of 1/Omega's mantissa over every 16-bit mantissa
(the same integer recurrences as the RTL, hdl/setup_unit/setup.py), and the largest fragment error the
RTL shows against the float model on the same triangles.

    make recip-cost   (python -m flows.recip_cost [--triangles N] [--screen-bits B] [--simulator S])
"""
import argparse
import time

import numpy as np

from golden import MODELS, TYPICAL_SIZE, random_triangles, raster_hard_cases
from hdl.arith import recip_seed
from hdl.units import make_unit

from sim.run import simulate
from sim.cli_common import user_errors
from sim.simulators import SIMS

CONFIGS = [("newton", 0), ("newton", 1), ("newton", 2), ("newton", 3), ("divide", 0)]


def recip_error(method, iters, R=28, bits=16):
    """Relative error of the reciprocal over mantissas m = n / 2**(bits-1), n in
    [2**(bits-1), 2**bits): the RTL's integer recurrence, in numpy."""
    n = np.arange(1 << (bits - 1), 1 << bits, dtype=object)
    if method == "divide":
        r = (1 << (R + bits - 1)) // n
    else:
        seed = recip_seed(8, R).contents
        r = np.array([int(seed[(int(k) >> (bits - 1 - 8)) & 255]) for k in n], dtype=object)
        for _ in range(iters):
            t = (2 << R) - (n * r >> (bits - 1))
            r = (r * t) >> R
    m = n.astype(float) / 2 ** (bits - 1)
    return float(np.max(np.abs(r.astype(float) / 2 ** R * m - 1)))


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.recip_cost", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--triangles", type=int, default=200,
                    help="random triangles of typical size after the hard cases (default 200)")
    ap.add_argument("--screen-bits", type=int, default=7, help="screen 2^n pixels square (7)")
    ap.add_argument("--simulator", choices=SIMS, default="verilator")
    args = ap.parse_args(argv)
    with user_errors():
        base = {"screen_bits": args.screen_bits}
        params = make_unit("raster", spec=True, **base).params
        hard, _ = raster_hard_cases(**params)
        extra = random_triangles(np.random.default_rng(4), args.triangles, **params,
                                 size=TYPICAL_SIZE)
        inputs = {k: np.concatenate([hard[k], extra[k]]) for k in hard}
        side = 1 << args.screen_bits
        print(f"raster on a {side} x {side} screen, {len(hard['x0'])} hard-case and "
              f"{args.triangles} random triangles, on {args.simulator}")
        print("| reciprocal | setup clocks per triangle | relative error of 1/m | max fragment "
              "error (LSB) | fragments | sim time (s) |")
        print("| --- | --- | --- | --- | --- | --- |")
        for method, iters in CONFIGS:
            unit = make_unit("raster", spec=True, **base, recip=method, recip_iters=iters)
            label = "divider" if method == "divide" else f"Newton-Raphson, {iters} step(s)"
            t0 = time.time()
            out, info = simulate("raster", unit.params, inputs, args.simulator, progress=True)
            want = MODELS["raster"].run(inputs, **unit.params)
            if len(out["tri"]) != len(want["tri"]):
                err = float("inf")
            else:
                err = max(float(np.abs(out[k] - want[k]).max()) for k in want
                          if k.startswith("v"))
            print(f"| {label} | {unit.timing[0]} | {recip_error(method, iters):.2e} | "
                  f"{err:.2f} | {len(out['tri']):,} | {time.time() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main()
