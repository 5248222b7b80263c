"""The stage list (scene/registry.py): what each stage declares composes into the top, and a
new effect is one file, registered. The README's worked examples (``docs/examples/``: the
depth cue, and fog with a scene table and a channel of its own) are put after ``Colour`` and
rendered, RTL against their models."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from scene import driver as S, pipeline
from scene.pipeline import ScenePipeline, units_in

EXAMPLES = Path(__file__).resolve().parent.parent / "docs" / "examples"


def _example(name="depth_cue", cls="DepthCue"):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return getattr(mod, cls)


def _rtl_and_model(prep):
    """The RTL's picture on Amaranth's simulator and the model's, with the model's coverage."""
    from sim.run import simulate
    out, info = simulate("scene", prep["params"], S.rtl_inputs(prep), "amaranth")
    img, cov, _ = S.model(prep)
    rgb = np.stack([out[c] for c in "rgb"], -1).astype(np.uint8)
    rtl, rcov = S.framebuffer(prep["size"], out["x"], out["y"], out["depth"], rgb,
                              prep["scene"]["image"]["background"])
    assert (rcov == cov).all() and cov.sum() > 100
    return rtl, img, cov, info


@pytest.mark.parametrize("scene", ["default", "phong", "bump_xz", "bump_polar", "bump_angular"])
def test_latency_is_the_stages_sum(scene):
    """The top's latency is the raster's plus each stage's, each from its units, plus a clock
    for each register slice between two shading stages."""
    prep = S.prepare(S.load(f"scenes/{scene}.toml"))
    pipe = prep["pipeline"]
    assert pipe.latency == sum(s.latency for s in pipe.stages) + len(pipe.stages) - 2
    assert [s.name for s in pipe.stages][0] == "raster" and pipe.stages[-1].name == "colour"
    assert units_in(ScenePipeline(**prep["params"])) == sorted(s.name for s in pipe.stages)


def test_a_new_effect_is_one_file_and_one_line():
    """The depth cue, added to the list: it is built (a submodule of its own, its uniform a
    port of the top), and the RTL's pixels are its model's on Amaranth's simulator, within
    the one level the default pipeline allows, and darker than without it."""
    cue = _example()
    data = {"image": {"width": 32, "height": 32}}
    plain = S.prepare(S.parse(data, "plain"))
    with pipeline.registered(cue):
        prep = S.prepare(S.parse(data, "cue"))
        rtl, img, cov, info = _rtl_and_model(prep)
    assert [s.name for s in prep["pipeline"].stages][-2:] == ["colour", "depth_cue"]
    assert prep["uniforms"]["cue_near"] == 255
    assert info["latency"] == prep["pipeline"].latency == plain["pipeline"].latency + 2 + 1   # its own, a slice
    assert np.abs(rtl.astype(int) - img.astype(int))[cov].max() <= 1
    before, _, _ = S.model(plain)
    assert (img[cov].astype(int) <= before[cov]).all() and (img[cov] < before[cov]).any()


def test_an_effect_with_its_own_scene_table_and_channel():
    """Fog (``docs/examples/fog.py``), added by its file and one line: its ``[fog]`` table is
    parsed with its rules (an unknown key, a far before the near, named in one line), its fog
    factor rides the raster as a channel of its own, and the RTL's pixels are its model's
    within the one level the default pipeline allows (the blend itself is exact integer
    arithmetic in both: fog + (c - fog) w / 256). The far side of the torus is pulled toward
    the fog's colour, the near side is not."""
    fog = _example("fog", "Fog")
    data = {"image": {"width": 32, "height": 32}, "fog": {"near": 3.4, "far": 4.6,
                                                          "color": [1.0, 1.0, 1.0]}}
    with pytest.raises(S.SceneError, match=r"^fog: unknown table"):
        S.parse(data)                                        # not in the list yet
    plain = S.prepare(S.parse({"image": data["image"]}, "plain"))
    with pipeline.registered(fog):
        with pytest.raises(S.SceneError, match=r"^fog\.density: unknown key \(known: near, far, color\)$"):
            S.parse({"fog": {"density": 1.0}})
        with pytest.raises(S.SceneError, match=r"^fog\.far: must be beyond fog\.near \(3\.4\), not 3$"):
            S.prepare(S.parse({"fog": {"near": 3.4, "far": 3.0}}))
        prep = S.prepare(S.parse(data, "fog"))
        rtl, img, cov, _ = _rtl_and_model(prep)
    assert [s.name for s in prep["pipeline"].stages][-2:] == ["colour", "fog"]
    assert [n for n, _ in prep["pipeline"].channels][-1] == "fog"
    assert [prep["uniforms"][f"fog_{c}"] for c in "rgb"] == [255, 255, 255]
    assert np.abs(rtl.astype(int) - img.astype(int))[cov].max() <= 1
    before, _, _ = S.model(plain)
    lifted = (img[cov].astype(int) - before[cov]).min(-1)
    assert (lifted >= -1).all()                  # toward white, never away (1: the rounding)
    assert (lifted > 40).mean() > 0.1 and (lifted <= 1).mean() > 0.1    # far fogged, near not


@pytest.mark.parametrize("seed", range(4))
def test_the_register_slice_between_stages_keeps_the_stream(seed):
    """``hdl.unit.skid``, the join of every two shading stages, under random stalls on both
    sides: every item taken comes out once and in order, an offered output is held with its
    payload until taken, and with nothing stalled an item is out the next clock, one a
    clock. Its outputs and its input's ready are registers: each is checked not to move
    within a clock when the other side's handshake changes."""
    from types import SimpleNamespace
    from amaranth.hdl import Module, Signal
    from amaranth.sim import Simulator
    from hdl.unit import skid

    rng = np.random.default_rng(seed)
    m = Module()
    src = SimpleNamespace(valid=Signal(), ready=Signal(), payload=Signal(8))
    dst = SimpleNamespace(valid=Signal(), ready=Signal(), payload=Signal(8))
    busy = Signal()
    m.d.comb += busy.eq(skid(m, "t", src, dst))
    # the first 40 clocks with nothing stalled, then random stalls on both sides, then drain
    offer = np.r_[np.ones(40), rng.random(400) < 0.7, np.zeros(20)].astype(int)
    take = np.r_[np.ones(40), rng.random(400) < 0.6, np.ones(20)].astype(int)
    sent, got, seen = [], [], []

    async def bench(ctx):
        nxt, last = 0, None
        for t in range(len(offer)):
            ctx.set(src.valid, int(offer[t]))
            ctx.set(src.payload, nxt & 255)
            ctx.set(dst.ready, 0)
            regs = (ctx.get(src.ready), ctx.get(dst.valid), ctx.get(dst.payload))
            ctx.set(dst.ready, int(take[t]))
            assert (ctx.get(src.ready), ctx.get(dst.valid), ctx.get(dst.payload)) == regs
            if last is not None:           # the output stalled a clock ago: held, unchanged
                assert ctx.get(dst.valid) and ctx.get(dst.payload) == last
            if ctx.get(src.valid) and ctx.get(src.ready):
                sent.append((t, nxt & 255))
                nxt += 1
            last = None
            if ctx.get(dst.valid):
                if ctx.get(dst.ready):
                    got.append((t, ctx.get(dst.payload)))
                else:
                    last = ctx.get(dst.payload)
            seen.append(ctx.get(busy))
            await ctx.tick()

    sim = Simulator(m)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    assert [p for _, p in got] == [p for _, p in sent] and len(sent) > 200
    assert [t for t, _ in got[:39]] == [t + 1 for t, _ in sent[:39]]    # latency 1, 1 a clock
    assert not seen[-1] and any(seen)
