"""``make fpga``'s flow: the serial wrapper works, and one small unit goes through synthesis and
place and route on both devices (one seed each; the full report is ``make fpga``)."""
from amaranth.sim import Simulator

from golden.fenney import texel_decode
from hdl.units import make_unit
from sim.fpga import SerialWrapper, markdown, run


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
