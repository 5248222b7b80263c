"""The Fenney units: full sweeps and named hard cases on the RTL (every unit's backpressure and
throughput tests are in test_units_rtl.py).

Bounds: texel_decode, fenney_power, the shade of fenney_polar and fenney_xz's p are bit-exact
(bound 0; fenney_xz: p must be P(X) for an X within fenney_dot's bound). fenney_dot and the
intensity of fenney_polar are held to the per-row bounds derived in golden/fenney.py from
their fraction bits and table errors.
"""
import numpy as np
import pytest

from golden import MODELS
from hdl.units import UNITS

from .conftest import assert_golden, long_where, per_simulator, stream

# the full sweeps: texel_decode's 65,536 texels, fenney_power's 262,144 inputs and
# fenney_polar's S x (R - Q) on Verilator, the fastest; texel_decode's on the event-driven
# simulators too in make soak (30 s each)
FULL_SWEEPS = [*long_where(per_simulator(["texel_decode"]), "amaranth-texel_decode",
                           "icarus-texel_decode"),
               *per_simulator(["fenney_power", "fenney_polar"], only=("verilator",))]


@pytest.mark.parametrize("simulator,name", FULL_SWEEPS)
def test_full_sweep(simulator, name):
    inputs = MODELS[name].vectors(np.random.default_rng(11), None)
    out, _ = stream(name, inputs, simulator)
    assert_golden(name, inputs, out)


@pytest.mark.parametrize("simulator,name", list(per_simulator(["fenney_power"],
                                                            only=("amaranth", "icarus"))))
def test_power_random_subset(simulator, name):
    """The power unit's random subset on the paths that do not sweep all 262,144 inputs
    (Verilator sweeps them; here the hard cases come first, then random rows)."""
    inputs = MODELS["fenney_power"].vectors(np.random.default_rng(5), 10_000)
    out, _ = stream("fenney_power", inputs, simulator)
    assert_golden("fenney_power", inputs, out)


def test_xz_latency_is_the_sum_of_its_parts():
    for normalize in (False, True):
        xz = UNITS["fenney_xz"].spec(normalize=normalize)
        parts = [UNITS[n].spec(**p) for n, p in (("texel_decode", {}),
                 ("fenney_dot", {"normalize": normalize}), ("fenney_power", {}))]
        assert xz.latency == sum(p.latency for p in parts) == (21 if normalize else 19)


# The hard cases of design/math-notes.md §5, with the values the patent's formulas give.
HARD = {
    "texel_decode": [  # (inputs, expected outputs)
        ({"texel_x": 255, "texel_z": 127}, {"x": 254, "y": 1, "z": 0, "invalid": 1}),
        ({"texel_x": 255, "texel_z": 255}, {"x": 254, "y": 0, "z": 254, "invalid": 1}),
        ({"texel_x": 0, "texel_z": 0}, {"x": -254, "y": 0, "z": -254, "invalid": 1}),
        ({"texel_x": 191, "texel_z": 190}, {"x": 128, "y": 1, "z": 126, "invalid": 0}),
        ({"texel_x": 191, "texel_z": 191}, {"x": 128, "y": 0, "z": 128, "invalid": 1}),
        ({"texel_x": 127, "texel_z": 127}, {"x": 0, "y": 255, "z": 0, "invalid": 0}),
    ],
    "fenney_power": [
        ({"x": 0, "c": 0}, {"p": 0}), ({"x": 1023, "c": 0}, {"p": 1023}),
        ({"x": 1023, "c": 255}, {"p": 1022}), ({"x": 0, "c": 255}, {"p": 0}),
        ({"x": 500, "c": 0}, {"p": 500}),
        # k = 263: L = 1023 - (263 * 23 >> 3) = 267, Q = 267**2 >> 10 = 69,
        # P = 267 + (255 * (69 - 267) >> 8) = 267 - 198
        ({"x": 1000, "c": 255}, {"p": 69}),
    ],
    "fenney_dot": [   # light below the horizon saturates at 0; straight up at full scale
        ({"x": 0, "y": 255, "z": 0, "lx": 0, "ly": -127, "lz": 0, "h": 255}, {"x": 0}),
        ({"x": 0, "y": 255, "z": 0, "lx": 0, "ly": 127, "lz": 0, "h": 255}, {"x": 1023}),
        ({"x": 0, "y": 255, "z": 0, "lx": 0, "ly": -127, "lz": 0, "h": 0}, {"x": 1023}),
        ({"x": 0, "y": 255, "z": 0, "lx": 0, "ly": 0, "lz": 0, "h": 255}, {"x": 0}),
    ],
    "fenney_polar": [  # sums past 255 and below 0 clamp; R - Q wraps
        ({"s": 0, "r": 0, "k1": 255, "k2": 255, "k3": 255, "q": 0, "c": 0},
         {"intensity": 255, "shade": 1023}),
        ({"s": 0, "r": 128, "k1": 0, "k2": 0, "k3": 255, "q": 0, "c": 0},
         {"intensity": 0, "shade": 0}),
        ({"s": 0, "r": 1, "k1": 0, "k2": 0, "k3": 255, "q": 255, "c": 0},  # R - Q = 2 steps
         {"intensity": 255, "shade": 1023}),
        ({"s": 0, "r": 64, "k1": 100, "k2": 0, "k3": 255, "q": 0, "c": 0},  # cos 90 = 0
         {"intensity": 100, "shade": 401}),
    ],
}


@pytest.mark.parametrize("simulator,name", list(per_simulator(list(HARD))))
def test_hard_cases(simulator, name):
    rows, want = zip(*HARD[name])
    inputs = {k: np.array([r[k] for r in rows]) for k in rows[0]}
    out, _ = stream(name, inputs, simulator)
    for k in want[0]:
        assert out[k].tolist() == [w[k] for w in want], k
    assert_golden(name, inputs, out)
