"""The Fenney units' RTL against their golden models, on every simulator.

Bounds: texel_decode, fenney_power, the shade of fenney_polar and fenney_xz's p are bit-exact
(bound 0; fenney_xz: p must be P(X) for an X within fenney_dot's bound). fenney_dot and the
intensity of fenney_polar are held to the per-row bounds derived in golden/fenney.py from
their fraction bits and table errors.
"""
import numpy as np
import pytest

from golden import MODELS
from hdl.units import UNITS

from .conftest import SIMULATORS, assert_golden, params_of, stream

CONFIGS = [("texel_decode", {}), ("fenney_power", {}), ("fenney_dot", {}),
           ("fenney_dot", {"normalize": True}), ("fenney_xz", {}),
           ("fenney_xz", {"normalize": True}), ("fenney_polar", {})]
IDS = [n + "".join(f"-{k}={v}" for k, v in p.items()) for n, p in CONFIGS]


def grouped(simulator, name):
    return pytest.mark.xdist_group(f"{simulator}-{name}")


def cases():
    for sim in SIMULATORS:
        for (name, params), ident in zip(CONFIGS, IDS):
            yield pytest.param(sim.values[0], name, params, marks=[*sim.marks,
                               grouped(sim.values[0], name)], id=f"{sim.values[0]}-{ident}")


@pytest.mark.parametrize("simulator,name,params", list(cases()))
def test_backpressure(simulator, name, params):
    """Hard cases then random rows, with random valid gaps (30 %) and ready stalls (40 %):
    every output within its bound, none lost, repeated or reordered (rows compare 1:1)."""
    inputs = MODELS[name].vectors(np.random.default_rng(7), 12_000, **params_of(name, params))
    out, _ = stream(name, inputs, simulator, params, p_valid=0.7, p_ready=0.6, seed=3)
    assert_golden(name, inputs, out, params)


@pytest.mark.parametrize("simulator,name,params", list(cases()))
def test_one_per_clock(simulator, name, params):
    """With valid and ready held high, n rows take n + latency cycles, and the first output
    appears exactly ``latency`` cycles after the first input."""
    inputs = MODELS[name].vectors(np.random.default_rng(1), 500, **params_of(name, params))
    n = len(next(iter(inputs.values())))
    out, info = stream(name, inputs, simulator, params)
    latency = UNITS[name].spec(**params).latency
    assert info["latency"] == latency
    assert info["cycles"] == n + latency
    assert_golden(name, inputs, out, params)


def full_sweeps():
    # (unit, simulators that run its full sweep)
    plan = {"texel_decode": ("amaranth", "icarus", "verilator"),  # all 65,536 texels
            "fenney_power": ("verilator",),                       # all 262,144 inputs
            "fenney_polar": ("verilator",)}                       # every S x (R - Q)
    for sim in SIMULATORS:
        for name, sims in plan.items():
            if sim.values[0] in sims:
                yield pytest.param(sim.values[0], name, marks=[*sim.marks,
                                   grouped(sim.values[0], name)], id=f"{sim.values[0]}-{name}")


@pytest.mark.parametrize("simulator,name", list(full_sweeps()))
def test_full_sweep(simulator, name):
    inputs = MODELS[name].vectors(np.random.default_rng(11), None)
    out, _ = stream(name, inputs, simulator)
    assert_golden(name, inputs, out)


@pytest.mark.parametrize("simulator", SIMULATORS)
def test_power_random_subset(simulator):
    """The power unit's random subset on the paths that do not sweep all 262,144 inputs."""
    inputs = MODELS["fenney_power"].vectors(np.random.default_rng(5), 40_000)
    out, _ = stream("fenney_power", inputs, simulator)
    assert_golden("fenney_power", inputs, out)


def test_xz_latency_is_the_sum_of_its_parts():
    for normalize in (False, True):
        xz = UNITS["fenney_xz"].spec(normalize=normalize)
        parts = [UNITS[n].spec(**p) for n, p in (("texel_decode", {}),
                 ("fenney_dot", {"normalize": normalize}), ("fenney_power", {}))]
        assert xz.latency == sum(p.latency for p in parts) == (10 if normalize else 9)
