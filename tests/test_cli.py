"""The command-line contract: ``python -m sim`` and ``python -m golden`` as a user runs them."""
import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from golden import MODELS, raster
from hdl.units import UNITS

ROOT = Path(__file__).resolve().parent.parent


def cli(*args):
    return subprocess.run([sys.executable, "-m", *args], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)


def test_units_json():
    r = cli("sim", "units", "--json")
    assert r.returncode == 0, r.stderr
    units = {u["name"]: u for u in json.loads(r.stdout)["units"]}
    assert set(units) == set(UNITS)
    assert units["rotation"]["param_ranges"]["method"] == {"choices": ["paper", "exact"]}
    assert units["fenney_dot"]["param_ranges"]["rsqrt_bits"] == {"min": 4, "max": 16}
    assert units["fenney_polar"]["outputs"] == [
        {"name": "intensity", "width": 8, "signed": False, "frac_bits": 0, "unit": "1/255"},
        {"name": "shade", "width": 10, "signed": False, "frac_bits": 10, "unit": "1"}]
    assert units["texel_decode"]["inputs"][0]["name"] == "texel_x"


def test_units_text_lists_every_parameter():
    """The plain listing prints every unit's parameters, the per-channel strings among them
    (the raster's groups once stopped it with a KeyError)."""
    r = cli("sim", "units")
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
    assert "param  groups       = 0          (one per channel, comma-separated)" in r.stdout
    assert "param  flat         = 0          (0..8)" in r.stdout


@pytest.mark.parametrize("name,params", [("fenney_dot", {"normalize": True}),
                                         ("fenney_polar", {}), ("texel_decode", {})])
def test_sim_run_and_golden_run_agree(name, params, tmp_path):
    inputs = MODELS[name].vectors(np.random.default_rng(2), 300)
    np.savez(tmp_path / "in.npz", **inputs)
    extra = [a for k, v in params.items() for a in ("--param", f"{k}={v}")]
    r = cli("sim", "run", name, "--in", str(tmp_path / "in.npz"), "--out",
            str(tmp_path / "rtl.npz"), "--simulator", "amaranth", *extra)
    assert r.returncode == 0, r.stderr
    r = cli("golden", "run", name, "--in", str(tmp_path / "in.npz"), "--out",
            str(tmp_path / "gold.npz"), *extra)
    assert r.returncode == 0, r.stderr
    params = UNITS[name].spec(**params).params
    for out in ("rtl.npz", "gold.npz"):          # both within the derived bounds
        got = dict(np.load(tmp_path / out))
        for field, (err, bound) in MODELS[name].check(inputs, got, **params).items():
            assert got[field].dtype == np.int64 and len(got[field]) == len(err)
            assert np.all(err <= bound + 1e-9), (out, field)
    if MODELS[name].exact:
        rtl, gold = np.load(tmp_path / "rtl.npz"), np.load(tmp_path / "gold.npz")
        assert all(np.array_equal(rtl[k], gold[k]) for k in gold.files)


@pytest.mark.parametrize("arrays,message", [
    ({"texel_x": [1, 2]}, "field 'texel_z' is missing"),
    ({"texel_x": [1, 256], "texel_z": [0, 0]}, "field 'texel_x' (u8, range 0..255) has 256 at row 1"),
    ({"texel_x": [1.0, np.nan], "texel_z": [0, 0]}, "field 'texel_x' has a non-finite value"),
    ({"texel_x": [-1], "texel_z": [0]}, "has -1 at row 0"),
])
def test_bad_input_is_a_clear_error(arrays, message, tmp_path):
    np.savez(tmp_path / "in.npz", **{k: np.array(v) for k, v in arrays.items()})
    for tool in ("sim", "golden"):
        r = cli(tool, "run", "texel_decode", "--in", str(tmp_path / "in.npz"), "--out",
                str(tmp_path / "out.npz"))
        assert r.returncode == 2
        assert message in r.stderr and "Traceback" not in r.stderr
        assert not (tmp_path / "out.npz").exists()


def test_bad_params_and_files(tmp_path):
    r = cli("sim", "run", "fenney_dot", "--in", str(tmp_path / "none.npz"), "--out", "x.npz")
    assert r.returncode == 2 and "no such file" in r.stderr
    (tmp_path / "junk.npz").write_text("not a zip")
    r = cli("golden", "run", "fenney_dot", "--in", str(tmp_path / "junk.npz"), "--out", "x.npz")
    assert r.returncode == 2 and "not an npz file" in r.stderr
    np.savez(tmp_path / "in.npz", s=[0])
    r = cli("sim", "run", "fenney_polar", "--in", str(tmp_path / "in.npz"), "--out", "x.npz",
            "--param", "trig_bits=40")
    assert r.returncode == 2 and "trig_bits must be in 4..16, not 40" in r.stderr


def test_extra_fields_are_warned_about(tmp_path):
    np.savez(tmp_path / "in.npz", x=[0, 1023], c=[0, 255], colour=[1, 2])
    r = cli("golden", "run", "fenney_power", "--in", str(tmp_path / "in.npz"), "--out",
            str(tmp_path / "out.npz"))
    assert r.returncode == 0 and "ignoring field(s) colour" in r.stderr
    assert np.load(tmp_path / "out.npz")["p"].tolist() == [0, 1022]


def _texels(path, n=4):
    np.savez(path, texel_x=np.arange(n) % 256, texel_z=np.arange(n) % 256)


def _fails(r, *needles):
    """Exit code 2, one line on stderr naming the problem, no traceback."""
    assert r.returncode == 2, (r.returncode, r.stderr)
    lines = [line for line in r.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and lines[0].startswith("error: "), r.stderr
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])


def _run(tool, path, out, *extra):
    return cli(tool, "run", "texel_decode", "--in", str(path), "--out", str(out), *extra)


@pytest.mark.parametrize("tool", ["sim", "golden"])
def test_bad_files_are_named(tool, tmp_path):
    _texels(tmp_path / "good.npz", 1000)
    data = (tmp_path / "good.npz").read_bytes()
    (tmp_path / "cut.npz").write_bytes(data[: len(data) // 2])
    _fails(_run(tool, tmp_path / "cut.npz", tmp_path / "o.npz"), "cut.npz", "truncated")
    np.save(tmp_path / "one.npy", np.arange(4))
    _fails(_run(tool, tmp_path / "one.npy", tmp_path / "o.npz"), "one.npy", "single .npy")
    (tmp_path / "text.npz").write_text("texel_x,texel_z\n1,2\n")
    _fails(_run(tool, tmp_path / "text.npz", tmp_path / "o.npz"), "text.npz", "not an npz")
    _fails(_run(tool, tmp_path, tmp_path / "o.npz"), "is a directory")
    np.savez(tmp_path / "huge.npz", texel_x=np.array([1e30]), texel_z=np.array([0]))
    _fails(_run(tool, tmp_path / "huge.npz", tmp_path / "o.npz"), "huge.npz", "'texel_x'",
           "has 1e+30 at row 0")
    assert not (tmp_path / "o.npz").exists()


@pytest.mark.parametrize("tool", ["sim", "golden"])
def test_output_path_is_checked_first_and_kept(tool, tmp_path):
    _texels(tmp_path / "in.npz")
    r = _run(tool, tmp_path / "in.npz", tmp_path / "nowhere" / "out.npz")
    _fails(r, "nowhere", "does not exist")
    assert r.stdout == ""                              # failed before any simulation
    r = _run(tool, tmp_path / "in.npz", tmp_path / "noext")
    assert r.returncode == 0 and "noext" in r.stdout, r.stderr
    assert (tmp_path / "noext").exists() and not (tmp_path / "noext.npz").exists()
    assert set(np.load(tmp_path / "noext")) == {"x", "y", "z", "invalid"}


@pytest.mark.parametrize("tool", ["sim", "golden"])
def test_zero_rows_give_zero_rows_with_a_note(tool, tmp_path):
    np.savez(tmp_path / "in.npz", texel_x=np.zeros(0, int), texel_z=np.zeros(0, int))
    r = _run(tool, tmp_path / "in.npz", tmp_path / "out.npz")
    assert r.returncode == 0 and "0 rows" in r.stderr, r.stderr
    assert all(len(v) == 0 for v in np.load(tmp_path / "out.npz").values())


def test_ctrl_c_is_one_line_and_exit_130(tmp_path):
    """SIGINT once the simulation is under way (its progress bar is up): exit 130, one line.
    The child gets SIGINT's default disposition, as under a terminal: a shell without job
    control (CI's, a background job) starts its children with SIGINT ignored."""
    _texels(tmp_path / "in.npz", 2_000_000)
    proc = subprocess.Popen([sys.executable, "-m", "sim", "run", "texel_decode", "--in",
                             str(tmp_path / "in.npz"), "--out", str(tmp_path / "out.npz")],
                            cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    seen = b""
    while b"texel_decode on amaranth" not in seen:
        chunk = os.read(proc.stderr.fileno(), 4096)
        assert chunk, f"exited early: {seen!r}"
        seen += chunk
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 130, (proc.returncode, err)
    text = (seen + err).decode()
    assert "interrupted" in text and "Traceback" not in text
    assert not (tmp_path / "out.npz").exists()


def test_raster_runs_say_triangles_culled_fragments(tmp_path):
    inputs = MODELS["raster"].vectors(np.random.default_rng(0), 16, screen_bits=5)
    np.savez(tmp_path / "in.npz", **inputs)
    want = f"16 triangles ({raster.culled(inputs)} culled) -> "
    for tool, extra in (("sim", ["--simulator", "amaranth"]), ("golden", [])):
        r = cli(tool, "run", "raster", "--in", str(tmp_path / "in.npz"), "--out",
                str(tmp_path / f"{tool}.npz"), "--param", "screen_bits=5", *extra)
        assert r.returncode == 0, r.stderr
        frags = len(np.load(tmp_path / f"{tool}.npz")["tri"])
        assert f"{want}{frags:,} fragments" in r.stdout, r.stdout


def test_check_judges_a_users_outputs(tmp_path):
    """``sim check UNIT --in --out``: PASS within the derived bounds, FAIL (exit 1) beyond."""
    inputs = MODELS["fenney_polar"].vectors(np.random.default_rng(3), 400)
    np.savez(tmp_path / "in.npz", **inputs)
    r = cli("golden", "run", "fenney_polar", "--in", str(tmp_path / "in.npz"), "--out",
            str(tmp_path / "gold.npz"))
    assert r.returncode == 0, r.stderr
    r = cli("sim", "check", "fenney_polar", "--in", str(tmp_path / "in.npz"), "--out",
            str(tmp_path / "gold.npz"))
    assert r.returncode == 0 and r.stdout.startswith("PASS  fenney_polar"), r.stdout + r.stderr
    assert "of its bound" in r.stdout
    gold = dict(np.load(tmp_path / "gold.npz"))
    gold["intensity"][7] = (gold["intensity"][7] + 3) % 256          # 3 levels off: > bound
    np.savez(tmp_path / "bad.npz", **gold)
    r = cli("sim", "check", "fenney_polar", "--in", str(tmp_path / "in.npz"), "--out",
            str(tmp_path / "bad.npz"))
    assert r.returncode == 1 and r.stdout.startswith("FAIL  fenney_polar"), r.stdout
    assert "1 rows over their bound" in r.stdout
    np.savez(tmp_path / "short.npz", **{k: v[:10] for k, v in gold.items()})
    _fails(cli("sim", "check", "fenney_polar", "--in", str(tmp_path / "in.npz"), "--out",
               str(tmp_path / "short.npz")), "10 rows")


def test_params_apply_where_a_unit_has_them():
    from sim.__main__ import params_for, UsageError
    got = params_for(list(UNITS), ["channels=1"], None)
    assert got["raster"] == {"channels": 1} and got["texel_decode"] == {}
    got = params_for(list(UNITS), ["trig_bits=12"], None)
    assert {n for n, p in got.items() if p} == {"fenney_polar", "illum", "rotation",
                                                "bump_polar"}
    with pytest.raises(UsageError, match="no unit has a parameter 'colour'"):
        params_for(list(UNITS), ["colour=1"], None)


def test_check_streams_n_rows_and_writes_waves_only_on_request():
    """``make sim``'s command: exactly n rows, a verdict line, a waveform only with --waves,
    and that waveform in one place (moved from the simulator's directory, not copied)."""
    from sim.simulators import available
    from sim.verilog import BUILD
    r = cli("sim", "check", "fenney_power", "--simulator", "amaranth", "--vectors", "20")
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("PASS  fenney_power") and "20 rows" in r.stdout
    assert "bit-exact: all 20 rows" in r.stdout and "waves:" not in r.stdout
    reason = available("icarus")
    if reason:
        pytest.skip(f"the waveform half needs Icarus: {reason}")
    wave = BUILD / "sim" / "icarus" / "fenney_power.fst"
    wave.unlink(missing_ok=True)
    r = cli("sim", "check", "fenney_power", "--simulator", "icarus", "--vectors", "20",
            "--waves")
    assert r.returncode == 0 and f"waves: {wave}" in r.stdout, r.stdout + r.stderr
    assert wave.stat().st_size > 0
    assert not list((BUILD / "cocotb" / "icarus").rglob("*.fst"))


@pytest.mark.xdist_group("verilator-texel_decode")
def test_verilator_models_are_built_once(tmp_path):
    """A second ``sim run`` on Verilator finds the model built by the first (on disk, keyed by
    the Verilog's hash), and says nothing about building."""
    from sim.simulators import available
    reason = available("verilator")
    if reason:
        pytest.skip(reason)
    _texels(tmp_path / "in.npz", 50)
    for k in range(2):
        r = cli("sim", "run", "texel_decode", "--in", str(tmp_path / "in.npz"), "--out",
                str(tmp_path / "out.npz"), "--simulator", "verilator")
        assert r.returncode == 0, r.stderr
    assert "building" not in r.stderr, r.stderr
    gold = MODELS["texel_decode"].run(dict(np.load(tmp_path / "in.npz")))
    assert all(np.array_equal(np.load(tmp_path / "out.npz")[k], gold[k]) for k in gold)


@pytest.mark.xdist_group("verilator-texel_decode")
def test_batch_trace_window(tmp_path):
    """``sim run --simulator verilator --trace F --trace-window A:B``: a VCD of exactly those
    cycles (two time steps a cycle), to open a failure in a viewer."""
    from sim.simulators import available
    reason = available("verilator")
    if reason:
        pytest.skip(reason)
    _texels(tmp_path / "in.npz", 200)
    r = cli("sim", "run", "texel_decode", "--in", str(tmp_path / "in.npz"), "--out",
            str(tmp_path / "out.npz"), "--simulator", "verilator", "--trace",
            str(tmp_path / "w.vcd"), "--trace-window", "10:50")
    assert r.returncode == 0, r.stderr
    lines = (tmp_path / "w.vcd").read_text().splitlines()
    assert sum(line.startswith("#") for line in lines) == 2 * 41
    assert any("i_texel_x" in line for line in lines)
    _fails(cli("sim", "run", "texel_decode", "--in", str(tmp_path / "in.npz"), "--out",
               str(tmp_path / "out.npz"), "--trace-window", "10:50"), "needs --trace")


@pytest.mark.parametrize("arg,message", [
    ("foo=1", "--raster: 'foo=1' is not KNOB=VALUE with a knob of setup_mults, row_mults, setup_ii"),
    ("setup_ii=fast", "--raster: setup_ii must be a whole number, not 'fast'"),
    ("setup_narrow=9", "setup_narrow must be in 0..6"),
    ("setup_ii=8", "setup_ii=8 is too short: the setup's 54 products"),
    ("row_serial=2,row_mults=2", "row_mults=2 and row_serial=2: the row engine is one")])
def test_render_raster_knobs_are_checked(arg, message, tmp_path):
    """``sim render --raster``: a wrong knob or setting is one line naming it, exit 2."""
    r = cli("sim", "render", "scenes/default.toml", "--out", str(tmp_path / "o"),
            "--simulator", "amaranth", "--raster", arg)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert message in r.stderr, r.stderr
    assert "UnusedElaboratable" not in r.stderr, r.stderr


@pytest.mark.parametrize("args,message", [
    (["--units", "scene_bump_xz", "--raster", "row_serial=2,row_mults=2"],
     "row_mults=2 and row_serial=2: the row engine is one"),
    (["--units", "colour", "--raster", "row_serial=2"],
     "the knobs are the raster's and the scene pipelines'"),
    (["--units", "raster", "--raster", "row_narrow=30"], "row_narrow must be in 0..24"),
    (["--units", "scene", "--raster", "row_serial=x"], "row_serial must be a whole number")])
def test_fpga_raster_knobs_are_checked(args, message):
    """``python -m flows.fpga --raster`` (``make fpga RASTER=``): checked before any synthesis,
    one line naming the knob, exit 2."""
    r = cli("flows.fpga", *args)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert message in r.stderr, r.stderr
