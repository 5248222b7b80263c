"""The shared machinery: formats, the LUT builder, stream packing, the unit registry, the
pipeline's latency bookkeeping, constructor validation, and the Verilog export."""
import gc
import json

import numpy as np

import pytest
from hypothesis import given, strategies as st

from hdl.fixed import Field, FieldError, Fixed, check_arrays, s, u
from hdl.lut import build_lut
from hdl.units import UNITS, describe, make_unit, parse_params, ParamError
from sim.stream import Traffic, pack, unpack
from sim.verilog import export, lint


def test_check_arrays_names_the_field():
    fields = (Field("a", u(8)), Field("b", s(9)))
    ok, extra = check_arrays(fields, {"a": [0, 255], "b": [-256, 255], "c": [1, 2]})
    assert extra == ["c"] and ok["b"].tolist() == [-256, 255]
    with pytest.raises(FieldError, match="'b' is missing"):
        check_arrays(fields, {"a": [1]})
    with pytest.raises(FieldError, match=r"'a' \(u8, range 0..255\) has 256 at row 1"):
        check_arrays(fields, {"a": [0, 256], "b": [0, 0]})
    with pytest.raises(FieldError, match=r"'b' \(s9, range -256..255\) has -257 at row 0"):
        check_arrays(fields, {"a": [0], "b": [-257]})
    with pytest.raises(FieldError, match="'a' has a non-finite value"):
        check_arrays(fields, {"a": [np.nan], "b": [0]})
    with pytest.raises(FieldError, match="'a' has a non-finite value"):
        check_arrays(fields, {"a": [np.inf], "b": [0]})
    with pytest.raises(FieldError, match="holds raw integers"):
        check_arrays(fields, {"a": [1.5], "b": [0]})
    with pytest.raises(FieldError, match="'b' has 2 rows, others have 1"):
        check_arrays(fields, {"a": [1], "b": [0, 1]})
    with pytest.raises(FieldError, match="dtype"):
        check_arrays(fields, {"a": ["x"], "b": [0]})


def test_lut_builder_error_bounds():
    # exact inputs: the error is the rounding, at most half an LSB, and measured, not assumed
    lut = build_lut(lambda a: a / 3, 4, u(8, 2))
    assert lut.contents.tolist() == [round(a * 4 / 3) for a in range(16)]
    assert lut.max_error == pytest.approx(max(abs(a * 4 / 3 - round(a * 4 / 3))
                                              for a in range(16)))
    # interval inputs: entries at bin centres; error includes the change across a bin
    lut = build_lut(lambda x: x, 3, u(8, 4), domain=(0.0, 8.0))
    assert lut.contents.tolist() == [8 + 16 * a for a in range(8)]
    assert lut.max_error == pytest.approx(8.0)          # half a bin of 16 LSB
    assert lut.address_of([0.0, 7.99, 100.0]).tolist() == [0, 7, 7]
    with pytest.raises(ValueError, match="do not fit"):
        build_lut(lambda a: a * 100, 4, u(8))           # never saturated silently
    with pytest.raises(ValueError, match="non-finite"):
        build_lut(lambda a: np.where(a > 0, a, np.nan), 4, u(8))
    with pytest.raises(ValueError, match="address width"):
        build_lut(lambda a: a, 0, u(8))


@given(st.lists(st.tuples(st.integers(0, 255), st.integers(-256, 255), st.integers(0, 1)),
                min_size=1, max_size=50))
def test_pack_unpack_round_trip(rows):
    fields = [Field("a", u(8)).describe(), Field("b", s(9)).describe(),
              Field("c", u(1)).describe()]
    arrays = {k: np.array(col) for k, col in zip("abc", zip(*rows))}
    words = pack(fields, arrays)
    assert all(0 <= w < 2**18 for w in words)
    back = unpack(fields, words)
    assert all(np.array_equal(back[k], arrays[k]) for k in "abc")


def test_traffic_holds_payload_until_accepted():
    t = Traffic([10, 20, 30], p_valid=0.5, p_ready=0.5, seed=4)
    offered = []
    while t.sent < 3:
        valid, payload, _ = t.drive()
        ready = len(offered) % 3 == 0                   # the DUT accepts every third cycle
        if valid:
            offered.append((payload, ready))
        t.edge(ready, 0, 0)
    accepted = [p for p, r in offered if r]
    assert accepted == [10, 20, 30]                     # in order, none lost or repeated
    held = [p for p, r in offered if not r]
    assert set(held) <= {10, 20, 30}


def test_registry_json_contract():
    units = [describe(n) for n in UNITS]
    text = json.dumps({"units": units})
    for unit in json.loads(text)["units"]:
        assert set(unit) >= {"name", "params", "inputs", "outputs"}
        for f in unit["inputs"] + unit["outputs"]:
            assert set(f) == {"name", "width", "signed", "frac_bits", "unit"}
    for unit in units:
        assert set(unit["param_ranges"]) == set(unit["params"])
    names = {u["name"] for u in units}
    assert names == {"texel_decode", "fenney_power", "fenney_dot", "fenney_xz", "fenney_polar",
                     "illum", "rotation", "bump_polar", "peercy", "raster", "phong",
                     "power_table", "colour"}
    raster = next(u for u in units if u["name"] == "raster")      # screen and reciprocal
    assert {"screen_bits", "sub_bits", "channels", "modes", "recip", "recip_iters"} \
        <= set(raster["params"])
    assert [f["name"] for f in raster["outputs"]] == ["tri", "x", "y", "v0", "v1"]
    dot = next(u for u in units if u["name"] == "fenney_dot")
    assert dot["params"] == {"normalize": False, "rsqrt_bits": 12}
    assert [f["name"] for f in dot["inputs"]] == ["x", "y", "z", "lx", "ly", "lz", "h"]


def test_golden_models_cover_every_unit():
    from golden import MODELS
    assert set(MODELS) == set(UNITS)


# a constructor that refuses its parameters leaves an object that is never elaborated, and
# Amaranth says so when it is collected (make_unit and spec build in files that tell it not to)
@pytest.mark.filterwarnings("ignore:.*created but never used")
def test_constructor_validation():
    with pytest.raises(TypeError, match="normalize must be True or False, not 1"):
        UNITS["fenney_dot"](normalize=1)
    with pytest.raises(ValueError, match="rsqrt_bits must be in 4..16, not 20"):
        UNITS["fenney_dot"](rsqrt_bits=20)
    with pytest.raises(TypeError, match="unknown parameter"):
        UNITS["texel_decode"](width=3)
    with pytest.raises(TypeError, match="trig_bits must be an integer"):
        UNITS["fenney_polar"](trig_bits="ten")
    with pytest.raises(ParamError, match="unknown unit 'nope'"):
        make_unit("nope")
    with pytest.raises(ParamError, match="must be an integer, not 'x'"):
        parse_params("fenney_polar", ["trig_bits=x"])
    with pytest.raises(ParamError, match="expected NAME=VALUE"):
        parse_params("fenney_polar", ["trig_bits"])
    assert parse_params("fenney_dot", ["normalize=true", "rsqrt_bits=0x0e"]) == \
        {"normalize": True, "rsqrt_bits": 14}
    gc.collect()              # the refused objects, while their warning is ignored here


def test_fixed_formats():
    assert (s(9).min, s(9).max, u(10).max) == (-256, 255, 1023)
    with pytest.raises(ValueError):
        Fixed(0)


@pytest.mark.parametrize("name", list(UNITS))
def test_verilog_exports_lint_clean(name, tmp_path):
    """One port per field, named after it, and a field map beside the Verilog that lists
    every port of the top module with its width, signedness and scale."""
    path = export(name, None, tmp_path)
    text = path.read_text()
    header = text[text.index(f"module {name}("):]
    header = header[:header.index(");")]
    unit = make_unit(name, spec=True)
    ports = {"clk", "rst", "i_valid", "i_ready", "o_valid", "o_ready",
             *(f"i_{f.name}" for f in unit.inputs), *(f"o_{f.name}" for f in unit.outputs),
             *unit.status_ports}
    assert set("".join(header[header.index("(") + 1:].split()).split(",")) == ports
    fmap = json.loads(path.with_suffix(".json").read_text())
    assert {p["port"] for p in fmap["ports"]} == ports
    assert fmap["latency"] == unit.latency
    for f in unit.inputs:
        entry = next(p for p in fmap["ports"] if p["port"] == f"i_{f.name}")
        assert (entry["width"], entry["signed"], entry["frac_bits"]) == \
            (f.fmt.width, f.fmt.signed, f.fmt.frac_bits)
        width = f"[{f.fmt.width - 1}:0] " if f.fmt.width > 1 else ""
        assert f"input {width}i_{f.name};" in text
    lint(path, name)            # raises on any warning we have not accepted by name


@pytest.mark.parametrize("name", ["power_table", "illum"])
def test_ecp5_forms_with_block_rams_lint_clean(name, tmp_path):
    """A unit's ECP5 form (``sim verilog --target ecp5``): its table reads are DP16KD
    instances on their output registers (hdl/bram.py), its products MULT18X18D; both
    primitives resolve against Yosys's cell libraries and the whole lints clean."""
    path = export(name, out_dir=tmp_path, target="ecp5")
    text = path.read_text()
    assert "DP16KD" in text and '"OUTREG"' in text
    lint(path, name, target="ecp5")


def test_param_ranges_are_enforced_and_described():
    """The ranges ``sim units --json`` shows are the ones the constructors enforce (the
    rotation's asin table needs asin_bits <= trig_bits + 1, the raster's row_mults at most
    its row engine's products a row, its setup_serial a row_serial: set the other one to
    allow it)."""
    needs = {"trig_bits": {"asin_bits": 4}, "asin_bits": {"trig_bits": 16},
             "row_mults": {"channels": 12}, "setup_serial": {"row_serial": 1}}
    for name, cls in UNITS.items():
        ranges = describe(name)["param_ranges"]
        assert set(ranges) == set(cls.PARAMS)
        for key, r in ranges.items():
            other = {k: v for k, v in needs.get(key, {}).items() if k in cls.PARAMS}
            if "min" in r:
                make_unit(name, spec=True, **other, **{key: r["min"]})
                make_unit(name, spec=True, **other, **{key: r["max"]})
                with pytest.raises(ParamError, match=key):
                    make_unit(name, spec=True, **other, **{key: r["max"] + 1})
                with pytest.raises(ParamError, match=key):
                    make_unit(name, spec=True, **other, **{key: r["min"] - 1})
            elif "choices" in r:
                for choice in r["choices"]:
                    make_unit(name, spec=True, **{key: choice})
                with pytest.raises(ParamError, match=key):
                    make_unit(name, spec=True, **{key: "nonsense"})
            else:                   # a free string its unit parses (raster's groups)
                assert r == {"string": "one per channel, comma-separated"}
                make_unit(name, spec=True, **{key: cls.PARAMS[key]})
                with pytest.raises(ParamError, match=key):
                    make_unit(name, spec=True, **{key: "nonsense"})


@pytest.mark.parametrize("name", list(UNITS))
def test_vectors_n_means_n(name):
    from golden import MODELS
    for n in (0, 3, 2000):
        got = MODELS[name].vectors(np.random.default_rng(0), n)
        assert {len(v) for v in got.values()} == {n}


@pytest.mark.xdist_group("grouping-check")
def test_xdist_groups_hold(request):
    """Under ``--dist loadgroup`` each (simulator, unit) group must stay on one worker, or two
    workers build and wipe the same model at once. xdist marks a grouped test by suffixing its
    node id with ``@group``; a pytest that ignores the suffix (pytest 9 with xdist 3.8) fails
    here instead of intermittently in a simulator test."""
    if request.config.getoption("dist", "no") == "no" and \
            not getattr(request.config.option, "loadgroup", False):
        pytest.skip("not running under pytest-xdist --dist loadgroup")
    assert request.node.nodeid.endswith("@grouping-check")
