"""Every registered unit's RTL against its golden model, on every simulator.

Bounds are each unit's, derived in golden/: bit-exact units compare with bound 0, the others
within per-row bounds from their fraction bits and table errors (see each model's check).
"""
import numpy as np
import pytest

from golden import MODELS, TYPICAL_SIZE, random_triangles
from hdl.units import UNITS

from .conftest import assert_golden, long_where, params_of, per_simulator, stream

CONFIGS = [("texel_decode", {}), ("fenney_power", {}), ("fenney_dot", {}),
           ("fenney_dot", {"normalize": True}), ("fenney_xz", {}),
           ("fenney_xz", {"normalize": True}), ("fenney_polar", {}),
           ("illum", {}),
           ("illum", {"angle_bits": 8, "trig_bits": 10, "table_bits": 8, "shininess": 64}),
           ("rotation", {}),
           ("rotation", {"angle_bits": 10, "trig_bits": 12, "asin_bits": 10, "atan_bits": 6,
                         "prop_bits": 10}),
           ("rotation", {"method": "exact"}),
           ("bump_polar", {}),
           ("peercy", {}),
           ("phong", {}),
           ("power_table", {"shininess": 128.0}),
           ("colour", {})]


MANY = {"raster"}    # many outputs per input: tests/test_raster_rtl.py


def test_every_unit_is_covered():
    assert {name for name, _ in CONFIGS} | MANY == set(UNITS)


# On Icarus (cocotb), the backpressure of the units with the most hard cases (rotation's
# 1,225 in each of its forms, and texel_decode's codes) in make test; every unit in make soak.
# test_simulators_agree holds every unit's Icarus rows to Amaranth's, bit for bit.
ICARUS_SOAK = [p.id for p in per_simulator(CONFIGS, only=("icarus",))
               if p.values[1] not in ("texel_decode", "rotation")]
# On Verilator, each unit's variants (a model each to build, 10-30 s) in make soak; Amaranth
# runs them in make test. rotation's exact form stays: tests/test_rotation_rtl.py builds it.
VARIANTS_SOAK = [p.id for p in per_simulator(CONFIGS, only=("verilator",))
                 if p.values[2] and p.values[2] != {"method": "exact"}
                 and sum(n == p.values[1] for n, _ in CONFIGS) > 1]
# bump_polar on Verilator (a model of its own, 47 s) in make soak: in make test Amaranth runs
# its backpressure and one row a clock, test_simulators_agree holds the simulators to each
# other, and the angular scene runs it on Verilator under random stalls on both sides
# (tests/test_bump_scenes.py)
VARIANTS_SOAK.append("verilator-bump_polar")


@pytest.mark.parametrize("simulator,name,params", long_where(per_simulator(CONFIGS),
                                                            *ICARUS_SOAK, *VARIANTS_SOAK))
def test_backpressure(simulator, name, params):
    """Hard cases then random rows, with random valid gaps (30 %) and ready stalls (40 %):
    every output within its bound, none lost, repeated or reordered (rows compare 1:1). The
    batch path's harness draws its own stalls and also checks that a stalled output holds its
    payload. 12,000 rows on the batch path; 1,500 on the event-driven simulators, whose rows
    cost a hundred times more (every hard case is among them: the hard cases come first, at
    most 1,225, rotation's and bump_polar's)."""
    n = 12_000 if simulator == "verilator" else 1_500
    inputs = MODELS[name].vectors(np.random.default_rng(7), n, **params_of(name, params))
    out, _ = stream(name, inputs, simulator, params, p_valid=0.7, p_ready=0.6, seed=3)
    assert_golden(name, inputs, out, params)


@pytest.mark.parametrize("simulator,name,params", long_where(per_simulator(
    CONFIGS, only=("amaranth", "verilator")), *VARIANTS_SOAK))
def test_one_per_clock(simulator, name, params):
    """With valid and ready held high, n rows take n + latency cycles, and the first output
    appears exactly ``latency`` cycles after the first input. (On Icarus:
    test_simulators_agree, the same cycle count as Amaranth's, bit for bit.)"""
    rows = 2000 if simulator == "verilator" else 1300      # past the hard cases (1,225)
    inputs = MODELS[name].vectors(np.random.default_rng(1), rows, **params_of(name, params))
    n = len(next(iter(inputs.values())))
    out, info = stream(name, inputs, simulator, params)
    latency = UNITS[name].spec(**params).latency
    assert info["latency"] == latency
    assert info["cycles"] == n + latency
    assert_golden(name, inputs, out, params)


def test_bump_polar_latency_is_the_sum_of_its_parts():
    bump = UNITS["bump_polar"].spec()
    assert bump.latency == 2 * UNITS["rotation"].spec().latency + UNITS["illum"].spec().latency


# bump_polar's three-way agreement runs in make soak: its Verilator model is the largest unit
# build here (about 45 s); in make test bump_polar runs on Verilator inside the angular scene
# (under stalls, against the model) and on Amaranth in its unit rows
AGREE = [pytest.param(name, {"screen_bits": 6} if name == "raster" else {}, id=name,
                      marks=[pytest.mark.long] if name == "bump_polar" else [])
         for name in UNITS]
# cocotb-verilator runs the very cocotb bench that Icarus runs, on the very Verilator of the
# batch path: what it adds is their join, which the unit with the smallest model shows in
# make test (a model each to build: 10-50 s); make soak holds every other unit to it as well
COCOTB_VERILATOR = ("texel_decode",)
SLOW_BUILDS = {("cocotb-verilator", n) for n in UNITS if n not in COCOTB_VERILATOR}


@pytest.mark.long
@pytest.mark.parametrize("name,params", [a for a in AGREE if a[0] not in COCOTB_VERILATOR],
                         ids=[a[0] for a in AGREE if a[0] not in COCOTB_VERILATOR])
def test_slow_builds_agree_on_cocotb_verilator(name, params):
    """test_simulators_agree's rows on cocotb-verilator for the units it leaves out."""
    from sim.simulators import available
    if available("cocotb-verilator"):
        pytest.skip(f"cocotb-verilator: {available('cocotb-verilator')}")
    rows = _agree_inputs(name, params)
    ref_out, ref_info = stream(name, rows, "amaranth", params)
    out, info = stream(name, rows, "cocotb-verilator", params)
    for k in ref_out:
        assert np.array_equal(out[k], ref_out[k]), k
    assert (info["cycles"], info["latency"]) == (ref_info["cycles"], ref_info["latency"])


def _agree_inputs(name, params):
    rng = np.random.default_rng(4)
    if name == "raster":                       # 30 typical triangles: about 2,000 fragments
        return random_triangles(rng, 30, **params_of(name, params), size=TYPICAL_SIZE)
    return MODELS[name].vectors(rng, 300, **params_of(name, params))


@pytest.mark.parametrize("name,params", AGREE)
def test_simulators_agree(name, params):
    """The same rows through every simulator here give the same output rows, bit for bit,
    with the same cycle counts (ready and valid held high)."""
    from sim.simulators import SIMS, available
    inputs = _agree_inputs(name, params)
    sims = [s for s in SIMS if available(s) is None and (s, name) not in SLOW_BUILDS]
    assert "amaranth" in sims and "verilator" in sims
    runs = {s: stream(name, inputs, s, params) for s in sims}
    ref_out, ref_info = runs["amaranth"]
    for sim, (out, info) in runs.items():
        assert set(out) == set(ref_out), sim
        for k in ref_out:
            assert np.array_equal(out[k], ref_out[k]), (sim, k)
        assert (info["cycles"], info["latency"]) == (ref_info["cycles"], ref_info["latency"]), sim


@pytest.mark.xdist_group("verilator-fenney_power")
def test_short_soak_on_the_batch_path():
    """make soak's short version: a million rows through fenney_power on the batch path with
    valid gaps and ready stalls, bit-exact against the patent's formula; the harness itself
    fails if a stalled output changes. (make soak: 10 million rows per unit.)"""
    from flows.soak import soak_rows
    ok, text = soak_rows("fenney_power", 1_000_000)
    assert ok, text
    assert text.startswith("1,000,000 rows in, 1,000,000 out")
