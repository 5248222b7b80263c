"""Scenes (design/scenes.md): the parser, the composition of the pipeline, renders through the
RTL on every simulator against the float model, and the methods' image error.

Bounds: the RTL image must cover exactly the model's pixels and stay within 1 level of it
(the raster's values are within one LSB of 2^-14 of its float model, which moves the 8-bit
colour by far less than a level except at a rounding edge). The methods' PSNR against the
reference: the figures the issue measured with an independent renderer on the default torus
(linear about 25 dB, X-shading about 44, exact mid-edges about 55), within 1 dB.
"""
import math
import tomllib
import subprocess
import sys

import numpy as np
import pytest

from golden import fenney
from scene import driver as S
from scene.pipeline import ScenePipeline, units_in
from hdl.span_unit.raster import Raster

from sim.simulators import available

from .conftest import longest_empty_run, per_simulator

SCENES = "scenes"


def parse(text):
    import tomllib
    return S.parse(tomllib.loads(text), "t")


def test_defaults_are_the_contract():
    s = parse("")
    for table, keys in S.tables()[0].items():
        assert s[table] == keys, table
    d = S.load(f"{SCENES}/default.toml")
    assert (d["image"]["width"], d["shading"]["method"], d["bump"]["method"]) == \
        (256, "xshading", "none")


BAD = [
    ("[material]\nshininess = nan", "material.shininess: must be a finite number >= 1"),
    ("[material]\nshininess = 0.5", "material.shininess: must be a finite number >= 1, not 0.5"),
    ("[material]\nshininess = inf", "material.shininess: must be a finite number >= 1, not inf"),
    ("[material]\nshininess = \"shiny\"", "material.shininess: must be a finite number"),
    ("[material]\ndiffuse = true", "material.diffuse: must be a finite number"),
    ("[material]\ncolor = [1, 0]", "material.color: must be a list of 3 numbers"),
    ("[material]\ncolor = [1, 0, -0.1]", "material.color[2]: must be"),
    ("[material]\nglossy = 1", "material.glossy: unknown key"),
    ("[lighting]\nx = 1", "lighting: unknown table"),
    ("[image]\nwidth = 8", "image.width: must be an integer in 16..1024"),
    ("[image]\nwidth = 64.5", "image.width: must be an integer"),
    ("[mesh]\nshape = \"teapot\"", "mesh.shape: must be one of torus, sphere, plane"),
    ("[mesh]\nsegments = [12, 2]", "mesh.segments[1]: must be an integer in 3..256"),
    ("[shading]\nmethod = \"gouraud\"", "shading.method: must be one of"),
    ("[shading]\nspecular = 1", "shading.specular: must be true or false"),
    ("lights = []", "lights: must be one or more"),
    ("[[lights]]\nto_light = [0, 0, 0]", "lights[0].to_light: must not be the zero vector"),
    ("[[lights]]\ncolor = [1, 1, 3]", "lights[0].color[2]: must be a finite number in 0..2"),
    ("[[lights]]\ntype = \"spot\"", "lights[0].type: must be one of directional"),
    ("[camera]\nup = [0, 1, -0.7142857142857143]", "camera.up: must not be parallel"),
    ("[camera]\neye = [0, 0, 0]", "camera.target: must differ from camera.eye"),
    ("[bump]\nmethod = \"angular\"\nrotation = \"magic\"", "bump.rotation: must be one of paper, exact"),
    ("[image]\nwidth = 64\n[camera]\nfov_y = 180.0", "camera.fov_y: must be a finite number in 1..170"),
    ("\n".join(["[[lights]]"] * 5), "lights: 5 lights; the pipeline shades at most 4"),
    ("[bump]\nmethod = \"fenney_polar\"\nrenormalize = true",
     "bump.renormalize: only with bump.method = \"fenney_xz\""),
    ("[turntable]\nspin = \"camera\"", "turntable.spin: must be one of light, mesh"),
    ("[bump]\nmethod = \"fenney_xz\"\n" + "\n".join(["[[lights]]"] * 2),
     "lights: 2 lights need 15 raster channels (depth, s, t, l0x, l0y, l0z, h0x"),
]


@pytest.mark.parametrize("text,message", BAD, ids=[m.split(":")[0] for _, m in BAD])
def test_bad_scenes_name_the_key(text, message):
    with pytest.raises(S.SceneError) as e:
        parse(text)
    assert message in str(e.value)


def test_bad_files_exit_2_without_a_traceback(tmp_path):
    """Whatever a scene file holds, its failure is one line naming the file (and the key,
    where one is wrong), exit 2: among them an integer past Python's 4,300-digit conversion
    limit, which tomllib raises as a plain ValueError, and a float of as many digits (inf)."""
    (tmp_path / "bad.toml").write_text("[material\nshininess = 3")
    (tmp_path / "nan.toml").write_text("[material]\nshininess = nan")
    (tmp_path / "long_int.toml").write_text("[image]\nwidth = " + "1" * 4301)
    (tmp_path / "long_top.toml").write_text("width = " + "1" * 5000)
    (tmp_path / "long_float.toml").write_text("[material]\nambient = " + "1" * 4301 + ".5")
    (tmp_path / "deep.toml").write_text("a = " + "[" * 5000 + "]" * 5000)
    for name, msg in (("bad", "not a valid TOML file"),
                      ("nan", "material.shininess: must be a finite number"),
                      ("missing", "cannot read the scene file"),
                      ("long_int", "not a readable scene file: Exceeds the limit (4300 digits)"),
                      ("long_top", "not a readable scene file: Exceeds the limit (4300 digits)"),
                      ("long_float", "material.ambient: must be a finite number in 0..1, not inf"),
                      ("deep", "nested too deeply")):
        path = tmp_path / f"{name}.toml"
        r = subprocess.run([sys.executable, "-m", "sim", "render", str(path), "--simulator",
                            "amaranth", "--out", str(tmp_path / "o")],
                           capture_output=True, text=True)
        assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
        assert r.stderr.splitlines() == [f"error: {path}: " + r.stderr.split(f"{path}: ", 1)[1]
                                         .rstrip("\n")] and msg in r.stderr, r.stderr


# ---- composition -----------------------------------------------------------------------------

@pytest.mark.parametrize("scene,units", [
    ("default", ["colour", "power_table", "raster"]),
    ("diffuse", ["colour", "raster"]),                       # specular = false: no power
    ("fenney_power", ["colour", "fenney_power", "raster"]),
    ("phong", ["colour", "phong", "power_table", "raster"]),
    ("linear", ["colour", "power_table", "raster"]),
])
def test_each_scene_builds_only_its_units(scene, units):
    prep = S.prepare(S.load(f"{SCENES}/{scene}.toml"))
    design = ScenePipeline(**prep["params"])
    assert units_in(design) == units
    assert [p[0] for p in prep["pipeline"].parts()] == sorted(units, key=[
        "raster", "phong", "power_table", "fenney_power", "colour"].index)


def test_linear_builds_no_mid_edge_logic():
    """A linear scene's raster interpolates linearly on every channel, so its setup has no
    mid-edge terms: fewer products on its shared multiplier than X-shading's, so fewer clocks
    per triangle, and no square root (exact's)."""
    params = {m: S.prepare(S.load(f"{SCENES}/{m}.toml"))["params"]
              for m in ("linear", "default", "exact")}
    raster = {m: ScenePipeline.spec(**p).parts()[0][1] for m, p in params.items()}
    assert raster["linear"]["modes"] == "linear,linear,linear"
    clocks = {m: Raster.spec(**r).timing[0] for m, r in raster.items()}
    assert clocks["linear"] < clocks["default"] < clocks["exact"], clocks
    assert "rsqrt_seed" not in _rtlil_text(params["default"])
    assert "rsqrt_seed" in _rtlil_text(params["exact"])


def _rtlil_text(params):
    from amaranth.back import rtlil
    return rtlil.convert(ScenePipeline(**params))


def test_scene_verilog_is_lint_clean(tmp_path):
    r = subprocess.run([sys.executable, "-m", "sim", "verilog", "--scene",
                        f"{SCENES}/default.toml", "--out", str(tmp_path)],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "lint clean" in r.stdout and (tmp_path / "scene_default.v").exists()


# ---- rendering -------------------------------------------------------------------------------

@pytest.mark.parametrize("simulator,name", list(per_simulator(["scene"])))
def test_small_scene_rtl_matches_model(simulator, name, tmp_path):
    """The default scene at 64 x 64 through the RTL: exactly the model's pixels, every one
    within 1 level; and the metrics scenes.md lists."""
    from sim.render import render
    m = render(f"{SCENES}/default.toml", tmp_path, simulator, (64, 64), quiet=True)
    assert m["rtl_vs_model"]["coverage_mismatch"] == 0
    assert m["rtl_vs_model"]["max_abs"] <= 1
    assert m["fragments"] == m["fragments_model"] > 1000
    assert m["triangles"] == {"in": 288, "culled": 152, "drawn": 136}
    assert [u["name"] for u in m["units"]] == ["raster", "power_table", "colour"]
    assert abs(m["rtl_vs_reference"]["psnr_db"] - m["model_vs_reference"]["psnr_db"]) <= 1
    assert m["latency"] == ScenePipeline.spec(**m["pipeline"]["params"]).latency
    assert m["rtl_vs_ideal"]["psnr_db"] > 40 and m["ideal_vs_reference"]["psnr_db"] > 40
    for f in ("rtl.png", "model.png", "ideal.png", "reference.png", "diff.png", "metrics.json"):
        assert (tmp_path / f).stat().st_size > 0


OVERLAPPED = {"setup_ii": 16, "setup_mults": 2, "setup_narrow": 2}   # docs/quadratic.md


@pytest.mark.skipif(bool(available("verilator")), reason=f"verilator: {available('verilator')}")
@pytest.mark.parametrize("scene,tables", [
    ("default", {"mesh": {"segments": [96, 64]}}),
    pytest.param("default", {"mesh": {"segments": [96, 64]}, "hardware": OVERLAPPED},
                 marks=pytest.mark.long),           # a knob issue 49 retires: make soak
    ("default", {"camera": {"eye": [0.0, -35.0, 25.0]}, "image": {"width": 48, "height": 48}}),
    # each a model of its own: make soak runs them (the raster's empty triangles are the same
    # walker whatever the channels' modes; the bump methods' are all in make test)
    pytest.param("linear", {"mesh": {"segments": [96, 64]}}, marks=pytest.mark.long),
    pytest.param("exact", {"camera": {"eye": [0.0, -35.0, 25.0]},
                           "image": {"width": 48, "height": 48}}, marks=pytest.mark.long),
    pytest.param("phong", {"camera": {"eye": [0.0, -35.0, 25.0]},
                           "image": {"width": 48, "height": 48}}, marks=pytest.mark.long)],
    ids=["xshading-dense", "xshading-dense-overlapped", "xshading-far", "linear-dense",
         "exact-far", "phong-far"])
def test_dense_scenes_render(scene, tables):
    """Dense meshes (runs of triangles that cover no pixel: sub-pixel ones, and a torus seen
    from far away) through each shading method's pipeline on the batch path, at 64 x 64
    (the default scene's model at that size, above): every fragment the model's, in its order,
    and each pixel within one level of it (the shading units are bit-exact or within one).
    Once with the setup overlapping triangles (a triangle every 16 clocks), under stalls."""
    from sim.run import simulate
    data = tomllib.loads(open(f"{SCENES}/{scene}.toml").read()) if scene != "default" else {}
    tables = dict(tables)
    hardware = tables.pop("hardware", None)
    for key, table in {"image": {"width": 64, "height": 64}, **tables}.items():
        data.setdefault(key, {}).update(table)
    prep = S.prepare(S.parse(data, "dense"), hardware)
    out, _ = simulate("scene", prep["params"], S.rtl_inputs(prep), "verilator",
                      p_valid=0.9, p_ready=0.7, seed=4)
    frag, _ = S.model_fragments(prep)
    assert longest_empty_run(len(prep["inputs"]["x0"]), frag["tri"]) > 16
    for key in ("tri", "x", "y"):
        np.testing.assert_array_equal(out[key], frag[key])
    img, cov, _ = S.model(prep)
    rgb = np.stack([out[c] for c in "rgb"], -1).astype(np.uint8)
    rtl, rcov = S.framebuffer(prep["size"], out["x"], out["y"], out["depth"], rgb,
                              prep["scene"]["image"]["background"])
    assert (rcov == cov).all() and np.abs(rtl.astype(int) - img.astype(int))[cov].max() <= 1


@pytest.mark.parametrize("scene", [
    "diffuse",
    # Phong with Fenney's power and two lights is in make test on Verilator
    # (tests/test_fuzz.py, against its derived bound); on Amaranth in make soak
    *(pytest.param(s, marks=pytest.mark.long) for s in ("phong", "fenney_power",
                                                        "sphere_two_lights"))])
def test_other_pipelines_on_amaranth(scene, tmp_path):
    """Phong, Fenney's power, two lights and diffuse-only, at 32 x 32 on Amaranth's
    simulator: the RTL against the model."""
    from sim.render import render
    m = render(f"{SCENES}/{scene}.toml", tmp_path, "amaranth", (32, 32), quiet=True)
    assert m["rtl_vs_model"]["coverage_mismatch"] == 0
    assert m["rtl_vs_model"]["max_abs"] <= 1
    assert m["fragments"] > 150


def test_one_pixel_triangle():
    """A triangle that covers one pixel centre gives one fragment, coloured like the model."""
    from sim.run import simulate
    prep = S.prepare(S.parse({"image": {"width": 32, "height": 32}}))
    S_ = 1 << prep["params"]["sub_bits"]
    one = {k: v[:1].copy() for k, v in prep["inputs"].items()}
    for k, (x, y) in enumerate([(10 * S_ + 2, 10 * S_ + 2), (11 * S_ - 2, 10 * S_ + 4),
                                (10 * S_ + 4, 11 * S_ - 2)]):
        one[f"x{k}"][:], one[f"y{k}"][:] = x, y
    prep = {**prep, "inputs": one}
    out, _ = simulate("scene", prep["params"], S.rtl_inputs(prep), "amaranth")
    assert (list(out["x"]), list(out["y"])) == ([10], [10])
    img, cov, n = S.model(prep)
    assert n == 1 and cov.sum() == 1
    assert np.abs(img[10, 10].astype(int) - [out[c][0] for c in "rgb"]).max() <= 1


@pytest.mark.parametrize("method,expected", [("linear", 25), ("xshading", 44), ("exact", 55)])
def test_method_error_on_the_default_torus(method, expected):
    """The float model of each method against the reference, on the default 256 x 256 torus,
    beside the issue's independent measurements ("about" 25, 44 and 55 dB), within 1.5 dB:
    measured here 24.7, 44.1 and 54.0 (54.1 with the exact power instead of the table, so the
    last dB is not the hardware's formats)."""
    from sim.render import compare
    scene = S.load(f"{SCENES}/default.toml")
    scene["shading"]["method"] = method
    prep = S.prepare(scene)
    img, cov, _ = S.model(prep)
    ref, rcov = S.reference(prep)
    assert abs(compare(img, cov, ref, rcov)["psnr_db"] - expected) <= 1.5


def test_phong_model_reaches_50_db():
    from sim.render import compare
    prep = S.prepare(S.load(f"{SCENES}/phong.toml"))
    img, cov, _ = S.model(prep)
    ref, rcov = S.reference(prep)
    assert compare(img, cov, ref, rcov)["psnr_db"] >= 50


def test_fenney_concentration_fits_the_exponent():
    """C from the fit: its fitted exponent within 10 % of n, where the range allows."""
    from golden.fenney import power_exponent
    for n in (8.0, 32.0, 100.0):
        c = fenney.concentration_for(n)
        assert abs(math.log(power_exponent(c)[0] / n)) < 0.1, (n, c)


def test_phong_ideal_is_the_reference():
    """The float ideal of per-pixel Phong (the same affine normal, normalised exactly, the
    exact power) is the reference itself: every pixel equal. So the ideal's machinery (the
    unrounded raster inputs, each stage's exact function, the colour sum) adds nothing."""
    prep = S.prepare(S.load(f"{SCENES}/phong.toml"))
    img, cov = S.ideal(prep)
    ref, rcov = S.reference(prep)
    assert (cov == rcov).all() and (img == ref).all()


def test_ideal_raster_is_the_quadratic_through_the_samples():
    """The ideal raster's X-shading value at each pixel is the quadratic through the three
    vertex values and the three mid-edge samples (seed 001 eq 27-32), evaluated here in its
    barycentric (Lagrange) form at the exact pixel centre from the unrounded vertices:
    a formulation independent of the setup's (u, v) map."""
    from golden import quadratic as q
    prep = S.prepare(S.load(f"{SCENES}/default.toml"))
    raster = prep["pipeline"].stages[0]
    frag, ch = raster.ideal(prep)
    real, k = prep["real"], [n for n, _, _ in raster.all_channels].index("d0")
    t = frag["tri"]
    x = np.stack([real[f"x{c}"][t] for c in range(3)], -1) / 16
    y = np.stack([real[f"y{c}"][t] for c in range(3)], -1) / 16
    I = [real[f"v{k}_{c}"][t] * 2.0**-14 for c in range(3)]
    e = [real[n][t] * 2.0**-15 for n in ("e01", "e02", "e12")]
    mids = q.xshading_samples(*I, *e)[:, 3:]                        # m01, m02, m12
    px, py = frag["x"] + 0.5, frag["y"] + 0.5
    det = (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0])
    w1 = ((px - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (py - y[:, 0])) / det
    w2 = ((x[:, 1] - x[:, 0]) * (py - y[:, 0]) - (px - x[:, 0]) * (y[:, 1] - y[:, 0])) / det
    w = [1 - w1 - w2, w1, w2]
    want = sum(I[i] * w[i] * (2 * w[i] - 1) for i in range(3)) + 4 * (
        mids[:, 0] * w[0] * w[1] + mids[:, 1] * w[0] * w[2] + mids[:, 2] * w[1] * w[2])
    np.testing.assert_allclose(ch["d0"], want, atol=1e-9)


@pytest.mark.parametrize("scene", ["default", "linear", "exact", "fenney_power", "bump_polar",
                                   "bump_xz", "bump_angular_exact"])
def test_ideal_splits_the_error(scene):
    """ideal.png: the method's own error (ideal against the reference) and the formats'
    (the model, with the RTL's formats, against the ideal). The formats never cost much of
    a method whose own error is large: the ideal is at least the model less 0.5 dB."""
    from sim.render import compare
    prep = S.prepare(S.load(f"{SCENES}/{scene}.toml"))
    img, cov, _ = S.model(prep)
    idl, icov = S.ideal(prep)
    ref, rcov = S.reference(prep)
    own, fmt = compare(idl, icov, ref, rcov), compare(img, cov, ref, rcov)
    assert own["coverage_mismatch"] == 0 and own["psnr_db"] >= fmt["psnr_db"] - 0.5


@pytest.mark.parametrize("scene", ["default", "phong", "bump_polar", "bump_xz_renorm",
                                   "bump_angular_exact"])
def test_every_group_of_formats_gives_the_model(scene):
    """flows.losses runs the ideal with groups of stages as their models: with every group the
    image is the model's, pixel for pixel (the conversions between the ideal's reals and the
    models' codes lose nothing), so each group's loss is a share of the model's."""
    from flows.losses import GROUPS
    prep = S.prepare(S.load(f"{SCENES}/{scene}.toml"))
    img, cov, _ = S.model(prep)
    mixed, mcov = S.ideal(prep, GROUPS)
    assert (cov == mcov).all() and (img == mixed).all()
