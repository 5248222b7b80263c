"""Stages of one's own (scene/registry.py): each is checked as it is registered, every list
derived from the stages sees it when asked, and a shading method the seeds do not have
(``docs/examples/half_lambert.py``) renders through every tool, its RTL within its bound of
its model."""
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from amaranth.hdl import signed
from amaranth.lib import data
from amaranth.sim import Simulator

from flows.sby import tools_env
from scene import driver as S, registry
from scene.pipeline import ScenePipeline
from scene.stage import Stage, StageError, StageUnit

from .test_stages import EXAMPLES, _example, _rtl_and_model

ROOT = Path(__file__).resolve().parent.parent
HalfLambert = _example("half_lambert", "HalfLambert")


class _Mine(Stage):
    """A stage that gives every required hook: each check below takes one away."""
    name = "mine"
    latency = 0

    def rtl(self, p, v, uni):
        return v

    def model(self, prep, frag, ch, bound):
        return ch

    def ideal(self, prep, frag, ch):
        return ch


def _variant(**attrs):
    return type("Variant", (_Mine,), attrs)


@pytest.mark.parametrize("attrs,message", [
    ({"latency": Stage.latency}, "stage 'mine': latency: missing (required: latency, rtl/build, "
                                 "model, ideal; scene/stage.py)"),
    ({"rtl": Stage.rtl}, "stage 'mine': rtl or build: missing"),
    ({"model": Stage.model}, "stage 'mine': model: missing"),
    ({"ideal": Stage.ideal}, "stage 'mine': ideal: missing"),
    ({"name": "colour"}, "stage 'colour': name: taken by scene.stages.colour.Colour"),
    ({"name": "my stage"}, "name: must be a Python identifier (the submodule's name in the top), "
                           "not 'my stage'"),
    ({"channels": (("fog", "cubic", 0),)}, "stage 'mine': channels: 'fog' has mode 'cubic'; "
                                           "the raster's modes are xshading, exact, linear"),
    ({"when": {"method": "mine"}}, "stage 'mine': interpolates: a shading method's stage says "
                                   "in which of the raster's modes"),
    ({"when": {"method": "mine"}, "interpolates": "quadratic"},
     "stage 'mine': interpolates: 'quadratic' is not one of the raster's modes"),
    ({"when": {"method": "linear"}, "interpolates": "linear"},
     "stage 'mine': when: method 'linear' is the raster's own mode"),
    ({"before": "fog"}, "stage 'mine': before: 'fog' names no stage it can go before"),
    ({"before": "raster"}, "stage 'mine': before: 'raster' names no stage it can go before"),
    ({"build_params": {"lights": (2, (1, 4))}},
     "stage 'mine': build_params: 'lights' is the pipeline's own parameter"),
])
def test_a_stage_is_checked_when_it_is_registered(attrs, message):
    """A missing required hook, a name that is taken, a channel mode the raster does not have
    (and the rest of what a stage declares): one line naming the stage and the hook, and
    nothing registered."""
    before = registry.stages()
    with pytest.raises(StageError) as e:
        registry.register(_variant(**attrs))
    assert message in str(e.value) and "\n" not in str(e.value), e.value
    assert registry.stages() == before
    with pytest.raises(StageError, match="not a scene.stage.Stage subclass"):
        registry.register(object)
    registry.check(_Mine)                # the complete one passes


def test_a_registered_method_is_seen_by_every_list():
    """Registered after import, half-Lambert's method and build parameter are in the scene's
    rules, the pipeline's parameters and ranges, ``sim units --json``, the CLI's help,
    ``make formal``'s pipelines, ``make fuzz``'s RTL configurations, ``make tradeoffs``' shading
    rows and its own sweep, and the gallery; taken out again, in none of them."""
    from flows import formal, fuzz, tradeoffs
    from hdl.units import describe
    from sim.__main__ import parser
    from sim.render import gallery_scenes

    def seen():
        scene = describe("scene")
        help_text = parser()._subparsers._group_actions[0].choices["render"].format_help()
        return {"rules": "half_lambert" in S.tables()[1]["shading"]["method"][1],
                "params": ScenePipeline.PARAMS.get("hl_bits") == 14,
                "ranges": ScenePipeline.RANGES.get("hl_bits") == (8, 14),
                "units": "half_lambert" in scene["param_ranges"]["method"]["choices"]
                and "hl_bits" in scene["params"],
                "help": "half_lambert" in " ".join(help_text.split()),
                "formal": "scene_half_lambert" in formal.targets(),
                "fuzz": "half_lambert" in fuzz.rtl_configs(),
                "tradeoffs": {(r["knob"], r["setting"]) for r in tradeoffs.configurations()}
                >= {("shading", "half_lambert"), ("half-Lambert h bits", "8")},
                "gallery": "half_lambert" in [s["name"] for s in gallery_scenes()]}
    assert not any(seen().values()), seen()
    with pytest.raises(S.SceneError, match="shading.method: must be one of xshading, exact, "
                                           "linear, phong, not 'half_lambert'"):
        S.load(EXAMPLES / "half_lambert.toml")
    with registry.registered(HalfLambert):
        assert all(seen().values()), seen()
        prep = S.prepare(S.load(EXAMPLES / "half_lambert.toml"))
        assert [s.name for s in prep["pipeline"].stages] == ["raster", "power_table",
                                                             "half_lambert", "colour"]
        assert prep["pipeline"].channels == [("depth", "linear"), ("d0", "xshading"),
                                             ("s0", "xshading")]     # the stage's mode
        with pytest.raises(S.SceneError, match="hl_bits must be in 8..14, not 4"):
            S.prepare(S.load(EXAMPLES / "half_lambert.toml"), {"hl_bits": 4})
        # with a bump method, its L' and H' channels in the method's mode, not its name, and
        # d' from the bump stages' N.L
        bump = S.prepare(S.parse({"shading": {"method": "half_lambert"},
                                  "bump": {"method": "fenney_xz", "size": 16}}, "bump"))
        assert {m for _, m in bump["pipeline"].channels} == {"linear", "xshading"}
        assert [s.name for s in bump["pipeline"].stages][-3:] == ["power_table", "half_lambert",
                                                                  "colour"]
        # make tradeoffs' shading row: the default scene's file, the method set over it
        over = S.prepare(S.load(ROOT / "scenes" / "default.toml"), {"method": "half_lambert"})
        assert [s.name for s in over["pipeline"].stages] == [s.name for s in
                                                             prep["pipeline"].stages]
    assert not any(seen().values()), seen()


@pytest.mark.parametrize("bits", [14, 8])
def test_half_lambert_stage_is_bit_exact_on_every_code(bits):
    """The stage alone on Amaranth's simulator, every one of VALUE's 65,536 codes of d in
    order, one a clock: the RTL is its integer model exactly (the clamp, the floor, h's top
    ``hl_bits`` bits, the square rounded half up), and the model is within its rounding of the
    ideal ((d + 1) / 2)^2 on [-1, 1]: 2^-hl_bits of h, times 2h <= 2, plus half an LSB."""
    stage = HalfLambert({"lights": 1, "hl_bits": bits})
    dut = StageUnit(stage, data.StructLayout({"d0": signed(16)}))
    codes = np.arange(-1 << 15, 1 << 15)
    got = []

    async def bench(ctx):
        ctx.set(dut.o.ready, 1)
        k = 0
        while len(got) < len(codes):
            ctx.set(dut.i.valid, k < len(codes))
            ctx.set(dut.i.payload.d0, int(codes[min(k, len(codes) - 1)]))
            _, _, valid, d = await ctx.tick().sample(dut.o.valid, dut.o.payload.d0)
            k += 1
            if valid:
                got.append(d)
    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.run()
    want = stage.half_lambert(codes)
    assert (np.array(got) == want).all()
    d = codes / (1 << 14)
    inside = np.abs(d) <= 1
    err = np.abs(want * 2.0 ** -14 - ((d + 1) / 2) ** 2)[inside]
    assert err.max() <= 2 * 2.0 ** -bits + 2.0 ** -15
    assert (want[codes < -(1 << 14)] == 0).all() and (want[codes > 1 << 14] == 1 << 14).all()


def test_half_lambert_renders_within_a_level_of_its_model():
    """A 32 x 32 torus with two lights through the RTL on Amaranth's simulator: within the one
    level the default pipeline allows (the stage's own derived bound, above, moves d by less
    than 2^-13, and the raster's d is within an LSB of its model), and never darker than the
    same scene by X-shading, since ((d + 1) / 2)^2 >= max(d, 0) on [-1, 1]: its back is lit."""
    scene = {"image": {"width": 32, "height": 32}, "shading": {"method": "half_lambert"},
             "lights": [{"to_light": [-1.0, -1.0, 2.0]}, {"to_light": [1.0, 0.5, -0.5],
                                                          "color": [0.5, 0.5, 0.5]}]}
    plain = S.prepare(S.parse({**scene, "shading": {"method": "xshading"}}, "plain"))
    with registry.registered(HalfLambert):
        prep = S.prepare(S.parse(scene, "half_lambert"))
        rtl, img, cov, _ = _rtl_and_model(prep)
    assert np.abs(rtl.astype(int) - img.astype(int))[cov].max() <= 1
    before, _, _ = S.model(plain)
    lift = img[cov].astype(int) - before[cov]
    assert (lift >= -1).all() and (lift.max(-1) > 10).mean() > 0.2


def _run(args, env, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "sim", *args], capture_output=True, text=True,
                          env={**os.environ, **env}, cwd=cwd)


def test_stages_from_outside_the_tree(tmp_path):
    """The two ways in that every tool reads: ``SHADING_STAGES`` (a file) and the entry-point
    group ``shading_hw.stages`` of an installed package (a dist-info folder on the path, as
    pip writes it). Each puts half-Lambert in ``sim units --json``; a file that is not there,
    or a stage that fails its check, is one line and exit 2."""
    r = _run(["units", "--json"], {registry.ENV: str(EXAMPLES / "half_lambert.py")})
    scene = next(u for u in json.loads(r.stdout)["pipelines"] if u["name"] == "scene")
    assert "half_lambert" in scene["param_ranges"]["method"]["choices"], r.stderr
    site = tmp_path / "site"
    (site / "my_shading").mkdir(parents=True)
    (site / "my_shading" / "__init__.py").write_text(
        (EXAMPLES / "half_lambert.py").read_text())
    info = site / "my_shading-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: my-shading\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[{registry.ENTRY_POINTS}]\n"
                                           "half_lambert = my_shading:HalfLambert\n")
    r = _run(["units", "--json"], {"PYTHONPATH": f"{site}{os.pathsep}{ROOT}"})
    scene = next(u for u in json.loads(r.stdout)["pipelines"] if u["name"] == "scene")
    assert "half_lambert" in scene["param_ranges"]["method"]["choices"], r.stderr
    (tmp_path / "bad.py").write_text("from scene.stage import Stage\n\n\n"
                                     "class Bad(Stage):\n    name = 'bad'\n")
    for item, message in ((str(tmp_path / "none.py"), "none.py: no such file"),
                          (str(tmp_path / "bad.py"), "stage 'bad': latency: missing")):
        r = _run(["units"], {registry.ENV: item})
        assert r.returncode == 2 and r.stderr.count("\n") == 1 and message in r.stderr \
            and r.stderr.startswith("error: "), r.stderr


@pytest.mark.skipif(shutil.which("yowasp-sby", path=tools_env()["PATH"]) is None,
                    reason="yowasp-sby is not installed")
def test_a_stage_of_ones_own_is_proven_alone():
    """``make formal``'s ``stage_half_lambert`` (``scene.stage_alone``: the stage as a one-row
    unit, in the pipeline that wants it): every property proven by k-induction with the
    one-row shadow, as every unit is, and a mutant that drops an item caught by ``order``, so
    the proof can fail. Not a target until the stage is registered."""
    from flows import formal
    assert "stage_half_lambert" not in formal.targets()
    with registry.registered(HalfLambert):
        unit, params = formal.targets()["stage_half_lambert"]
        proof = formal.run("stage_half_lambert", unit, params, "prove", only=formal.ORDER)
        assert proof["status"] == "pass" and not proof["failed"], proof
        assert "successful proof by k-induction" in open(proof["log"]).read()
        r = formal.run("stage_half_lambert", unit, params, "bmc", "dropped")
        assert formal.caught(r), r
