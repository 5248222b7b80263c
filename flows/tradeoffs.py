"""``make tradeoffs``: what accuracy costs, every knob measured side by side.

Each configuration (a knob and one of its settings, the others at their defaults) is measured
in one task:

- **error:** the scene rendered through the RTL on the batch path against the float64
  reference: PSNR, maximum and mean FLIP over the covered pixels (``sim.render``); and the
  knob's unit, its golden vectors through the RTL, against its *exact* function (not its
  model): maximum, 99th percentile and mean, in the unit the row names;
- **time:** the design's latency, fragments per clock on the scene, Fmax on ECP5-25F -6
  (``flows.fpga``'s flow, median over ``--seeds``), and ns per pixel = cycles per fragment /
  Fmax;
- **area:** LUT4, FF, MULT18X18D, DP16KD placed on the ECP5-25F (synthesis counts where it does
  not fit), and whether it fits an iCE40 UP5K (placed there too);
- **simulation cost:** the render's wall time on the batch path, and the unit test's (golden
  vectors through the RTL, checked against the model's derived bound).

The design of a row is the units its knob changes: for the shading method, every unit of the
scene's pipeline (area summed, Fmax the slowest unit's; the texture ROM is not a unit and is
left out); for the others, the one unit. Rows are cached in ``build/tradeoffs/cache/`` by a
hash of the design's Verilog, the scene file and the row's settings, so a rerun measures only
what changed; place and route has its own cache (``build/fpga/cache``).

The sweep runs through an executor: a local process pool with a progress bar, or with
``--dask ADDRESS`` a Dask distributed cluster, one task per configuration.

    make tradeoffs [QUICK=1] [DASK=tcp://host:8786]
    python -m flows.tradeoffs [--quick] [--dask ADDRESS] [--seeds N] [-j N] [--knobs a,b]

Writes ``build/tradeoffs/tradeoffs.json``, ``report.md`` and the Pareto plots.
"""
import argparse
import fcntl
import functools
import hashlib
import json
import time
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from hdl.span_unit.plan import ROW_MULTS
from scene.parse import load
from scene import registry
from sim.cli_common import UsageError, user_errors
from sim.jobs import run
from sim.verilog import BUILD, SCENES

OUT = BUILD / "tradeoffs"
FLOW = "tradeoffs-2"          # bump when a measurement changes: the row cache's key has it
ECP5_25F = {"LUT4": 24288, "FF": 24288, "MULT18X18D": 28, "DP16KD": 56}


# ---- the sweep -------------------------------------------------------------------------------

def _row(knob, setting, design, *, scene=None, hardware=None, size=None, unit=None,
         default=False):
    return {"knob": knob, "setting": setting, "default": default, "design": design,
            "scene": scene, "hardware": hardware or {}, "size": size, "unit": unit}


def _sweep_row(sw):
    """A stage's row (``scene.stage.Sweep``): its design, the unit alone, the scene's raster or
    its whole pipeline."""
    design = ([[sw.unit, sw.params]] if sw.build == "unit" else
              [_scene_parts(sw.scene, sw.hardware)[0]] if sw.build == "raster" else
              [["scene", _scene_params(sw.scene, sw.hardware)]])
    unit = None if sw.rows is False else {"name": sw.unit, "params": sw.params,
                                          "rows": sw.rows}
    return _row(sw.knob, sw.setting, design, scene=sw.scene, hardware=sw.hardware, unit=unit,
                default=sw.default)


def _scene_params(scene, hardware=None, size=None):
    """A scene's pipeline parameters, as ``sim.render`` builds it."""
    from scene import driver as S
    sc = S.load(SCENES / f"{scene}.toml")
    if size:
        sc["image"]["width"] = sc["image"]["height"] = size
        sc = S.parse({k: v for k, v in sc.items() if k != "name"}, sc["name"])
    return {**S.prepare(sc)["params"], **(hardware or {})}


def _scene_parts(scene, hardware=None, size=None):
    """The units a scene's pipeline is built from, with their parameters."""
    from hdl.units import make_unit
    pipe = make_unit("scene", spec=True, **_scene_params(scene, hardware, size))
    return [[name, p] for name, p, _ in pipe.parts()]


def configurations(quick=False, knobs=None):
    """Every row of the sweep: one knob at a time, the rest at their defaults."""
    def raster(size=None, **hw):        # the default scene's raster, as rendered
        return [_scene_parts("default", hw, size)[0]]

    def unit_raster(size=None, **hw):
        return {"name": "raster", "params": raster(size, **hw)[0][1], "rows": 40}
    rows = []
    # shading method: each registered method's scene (scenes/<method>.toml, or the default
    # scene, with the method set where it is not the default's), its pipeline; its accuracy
    # measured on the unit of the stage that gives the method (phong) or on the raster
    from hdl.units import UNITS
    default = load(SCENES / "default.toml")["shading"]["method"]
    for m in registry.methods():
        own = m != default and (SCENES / f"{m}.toml").exists()
        scene, hw = (m, {}) if own else ("default", {} if m == default else {"method": m})
        parts = [[n, p] for n, p in _scene_parts(scene, hw) if n != "texture"]
        if any(n not in UNITS for n, _ in parts):  # a stage with no unit of its own: the
            parts = [["scene", _scene_params(scene, hw)]]      # pipeline is the design
        owner = next((s.name for s in registry.stages() if s.when.get("method") == m), None)
        unit = ({"name": owner, "params": {}, "rows": 4000} if owner in UNITS else
                None if owner else {"name": "raster", "params": dict(parts[0][1]), "rows": 40})
        rows.append(_row("shading", m, parts, scene=scene, hardware=hw, unit=unit,
                         default=m == default))
    # the raster's widths, derived from the screen size (VALUE's 14 fraction bits out): the
    # default scene rendered at each size
    for bits in (6, 8, 10):
        rows.append(_row("screen", f"{1 << bits} px", raster(1 << bits), scene="default",
                         size=1 << bits, unit=unit_raster(1 << bits), default=bits == 8))
    # the setup's reciprocal
    for recip, iters in (("newton", 0), ("newton", 1), ("newton", 2), ("newton", 3),
                         ("divide", 0)):
        hw = {"recip": recip, "recip_iters": iters}
        rows.append(_row("reciprocal", "divider" if recip == "divide" else f"NR {iters}",
                         raster(**hw), scene="default", hardware=hw, unit=unit_raster(**hw),
                         default=(recip, iters) == ("newton", 2)))
    # the raster's multipliers: the setup's (clocks per triangle), the row engine's (its
    # row interval, ceil(products / multipliers))
    for n in (1, 2, 3):
        hw = {"setup_mults": n}
        rows.append(_row("setup multipliers", str(n), raster(**hw), scene="default",
                         hardware=hw, unit=unit_raster(**hw), default=n == 1))
    # the setup overlapping triangles: one every setup_ii clocks, on wide (four MULT18X18D)
    # and narrow (one) multipliers; the default takes one triangle at a time
    for label, hw in (("one at a time", {}),
                      ("27, 2 wide", {"setup_ii": 27, "setup_mults": 2}),
                      ("16, 2 wide + 2 narrow", {"setup_ii": 16, "setup_mults": 2,
                                                 "setup_narrow": 2}),
                      ("16, 2 wide + 2 narrow, 6 row multipliers",     # the dense torus at 0.54
                       {"setup_ii": 16, "setup_mults": 2, "setup_narrow": 2, "row_mults": 6})):
        rows.append(_row("setup interval", label, raster(**hw), scene="default",
                         hardware=hw, unit=unit_raster(**hw), default=not hw))
    for n in (0, 1, 3, 4, 6):     # 0: ROW_MULTS (2); 4: one a channel and one more; 6: a row in 3
        hw = {"row_mults": n}
        rows.append(_row("row multipliers", f"{ROW_MULTS} (default)" if n == 0 else str(n),
                         raster(**hw), scene="default", hardware=hw, unit=unit_raster(**hw),
                         default=n == 0))
    # the row engine's channels in turn on one datapath of n multipliers (a further channel
    # costs clocks per row, not multipliers)
    for n in (3, 5):
        hw = {"row_serial": n}
        rows.append(_row("row engine", f"channels in turn, {n} multipliers", raster(**hw),
                         scene="default", hardware=hw, unit=unit_raster(**hw)))
    # the setup's channels in turn too (their constants in a RAM the row engine's jobs read)
    for n in (1, 2):
        hw = {"row_serial": 3, "setup_serial": n}
        rows.append(_row("setup channels", f"in turn, {n} multiplier{'s' * (n > 1)} (row 3)",
                         raster(**hw), scene="default", hardware=hw, unit=unit_raster(**hw)))
    # block floating point (issue 49): the narrow row engine's mantissa bits, the wide
    # engine for the triangles its derived bound cannot hold (docs/quadratic.md)
    for n in (0, 18, 20, 21, 22):
        hw = {"row_narrow": n} if n else {}
        rows.append(_row("row mantissa bits", f"{n} (narrow engine)" if n else "wide only",
                         raster(**hw), scene="default", hardware=hw, unit=unit_raster(**hw),
                         default=n == 0))
    # each stage's own rows (Stage.sweeps): its units' settings, in the stages' order
    sweeps = [sw for cls in registry.stages() for sw in cls.sweeps()]
    if quick:       # no raster: a few minutes
        sweeps, rows = [sw for sw in sweeps if sw.quick], []
    rows += [_sweep_row(sw) for sw in sweeps]
    if knobs:
        rows = [r for r in rows if r["knob"] in knobs]
    return rows


# ---- measuring one row -----------------------------------------------------------------------

@contextmanager
def _lock(*tag):
    """One process at a time on a shared build (a design's place and route, a simulator
    model): workers of the pool or of a Dask cluster on this machine queue here."""
    path = OUT / "locks" / (hashlib.sha256(json.dumps(tag, sort_keys=True).encode())
                            .hexdigest()[:16] + ".lock")
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def _verilog_hash(name, params):
    from amaranth.back import verilog
    from hdl.units import make_unit
    text = verilog.convert(make_unit(name, **params), name="top", emit_src=False)
    return hashlib.sha256(text.encode()).hexdigest()


def row_key(cfg, opts):
    """The row cache's key: the designs' Verilog, the scene file, the settings, the flow."""
    h = hashlib.sha256(json.dumps([FLOW, cfg, opts], sort_keys=True).encode())
    for name, params in cfg["design"]:
        h.update(_verilog_hash(name, params).encode())
    if cfg["scene"]:
        h.update((SCENES / f"{cfg['scene']}.toml").read_bytes())
    return h.hexdigest()[:16]


def _area(design, seeds):
    """Synthesis and place and route of each part on ECP5 (and a UP5K fit, one seed)."""
    from . import fpga
    out = {"LUT4": 0, "FF": 0, "MULT18X18D": 0, "DP16KD": 0, "fits_ecp5": True,
           "fits_up5k": True, "fmax_mhz": None, "fmax_parts": {}, "pnr_s": 0.0}
    fmax = []
    for name, params in design:
        for device in ("ecp5", "ice40"):
            if device == "ice40" and not out["fits_ecp5"]:
                # the UP5K is smaller than the 25F in every resource (LUT4, multipliers, RAM
                # bits): what does not fit the one cannot fit the other, so it is not synthesised
                out["fits_up5k"] = False
                continue
            with _lock("fpga", name, params, device):
                work, synth = fpga.synthesise(name, name, params, device)
                runs = [fpga.place(work, device, s) for s in range(1, (seeds if device == "ecp5"
                                                                       else 1) + 1)]
            row = fpga.summarise(name, device, synth, runs)
            out["pnr_s"] += sum(r["pnr_s"] for r in runs) + synth["synth_s"]
            if device == "ice40":
                out["fits_up5k"] &= row["fits"]
                continue
            out["fits_ecp5"] &= row["fits"]
            for col in ("LUT4", "FF", "MULT18X18D", "DP16KD"):
                out[col] += row["util"].get(col, 0)
            if row["fits"]:
                fmax.append(row["fmax"])
                out["fmax_parts"][name] = row["fmax"]
    if fmax and out["fits_ecp5"]:       # every part placed: the slowest part's clock
        out["fmax_mhz"] = min(fmax)
    out["pnr_s"] = round(out["pnr_s"], 1)
    return _fits(out)


def _image(cfg, simulator, key):
    from sim.render import render
    size = (cfg["size"], cfg["size"]) if cfg["size"] else None
    params = _scene_params(cfg["scene"], cfg["hardware"], cfg["size"])
    with _lock("build", "scene", params):
        _build("scene", params, simulator)
    m = render(SCENES / f"{cfg['scene']}.toml", OUT / "render" / key, simulator, size=size,
               quiet=True, hardware=cfg["hardware"] or None)
    rr = m["rtl_vs_reference"]
    return {"psnr_db": rr["psnr_db"], "max_abs": rr["max_abs"], "flip": rr["flip"],
            "ideal_psnr_db": m["ideal_vs_reference"]["psnr_db"],
            "model_psnr_db": m["model_vs_reference"]["psnr_db"],
            "rtl_vs_ideal_db": m["rtl_vs_ideal"]["psnr_db"],
            "within_1_of_phong": rr["within_1"],
            "fragments": m["fragments"], "cycles": m["cycles"],
            "frags_per_clock": round(m["fragments"] / m["cycles"], 4),
            "render_wall_s": m["rtl_wall_s"], "size": m["size"]}


def _build(name, params, simulator):
    if simulator == "verilator":
        from sim.batch import build
        build(name, params)
    elif simulator != "amaranth":
        from sim.cocotb_run import build
        build(name, params, simulator)


def _unit_error(unit, simulator):
    from golden import MODELS
    from sim.run import simulate
    name, params, n = unit["name"], unit["params"], unit["rows"]
    model = MODELS[name]
    inputs = model.exact_vectors(np.random.default_rng(11), n, **params)
    with _lock("build", name, params):
        _build(name, params, simulator)
    t0 = time.perf_counter()
    out, _ = simulate(name, params, inputs, simulator)
    within = all(bool(np.all(e <= b)) for e, b in model.check(inputs, out, **params).values())
    wall = time.perf_counter() - t0
    row = {"unit_within_bound": within, "unit_test_wall_s": round(wall, 3)}
    if model.against_exact is None:       # a unit with no exact function to price against
        return row
    err, what = model.against_exact(inputs, out, **params)
    return {**row, "unit_err_max": round(float(err.max()), 4),
            "unit_err_p99": round(float(np.percentile(err, 99)), 4),
            "unit_err_mean": round(float(err.mean()), 4), "unit_err_in": what,
            "unit_rows": len(err)}


def _fits(row):
    """A design of several units fits the 25F only if their sum does (each placed alone)."""
    if "fits_ecp5" in row:
        row["fits_ecp5"] = row["fits_ecp5"] and all(row[c] <= n for c, n in ECP5_25F.items())
    return row


def measure(cfg, opts):
    """One row: every column this configuration has. Runs in a worker; cached by row_key."""
    key = row_key(cfg, opts)
    cache = OUT / "cache" / f"{key}.json"
    if opts.get("cache", True) and cache.exists():
        return _fits({**json.loads(cache.read_text()), "cached": True})
    from hdl.units import make_unit
    row = {k: cfg[k] for k in ("knob", "setting", "default", "scene", "hardware", "design")}
    row["latency"] = sum(make_unit(n, spec=True, **p).latency for n, p in cfg["design"])
    if cfg["design"][0][0] == "raster":
        row["setup_clocks"] = make_unit(*cfg["design"][0][:1], spec=True,
                                        **cfg["design"][0][1]).timing[0]
    if opts["counts"]:
        from .report import count
        with _lock("count", cfg["design"]):
            counts = [count(n, p, OUT / "yosys" / key) for n, p in cfg["design"]]
        row["yosys"] = {k: sum(c[k] for c in counts) for k in ("mul", "add", "tables",
                                                                "table_bits", "flop_bits")}
    if opts["seeds"]:
        try:
            row.update(_area(cfg["design"], opts["seeds"]))
        except RuntimeError as e:     # a design the flow cannot build: the row keeps the rest
            row["area_error"] = str(e)
    if cfg["scene"] and opts["render"]:
        row.update(_image(cfg, opts["simulator"], key))
        if row.get("fmax_mhz"):
            row["ns_per_pixel"] = round(row["cycles"] / row["fragments"] * 1e3
                                        / row["fmax_mhz"], 3)
    if cfg["unit"]:
        row.update(_unit_error(cfg["unit"], opts["simulator"]))
    if opts.get("cache", True):
        cache.parent.mkdir(parents=True, exist_ok=True)
        cache.write_text(json.dumps(row, indent=1))
    return {**row, "cached": False}


# ---- executors -------------------------------------------------------------------------------

def sweep(cfgs, opts, jobs=2, dask=None, quiet=False):
    """Every row, in ``cfgs``' order: on a local process pool, or on a Dask cluster (an
    address, or a ``distributed.Client``)."""
    return run(measure, [(c, opts) for c in cfgs], jobs, dask,
               desc="tradeoffs", unit="config", quiet=quiet,
               label=lambda r: f"{r['knob']} {r['setting']}" + (" (cached)" if r.get("cached")
                                                                  else ""),
               key=lambda k, t: f"tradeoffs-{k}-{row_key(*t)}")


# ---- the report ------------------------------------------------------------------------------

DSP_LUT4 = 24288 // 28        # a MULT18X18D counted as the 25F's LUT4 per DSP in the plots


@functools.lru_cache(None)
def _default_geometry(scene):
    """Whether a scene shows the default scene's surface: its mesh, camera, image, material
    and bump (the plots compare PSNR on one picture; the shading may differ)."""
    view = lambda sc: [sc[k] for k in ("mesh", "camera", "image", "material", "bump")]
    return view(load(SCENES / f"{scene}.toml")) == view(load(SCENES / "default.toml"))


def _cost(r):
    return r["LUT4"] + DSP_LUT4 * r["MULT18X18D"] if "LUT4" in r else None


def _fmt(v, nd=2):
    if v is None:
        return "–"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:,.{nd}f}"
    return f"{v:,}" if isinstance(v, int) else str(v)


def table(rows):
    head = ["knob", "setting", "PSNR dB", "ideal / model dB", "RTL vs ideal dB", "max", "FLIP",
            "unit error max / p99 / mean",
            "latency", "frag/clk", "Fmax MHz", "ns/px", "LUT4", "FF", "MULT", "DP16KD",
            "fits 25F / UP5K", "render s", "unit test s"]
    out = ["| " + " | ".join(head) + " |", "|---" * len(head) + "|"]
    for r in rows:
        err = ("–" if "unit_err_max" not in r else
               f"{r['unit_err_max']:.3g} / {r['unit_err_p99']:.3g} / {r['unit_err_mean']:.3g}")
        fits = (f"{_fmt(r['fits_ecp5'])} / {_fmt(r['fits_up5k'])}" if "fits_ecp5" in r
                else "–")
        out.append("| " + " | ".join([
            r["knob"], f"**{r['setting']}**" if r["default"] else r["setting"],
            _fmt(r.get("psnr_db")),
            f"{_fmt(r.get('ideal_psnr_db'))} / {_fmt(r.get('model_psnr_db'))}",
            _fmt(r.get("rtl_vs_ideal_db")), _fmt(r.get("max_abs")), _fmt(r.get("flip"), 4), err,
            _fmt(r.get("latency")), _fmt(r.get("frags_per_clock"), 3), _fmt(r.get("fmax_mhz"), 1),
            _fmt(r.get("ns_per_pixel")), _fmt(r.get("LUT4")), _fmt(r.get("FF")),
            _fmt(r.get("MULT18X18D")), _fmt(r.get("DP16KD")), fits,
            _fmt(r.get("render_wall_s")), _fmt(r.get("unit_test_wall_s"))]) + " |")
    return out


def pareto(points):
    """Indices of the points no other point beats on both (cost lower, error lower)."""
    front = []
    for i, (c, e) in enumerate(points):
        if not any((c2 <= c and e2 <= e) and (c2 < c or e2 < e) for c2, e2 in points):
            front.append(i)
    return sorted(front, key=lambda i: points[i][0])


def plots(rows, out):
    """PSNR against cost, time and simulation time, on the default scene's geometry; each
    knob's Pareto front joined (a knob's designs are of one kind: whole pipelines for the
    shading method, one unit otherwise), the defaults labelled."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    pts = [r for r in rows if r.get("psnr_db") is not None and r["scene"]
           and _default_geometry(r["scene"])
           and r.get("size") == [256, 256]]
    axes = [("cost", f"LUT4 + {DSP_LUT4} x MULT18X18D (ECP5-25F)", _cost),
            ("ns_per_pixel", "ns per pixel (cycles per fragment / Fmax)",
             lambda r: r.get("ns_per_pixel")),
            ("sim_time", "batch-path render wall time (s)", lambda r: r.get("render_wall_s"))]
    paths = []
    for name, label, fx in axes:
        have = [r for r in pts if fx(r) is not None]
        if not have:
            continue
        fig, ax = plt.subplots(figsize=(7.5, 4.8))
        knobs = sorted({r["knob"] for r in have})
        for k, knob in enumerate(knobs):
            sel = [r for r in have if r["knob"] == knob]
            ax.scatter([fx(r) for r in sel], [r["psnr_db"] for r in sel], color=f"C{k}",
                       label=knob, zorder=3)
            for r in sel:
                ax.annotate(r["setting"] + (" (default)" if r["default"] else ""),
                            (fx(r), r["psnr_db"]), fontsize=7, xytext=(4, 3),
                            textcoords="offset points",
                            weight="bold" if r["default"] else "normal")
            front = pareto([(fx(r), -r["psnr_db"]) for r in sel])     # within the knob:
            ax.plot([fx(sel[i]) for i in front], [sel[i]["psnr_db"] for i in front], "--",
                    color=f"C{k}", lw=1, zorder=2)     # designs of one kind compare
        ax.plot([], [], "k--", lw=1, label="Pareto front (per knob)")
        ax.set(xlabel=label, ylabel="PSNR against the reference (dB, default scene)",
               title=f"What accuracy costs: error against {name.replace('_', ' ')}")
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = out / f"pareto_{name}.png"
        fig.savefig(path, dpi=110)
        plt.close(fig)
        paths.append(path)
    return paths


def _pick(rows, knob, setting):
    return next((r for r in rows if r["knob"] == knob and r["setting"] == setting), None)


def answers(rows):
    """The report's questions, from the measured rows."""
    lines = []
    # whole pipelines only: the other knobs' designs are one unit each
    shade = [r for r in rows if r["knob"] == "shading" and r.get("psnr_db") is not None
             and _cost(r) is not None]
    phong = _pick(rows, "shading", "phong")
    if phong and shade:
        ok = [r for r in shade if r is not phong and r.get("within_1_of_phong") is not None
              and r["within_1_of_phong"] >= 0.99]
        if ok:
            best = min(ok, key=_cost)
            lines.append(f"- **Cheapest within 1 level of Phong** (99 % of the default scene's "
                         f"pixels within one 8-bit level of the per-pixel Phong reference): "
                         f"{best['knob']} = {best['setting']}, {_fmt(best['LUT4'])} LUT4 and "
                         f"{best['MULT18X18D']} MULT18X18D, {best['psnr_db']} dB.")
        else:
            near = max((r for r in shade if r is not phong),
                       key=lambda r: r.get("within_1_of_phong") or 0)
            lines.append(f"- **Cheapest within 1 level of Phong:** no other "
                         f"pipeline reaches 99 % of pixels within one level of the per-pixel "
                         f"Phong reference (float64, exact power); the closest is "
                         f"{near['knob']} = {near['setting']} at "
                         f"{100 * (near.get('within_1_of_phong') or 0):.1f} %.")
    timed = [r for r in shade if r.get("ns_per_pixel")]
    if timed:
        fast = min(timed, key=lambda r: r["ns_per_pixel"])
        lines.append(f"- **Fastest pipeline:** {fast['knob']} = {fast['setting']}: "
                     f"{fast['ns_per_pixel']} ns per pixel ({fast['fmax_mhz']} MHz, "
                     f"{fast['frags_per_clock']} fragments per clock).")
    for knob in dict.fromkeys(r["knob"] for r in rows):
        sel = [r for r in rows if r["knob"] == knob and r.get("psnr_db") is not None
               and _cost(r) is not None]
        if len(sel) < 2:
            continue
        sel.sort(key=lambda r: r["psnr_db"])
        if sel[-1]["psnr_db"] - sel[0]["psnr_db"] < 0.1:   # no step in accuracy to price
            span = lambda k, f=_fmt: f"{f(min(r[k] for r in sel))}-{f(max(r[k] for r in sel))}"
            errs = ", ".join(f"{r['setting']} {r['unit_err_max']:.3g}" for r in sel
                             if "unit_err_max" in r)
            lines.append(f"- **{knob}:** the same image within 0.1 dB ({span('psnr_db')} dB) "
                         f"at every setting; what changes is the cost, LUT4 {span('LUT4')}"
                         + (f", ns/px {span('ns_per_pixel')}"
                            if all(r.get("ns_per_pixel") for r in sel) else "")
                         + (f", and the unit's own error (max: {errs})" if errs else "") + ".")
            continue
        steps = []
        for a, b in zip(sel, sel[1:]):
            steps.append(f"{a['setting']} → {b['setting']}: {b['psnr_db'] - a['psnr_db']:+.2f} "
                         f"dB for {b['LUT4'] - a['LUT4']:+,} LUT4, "
                         f"{b['MULT18X18D'] - a['MULT18X18D']:+d} MULT18X18D"
                         + (f", {b['ns_per_pixel'] - a['ns_per_pixel']:+.2f} ns/px"
                            if a.get("ns_per_pixel") and b.get("ns_per_pixel") else ""))
        lines.append(f"- **{knob}, each step up in accuracy:** " + "; ".join(steps) + ".")
    return lines


def claims(rows):
    """The seeds' headline claims beside what the hardware here measures."""
    out = ["| seed | claim | measured here | verdict |", "|---|---|---|---|"]
    xs, ex = _pick(rows, "shading", "xshading"), _pick(rows, "shading", "exact")
    if xs and ex and "setup_clocks" in xs and "setup_clocks" in ex:
        ratio = ex["setup_clocks"] / xs["setup_clocks"]
        area = (f"; {_fmt(xs.get('LUT4'))} against {_fmt(ex.get('LUT4'))} LUT4, "
                f"{xs['yosys']['mul']} against {ex['yosys']['mul']} multipliers (Yosys)"
                if "LUT4" in xs and "LUT4" in ex and "yosys" in xs else "")
        out.append(f"| 001 Table 1 | X-shading's setup about 3x faster than earlier setups | "
                   f"setup clocks per triangle: X-shading {xs['setup_clocks']}, exact mid-edges "
                   f"{ex['setup_clocks']} ({ratio:.2f}x){area} | "
                   f"{'confirmed' if ratio >= 2.5 else 'refuted in hardware'}: the exact "
                   f"setup's square roots share the one scheduled multiplier, so it costs "
                   f"{100 * (ratio - 1):.0f} % more clocks, not 3x |")
    lin, ph = _pick(rows, "shading", "linear"), _pick(rows, "shading", "phong")
    if xs and ph and lin and all("LUT4" in r and r.get("psnr_db") for r in (xs, ph, lin)):
        ns = lambda r: _fmt(r.get("ns_per_pixel"))
        slower = (ph["ns_per_pixel"] / xs["ns_per_pixel"] - 1) * 100 \
            if ph.get("ns_per_pixel") and xs.get("ns_per_pixel") else None
        out.append(
            f"| 000 Table 2 | vector normalisation 37 % slower than quadratic interpolation; "
            f"linear the cheapest | ns/px linear {ns(lin)}, X-shading {ns(xs)}, Phong {ns(ph)}"
            f"{f' (Phong {slower:+.0f} %)' if slower is not None else ''}; LUT4 + MULT "
            f"{_fmt(lin['LUT4'])} + {lin['MULT18X18D']}, {_fmt(xs['LUT4'])} + "
            f"{xs['MULT18X18D']}, {_fmt(ph['LUT4'])} + {ph['MULT18X18D']}; PSNR "
            f"{lin['psnr_db']}, {xs['psnr_db']}, {ph['psnr_db']} dB | in hardware every method "
            f"takes one fragment per clock, so the cost moves from time to area: Phong "
            f"{'costs more' if _cost(ph) > _cost(xs) else 'costs less'} area than X-shading "
            f"({_cost(ph):,} against {_cost(xs):,} LUT4-equivalents); linear "
            f"{'is' if _cost(lin) <= min(_cost(xs), _cost(ph)) else 'is not'} the cheapest |")
    pc, ang = _pick(rows, "bump architecture", "Cartesian (Peercy)"), \
        _pick(rows, "bump architecture", "angular (seed 003)")
    if pc and ang and "yosys" in pc and "yosys" in ang:
        fewer = 100 * (1 - ang["yosys"]["mul"] / pc["yosys"]["mul"])
        out.append(
            f"| 003 | 78 % fewer multiplications than earlier bump-mapping architectures "
            f"(Table 1: Peercy's setup 27 multipliers, 9 dividers, 3 SQRTs; ours 6 + 2) | "
            f"multipliers (Yosys): Peercy {pc['yosys']['mul']}, angular {ang['yosys']['mul']} "
            f"({fewer:.0f} % fewer); tables {pc['yosys']['tables']} against "
            f"{ang['yosys']['tables']} ({_fmt(ang['yosys']['table_bits'])} bits); placed: "
            f"{_fmt(pc.get('LUT4'))} against {_fmt(ang.get('LUT4'))} LUT4, "
            f"{_fmt(pc.get('MULT18X18D'))} against {_fmt(ang.get('MULT18X18D'))} MULT18X18D, "
            f"{_fmt(pc.get('DP16KD'))} against {_fmt(ang.get('DP16KD'))} DP16KD, "
            f"{_fmt(pc.get('fmax_mhz'), 1)} against {_fmt(ang.get('fmax_mhz'), 1)} MHz | "
            f"{'confirmed' if fewer >= 70 else 'partly confirmed' if fewer > 0 else 'refuted'}"
            f" for multipliers; the angular unit pays in tables |")
    fen = _pick(rows, "power", "fenney")
    tables = [r for r in rows if r["knob"] == "power" and r["setting"].startswith("table")
              and "unit_err_max" in r]
    if fen and tables and "unit_err_max" in fen:
        same = [r for r in tables if r["unit_err_max"] <= fen["unit_err_max"]]
        t = min(same, key=lambda r: r.get("LUT4", 0)) if same else None
        cmp = (f"the smallest table as accurate, {t['setting']} (max {t['unit_err_max']:.1f}): "
               f"{_fmt(t.get('LUT4'))} LUT4, {_fmt(t.get('MULT18X18D'))} MULT18X18D, "
               f"{_fmt(t.get('DP16KD'))} DP16KD" if t else "no table in the sweep is as "
               "inaccurate")
        y = fen.get("yosys", {})
        out.append(
            f"| 004 | the quadratic power approximation: 3 multipliers and 5 add/subtracts "
            f"in place of a table | fenney_power: {y.get('mul', '–')} multipliers, "
            f"{y.get('add', '–')} add/subtracts (Yosys), {_fmt(fen.get('LUT4'))} LUT4, "
            f"{_fmt(fen.get('MULT18X18D'))} MULT18X18D; error against x^32: max "
            f"{fen['unit_err_max']:.1f}, mean {fen['unit_err_mean']:.1f} LSB of 1/1024; "
            f"{cmp} | {'confirmed' if y.get('mul') == 3 else 'refuted'} for its counts; "
            f"a table of the same accuracy {'needs no multiplier' if t else 'n/a'} |")
    return out


def write(rows, out, opts, wall):
    out.mkdir(parents=True, exist_ok=True)
    (out / "tradeoffs.json").write_text(json.dumps(
        {"options": opts, "wall_s": round(wall, 1), "rows": rows}, indent=1) + "\n")
    figs = plots(rows, out)
    md = ["# What accuracy costs", "",
          f"{len(rows)} configurations, one knob at a time (the default in bold), measured by "
          f"`python -m flows.tradeoffs` in {wall:.0f} s ({opts['seeds']} place-and-route seed(s), "
          f"renders on {opts['simulator']}). Image error: the RTL's render against the "
          "float64 reference (per-pixel Phong, exact power; exact bump shading), PSNR, "
          "maximum (8-bit levels) and mean FLIP over covered pixels; beside it the method's "
          "float ideal (its algorithm with no format: the method's own error) and the float "
          "model with the RTL's formats against the same reference, and the RTL against the "
          "ideal (what the formats cost). Unit error: the knob's "
          "unit against its exact function, in the unit given in tradeoffs.json. Area: placed "
          "on ECP5-25F -6 (synthesis counts where it does not fit); a shading method's design is "
          "every unit of its pipeline, summed, its Fmax the slowest unit's. ns/px = cycles per "
          "fragment on the scene / Fmax.", "", *table(rows), "",
          *(f"- {r['knob']} = {r['setting']}: no area, the flow failed: {r['area_error']}"
            for r in rows if r.get("area_error")), "",
          "## For a user choosing a configuration", "", *answers(rows), "",
          "## The seeds' claims, in hardware", "", *claims(rows), ""]
    md += [f"![{p.stem}]({p.name})" for p in figs]
    (out / "report.md").write_text("\n".join(md) + "\n")
    return out / "report.md"


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.tradeoffs", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="a reduced sweep (no raster), minutes")
    ap.add_argument("--knobs", help="comma-separated knobs (default: all)")
    ap.add_argument("--dask", metavar="ADDRESS", help="a Dask scheduler (tcp://host:8786)")
    ap.add_argument("--seeds", type=int, default=1, help="place-and-route seeds (default 1)")
    ap.add_argument("-j", "--jobs", type=int, default=2, help="local worker processes")
    ap.add_argument("--simulator", default="verilator", help="renders' and unit tests' "
                    "simulator (default: the batch path)")
    ap.add_argument("--out", default=str(OUT))
    args = ap.parse_args(argv)
    with user_errors():
        cfgs = configurations(args.quick)
        known = list(dict.fromkeys(c["knob"] for c in configurations()))
        if args.knobs:
            want = [k.strip() for k in args.knobs.split(",")]
            bad = [k for k in want if k not in known]
            if bad:
                raise UsageError(f"--knobs: unknown {', '.join(bad)}; known: {', '.join(known)}")
            cfgs = [c for c in cfgs if c["knob"] in want]
        if args.seeds < 0:
            raise UsageError("--seeds must be 0 (no place and route) or more")
        opts = {"seeds": args.seeds, "simulator": args.simulator, "render": True,
                "counts": True}
        t0 = time.time()
        rows = sweep(cfgs, opts, args.jobs, args.dask)
        path = write(rows, Path(args.out), opts, time.time() - t0)
    print(path.read_text())
    print(f"wrote {path} and {path.parent / 'tradeoffs.json'}")


if __name__ == "__main__":
    main()
