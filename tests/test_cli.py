"""The command-line contract: ``python -m sim`` and ``python -m golden`` as a user runs them."""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from golden import MODELS
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
    assert units["fenney_polar"]["outputs"] == [
        {"name": "intensity", "width": 8, "signed": False, "frac_bits": 0, "unit": "1/255"},
        {"name": "shade", "width": 10, "signed": False, "frac_bits": 10, "unit": "1"}]
    assert units["texel_decode"]["inputs"][0]["name"] == "texel_x"


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
    assert r.returncode == 2 and "not a readable npz" in r.stderr
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
