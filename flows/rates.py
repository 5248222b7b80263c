"""Fragments per clock on issue 49's three meshes, through the default pipeline's RTL on
Verilator, in the cycles `make render` counts: the default torus (12 x 12
segments), Wuson (the OBJ) and a 64 x 64-segment torus at 256 x 256; per raster setting
(``--raster``, as ``make render``'s), and the share of rows on the narrow row engine where it
is built (``flows.bfp.built_share``: the setup's choice from the float model's constants).

    python -m flows.rates [--raster row_narrow=21] ...   (a minute or two a setting)
"""
import argparse

from scene import driver as S
from sim.cli_common import raster_knobs
from sim.render import run_rtl
from sim.verilog import SCENES

from .bfp import MESHES, _scene_inputs, built_share


def rate(name, segments, raster):
    """(fragments, cycles, fragments per clock) of a mesh through the RTL."""
    scene = S.load(SCENES / f"{name}.toml")          # 256 x 256, as flows.bfp's
    if segments:
        scene["mesh"]["segments"] = segments
    prep = S.prepare(scene, raster_knobs(raster) if raster else None)
    _, _, frags, info, _, _ = run_rtl(prep, "verilator")
    n = len(frags["x"])
    return n, info["cycles"], n / info["cycles"]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--raster", action="append", default=[],
                    help="a raster setting (KNOB=N,...); several: one row each; none: the "
                         "default")
    args = ap.parse_args(argv)
    settings = args.raster or [""]
    print("| raster | " + " | ".join(label for label, _, _ in MESHES) + " |")
    print("| --- | " + " | ".join("---" for _ in MESHES) + " |")
    for setting in settings:
        knobs = raster_knobs(setting) if setting else {}
        cells = []
        for label, name, seg in MESHES:
            n, cycles, r = rate(name, seg, setting)
            cell = f"{r:.3f} ({n:,} in {cycles:,})"
            if knobs.get("row_narrow"):
                inputs, sb, sub, modes = _scene_inputs(name, seg)
                _, rows = built_share(inputs, knobs["row_narrow"], sb, sub, modes)
                cell += f", {rows * 100:.0f} % of rows narrow"
            cells.append(cell)
        print(f"| {setting or 'default'} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
