"""The short version of make fuzz: generated scenes (malformed and valid-but-hard) each give a
clear error naming the key or a picture, never a traceback; valid ones through the RTL on the
batch path match their model (the pixels covered, each within 1 level); malformed npz inputs
to sim run, golden run and sim check each exit 2 with one line."""
import warnings

import pytest

from flows.fuzz import MALFORMED, fuzz_npz, fuzz_scenes
from sim.simulators import available


def test_generated_scenes(tmp_path):
    """20 scenes of each class, valid ("hard") and malformed. A class at a time: drawn
    together, hypothesis's choices left some classes out of 200 scenes."""
    for kind in ("hard", *MALFORMED):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            counts, failures = fuzz_scenes(20, 3, tmp_path / kind, kinds=(kind,))
        assert not failures, failures[:3]
        assert sum(n for (k, _), n in counts.items() if k == kind) == 20, (kind, counts)
        if kind == "hard":
            assert counts["hard", "ok"] >= 5, counts    # a quarter render, as before (20 of 67)


@pytest.mark.parametrize("body", [
    pytest.param("v = " + "[" * 50000 + "1" + "]" * 50000, id="arrays"),  # past the recursion limit
    pytest.param("v = " + "{ a = " * 5000 + "1" + " }" * 5000, id="tables"),
    pytest.param("v = \"" + "x" * (2 << 20) + "\"", id="megabytes"),   # no scene needs them
])
def test_toml_extreme_in_nesting_or_size_is_one_line(tmp_path, body):
    """The class of scene file that gave tracebacks (issue 51): tomllib's recursion, and a
    file of megabytes, each refused where the file is read, in one line naming it."""
    from scene.driver import SceneError, load
    path = tmp_path / "deep.toml"
    path.write_text("[image]\nwidth = 64\n[extra]\n" + body + "\n")
    with pytest.raises(SceneError) as e:
        load(path)
    assert str(path) in str(e.value) and "\n" not in str(e.value)


@pytest.mark.skipif(bool(available("verilator")), reason=f"verilator: {available('verilator')}")
@pytest.mark.parametrize("config", [
    pytest.param("xshading", marks=pytest.mark.xdist_group("verilator-scene")),
    pytest.param("fenney_polar", marks=pytest.mark.xdist_group("verilator-scene-bump"))])
def test_generated_scenes_through_the_rtl(config, tmp_path):
    """Two configurations whose 64 x 64 models other tests build (test_scenes,
    test_bump_scenes): each render the model's fragments, each within its bound."""
    counts, failures = fuzz_scenes(0, 5, tmp_path, rtl=6, configs=[config])
    assert not failures, failures[:3]
    assert counts["rtl", "within bound"] >= 4


def test_malformed_npz(tmp_path):
    counts, failures = fuzz_npz(400, 3, tmp_path)
    assert not failures, failures[:3]
    assert sum(counts.values()) == 400


@pytest.mark.skipif(bool(available("verilator")), reason=f"verilator: {available('verilator')}")
@pytest.mark.xdist_group("verilator-scene")
def test_vertex_at_the_coordinate_fields_edge():
    """What make fuzz found: a dense torus whose vertices round to one past the coordinate
    field; the driver now culls such triangles (prepare checks every field), so the RTL covers
    exactly the model's pixels."""
    from scene import driver as S
    from flows.fuzz import rtl_check
    prep = S.prepare(S.load("tests/data/fuzz_coordinate_edge.toml"))
    assert rtl_check(prep) is None


@pytest.mark.skipif(bool(available("verilator")), reason=f"verilator: {available('verilator')}")
def test_phong_fenney_two_lights_within_its_derived_bound():
    """The scene of issue 51 (tests/data/phong_fenney_two_lights.toml): phong's RTL is within
    its derived bound of the float s the model rounds, so where s lies that close to a
    multiple of 16 the power's X = floor(s / 16) may be the next one, and at C = 255 one X
    step is up to 63/1024 of the power. Each fragment is within 1 level of a colour that
    those X steps allow (``FenneyPower.candidates``), though not always of the
    model's own: the bound this combination really has."""
    from pathlib import Path
    from flows.fuzz import rtl_check
    from scene import driver as S
    prep = S.prepare(S.load(Path(__file__).with_name("data") / "phong_fenney_two_lights.toml"))
    assert rtl_check(prep) is None
