"""``python -m sim render SCENE.toml``: a scene through the RTL of its pipeline, beside the float
model of the same method and the float64 reference (``design/scenes.md``, "What a render
writes").

The RTL streams fragments (x, y, depth, r, g, b); the depth test and the framebuffer are here,
as a model of external memory (``scene/pipeline.py`` says why).
"""
import json
import sys
import time
from pathlib import Path

import numpy as np

from scene import driver as S, obj


from .stream import Memory
from .verilog import BUILD, SCENES

__all__ = ["render", "compare", "flip", "gallery"]


def compare(a, cov_a, b, cov_b):
    """max_abs, psnr_db, pixels_over_1 and the share within 1 level over the pixels both cover
    (8-bit levels), and the pixels only one covers."""
    both = cov_a & cov_b
    d = np.abs(a[both].astype(np.int64) - b[both].astype(np.int64))
    mse = float(np.mean(d.astype(float) ** 2)) if d.size else 0.0
    return {"max_abs": int(d.max()) if d.size else 0,
            "within_1": round(float((d.max(-1) <= 1).mean()), 4) if d.size else 1.0,
            "psnr_db": round(10 * np.log10(255.0 ** 2 / mse), 2) if mse > 0 else float("inf"),
            "pixels_over_1": int((d.max(-1) > 1).sum()) if d.size else 0,
            "coverage_mismatch": int((cov_a ^ cov_b).sum())}


def save_png(path, img):
    from PIL import Image
    Image.fromarray(img).save(path)


def save_diff(path, rtl, ref, cov, title):
    """|rtl - reference| (largest over R, G, B) as a heat map with its scale."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    d = np.abs(rtl.astype(int) - ref.astype(int)).max(-1).astype(float)
    d[~cov] = np.nan
    h, w = d.shape
    fig, ax = plt.subplots(figsize=(4 + 1.2, 4 * h / w), dpi=100)
    im = ax.imshow(d, cmap="inferno", vmin=0, vmax=max(1.0, np.nanmax(d) if cov.any() else 1))
    ax.set_title(title, fontsize=9)
    ax.set_axis_off()
    fig.colorbar(im, ax=ax, label="|RTL - reference|, 8-bit levels")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def flip(test, ref, cov):
    """Mean FLIP (NVIDIA's perceptual error, flip-evaluator, LDR sRGB at 67 pixels per degree)
    over the pixels both images cover."""
    import flip_evaluator
    emap, _, _ = flip_evaluator.evaluate(ref.astype(np.float32) / 255, test.astype(np.float32)
                                         / 255, "LDR", applyMagma=False)
    emap = np.asarray(emap).reshape(cov.shape)
    return round(float(emap[cov].mean()), 5) if cov.any() else 0.0


def run_rtl(prep, simulator="verilator", mem_latency=12, mem_ready=1.0, progress=None):
    """A prepared scene through its pipeline's RTL (the model built first, and not timed):
    (image, covered, fragments, info, memory, wall seconds)."""
    from .run import simulate
    params = prep["params"]
    if simulator == "verilator":                # build (or find) the model before timing
        from .batch import build
        build("scene", params)
    elif simulator != "amaranth":
        from .cocotb_run import build
        build("scene", params, simulator)
    t0 = time.time()
    memory = None if prep["memory"] is None else \
        Memory(prep["memory"], latency=mem_latency, p_ready=mem_ready)
    frags, info = simulate("scene", params, S.rtl_inputs(prep), simulator, memory=memory,
                           progress=progress)
    wall = time.time() - t0
    rgb = np.stack([frags[c] for c in "rgb"], -1).astype(np.uint8)
    rtl, cov = S.framebuffer(prep["size"], frags["x"], frags["y"], frags["depth"], rgb,
                             prep["scene"]["image"]["background"])
    return rtl, cov, frags, info, memory, wall


def render(scene_path, out_dir=None, simulator="verilator", size=None, quiet=False,
           hardware=None, mem_latency=12, mem_ready=1.0):
    """Render a scene (a file, or a parsed scene); writes the five files of scenes.md and
    returns the metrics. ``hardware``: pipeline parameters that are not scene keys (``make tradeoffs``'s knobs:
    the reciprocal, the power table's bits, fenney_dot's renormalisation). ``mem_latency``,
    ``mem_ready``: the texture memory's latency and the chance each clock that it takes a
    request and offers a response (``sim.stream.Memory``)."""
    scene = scene_path if isinstance(scene_path, dict) else S.load(scene_path)
    if size:
        scene["image"]["width"], scene["image"]["height"] = size
        scene = S.parse({k: v for k, v in scene.items() if k != "name"}, scene["name"])
    out_dir = Path(out_dir or BUILD / "render" / scene["name"])
    out_dir.mkdir(parents=True, exist_ok=True)
    prep = S.prepare(scene, hardware)
    pipe, params = prep["pipeline"], prep["params"]
    rtl, cov, frags, info, memory, wall = run_rtl(prep, simulator, mem_latency, mem_ready,
                                                  None if quiet else f"scene {scene['name']}")
    model, mcov, n_model = S.model(prep)
    ideal, icov = S.ideal(prep)
    ref, rcov = S.reference(prep)
    save_png(out_dir / "rtl.png", rtl)
    save_png(out_dir / "model.png", model)
    save_png(out_dir / "ideal.png", ideal)
    save_png(out_dir / "reference.png", ref)
    vs_ref = compare(rtl, cov, ref, rcov)
    bump = scene["bump"]["method"]
    save_diff(out_dir / "diff.png", rtl, ref, cov & rcov,
              f"{scene['name']}: {params['method'] if bump == 'none' else bump}, RTL vs reference: "
              f"{vs_ref['psnr_db']} dB, max {vs_ref['max_abs']}")
    n = len(frags["x"])
    drawn = prep["triangles"]["drawn"]
    units = []
    for stage in pipe.stages:
        unit = {**stage.describe(), "items_in": drawn if stage.name == "raster" else n,
                "items_out": n}
        units.append(unit)
    metrics = {"scene": scene["name"], "method": params["method"],
               "bump": scene["bump"]["method"], "simulator": simulator,
               "size": list(prep["size"]), "triangles": prep["triangles"],
               **({"mesh": obj.read(scene["mesh"]["file"]).counts}
                  if scene["mesh"]["shape"] == "obj" else {}),
               "fragments": n, "fragments_model": n_model, "cycles": info["cycles"],
               "fragments_per_clock": round(n / info["cycles"], 4) if info["cycles"] else None,
               **({"memory": {"latency": mem_latency, "ready": mem_ready,
                              "words_read": info.get("memory_reads"),
                              "words_per_fragment": round(info["memory_reads"] / n, 4)
                              if n and info.get("memory_reads") is not None else None}}
                  if memory is not None else {}),
               "load": {"words": len(prep["load"][0]), "cycles": info.get("loading")},
               "latency": info["latency"], "rtl_wall_s": round(wall, 3),
               "sim_px_per_s": round(n / wall, 1) if wall > 0 else None,
               "pipeline": {"params": params, "latency": pipe.latency,
                            "registers": prep["uniforms"],
                            "label": next((s.label for s in reversed(pipe.stages)
                                           if s.bump and s.label), None)},
               "units": units,
               "rtl_vs_model": compare(rtl, cov, model, mcov),
               "rtl_vs_reference": {**{k: vs_ref[k] for k in ("psnr_db", "max_abs",
                                                              "within_1")},
                                    "flip": flip(rtl, ref, cov & rcov)},
               "model_vs_reference": {k: v for k, v in compare(model, mcov, ref, rcov).items()
                                      if k in ("psnr_db", "max_abs")},
               "ideal_vs_reference": {k: v for k, v in compare(ideal, icov, ref, rcov).items()
                                      if k in ("psnr_db", "max_abs")},
               "rtl_vs_ideal": {k: v for k, v in compare(rtl, cov, ideal, icov).items()
                                if k in ("psnr_db", "max_abs")}}
    (out_dir / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    if not quiet:
        rm, rr = metrics["rtl_vs_model"], metrics["rtl_vs_reference"]
        if "mesh" in metrics:
            c = metrics["mesh"]
            print(f"{scene['name']}: {scene['mesh']['file']}: {c['triangles']:,} triangles "
                  f"from {c['faces']:,} faces, normals from {c['normals_from']}, texture "
                  f"coordinates from {c['texcoords_from']}")
        print(f"{scene['name']}: {drawn} triangles ({prep['triangles']['culled']} culled) -> "
              f"{n:,} fragments, {info['cycles']:,} cycles, {wall:.1f} s on {simulator}; "
              f"units: {', '.join(_names(u) for u in units)}\n"
              f"  RTL vs model: max {rm['max_abs']} levels, {rm['pixels_over_1']} pixels over 1, "
              f"coverage mismatch {rm['coverage_mismatch']}; RTL vs reference: "
              f"{rr['psnr_db']} dB (model: {metrics['model_vs_reference']['psnr_db']} dB, "
              f"ideal: {metrics['ideal_vs_reference']['psnr_db']} dB), max {rr['max_abs']}, "
              f"FLIP {rr['flip']}; RTL vs ideal {metrics['rtl_vs_ideal']['psnr_db']} dB\n"
              f"  wrote {', '.join(f'{out_dir}/{f}' for f in ('rtl.png', 'model.png', 'ideal.png', 'reference.png', 'diff.png', 'metrics.json'))}")
    return metrics


def _names(unit):
    parts = unit.get("parts")
    return unit["name"] + (f" ({', '.join(p['name'] for p in parts)})" if parts else "")


def gallery_scenes(scenes_dir=None):
    """The gallery's scenes: every file in ``scenes/`` (the default first), then, for each
    registered shading method that none of them uses (a method of one's own:
    ``scene.registry``), the default scene through it, named after the method."""
    from scene import registry
    paths = sorted(Path(scenes_dir or SCENES).glob("*.toml"),
                   key=lambda p: (p.stem != "default", p.stem))
    scenes = [S.load(p) for p in paths]
    used = {sc["shading"]["method"] for sc in scenes}
    default = next((sc for sc in scenes if sc["name"] == "default"), None)
    for m in (m for m in registry.methods() if m not in used and default):
        data = {k: v for k, v in default.items() if k != "name"}
        scenes.append(S.parse({**data, "shading": {**data["shading"], "method": m}}, m))
    return scenes


def gallery(scenes_dir=None, simulator="verilator"):
    """Render the gallery's scenes (``gallery_scenes``) and write one contact sheet,
    ``build/render/gallery.png``: each scene's RTL image labelled with its method and its PSNR
    against the reference, and the default scene's reference."""
    from PIL import Image, ImageDraw
    scenes = gallery_scenes(scenes_dir)
    tiles = []
    for scene in scenes:
        m = render(scene, simulator=simulator)
        out = BUILD / "render" / m["scene"]
        q = m["pipeline"]["params"]
        if m["bump"] == "none":
            what = f"{m['method']}, {q['power'] if q['specular'] else 'diffuse'}"
        else:
            what = f"{m['bump']}, {m['pipeline']['label']}"
        label = (f"{m['scene']}: {what}", f"{m['rtl_vs_reference']['psnr_db']} dB vs reference")
        tiles.append((Image.open(out / "rtl.png").convert("RGB"), label))
        if m["scene"] == "default":
            tiles.append((Image.open(out / "reference.png").convert("RGB"),
                          ("reference: per-pixel Phong,", "float64, exact power")))
    w = max(t.width for t, _ in tiles)
    h = max(t.height for t, _ in tiles)
    cols = min(4, len(tiles))
    rows = -(-len(tiles) // cols)
    sheet = Image.new("RGB", (cols * w, rows * (h + 30)), "white")
    draw = ImageDraw.Draw(sheet)
    for k, (tile, label) in enumerate(tiles):
        x, y = (k % cols) * w, (k // cols) * (h + 30)
        sheet.paste(tile, (x, y))
        draw.text((x + 4, y + h + 2), label[0], fill="black")
        draw.text((x + 4, y + h + 15), label[1], fill="black")
    path = BUILD / "render" / "gallery.png"
    sheet.save(path)
    print(f"wrote {path} ({len(scenes)} scenes)")
    return path


if __name__ == "__main__":
    from .cli_common import user_errors
    with user_errors():
        gallery(simulator=sys.argv[1] if len(sys.argv) > 1 else "verilator")
