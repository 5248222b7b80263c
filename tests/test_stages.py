"""The stage list (scene/pipeline.py): what each stage declares composes into the top, and a
new effect is one file plus one line. The README's worked example
(``docs/examples/depth_cue.py``) is put after ``Colour`` and rendered, RTL against its model."""
import importlib.util
from pathlib import Path

import numpy as np
import pytest

from scene import driver as S, pipeline
from scene.pipeline import ScenePipeline, units_in

EXAMPLE = Path(__file__).resolve().parent.parent / "docs" / "examples" / "depth_cue.py"


def _example():
    spec = importlib.util.spec_from_file_location("depth_cue", EXAMPLE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.DepthCue


@pytest.mark.parametrize("scene", ["default", "phong", "bump_xz", "bump_polar", "bump_angular"])
def test_latency_is_the_stages_sum(scene):
    """The top's latency is the raster's plus each stage's, each from its units."""
    prep = S.prepare(S.load(f"scenes/{scene}.toml"))
    pipe = prep["pipeline"]
    assert pipe.latency == sum(s.latency for s in pipe.stages)
    assert [s.name for s in pipe.stages][0] == "raster" and pipe.stages[-1].name == "colour"
    assert units_in(ScenePipeline(**prep["params"])) == sorted(s.name for s in pipe.stages)


def test_a_new_effect_is_one_file_and_one_line(monkeypatch):
    """The depth cue, added to the list: it is built (a submodule of its own, its uniform a
    port of the top), and the RTL's pixels are its model's on Amaranth's simulator, within
    the one level the default pipeline allows, and darker than without it."""
    from sim.run import simulate
    cue = _example()
    data = {"image": {"width": 32, "height": 32}}
    plain = S.prepare(S.parse(data, "plain"))
    monkeypatch.setattr(pipeline, "STAGES", pipeline.STAGES + (cue,))
    prep = S.prepare(S.parse(data, "cue"))
    assert [s.name for s in prep["pipeline"].stages][-2:] == ["colour", "depth_cue"]
    assert prep["uniforms"]["cue_near"] == 255
    out, info = simulate("scene", prep["params"], S.rtl_inputs(prep), "amaranth")
    assert info["latency"] == prep["pipeline"].latency == plain["pipeline"].latency + 2
    img, cov, _ = S.model(prep)
    rgb = np.stack([out[c] for c in "rgb"], -1).astype(np.uint8)
    rtl, rcov = S.framebuffer(prep["size"], out["x"], out["y"], out["depth"], rgb,
                              prep["scene"]["image"]["background"])
    assert (rcov == cov).all() and cov.sum() > 100
    assert np.abs(rtl.astype(int) - img.astype(int))[cov].max() <= 1
    before, _, _ = S.model(plain)
    assert (img[cov].astype(int) <= before[cov]).all() and (img[cov] < before[cov]).any()
