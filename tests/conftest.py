"""Shared test helpers: the simulators, streaming through any of them, checking against golden.

Tests that use one (simulator, unit) pair are grouped onto one xdist worker, so each Verilog
model is built once per run.
"""
import os

import numpy as np
import pytest

# Batch models built for the tests are optimised for build time (sim/batch: SHADE_BATCH_OPT);
# set before sim.batch is imported, and inherited by the CLI's subprocesses.
os.environ.setdefault("SHADE_BATCH_OPT", "-O0")
from hypothesis import HealthCheck, settings

# Property tests check values, not speed: no per-example deadline, and no health check that
# times example generation, on a loaded CI machine. The same examples on every run
# (derandomize), so that make test gives one answer for one commit; make fuzz explores (a
# fresh clone's random draw found phi' = 2 pi once: tests/test_angular_models.py keeps it).
settings.register_profile("shading", deadline=None, derandomize=True,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("shading")

# Load balance on make test's two workers: the tests that take longest on a fresh clone (each
# builds a simulator model of its own, 30-70 s; README, make test) start first, so that no
# worker is left running one of them while the other idles at the end. Only the order
# changes: no outcome depends on it.
FIRST = ("test_angular_scene_rtl_within_bound", "test_a_small_scene_through_the_board_core",
         "test_xz_scene_rtl_within_bound", "test_simulators_agree", "test_generated_scenes",
         "test_phong_fenney_two_lights", "test_an_effect_with_its_own",
         "test_a_new_effect_is_one_file", "test_onchip_texture_is_the_external_one",
         "test_hard_cases", "test_edge_constant_groups", "test_a_raster_part_proven",
         "test_the_setup_proven")


def pytest_collection_modifyitems(items):
    rank = lambda item: next((k for k, name in enumerate(FIRST)
                              if item.name.startswith(name)), len(FIRST))
    items.sort(key=rank)                      # stable: the rest keep their order


from golden import MODELS
from hdl.units import make_unit
from sim.run import simulate
from sim.simulators import SIMS, available


def _sim_param(name):
    reason = available(name)
    marks = [pytest.mark.skip(reason=f"{name} tests skipped: {reason}")] if reason else []
    return pytest.param(name, marks=marks, id=name)


SIMULATORS = [_sim_param(s) for s in SIMS]


def params_of(name, params=None):
    return make_unit(name, spec=True, **(params or {})).params


def stream(name, inputs, simulator, params=None, **traffic):
    """Stream ``inputs`` through the RTL; returns ``(outputs, info)``."""
    return simulate(name, params_of(name, params), inputs, simulator, **traffic)


def assert_golden(name, inputs, outputs, params=None):
    """Every output row within its derived bound of the golden model (0 for bit-exact)."""
    params = params_of(name, params)
    n = len(next(iter(inputs.values())))
    for field, (err, bound) in MODELS[name].check(inputs, outputs, **params).items():
        assert len(outputs[field]) == n, f"{name}.{field}: {len(outputs[field])} rows of {n}"
        over = np.flatnonzero(err > np.broadcast_to(bound, err.shape) + 1e-9)
        if len(over):
            k = int(over[0])
            row = {f: int(v[k]) for f, v in inputs.items()}
            pytest.fail(f"{name}.{field}: {len(over)} rows beyond the bound; first, row {k}: "
                        f"inputs {row}, RTL {int(outputs[field][k])}, error {float(err[k]):.4f}"
                        f" > bound {float(np.broadcast_to(bound, err.shape)[k]):.4f}")
    return {f: (float(np.max(e)), float(np.max(b)))
            for f, (e, b) in MODELS[name].check(inputs, outputs, **params).items()}


# cocotb-verilator runs the very bench icarus runs, on Verilator: test_simulators_agree holds
# it to the other simulators row for row on every unit; the other RTL tests run on these.
DEFAULT_SIMS = ("amaranth", "icarus", "verilator")


def per_simulator(cases, only=DEFAULT_SIMS):
    """``pytest.param(simulator, *case)`` for every simulator in ``only`` and case, grouped
    by (simulator, unit) onto one xdist worker: ``case[0]`` is the unit's name."""
    for sim in SIMULATORS:
        name = sim.values[0]
        if name not in only:
            continue
        for case in cases:
            case = case if isinstance(case, tuple) else (case,)
            extra = "".join(f"-{k}={v}" for c in case[1:] if isinstance(c, dict)
                            for k, v in c.items())
            yield pytest.param(name, *case, id=f"{name}-{case[0]}{extra}", marks=[
                *sim.marks, pytest.mark.xdist_group(f"{name}-{case[0]}")])


def longest_empty_run(triangles, tri):
    """The longest run of triangles, one after another, with no fragment (``tri``: each
    fragment's triangle, of ``triangles``)."""
    covered = np.zeros(triangles, bool)
    covered[np.asarray(tri)] = True
    return int((np.diff(np.flatnonzero(np.r_[True, covered, True])) - 1).max())


def long_where(params, *ids):
    """``params`` with those whose id is in ``ids`` marked ``long`` (make soak runs them)."""
    return [pytest.param(*p.values, id=p.id, marks=[*p.marks, pytest.mark.long])
            if p.id in ids else p for p in params]
