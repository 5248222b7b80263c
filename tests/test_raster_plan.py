"""The raster's plan (``hdl/span_unit/plan.py``): one typed, frozen configuration, checked
when it is made, each error naming its knob; the raster unit's parameters and the scene's
raster stage give the same plan."""
import pytest

from hdl.span_unit.plan import KNOBS, Channel, RasterPlan
from hdl.units import ParamError, make_unit
from scene import driver as S
from sim.verilog import SCENES


def test_a_plan_and_its_parameters_are_one():
    plan = RasterPlan(8, 4, (Channel("linear"), Channel("xshading", 1, 10),
                             Channel("exact", 1)), "divide", 0, 2, setup_ii=40, setup_mults=2)
    assert RasterPlan.from_params(**plan.params()) == plan
    assert RasterPlan.from_params(**plan.params(defaults=False)) == plan
    unit = make_unit("raster", spec=True, **plan.params(defaults=False))
    assert unit.plan == plan and unit.groups == 2 and unit.precision == (14, 10, 14)
    short = RasterPlan(channels=(Channel(),) * 3).params(defaults=False)
    assert set(short) == {"screen_bits", "sub_bits", "channels", "modes", "recip",
                          "recip_iters"}          # defaults left out: the Verilog's name


@pytest.mark.parametrize("change,message", [
    (dict(setup_ii=3), "setup_ii=3 is too short"),
    (dict(row_serial=2, row_mults=3), "row_mults=3 and row_serial=2"),
    (dict(setup_serial=1), "setup_serial=1 needs row_serial > 0"),
    (dict(row_mults=14), "row_mults must be in 0..13"),
    (dict(recip_iters=4), "recip_iters must be in 0..3"),
    (dict(channels=(Channel(group=1),)), "groups must be numbered 0, 1"),
    (dict(channels=(Channel("cubic"),)), "unknown mode 'cubic'"),
    (dict(channels=(Channel(precision=15),)), "precision must be fraction bits from 1"),
])
def test_a_plan_refuses_naming_the_knob(change, message):
    with pytest.raises(ValueError, match=message):
        RasterPlan(**change)


def test_the_knobs_are_named_once():
    """The raster's, the scene pipeline's and the CLI's knobs are the plan's."""
    from hdl.span_unit import Raster
    from scene.pipeline import ScenePipeline
    from sim.cli_common import RASTER_KNOBS
    for k, (default, rng, _) in KNOBS.items():
        assert Raster.PARAMS[k] == ScenePipeline.PARAMS[k] == default
        assert Raster.RANGES[k] == ScenePipeline.RANGES[k] == rng
        assert k in RASTER_KNOBS


def test_the_scene_stage_builds_the_plan():
    prep = S.prepare(S.load(SCENES / "default.toml"), {"setup_ii": 40, "setup_mults": 2})
    stage = prep["pipeline"].raster
    assert stage.plan.setup_ii == 40 and [c.mode for c in stage.plan.channels] == [
        "linear", "xshading", "xshading"]
    assert make_unit("raster", spec=True, **stage.params).plan == stage.plan
    with pytest.raises(S.SceneError, match="setup_ii=3 is too short"):
        S.prepare(S.load(SCENES / "default.toml"), {"setup_ii": 3})
