"""The per-fragment shading units beyond test_units_rtl.py's backpressure and throughput
tests: the power table's full sweep, its error against the exact power, and the other
configurations.

Bounds: power_table and colour are bit-exact (their models define the table's bins and the
integer sum); phong within golden.shade.phong_check's derived bound.
"""
import numpy as np
import pytest

from golden import MODELS
from golden.shade import power_error
from hdl.shade_unit.power import power_lut

from .conftest import assert_golden, per_simulator, stream


@pytest.mark.parametrize("simulator,name,params", [
    *per_simulator([("power_table", {"shininess": 128.0})], only=("verilator",)),
    *per_simulator([("power_table", {"shininess": 1.0})], only=("amaranth",))])
def test_power_table_every_input(simulator, name, params):
    """All 65,536 values of s, bit-exact."""
    inputs = MODELS[name].vectors(np.random.default_rng(0), None, **params)
    assert len(inputs["s"]) == 65536
    out, _ = stream(name, inputs, simulator, params)
    assert_golden(name, inputs, out, params)


@pytest.mark.parametrize("n", [1.0, 8.0, 32.0, 128.0, 1024.0])
def test_power_table_error_is_the_tables(n):
    """Over every s in [0, 1], |table - s^n| stays within the table's own error as
    hdl.lut.build_lut derives it (rounding plus the change across a bin); for n up to 128
    that is under 5 LSB of 1/1024, half a level of 8-bit colour at ks = 1."""
    err = power_error(n, 6)
    assert err <= power_lut(n, 6).max_error + 1e-9
    if n <= 128:
        assert err < 5


@pytest.mark.parametrize("simulator,name,params", list(per_simulator(
    [("phong", {"lights": 2, "specular": False}), ("colour", {"lights": 2, "specular": False}),
     ("phong", {"rsqrt_iters": 1})], only=("amaranth",))))
def test_other_configurations(simulator, name, params):
    inputs = MODELS[name].vectors(np.random.default_rng(2), 4000, **params)
    out, _ = stream(name, inputs, simulator, params, p_valid=0.7, p_ready=0.6, seed=5)
    assert_golden(name, inputs, out, params)
