"""``make turntable``: a scene in motion, every frame through the RTL on the batch path.

The scene's ``[turntable]`` table (docs/scenes.md) says what moves: the mesh spinning, or the
lights orbiting, ``degrees`` over the animation about ``axis``; frame k of n is the scene with
``turntable.frame = k`` and ``frames = n``, so any frame is an ordinary scene. Each frame is an
independent job (``sim.jobs``): on a local process pool, or on a Dask cluster with
``--dask``. A job renders its frame through the RTL of every method asked for, and the float64
reference once; the simulator models are built before the jobs start and shared.

With no scene, the default torus with its light orbiting, through linear, X-shading and Phong
side by side: linear's highlight jumps from vertex to vertex, X-shading's moves as Phong's.

    make turntable [SCENE=...] [FRAMES=n] [DASK=tcp://host:8786]
    python -m sim.turntable [SCENE] [--frames N] [--methods a,b] [--size WxH] [--dask ADDR]

Writes ``build/turntable/<scene>/``: ``turntable.gif`` (each method's RTL and the reference
side by side, a frame each), ``psnr.png`` (each frame's PSNR against the reference, by
method), ``strip.png`` (six frames, a row per method) and ``turntable.json`` (the figures).
"""
import argparse
import copy
import json
import time
from pathlib import Path

import numpy as np

from scene import driver as S

from .cli_common import UsageError, user_errors
from .jobs import run
from .render import compare, run_rtl
from .verilog import BUILD, SCENES

DEFAULT_METHODS = ("linear", "xshading", "phong")
LABEL = 14                        # pixels of caption above each tile


def variant(scene, method, k, frames):
    """The scene shaded by ``method`` at frame ``k`` of ``frames`` (parsed again: the
    frame and the method are checked as a scene's keys are)."""
    sc = copy.deepcopy({key: v for key, v in scene.items() if key != "name"})
    sc["shading"]["method"] = method
    sc["turntable"].update(frame=k, frames=frames)
    return S.parse(sc, scene["name"])


def frame(scene, k, frames, methods, simulator="verilator"):
    """One frame: each method's RTL image and its figures against the reference."""
    t0 = time.time()
    out = {"frame": k, "rtl": {}, "figures": {}}
    for method in methods:
        prep = S.prepare(variant(scene, method, k, frames))
        rtl, cov, frags, info, _, wall = run_rtl(prep, simulator)
        if method == methods[0]:
            ref, rcov = S.reference(prep)
        vs = compare(rtl, cov, ref, rcov)
        out["rtl"][method] = rtl
        out["figures"][method] = {"psnr_db": vs["psnr_db"], "max_abs": vs["max_abs"],
                                  "fragments": len(frags["x"]), "cycles": info["cycles"],
                                  "rtl_wall_s": round(wall, 3)}
    out["reference"] = ref
    out["wall_s"] = round(time.time() - t0, 3)
    return out


def turntable(scene, frames=None, methods=None, simulator="verilator", jobs=2, dask=None,
              out_dir=None, quiet=False):
    """Every frame of ``scene`` (a parsed scene); writes the animation, the plot, the strip
    and the figures into ``out_dir``; returns the frames (``frame``'s results, in order)."""
    frames = frames or scene["turntable"]["frames"]
    methods = list(methods or [scene["shading"]["method"]])
    for method in methods:                        # every method's scene is valid, and its
        prep = S.prepare(variant(scene, method, 0, frames))      # model built, before the jobs
        if simulator == "verilator":
            from .batch import build
            build("scene", prep["params"])
    t0 = time.time()
    done = run(frame, [(scene, k, frames, methods, simulator) for k in range(frames)], jobs,
               dask, desc=f"turntable {scene['name']}", unit="frame", quiet=quiet,
               label=lambda r: " ".join(f"{m} {f['psnr_db']} dB"
                                        for m, f in r["figures"].items()),
               key=lambda k, t: f"turntable-{scene['name']}-{'-'.join(methods)}-{k}-of-{frames}")
    wall = time.time() - t0
    if out_dir is not None:
        write(scene, done, methods, Path(out_dir), wall, "dask" if dask else f"pool of {jobs}")
    return done


def _tiles(result, methods):
    """One animation frame: each method's RTL image and the reference, captioned."""
    from PIL import Image, ImageDraw
    imgs = [(m, result["rtl"][m], f"{m} {result['figures'][m]['psnr_db']} dB")
            for m in methods] + [("reference", result["reference"], "reference")]
    h, w = imgs[0][1].shape[:2]
    sheet = Image.new("RGB", (w * len(imgs), h + LABEL), "white")
    draw = ImageDraw.Draw(sheet)
    for k, (_, img, caption) in enumerate(imgs):
        sheet.paste(Image.fromarray(img), (k * w, LABEL))
        draw.text((k * w + 3, 1), caption, fill="black")
    return sheet


def write(scene, done, methods, out, wall, executor):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from PIL import Image, ImageDraw
    out.mkdir(parents=True, exist_ok=True)
    sheets = [_tiles(r, methods) for r in done]
    sheets[0].save(out / "turntable.gif", save_all=True, append_images=sheets[1:],
                   duration=120, loop=0)
    picks = sorted(set(np.linspace(0, len(done) - 1, min(6, len(done))).round().astype(int)))
    rows = [[r["rtl"][m] for r in (done[k] for k in picks)] for m in methods]
    rows.append([done[k]["reference"] for k in picks])
    strip = Image.fromarray(np.concatenate([np.concatenate(r, 1) for r in rows], 0))
    draw = ImageDraw.Draw(strip)
    h = rows[0][0].shape[0]
    for k, name in enumerate([*methods, "reference"]):
        for j, f in enumerate(picks):
            draw.text((j * rows[0][0].shape[1] + 3, k * h + 2),
                      f"{name}, frame {f}" if j == 0 else f"frame {f}", fill="white")
    strip.save(out / "strip.png")
    fig, ax = plt.subplots(figsize=(6, 3.2), dpi=100)
    for m in methods:
        ax.plot([r["frame"] for r in done], [r["figures"][m]["psnr_db"] for r in done],
                marker=".", label=m)
    turn = scene["turntable"]
    ax.set_xlabel(f"frame ({turn['spin']} turning {turn['degrees']:g} degrees over "
                  f"{len(done)} frames)")
    ax.set_ylabel("RTL vs reference, PSNR dB")
    ax.set_title(f"{scene['name']}: each frame through the RTL", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / "psnr.png")
    plt.close(fig)
    figures = {"scene": scene["name"], "frames": len(done), "methods": methods,
               "turntable": {**turn, "frames": len(done), "frame": None},
               "executor": executor, "wall_s": round(wall, 2),
               "wall_s_per_frame": round(wall / len(done), 3),
               "job_wall_s": [r["wall_s"] for r in done],
               "psnr_db": {m: {"min": min(r["figures"][m]["psnr_db"] for r in done),
                               "mean": round(float(np.mean([r["figures"][m]["psnr_db"]
                                                            for r in done])), 2),
                               "max": max(r["figures"][m]["psnr_db"] for r in done)}
                           for m in methods},
               "per_frame": [{"frame": r["frame"], **r["figures"]} for r in done]}
    (out / "turntable.json").write_text(json.dumps(figures, indent=1) + "\n")
    return figures


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m sim.turntable", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", help="a scene file (default: the default torus, "
                    "through linear, X-shading and Phong)")
    ap.add_argument("--frames", type=int, help="frames (default: the scene's "
                    "turntable.frames)")
    ap.add_argument("--methods", help="comma-separated shading methods, side by side "
                    "(default: the scene's own)")
    ap.add_argument("--size", help="WxH instead of the scene's image size")
    ap.add_argument("--dask", metavar="ADDRESS", help="a Dask scheduler (tcp://host:8786)")
    ap.add_argument("-j", "--jobs", type=int, default=2, help="local worker processes")
    ap.add_argument("--out", help="output directory (default: build/turntable/<scene>)")
    args = ap.parse_args(argv)
    with user_errors():
        scene = S.load(args.scene or Path(SCENES) / "default.toml")
        methods = args.methods.split(",") if args.methods else \
            None if args.scene else DEFAULT_METHODS
        if args.frames is not None and args.frames < 1:
            raise UsageError(f"--frames: must be 1 or more, not {args.frames}")
        if args.jobs < 1:
            raise UsageError(f"--jobs: must be 1 or more, not {args.jobs}")
        if args.size:
            try:
                w, h = (int(v) for v in args.size.lower().split("x"))
            except ValueError:
                raise UsageError(f"--size: must be WxH, not {args.size!r}") from None
            scene["image"].update(width=w, height=h)
            scene = S.parse({k: v for k, v in scene.items() if k != "name"}, scene["name"])
        out = Path(args.out or BUILD / "turntable" / scene["name"])
        done = turntable(scene, args.frames, methods, jobs=args.jobs, dask=args.dask,
                         out_dir=out)
        fig = json.loads((out / "turntable.json").read_text())
    print(f"{scene['name']}: {len(done)} frames in {fig['wall_s']} s "
          f"({fig['wall_s_per_frame']} s a frame, {fig['executor']}); RTL vs reference: " +
          "; ".join(f"{m} {p['min']}-{p['max']} dB" for m, p in fig["psnr_db"].items()))
    print(f"wrote {', '.join(str(out / f) for f in ('turntable.gif', 'psnr.png', 'strip.png', 'turntable.json'))}")


if __name__ == "__main__":
    main()
