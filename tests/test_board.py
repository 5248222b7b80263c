"""The board (board/): the TMDS encoder against the DVI rules and an independent model, the
UART at the bit level, the link's frames good and bad, the depth-tested framebuffer against
its model, and one whole video frame of a small scene on Verilator."""
import random
import struct

import numpy as np
import pytest
from amaranth.sim import Simulator

from board.framebuffer import MUTANTS, Framebuffer
from board.link import COUNTERS, KINDS, REPLY_BYTES, SYNC, Link, crc16
from board.protocol import Encoder, frame, parse_reply
from board.tmds import CONTROL, TMDSEncoder, decode, disparity, encode
from board.uart import UARTRx, UARTTx
from scene.framebuffer import board_frame, expand565
from sim.simulators import available
from sim.verilog import SCENES



# ---- TMDS -----------------------------------------------------------------------------------

def _tmds_rtl(data, c, de):
    dut, out = TMDSEncoder(), []

    async def bench(ctx):
        for k in range(len(data) + TMDSEncoder.latency):
            if k < len(data):
                ctx.set(dut.data, data[k]); ctx.set(dut.c, c[k]); ctx.set(dut.de, de[k])
            await ctx.tick()
            out.append(ctx.get(dut.symbol))
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    return out[TMDSEncoder.latency - 1:TMDSEncoder.latency - 1 + len(data)]


def _line(rng, n=800, active=640):
    """A line's inputs: random bytes while DE, random control bits in the blanking."""
    data = [rng.randrange(256) for _ in range(n)]
    de = [1 if k < active else 0 for k in range(n)]
    c = [rng.randrange(4) for _ in range(n)]
    return data, c, de


def test_tmds_rtl_equals_the_model_bit_for_bit():
    """Three lines of random data and controls, and the bytes that stress the disparity
    (0x00, 0xFF, alternating): every symbol equal to the model written from DVI 1.0's flow
    chart."""
    rng = random.Random(1)
    data, c, de = [], [], []
    for _ in range(3):
        d, cc, e = _line(rng)
        data += d; c += cc; de += e
    data += [0x00, 0xFF, 0x55, 0xAA, 0x0F, 0xF0] * 40
    c += [0] * 240
    de += [1] * 240
    assert _tmds_rtl(data, c, de) == encode(data, c, de)


def test_tmds_control_tokens_and_decoding():
    """Blanking sends DVI 1.0's four tokens by (c1, c0); every byte decodes back whatever
    the running disparity before it (each byte after every other byte, 65,536 pairs)."""
    assert encode([0] * 4, [0, 1, 2, 3], [0] * 4) == list(CONTROL)
    assert [decode(t) for t in CONTROL] == [("control", k) for k in range(4)]
    for a in range(256):
        seq = [a] * 2 + list(range(256))
        sym = encode(seq, [0] * len(seq), [1] * len(seq))
        assert [decode(s) for s in sym] == [("data", v) for v in seq]


def test_tmds_dc_balance_over_a_line():
    """The running disparity of a line's data symbols stays in [-8, 8] (derived in
    board/tmds.py: with cnt > 0 no branch adds, with cnt < 0 none takes, a step moves at most
    10 from an even value), on random lines and on runs of the most unbalanced bytes; and the
    RTL's own stream keeps it."""
    rng = random.Random(2)
    lines = [_line(rng)[0][:640] for _ in range(20)]
    lines += [[0x00] * 640, [0xFF] * 640, [0x00, 0xFF] * 320, [0x01, 0xFE] * 320]
    for line in lines:
        run = np.cumsum([disparity(s) for s in encode(line, [0] * 640, [1] * 640)])
        assert -8 <= run.min() and run.max() <= 8, (line[:4], run.min(), run.max())
    rtl = _tmds_rtl(lines[0], [0] * 640, [1] * 640)
    run = np.cumsum([disparity(s) for s in rtl])
    assert -8 <= run.min() and run.max() <= 8


# ---- UART -----------------------------------------------------------------------------------

def _simulate(dut, bench, *background):
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    for b in background:
        sim.add_testbench(b, background=True)
    sim.run()


def _line_bits(byte, stop=1):
    return [0] + [(byte >> k) & 1 for k in range(8)] + [stop]


def test_uart_receives_at_the_bit_level_with_baud_error():
    """Bytes driven onto the line bit by bit at the divisor x (1 +- 2 %) clocks a bit (a
    real FT231X's rate against the PLL's), a glitch shorter than half a bit, and a byte with a
    low stop bit: every byte received, the glitch ignored, the bad byte counted and dropped."""
    div = 16
    dut = UARTRx(div)
    rng = random.Random(3)
    sent = [rng.randrange(256) for _ in range(40)]
    got = []

    async def drive(ctx):
        ctx.set(dut.rx, 1)
        await ctx.tick().repeat(20)
        ctx.set(dut.rx, 0)                       # a glitch: 3 clocks low
        await ctx.tick().repeat(3)
        ctx.set(dut.rx, 1)
        await ctx.tick().repeat(3 * div)
        for k, byte in enumerate(sent + [0x5A]):
            rate = div * (1.02 if k % 2 else 0.98)
            bits = _line_bits(byte, stop=0 if k == len(sent) else 1)
            t = 0.0
            for b in bits:
                ctx.set(dut.rx, b)
                t += rate
                await ctx.tick().repeat(int(round(t)) - int(round(t - rate)))
            ctx.set(dut.rx, 1)
            await ctx.tick().repeat(2 * div)

    async def take(ctx):
        ctx.set(dut.o.ready, 1)
        async for _, _, v, p in ctx.tick().sample(dut.o.valid, dut.o.payload):
            if v:
                got.append(p)
    _simulate(dut, drive, take)
    assert got == sent


def test_uart_framing_error_counted():
    div = 8
    dut = UARTRx(div)
    seen = {}

    async def drive(ctx):
        ctx.set(dut.rx, 1)
        await ctx.tick().repeat(10)
        for b in _line_bits(0x33, stop=0) + [1] * 3 + _line_bits(0x44):
            ctx.set(dut.rx, b)
            await ctx.tick().repeat(div)
        ctx.set(dut.rx, 1)
        await ctx.tick().repeat(3 * div)
        seen["framing"] = ctx.get(dut.framing)
        seen["last"] = ctx.get(dut.o.payload)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(drive)
    sim.run()
    assert seen == {"framing": 1, "last": 0x44}


def test_uart_transmits_at_the_bit_level():
    """The transmitter's line sampled at each bit's middle: start, 8 bits LSB first, stop."""
    div = 10
    dut = UARTTx(div)
    sent = [0x00, 0xFF, 0xA5, 0x3C, 0x81]
    line = []

    async def feed(ctx):
        for b in sent:
            ctx.set(dut.i.payload, b)
            ctx.set(dut.i.valid, 1)
            await ctx.tick().until(dut.i.ready)
            await ctx.tick()
            ctx.set(dut.i.valid, 0)
        await ctx.tick().repeat(12 * div)

    async def watch(ctx):
        async for _, _, tx in ctx.tick().sample(dut.tx):
            line.append(tx)
    _simulate(dut, feed, watch)
    got, k = [], 0
    while k < len(line):                      # an independent receiver on the samples
        if line[k] == 0:
            mid = k + div // 2
            bits = [line[mid + j * div] for j in range(10)]
            assert bits[0] == 0 and bits[9] == 1, bits
            got.append(sum(b << j for j, b in enumerate(bits[1:9])))
            k = mid + 9 * div
        k += 1
    assert got == sent


# ---- the link -------------------------------------------------------------------------------

def _link_run(frames, tri_bits=20, known=((0, 4), (0x10000, 16)), buffer=64, timeout=60,
              gap=0):
    """Bytes of ``frames`` (a gap of ``gap`` + timeout clocks after each) into a Link;
    returns (rows, replies, clears)."""
    dut = Link(tri_bits, known, buffer, timeout)
    rows, tx, clears = [], [], []

    async def bench(ctx):
        for fr in frames:
            for b in fr:
                ctx.set(dut.i.valid, 1)
                ctx.set(dut.i.payload, b)
                await ctx.tick()
                ctx.set(dut.i.valid, 0)
                await ctx.tick().repeat(2)
            await ctx.tick().repeat(timeout + gap + 4 * REPLY_BYTES + 8 * buffer)

    async def sink(ctx):
        ctx.set(dut.tx.ready, 1)
        ctx.set(dut.drained, 1)
        rng = random.Random(5)
        async for _, _, ov, op, tv, tp, cl, co in ctx.tick().sample(
                dut.o.valid, dut.o.payload, dut.tx.valid, dut.tx.payload, dut.clear,
                dut.colour):
            ctx.set(dut.o.ready, rng.random() < 0.7)       # backpressure from the pipeline
            if tv:
                tx.append(tp)
            if cl:
                clears.append(co)

    async def take(ctx):
        async for _, _, ov, rd, op in ctx.tick().sample(dut.o.valid, dut.o.ready,
                                                         dut.o.payload):
            if ov and rd:
                rows.append((op.cmd, op.tri if not op.cmd else (op.addr, op.data)))
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.add_testbench(sink, background=True)
    sim.add_testbench(take, background=True)
    sim.run()
    replies = [parse_reply(tx[k:k + REPLY_BYTES]) for k in range(0, len(tx), REPLY_BYTES)]
    return rows, replies, clears


def _raw_frame(kind, seq, payload):
    """A frame of any kind byte, with a good CRC (``board.protocol.frame`` knows the kinds)."""
    body = struct.pack("<BBH", kind, seq, len(payload)) + payload
    return bytes(SYNC) + body + struct.pack("<H", crc16(body))


def _tris(values, nbytes=3):
    return b"".join(v.to_bytes(nbytes, "little") for v in values)


def test_link_applies_good_frames_under_backpressure():
    """Writes to known addresses and triangles, in order, each row once, with the pipeline's
    ready low 30 % of the clocks; a reply per frame."""
    writes = b"".join(Encoder.writes([1, 0x10005, 3], [7, 0xDEADBEEF, 9]))
    tris = [0x12345, 0xFFFFF, 0x00001, 0x54321]
    rows, replies, _ = _link_run([frame("writes", 1, writes), frame("triangles", 2, _tris(tris)),
                                  frame("status", 3)])
    assert rows == [(1, (1, 7)), (1, (0x10005, 0xDEADBEEF)), (1, (3, 9))] + \
        [(0, t) for t in tris]
    assert [(r["seq"], r["result"]) for r in replies] == [(1, "ok"), (2, "ok"), (3, "ok")]
    assert replies[-1]["good"] == 3


BAD = {   # what goes wrong: (the bytes, the counter that counts it, the reply's result)
    "bit error": (lambda: bytes(b ^ (4 if k == 9 else 0) for k, b in
                               enumerate(frame("triangles", 9, _tris([1, 2])))), "crc", "crc"),
    "cut frame": (lambda: frame("triangles", 9, _tris([1, 2, 3]))[:10], "cut", "cut"),
    "noise": (lambda: bytes([0x00, 0x13, 0xA5, 0x77, 0xFF, 0x5A]), "noise", None),
    "unknown address": (lambda: frame("writes", 9, b"".join(Encoder.writes([0x20000], [1]))),
                        "unknown", "ok"),
    "longer than the buffer": (lambda: frame("triangles", 9, _tris(range(30))), "long", "long"),
    "unknown kind": (lambda: _raw_frame(9, 9, b""), "kind", "kind"),
    "not whole records": (lambda: frame("triangles", 9, b"\x01\x02\x03\x04"), "kind", "kind"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_link_rejects_bad_input_and_takes_the_next_frame(case):
    """Each kind of bad input is counted, applies nothing, and the good frame after it is
    taken whole."""
    make, counter, result = BAD[case]
    good = frame("triangles", 10, _tris([0xABCDE, 0x13579]))
    rows, replies, _ = _link_run([make(), good])
    assert rows == [(0, 0xABCDE), (0, 0x13579)]
    assert replies[-1]["seq"] == 10 and replies[-1]["result"] == "ok"
    assert replies[-1][counter] >= 1, replies[-1]
    if result is not None:
        assert replies[0]["result"] == result and replies[0]["seq"] == 9
    others = [c for c in COUNTERS if c not in (counter, "good", "noise")]
    assert all(replies[-1][c] == 0 for c in others), replies[-1]


def test_link_clear_waits_for_the_pipeline_and_carries_the_colour():
    rows, replies, clears = _link_run([frame("clear", 4, struct.pack("<H", 0xF81F))])
    assert clears == [0xF81F] and replies[0]["result"] == "ok" and rows == []


# ---- the framebuffer ------------------------------------------------------------------------

def _framebuffer_rtl(W, H, frags, p_valid=0.8, seed=4, mutant=None):
    dut = Framebuffer(W, H, 8, 8, mutant=mutant)
    img = np.zeros((H, W, 3), np.uint8)
    n = len(frags["x"])
    rng = random.Random(seed)
    done = {}

    async def bench(ctx):
        ctx.set(dut.colour, 0x1234)
        ctx.set(dut.clear, 1)
        await ctx.tick()
        ctx.set(dut.clear, 0)
        await ctx.tick().until(~dut.busy)
        k = 0
        while k < n:
            ctx.set(dut.i.valid, rng.random() < p_valid)
            for f in frags:
                ctx.set(dut.i.payload[f], int(frags[f][k]))
            _, _, v, r = await ctx.tick().sample(dut.i.valid, dut.i.ready)
            k += bool(v and r)
        ctx.set(dut.i.valid, 0)
        await ctx.tick().until(~dut.busy)
        done["t"] = True
        for y in range(H):
            for x in range(W):
                ctx.set(dut.rd_addr, y * dut.w2 + x)
                await ctx.tick("pixel")
                await ctx.tick("pixel")
                img[y, x] = expand565(ctx.get(dut.rd_data))
        done["outside"], done["written"] = ctx.get(dut.outside), ctx.get(dut.written)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_clock(4e-8, domain="pixel")
    sim.add_testbench(bench)
    sim.run()
    return img, done["outside"], done["written"]


def _hazards(rng, n):
    """1,500 fragments on a 12 x 10 image (a 16-wide plane), many back to back on one pixel
    (the read-modify-write hazard), ties, the least depth, and fragments outside the image."""
    frags = {"x": [], "y": [], "depth": [], "r": [], "g": [], "b": []}
    for k in range(n):
        if k and rng.random() < 0.5:                 # the same pixel as the one before
            frags["x"].append(frags["x"][-1]); frags["y"].append(frags["y"][-1])
        else:
            frags["x"].append(rng.randrange(14)); frags["y"].append(rng.randrange(11))
        frags["depth"].append(rng.choice([rng.randrange(-32768, 32768), rng.randrange(-2, 3),
                                          -32768, -32767]))
    return frags


def _rising(rng, n):
    """Three pixels in any order with slowly rising depths, so that the three writes ahead of
    a fragment often hold its pixel in every combination, each nearer than the last."""
    frags = {"x": [], "y": [], "depth": []}
    for k in range(n):
        frags["x"].append(rng.choice([3, 4, 5])); frags["y"].append(2)
        frags["depth"].append(k // 6 + rng.randrange(-5, 6))
    return frags


def _depth_test_errors(make, n, p_valid, mutant=None):
    """The framebuffer's RTL on a stream against its model (scene/framebuffer.py): the pixels
    of the plane that differ, and the RTL's writes less the depth test's in stream order (a
    fragment writes when it is nearer than all before it at its pixel: a wrong forwarding
    choice writes where it should not, or fails to, and a later write may hide it in the
    plane); also the fragments outside the image, against the count."""
    rng = random.Random(6)
    W, H = 12, 10
    frags = make(rng, n)
    for c in "rgb":
        frags[c] = [rng.randrange(256) for _ in range(n)]
    img, outside, written = _framebuffer_rtl(W, H, frags, p_valid=p_valid, mutant=mutant)
    model = board_frame((W, H), {k: np.array(v) for k, v in frags.items()},
                        expand565(0x1234) / 255)
    best, wins = {}, 0
    for x, y, d in zip(frags["x"], frags["y"], frags["depth"]):
        if x < W and y < H and max(d, -32767) > best.get((x, y), -32768):
            best[(x, y)], wins = max(d, -32767), wins + 1
    return (int((img != model).any(-1).sum()), written - wins,
            outside - sum(x >= W or y >= H for x, y in zip(frags["x"], frags["y"])))


STREAMS = [(_hazards, 1500, 0.9), (_rising, 3000, 0.97)]


@pytest.mark.parametrize("make, n, p_valid", STREAMS, ids=["hazards", "rising"])
def test_framebuffer_depth_test_equals_its_model(make, n, p_valid):
    """The plane equals the model's pixel for pixel, and the RTL made exactly the writes of
    the depth test in stream order."""
    assert _depth_test_errors(make, n, p_valid) == (0, 0, 0)


@pytest.mark.parametrize("mutant", sorted(MUTANTS))
def test_framebuffer_forwarding_mutants_are_caught(mutant):
    """Each of the forwarding's five mutants (an enable dropped, a priority swapped:
    ``board.framebuffer.MUTANTS``) is caught by the test above: on one of its two streams,
    the plane or the count of writes differs from the depth test's."""
    errors = [_depth_test_errors(*stream, mutant=mutant)[:2] for stream in STREAMS]
    assert any(e != (0, 0) for e in errors), (mutant, errors)


# ---- one whole frame on Verilator -----------------------------------------------------------

def _bad_then_good(enc, prep):
    """Every kind of bad input the issue lists, each followed by good frames: the scene's
    clear and data, then before its triangles a frame with a bit error, a cut frame, bytes
    of noise, a write to an unknown address, a triangle outside the image, a frame longer than
    the buffer; then the scene's triangles."""
    from board.sim import Noise
    good = enc.scene(prep)
    head = [f for f in good if f[2] in (KINDS["clear"], KINDS["writes"])]
    tris = [f for f in good if f[2] == KINDS["triangles"]]
    flipped = bytearray(tris[0])
    flipped[20] ^= 0x10
    far = {k: np.array([v[0]]) for k, v in prep["inputs"].items()}
    S = 1 << prep["params"]["sub_bits"]
    for c in range(3):                          # beyond the right edge, inside the field
        far[f"x{c}"] = np.array([prep["size"][0] * S + 8 + 16 * c])
    bad = [bytes(flipped), tris[0][:25], Noise(b"\x00\xa5\x13\x5a\xff"),
           enc.chunks("writes", enc.writes([0x0F0000], [5]))[0],
           enc.chunks("triangles", enc.triangles(far))[0],
           frame("writes", 99, b"\x00" * (enc.payload + 7))]
    return head + bad + tris + [enc.status()]


@pytest.mark.skipif(available("verilator") is not None, reason="needs Verilator")
def test_a_small_scene_through_the_board_core_decodes_to_the_model(tmp_path):
    """The default torus at 64 x 64 (the pipeline's model test_scenes.py builds) through
    the link (with every kind of bad input before
    its triangles), the pipeline, the framebuffer and the scan-out on Verilator: one whole
    frame's symbols keep DVI's rules in the blanking and decode to the model's framebuffer
    (the pipeline's fragments through scene/framebuffer.py, scaled by 15 and centred)
    exactly; every bad input counted once."""
    from board.sim import run
    r = run(SCENES / "default.toml", tmp_path, size=(64, 64), progress=False,
            frames=_bad_then_good, fast=True)
    assert r["symbol_errors"] == [] and r["pixels_differ"] == 0, r
    counts = r["replies"]
    assert {k: counts[k] for k in ("crc", "cut", "long", "unknown", "offscreen", "kind",
                                   "dropped")} == {"crc": 1, "cut": 1, "long": 1, "unknown": 1,
                                                   "offscreen": 1, "kind": 0, "dropped": 0}
    assert counts["noise"] >= 5
    sym = np.load(tmp_path / "tmds.npy")
    assert sym.shape == (800 * 525, 3) and sym.dtype == np.uint16


# ---- the command line -----------------------------------------------------------------------

def _board_cli(*args):
    import subprocess
    import sys
    return subprocess.run([sys.executable, "-m", "board", *args], capture_output=True,
                          text=True)


def test_a_scene_too_large_for_the_planes_is_refused_in_one_line(tmp_path):
    """256 x 256 needs 65,536 words a plane; the 25F's block RAM holds 16,384 beside the
    pipeline: one line naming the keys and the limit, exit 2, nothing written."""
    r = _board_cli("sim", str(SCENES / "default.toml"), "--out", str(tmp_path / "o"))
    assert r.returncode == 2
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and "image.width and image.height" in lines[0] \
        and "16384" in lines[0], r.stderr
    assert not (tmp_path / "o" / "tmds.npy").exists()


def test_board_cli_rejects_bad_arguments_in_one_line(tmp_path):
    r = _board_cli("sim", str(SCENES / "default.toml"), "--out", str(tmp_path), "--size",
                   "12by12")
    assert r.returncode == 2 and r.stderr.strip().count("\n") == 0 and "--size" in r.stderr
    r = _board_cli("program", str(tmp_path / "missing.bit"))
    assert r.returncode == 2 and r.stderr.strip().count("\n") == 0


def test_host_sends_again_on_a_rejection_or_silence():
    """``python -m board send``'s host (board/send.py): a frame whose reply is a rejection or
    does not come is sent again; one that never succeeds ends in one OSError."""
    from board.send import RETRIES, Host

    def reply(seq, result):
        return bytes([0xC3, seq, ["ok", "crc", "cut", "long", "kind"].index(result)]) + \
            bytes(REPLY_BYTES - 3)

    class Port:                        # what pyserial's Serial does, scripted
        def __init__(self, answers):
            self.answers, self.sent = list(answers), []

        def write(self, data):
            self.sent.append(bytes(data))

        def read(self, n):
            return self.answers.pop(0) if self.answers else b""

        def reset_input_buffer(self):
            pass
    data = frame("status", 5)
    port = Port([reply(5, "crc"), b"", reply(4, "ok"), reply(5, "ok")])
    assert Host(port).exchange(data, 5)["result"] == "ok"
    assert port.sent == [data] * 4
    port = Port([])
    with pytest.raises(OSError, match="frame 5"):
        Host(port).exchange(data, 5)
    assert len(port.sent) == RETRIES + 1
