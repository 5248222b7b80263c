"""What the setup's reciprocal costs in time and buys in accuracy: for each way of computing
it (Newton-Raphson with 0-3 steps from a 256-entry seed, or the restoring divider), the setup
latency in clocks, the largest relative error of 1/Omega's mantissa over every 16-bit mantissa
(the same integer recurrences as the RTL, hdl/arith.py), and the largest fragment error the
RTL shows against the float model on the same triangles (Amaranth's simulator).

    python -m sim.recip_cost [--triangles N]
"""
import argparse
import sys
import time

import numpy as np

from golden import MODELS, random_triangles, raster_hard_cases
from hdl.arith import recip_seed
from hdl.units import make_unit

from .__main__ import simulate

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
    ap = argparse.ArgumentParser(prog="python -m sim.recip_cost", description=__doc__.split("\n")[0])
    ap.add_argument("--triangles", type=int, default=60)
    args = ap.parse_args(argv)
    base = {"screen_bits": 7}
    params = make_unit("raster", spec=True, **base).params
    hard, _ = raster_hard_cases(**params)
    extra = random_triangles(np.random.default_rng(4), args.triangles, **params)
    inputs = {k: np.concatenate([hard[k], extra[k]]) for k in hard}
    print("| reciprocal | setup latency (clocks) | relative error of 1/m | max fragment error (LSB) "
          "| fragments | sim time (s) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for method, iters in CONFIGS:
        p = {**base, "recip": method, "recip_iters": iters}
        unit = make_unit("raster", spec=True, **p)
        t0 = time.time()
        print(f"{method} {iters}: simulating...", file=sys.stderr, flush=True)
        out, info = simulate("raster", unit.params, inputs, "amaranth")
        want = MODELS["raster"].run(inputs, **unit.params)
        if len(out["tri"]) != len(want["tri"]):
            err = float("inf")
        else:
            err = max(float(np.abs(out[k] - want[k]).max()) for k in want if k.startswith("v"))
        label = "divider" if method == "divide" else f"Newton-Raphson, {iters} step(s)"
        print(f"| {label} | {unit.setup.latency} | {recip_error(method, iters):.2e} | {err:.2f} "
              f"| {len(out['tri'])} | {time.time() - t0:.0f} |", flush=True)


if __name__ == "__main__":
    main()
