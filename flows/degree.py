"""Issue 49's per-triangle degree, measured before it is built: the share of each mesh's drawn
triangles whose X-shading channels' mid-edge terms (seed 001 eq 32: a, b and c, the terms
that make the channel quadratic) all stay below a bound, half an output LSB at 14, 10 and 7
fraction bits. A triangle under the bound could be set up as linear with no loss beyond
that half LSB (|a u^2 + b v^2 + c u v| <= max(|a|, |b|, |c|) where u + v <= 1).

    python -m flows.degree      (seconds: the driver and numpy only)"""
import numpy as np

from golden.quadratic import xshading_uv
from hdl.setup_unit.formats import EDGE, VALUE
from scene import driver as S
from sim.verilog import SCENES

MESHES = [("default torus, 12 x 12 segments", "default", None),
          ("wuson (OBJ)", "wuson", None),
          ("torus, 64 x 64 segments, 256 x 256", "default", [64, 64])]
BITS = (14, 10, 7)


def worst_terms(prep):
    """Per drawn triangle, the largest |a|, |b|, |c| of its X-shading channels, reals."""
    inp = prep["inputs"]
    e = [inp[k] * EDGE.lsb for k in ("e01", "e02", "e12")]
    worst = np.zeros(len(inp["x0"]))
    for k, (_, mode) in enumerate(prep["pipeline"].channels):
        if mode == "xshading":
            a, b, c = xshading_uv(*(inp[f"v{k}_{j}"] * VALUE.lsb for j in range(3)),
                                  *e)[:, :3].T
            worst = np.maximum(worst, np.max(np.abs([a, b, c]), 0))
    return worst


def main():
    print("| mesh | triangles drawn | median largest term (LSB at 14 bits) | "
          + " | ".join(f"linear at {b} bits" for b in BITS) + " |")
    print("| --- | --- | --- | " + " | ".join("---" for _ in BITS) + " |")
    for label, name, segments in MESHES:
        scene = S.load(SCENES / f"{name}.toml")
        if segments:
            scene["mesh"]["segments"] = segments
        worst = worst_terms(S.prepare(scene))
        share = [f"{(worst < 2.0 ** -(b + 1)).mean() * 100:.1f} %" for b in BITS]
        print(f"| {label} | {len(worst):,} | {np.median(worst) / VALUE.lsb:,.0f} | "
              + " | ".join(share) + " |")


if __name__ == "__main__":
    main()
