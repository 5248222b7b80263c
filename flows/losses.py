"""Where each method's accuracy goes: from its float ideal to the model with the RTL's formats,
one group of formats at a time (part of ``make accuracy``).

For each gallery scene: the float ideal against the reference (the method's own error), then
the ideal with one group of stages run as their models instead (``scene.models.ideal``'s
``formats``): the raster (its vertex positions' 4 sub-pixel bits, its vertex values' and edge
constants' 14 and 15 fraction bits), the texels (the map's 8-bit codes, or 12-bit angles), the
shading (phong, fenney_dot, fenney_polar, bump_polar: their tables and widths), the power, the
colour (its 12-bit coefficients). Each loss is in dB against the ideal; all of them together
give the model exactly, which the RTL matches within its bounds (the gallery table).

    python -m flows.losses [SCENE ...]       # default: every scene in scenes/

Writes ``build/accuracy/losses.{md,json}``.
"""
import argparse
import json
from pathlib import Path

import numpy as np

from scene import driver as S

from sim.cli_common import user_errors
from sim.render import compare
from sim.verilog import BUILD, SCENES

GROUPS = ("raster", "texels", "shading", "power", "colour")
SUB_BITS = (6, 8, 10)          # the vertex positions' fraction bits tried beyond the RTL's 4


def _psnr(prep, ref, rcov, formats=(), real=None):
    img, cov = S.ideal({**prep, "real": real or prep["real"]}, formats)
    return compare(img, cov, ref, rcov)["psnr_db"]


def losses(path):
    """One scene's row (PSNR in dB against the reference): the ideal's; with each group's
    formats (``loss_db``: the ideal's less that); with the raster's positions alone and its
    values alone; with the positions at finer sub-pixel steps; the model's."""
    scene = S.load(path)
    prep = S.prepare(scene)
    ref, rcov = S.reference(prep)
    ideal = _psnr(prep, ref, rcov)
    row = {"scene": scene["name"], "method": prep["params"]["method"],
           "bump": scene["bump"]["method"], "ideal_db": ideal}
    row["psnr_db"] = {g: _psnr(prep, ref, rcov, (g,)) for g in GROUPS}
    row["loss_db"] = {g: round(ideal - p, 2) if np.isfinite(ideal) else None
                      for g, p in row["psnr_db"].items()}
    sub = prep["params"]["sub_bits"]
    rounded = lambda k: k[0] in "xy" and k[1:].isdigit()
    pos = {k: (np.asarray(prep["inputs"][k], float) if rounded(k) else v)
           for k, v in prep["real"].items()}
    val = {k: (v if rounded(k) else np.asarray(prep["inputs"][k], float))
           for k, v in prep["real"].items()}
    row["raster_positions_db"] = _psnr(prep, ref, rcov, real=pos)
    row["raster_values_db"] = _psnr(prep, ref, rcov, real=val)
    row["positions_at_sub_bits_db"] = {
        bits: _psnr(prep, ref, rcov, real={
            k: (np.rint(v * 2.0**(bits - sub)) / 2.0**(bits - sub) if rounded(k) else v)
            for k, v in prep["real"].items()}) for bits in SUB_BITS}
    img, cov, _ = S.model(prep)
    row["model_db"] = compare(img, cov, ref, rcov)["psnr_db"]
    return row


def _loss(ideal, psnr):
    """A loss in dB; where the ideal is the reference itself (phong: infinite PSNR), the PSNR
    the group leaves instead."""
    return f"{ideal - psnr:.2f}" if np.isfinite(ideal) else f"→ {psnr:.2f}"


def table(rows):
    head = ["scene", "method", "ideal dB", *(f"{g} dB" for g in GROUPS),
            "raster: positions / values dB", "positions at 6 / 8 / 10 sub-pixel bits dB",
            "model (all) dB", "ideal - model dB"]        # each a loss against the ideal
    out = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for r in rows:
        what = r["method"] if r["bump"] == "none" else r["bump"]
        out.append("| " + " | ".join([
            r["scene"], what, f"{r['ideal_db']:.2f}",
            *(_loss(r["ideal_db"], r["psnr_db"][g]) for g in GROUPS),
            f"{_loss(r['ideal_db'], r['raster_positions_db'])} / "
            f"{_loss(r['ideal_db'], r['raster_values_db'])}",
            " / ".join(_loss(r["ideal_db"], r["positions_at_sub_bits_db"][b]) for b in SUB_BITS),
            f"{r['model_db']:.2f}", _loss(r["ideal_db"], r["model_db"])]) + " |")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.losses", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", help="scene files (default: every scene in scenes/)")
    ap.add_argument("--out", default=str(BUILD / "accuracy"))
    args = ap.parse_args(argv)
    with user_errors():
        paths = args.scenes or sorted(Path(SCENES).glob("*.toml"))
        rows = []
        for p in paths:
            rows.append(losses(p))
            print(f"{rows[-1]['scene']}: ideal {rows[-1]['ideal_db']} dB, model "
                  f"{rows[-1]['model_db']} dB", flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "losses.json").write_text(json.dumps(rows, indent=1) + "\n")
    text = "\n".join(["# Where the accuracy goes: each group of formats' loss against the "
                      "float ideal (dB, PSNR against the reference)", "", *table(rows)]) + "\n"
    (out / "losses.md").write_text(text)
    print(text)
    print(f"wrote {out / 'losses.md'} and {out / 'losses.json'}")


if __name__ == "__main__":
    main()
