"""``make bench``: simulation speed, side by side. Every unit on every simulator that can run
here, in one run: cycles per second, rows per second (fragments for ``raster``), the model's
build time, and each path's speed as a ratio to the fastest. Writes ``build/bench/bench.json``
and ``build/bench/bench.md``.

Every simulator streams the same vectors (hard cases, then random rows), with ready and valid
held high; the default scene's pipeline renders the default scene's triangles (all of them on
the batch path, the first few on the others); the batch path streams the vectors repeated up
to ``--batch-rows`` (raster: a thousandth as many triangles, the scene a five-hundredth: about
a million fragments either way) so that its run is long enough to time (its process start-up
is included). Build times are those recorded when each
model was built (models are cached under ``build/``).

    make bench      (python -m flows.bench [--units U,U] [--batch-rows N])
"""
import argparse
import json
import sys
import time

import numpy as np

from golden import MODELS
from hdl.units import UNITS, make_unit

from sim.run import simulate
from sim.cli_common import unit_names, user_errors
from sim.simulators import SIMS, available
from sim.verilog import BUILD, SCENES

OUT = BUILD / "bench"
ROWS = {"amaranth": 5000, "icarus": 20000, "cocotb-verilator": 20000, "verilator": 20000}
TRIANGLES = {"amaranth": 4, "icarus": 40, "cocotb-verilator": 40, "verilator": 40}   # amaranth:
# about 110 cycles/s on the shared-multiplier raster (its thousands of registers), so few
RASTER = {"screen_bits": 10}
SCENE = SCENES / "default.toml"
SCENE_TRIANGLES = {"amaranth": 2, "icarus": 4, "cocotb-verilator": 4}   # verilator: all


def build_seconds(name, params, simulator):
    """The recorded build time of a cached model (None for Amaranth: nothing to build)."""
    if simulator == "amaranth":
        return None
    if simulator == "verilator":
        from sim.batch import build
        path = build(name, params).parent / "build_seconds"
    else:
        from sim.cocotb_run import build
        path = build(name, params, simulator)[1] / "build_seconds"
    return float(path.read_text()) if path.exists() else None


def measure(name, params, simulator, inputs, label=None):
    unit = make_unit(name, spec=True, **params)
    seconds_build = build_seconds(name, params, simulator)        # builds it if need be
    t0 = time.perf_counter()
    out, info = simulate(name, unit.params, inputs, simulator)
    seconds = time.perf_counter() - t0
    items = len(out["tri"]) if unit.status_ports else len(next(iter(out.values())))
    return {"unit": label or name, "simulator": simulator, "rows_in": len(next(iter(inputs.values()))),
            "items_out": items, "cycles": info["cycles"], "seconds": round(seconds, 3),
            "cycles_per_s": info["cycles"] / seconds, "items_per_s": items / seconds,
            "build_s": seconds_build}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.bench", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--units", help="comma-separated units, 'scene' for the default scene's "
                                    "pipeline (default: all of them)")
    ap.add_argument("--batch-rows", type=int, default=2_000_000,
                    help="rows the batch path streams, the vectors repeated (default 2,000,000;"
                         " raster: a thousandth as many triangles, scene a five-hundredth)")
    args = ap.parse_args(argv)
    with user_errors():
        names = unit_names(args.units, {**UNITS, "scene": None})
        sims = [s for s in SIMS if available(s) is None]
        for s in SIMS:
            if s not in sims:
                print(f"note: {s} skipped: {available(s)}", file=sys.stderr)
        rows = []
        for name in names:
            if name == "scene":
                rows += scene_rows(sims, args.batch_rows // 500)
                continue
            params = RASTER if name == "raster" else {}
            full = make_unit(name, spec=True, **params).params
            many = name == "raster"
            for sim in sims:
                n = (TRIANGLES if many else ROWS)[sim]
                inputs = MODELS[name].vectors(np.random.default_rng(1), n, **full)
                if sim == "verilator":
                    reps = max(1, (args.batch_rows // 1000 if many else args.batch_rows) // n)
                    inputs = {k: np.tile(v, reps) for k, v in inputs.items()}
                print(f"{name} on {sim}: {len(next(iter(inputs.values()))):,} "
                      f"{'triangles' if many else 'rows'}", file=sys.stderr, flush=True)
                rows.append(measure(name, full, sim, inputs))
        report(rows)


def scene_rows(sims, triangles):
    """The default scene's pipeline rendering the default scene: every triangle on the batch
    path (the scene repeated up to ``triangles``), the first few on the others (fragments per
    second either way)."""
    from scene.driver import load, prepare
    from scene.host import stream
    prep = prepare(load(SCENE))
    full = make_unit("scene", spec=True, **prep["params"]).params     # the key of its model
    rows = []
    for sim in sims:
        n = SCENE_TRIANGLES.get(sim)
        inputs = {k: v[:n] for k, v in prep["inputs"].items()}
        if n is None:                  # the batch path: the scene repeated, a run long enough
            reps = max(1, triangles // len(next(iter(inputs.values()))))    # to time
            inputs = {k: np.tile(v, reps) for k, v in inputs.items()}
        print(f"scene_default on {sim}: {len(next(iter(inputs.values()))):,} triangles",
              file=sys.stderr, flush=True)
        rows.append(measure("scene", full, sim, stream(inputs, prep["load"]),
                            label="scene_default"))
    return rows


def report(rows):
    OUT.mkdir(parents=True, exist_ok=True)
    for unit in {r["unit"] for r in rows}:
        mine = [r for r in rows if r["unit"] == unit]
        best = max(r["cycles_per_s"] for r in mine)
        cocotb = next((r["cycles_per_s"] for r in mine if r["simulator"] == "cocotb-verilator"),
                      None)
        for r in mine:
            r["ratio_to_fastest"] = r["cycles_per_s"] / best
            r["batch_over_cocotb_verilator"] = (r["cycles_per_s"] / cocotb
                                                if cocotb and r["simulator"] == "verilator"
                                                else None)
    (OUT / "bench.json").write_text(json.dumps({"rows": rows}, indent=2) + "\n")
    lines = ["| unit | simulator | rows in | items out | cycles | s | cycles/s | items/s | "
             "build s | / fastest | batch / cocotb-verilator |",
             "| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for r in rows:
        b = "" if r["build_s"] is None else f"{r['build_s']:.1f}"
        x = "" if r["batch_over_cocotb_verilator"] is None else \
            f"{r['batch_over_cocotb_verilator']:.0f}x"
        lines.append(f"| {r['unit']} | {r['simulator']} | {r['rows_in']:,} | "
                     f"{r['items_out']:,} | {r['cycles']:,} | {r['seconds']:.2f} | "
                     f"{r['cycles_per_s']:,.0f} | {r['items_per_s']:,.0f} | {b} | "
                     f"{r['ratio_to_fastest']:.4f} | {x} |")
    text = "\n".join(lines) + "\n"
    (OUT / "bench.md").write_text(text)
    print(text)
    print(f"written: {OUT / 'bench.json'}, {OUT / 'bench.md'}")


if __name__ == "__main__":
    main()
