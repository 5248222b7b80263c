"""``python -m board sim SCENE.toml --out DIR``: the board's core (everything but the PLL and
the DDR primitives) on Verilator, a scene sent through its link, and one whole video frame.

In: the host's frames (``board/protocol.py``) at the byte level into the link, a byte every
10 UART bit-times, each frame after the last one's reply (the UART itself is proven at the
bit level on its own: tests/test_board.py). Out, in ``DIR``:

- ``tmds.npy``: (420000, 3) uint16, the lanes' 10-bit symbols for every pixel clock of one
  frame (800 x 525, blanking included), lane 0 blue, 1 green, 2 red, bit 0 sent first;
- ``frame.png``: the 640 x 480 picture decoded back from them (``board.tmds.decode``);
- ``board.json``: clocks to render, link bytes, replies, and the pixels that differ from the
  model: the same scene's fragments (the pipeline's RTL on the batch path) through the
  framebuffer's model (``scene/framebuffer.py``), scaled and centred as the scan-out does.
"""
import functools
import hashlib
import json
import os
import struct
import subprocess
import sys
import time
from importlib.metadata import version
from pathlib import Path

import numpy as np

from scene import driver as S
from scene.framebuffer import board_frame, screen
from sim.batch import verilate
from sim.verilog import BUILD, build_lock

from .link import REPLY_BYTES
from .protocol import Encoder, parse_reply
from .tmds import decode
from .top import BAUD, CLOCKS, BoardCore, divisor
from .video import VGA, placement

__all__ = ["Noise", "prepare", "build", "simulate", "decode_frame", "run"]

HARNESS = Path(__file__).with_name("harness.cpp")
# pixel : core clocks, as the PLL makes them (25 : 100)
RATIO = (1, 4)


class Noise(bytes):
    """Bytes on the line that are no frame: the host expects no reply."""


def prepare(scene_path, size=None, board="ulx3s-25f", timeout=None):
    """A scene for the board: its image checked against the board's planes, its bump map on
    chip. Returns (prep, core); ``timeout``: the link's quiet clocks (``BoardCore``)."""
    scene = S.load(scene_path)
    if size:
        scene["image"]["width"], scene["image"]["height"] = size
        scene = S.parse({k: v for k, v in scene.items() if k != "name"}, scene["name"])
    hardware = {"texture": "onchip"} if scene["bump"]["method"] != "none" else None
    prep = S.prepare(scene, hardware)
    W, H = prep["size"]
    core = BoardCore(prep["params"], W, H, board, timeout=timeout)
    return prep, core


def build(core):
    """The core's Verilog in the harness, built once per design (``build/board/``)."""
    from amaranth.back import verilog
    text = verilog.convert(core, name="board_core", emit_src=False)
    tag = hashlib.sha1(text.encode()).hexdigest()[:10]
    base = BUILD / "board" / f"core-{tag}"
    exe = base / "obj" / "harness"
    with build_lock(base.parent / f"{base.name}.lock"):
        # -O1 even in the tests (whose batch models are -O0): a whole frame is long enough
        # that it pays for its build (the frame test: 82 s at -O0, 44 s at -O1, both building)
        opt = os.environ.get("SHADE_BOARD_OPT", "-O1")
        stamp = hashlib.sha1(json.dumps([text, HARNESS.read_text(), opt,
                                         version("verilator")]).encode()).hexdigest()
        done = base / "obj" / "stamp"
        if not (exe.exists() and done.exists() and done.read_text() == stamp):
            base.mkdir(parents=True, exist_ok=True)
            src = base / "board_core.v"
            src.write_text(text)
            print(f"board: building the Verilator model (once; cached under {base})",
                  file=sys.stderr, flush=True)
            verilate("board_core", src, HARNESS, base, opt, opt)
            done.write_text(stamp)
    return exe


def simulate(core, frames, progress=True, pace=None, ratio=RATIO):
    """``frames`` through the core, each bytes (a frame: the host waits for its reply) or
    ``Noise(bytes)`` (no reply); returns (symbols (N, 3), render clocks, reply bytes).
    ``pace``: core clocks a byte (the UART's by default); ``ratio``: pixel to core clocks."""
    exe = build(core)
    work = BUILD / "board" / "run"
    work.mkdir(parents=True, exist_ok=True)
    tag = f"{id(frames):x}-{time.time_ns()}"
    inp, out = work / f"in-{tag}.bin", work / f"out-{tag}.bin"
    inp.write_bytes(struct.pack("<I", len(frames)) + b"".join(
        struct.pack("<I", len(f) | (1 << 31 if isinstance(f, Noise) else 0)) + bytes(f)
        for f in frames))
    pace = pace or 10 * divisor(BAUD)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(frames), unit="frame", desc="board sim", file=sys.stderr)
    p = subprocess.Popen([str(exe), str(inp), str(out), str(pace), *map(str, ratio)],
                         stderr=subprocess.PIPE, text=True)
    err = []
    for line in p.stderr:
        if line.startswith("frame ") and bar is not None:
            bar.update(1)
        elif not line.startswith("frame "):
            err.append(line)
    p.wait()
    if bar is not None:
        bar.close()
    inp.unlink()
    if p.returncode != 0:
        raise RuntimeError("".join(err).strip() or f"the board harness failed ({p.returncode})")
    raw = out.read_bytes()
    out.unlink()
    render, n = struct.unpack_from("<II", raw)
    sym = np.frombuffer(raw, np.uint16, 3 * n, 8).reshape(n, 3).copy()
    (nr,) = struct.unpack_from("<I", raw, 8 + 6 * n)
    replies = raw[12 + 6 * n:12 + 6 * n + nr]
    return sym, render, replies


def decode_frame(sym, timing=VGA):
    """The symbols of one frame back to the picture: (480, 640, 3), and a list of what broke
    the rules (a data character outside the active picture, a token inside it, the syncs'
    tokens in the wrong place), in scan order, stopping after the line where it passes 20.
    Each symbol is decoded through a table of ``tmds.decode`` over all 1,024."""
    h, v = timing
    kinds, values = _symbol_table()
    grid = sym.reshape(v.total, h.total, 3) & 0x3FF
    kind, value = kinds[grid], values[grid]                 # kind: 1 a token (control)
    x, y = np.arange(h.total)[None, :], np.arange(v.total)[:, None]
    active = (x < h.active) & (y < v.active)
    hs = ~((h.active + h.front <= x) & (x < h.active + h.front + h.sync))
    vs = ~((v.active + v.front <= y) & (y < v.active + v.front + v.sync))
    want = np.stack([(vs.astype(int) << 1) | hs, np.zeros_like(x * y), np.zeros_like(x * y)],
                    -1)
    bad = np.where(active[..., None], kind != 0, (kind != 1) | (value != want))
    img = np.where(kind == 0, value, 0)[:v.active, :h.active, ::-1].astype(np.uint8)
    errors = []
    for yy, xx, lane in np.argwhere(bad):
        if len(errors) > 20 and yy > errors[-1][1]:
            break
        errors.append((int(xx), int(yy), int(lane), "a token in the picture"
                       if active[yy, xx] else
                       f"blanking: {('data', 'control')[kinds[grid[yy, xx, lane]]]} "
                       f"{values[grid[yy, xx, lane]]}"))
    return img, errors


@functools.lru_cache(maxsize=None)
def _symbol_table():
    """``tmds.decode`` of every 10-bit symbol: (kind, 1 for a token, 0 for data; value)."""
    pairs = [decode(s) for s in range(1024)]
    return (np.array([k == "control" for k, _ in pairs], np.int64),
            np.array([v for _, v in pairs], np.int64))


def run(scene_path, out_dir, size=None, board="ulx3s-25f", progress=True, frames=None,
        fast=False):
    """The whole check; writes the three files and returns board.json's contents.
    ``frames(encoder, prep)``: the link's traffic (by default ``encoder.scene(prep)``).
    ``fast`` (the tests): bytes 12 clocks apart, the link quiet after 2,000 clocks, the pixel
    clock half the core's, so the same checks take a fifth of the clocks."""
    from PIL import Image
    from sim.render import run_rtl
    prep, core = prepare(scene_path, size, board, timeout=2000 if fast else None)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    enc = Encoder(core.pipe, core.buffer)
    frames = frames(enc, prep) if frames else enc.scene(prep)
    t0 = time.time()
    sym, render, replies = simulate(core, frames, progress, *((12, (1, 2)) if fast else ()))
    wall = time.time() - t0
    np.save(out_dir / "tmds.npy", sym)
    img, errors = decode_frame(sym)
    Image.fromarray(img).save(out_dir / "frame.png")
    # the model: the pipeline's own fragments, the framebuffer's model, the scan-out's scale
    _, _, frags, _, _, _ = run_rtl(prep, "verilator", progress=None)
    W, H = prep["size"]
    model = screen(board_frame((W, H), frags, prep["scene"]["image"]["background"]),
                   *placement(W, H))
    Image.fromarray(model).save(out_dir / "model.png")
    differ = int((img != model).any(-1).sum())
    last = [parse_reply(replies[k:k + REPLY_BYTES])
            for k in range(0, len(replies), REPLY_BYTES)]
    report = {"scene": prep["scene"]["name"], "size": [W, H], "board": board,
              "clocks_to_render": render, "core_mhz": round(CLOCKS["sync"][0], 3),
              "baud": BAUD, "link_bytes": sum(len(f) for f in frames),
              "frames": len(frames), "replies": last[-1] if last else None,
              "fragments_model": len(frags["x"]), "symbol_errors": errors[:10],
              "pixels_differ": differ, "wall_s": round(wall, 1)}
    (out_dir / "board.json").write_text(json.dumps(report, indent=1) + "\n")
    return report
