"""The raster unit (setup -> span) on every simulator: exact top-left coverage against the
independent edge-function rule, values within one LSB of the float model of the same method
(the widths are derived for that in docs/quadratic.md), the hard cases, backpressure, cycle
counts, and a hypothesis search for triangles that break the bound."""
import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from golden import MODELS, random_triangles, raster, raster_bounds, raster_hard_cases
from hdl.units import ParamError, make_unit

from .conftest import long_where, per_simulator, stream

SMALL = {"screen_bits": 6}                    # 64 x 64: whole-screen triangles in seconds
# two channels in two groups of edge constants, and two flat words
GROUPS = {**SMALL, "channels": 2, "modes": "exact,xshading", "groups": "0,1", "flat": 2}


def check(inputs, out, params):
    """Coverage identical to the model's, values within the derived bound (below one LSB of
    each channel's precision: ``raster_bounds``) and multiples of that LSB; the worst error,
    in LSBs."""
    want = MODELS["raster"].run(inputs, **params)
    assert len(out["tri"]) == len(want["tri"]), \
        f"{len(out['tri'])} fragments, the coverage rule says {len(want['tri'])}"
    for k in ("tri", "x", "y"):
        bad = np.flatnonzero(out[k] != want[k])
        assert not len(bad), (f"fragment {bad[0]}: RTL (tri, x, y) = "
                              f"{(out['tri'][bad[0]], out['x'][bad[0]], out['y'][bad[0]])}, "
                              f"model {(want['tri'][bad[0]], want['x'][bad[0]], want['y'][bad[0]])}")
    for k in (k for k in want if k.startswith("f")):      # flat words: exactly their triangle's
        bad = np.flatnonzero(out[k] != want[k])
        assert not len(bad), f"fragment {bad[0]}: {k} = {out[k][bad[0]]}, not {want[k][bad[0]]}"
    worst = 0.0
    bounds = raster_bounds(params["channels"], params["precision"])
    for k in want:
        if k.startswith("v"):
            lsb, bound = bounds[int(k[1:])]
            err = np.abs(out[k] - want[k])
            assert err.max(initial=0) <= bound, (k, int(np.argmax(err)), float(err.max()), bound)
            assert not np.any(np.asarray(out[k]) % int(lsb)), f"{k} below its LSB"
            err = err / lsb
            worst = max(worst, float(err.max(initial=0)))
    return worst


# on the batch path in make test; Icarus's rows are held to Amaranth's bit for bit by
# tests/test_units_rtl.py::test_simulators_agree; both event-driven ones in make soak
@pytest.mark.parametrize("simulator,name", long_where(per_simulator(["raster"]),
                                                     "amaranth-raster", "icarus-raster"))
def test_hard_cases_with_backpressure(simulator, name):
    params = make_unit(name, spec=True, **SMALL).params
    hard, labels = raster_hard_cases(**params)
    rng = np.random.default_rng(5)
    extra = random_triangles(rng, 16, **params)
    inputs = {k: np.concatenate([hard[k], extra[k]]) for k in hard}
    out, info = stream(name, inputs, simulator, SMALL, p_valid=0.7, p_ready=0.6, seed=3)
    check(inputs, out, params)
    assert raster.culled({k: v[:2] for k, v in inputs.items()}) == 2    # the Omega = 0 cases
    assert info["culled"] == raster.culled(inputs)
    assert np.all(np.diff(out["tri"]) >= 0)                     # in triangle order


@pytest.mark.parametrize("simulator,name", list(per_simulator(["raster"])))
def test_one_fragment_per_clock(simulator, name):
    """A whole-screen triangle: 4,096 fragments in latency + 4,096 cycles, no bubble between
    rows; then a batch of small triangles, whose cycles we state (not a timing test: cycles)."""
    params = make_unit(name, spec=True, **SMALL).params
    hard, labels = raster_hard_cases(**params)
    k = labels.index("whole screen")
    one = {f: hard[f][k:k + 1] for f in hard}
    out, info = stream(name, one, simulator, SMALL)
    assert len(out["tri"]) == 64 * 64
    latency = make_unit(name, spec=True, **SMALL).latency
    assert info["latency"] == latency
    assert info["cycles"] <= latency + 64 * 64 + 2


def test_the_1024_screen_longest_spans_and_steepest_curvature():
    """Screen 1024 x 1024 (the default): a span across the whole screen, a larger triangle,
    and small triangles whose normals are 180 deg apart (the steepest curvature)."""
    p = {"modes": "exact,xshading"}
    params = make_unit("raster", spec=True, **p).params
    hard, labels = raster_hard_cases(**params)
    rng = np.random.default_rng(8)
    steep = random_triangles(rng, 30, **params, size=20)
    steep["e01"][:] = steep["e02"][:] = steep["e12"][:] = -32768              # N1.N2 = -1
    big = random_triangles(rng, 1, **params, size=60)
    pick = [labels.index(n) for n in ("longest span", "x1=0", "sub-pixel")]
    inputs = {k: np.concatenate([hard[k][pick], steep[k], big[k]]) for k in hard}
    out, info = stream("raster", inputs, "amaranth", p)
    assert check(inputs, out, params) <= 1.0
    rows = out["y"][out["tri"] == 0]
    assert np.bincount(rows).max() == 1024                    # spans across the whole screen


# in make soak: the exact mode is in make test in test_edge_constant_groups and the 1024
# screen; the reciprocal's forms are tradeoffs' knobs
@pytest.mark.long
@pytest.mark.parametrize("params", [{"modes": "exact,linear"}, {"recip": "divide"},
                                    {"modes": "linear,xshading", "recip_iters": 2}])
def test_modes_and_reciprocals_on_amaranth(params):
    p = make_unit("raster", spec=True, **SMALL, **params).params
    hard, _ = raster_hard_cases(**p)
    extra = random_triangles(np.random.default_rng(6), 12, **p)
    inputs = {k: np.concatenate([hard[k], extra[k]]) for k in hard}
    out, _ = stream("raster", inputs, "amaranth", {**SMALL, **params})
    check(inputs, out, p)


@pytest.mark.long          # the knobs issue 49 retires run in make soak (make test's budget)
def test_multiplier_knobs_keep_the_contract():
    """Three setup multipliers and two row-engine multipliers for three channels (the row
    engine's 18 products, u and v, seven for each quadratic channel and two for the linear
    one, every ceil(18 / 2) = 9 clocks, not ceil(18 / 4) = 5): the same fragments within
    the same bound, under backpressure, with the latency its schedules state; the setup's
    clocks fall (its critical path, not its products, then sets them: docs/quadratic.md)."""
    params = {**SMALL, "channels": 3, "modes": "exact,xshading,linear", "setup_mults": 3,
              "row_mults": 2}
    unit = make_unit("raster", spec=True, **params)
    base = make_unit("raster", spec=True, **{k: v for k, v in params.items()
                                             if not k.endswith("_mults")})
    assert unit.timing[1] == 9 and base.timing[1] == 5
    assert unit.timing[0] < base.timing[0]
    _keeps_the_contract(unit, params, 9, 0.7, 4)


@pytest.mark.long
def test_more_row_multipliers_keep_the_contract():
    """More row-engine multipliers than channels + 1: the default scene's three channels
    (18 products a row) on six, a row every ceil(18 / 6) = 3 clocks, not 5, so rows shorter
    than five pixels no longer leave the stepper waiting (the dense torus's rows: 0.464 ->
    0.510 fragments per clock with the overlapped setup, docs/quadratic.md); the same
    fragments within the same bound under backpressure, at the latency its schedule states."""
    params = {**SMALL, "channels": 3, "modes": "linear,xshading,xshading", "row_mults": 6}
    unit = make_unit("raster", spec=True, **params)
    assert unit.timing[1] == 3
    _keeps_the_contract(unit, params, 10, 0.7, 5)


@pytest.mark.parametrize("params", [                 # a tradeoffs knob: make soak
    pytest.param({"channels": 3, "modes": "linear,xshading,exact", "precision": "14,8,4"},
                 marks=pytest.mark.long),
    pytest.param({"channels": 3, "modes": "xshading,linear,xshading", "precision": "6,10,14",
                  "row_serial": 3, "setup_serial": 1}, marks=pytest.mark.long)])
def test_each_channel_keeps_its_own_precision(params):
    """``precision``: a channel rounded to p fraction bits keeps Phi, d and 2A to
    2 screen_bits + p + 6 (``Widths.fi``), so within one of its own LSBs (2**-p) of the float
    model over the longest spans (docs/quadratic.md derives it), its values multiples of
    that LSB; in the channels-in-turn engine too, where each job adds its own channel's
    rounding half."""
    params = {**SMALL, **params}
    unit = make_unit("raster", spec=True, **params)
    _keeps_the_contract(unit, params, 12, 0.7, 6)


def _keeps_the_contract(unit, params, rng, p_ready, seed, simulator="amaranth"):
    """The hard cases and 12 random triangles under backpressure: coverage, the 1-LSB bound,
    the culled count; a whole-screen triangle's first fragment at the stated latency."""
    p = unit.params
    hard, labels = raster_hard_cases(**p)
    extra = random_triangles(np.random.default_rng(rng), 12, **p)
    inputs = {k: np.concatenate([hard[k], extra[k]]) for k in hard}
    out, info = stream("raster", inputs, simulator, params, p_valid=0.8, p_ready=p_ready,
                       seed=seed)
    check(inputs, out, p)
    assert info["culled"] == raster.culled(inputs)
    k = labels.index("whole screen")
    _, info = stream("raster", {f: hard[f][k:k + 1] for f in hard}, simulator, params)
    assert info["latency"] == unit.latency


@pytest.mark.long          # the knobs issue 49 retires run in make soak (make test's budget)
@pytest.mark.parametrize("mults,modes", [(3, "exact,xshading,linear"), (1, "linear,linear")])
def test_channels_in_turn_keep_the_contract(mults, modes):
    """``row_serial``: the row engine's channels one after another on one datapath (nine
    products a job, u and v again in each: ceil(9 / 3) = 3 clocks a channel on three
    multipliers; four a job with linear channels only, on one), the walker's row taken at
    the last channel's start. The same fragments within the same bound under backpressure,
    the row interval channels x that, and the latency its schedule states."""
    params = {**SMALL, "channels": len(modes.split(",")), "modes": modes, "row_serial": mults}
    unit = make_unit("raster", spec=True, **params)
    assert unit.timing[1] == params["channels"] * -(-(9 if "x" in modes else 4) // mults)
    _keeps_the_contract(unit, params, 11, 0.6, 6)


IN_TURN = [{"modes": "xshading,linear,xshading", "groups": "0,0,1", "setup_serial": 1,
            "row_serial": 3},
           {"modes": "linear,xshading", "setup_serial": 2, "row_serial": 1}]


@pytest.mark.long          # the knobs issue 49 retires run in make soak (make test's budget)
@pytest.mark.parametrize("simulator,params", [
    pytest.param("amaranth", IN_TURN[0], id="amaranth-groups-1-mult"),
    pytest.param("amaranth", IN_TURN[1], id="amaranth-2-mults"),
    *(pytest.param(c.values[0], IN_TURN[0], id=f"{c.id}-groups-1-mult", marks=c.marks)
      for c in per_simulator(["raster"], only=("verilator", "icarus")))])
def test_setup_channels_in_turn_keep_the_contract(simulator, params):
    """``setup_serial``: the setup's channels one after another on a datapath of their own
    (eleven products a job: ceil(11 / M) clocks a channel on M multipliers, the first the
    setup's own, shared: its jobs start after the setup's last product), their constants
    in a memory of two triangles' slots that the row engine's jobs read at their channel;
    a linear channel through the X-shading datapath with its edge constants 0, and each
    channel with its own group's. The same fragments within the same bound under
    backpressure, the culled count and the latency its schedule states."""
    params = {**SMALL, "channels": len(params["modes"].split(",")), **params}
    unit = make_unit("raster", spec=True, **params)
    _keeps_the_contract(unit, params, 13, 0.6, 8, simulator)


def _smooth(rng, n, p):
    """Small triangles whose values and normals barely differ, as on a dense mesh: their
    coefficients are small, so the setup chooses the narrow row engine for them."""
    t = random_triangles(rng, n, **p, size=12)
    for ch in range(p["channels"]):
        base = rng.integers(-12000, 12000, n)
        for k in range(3):
            t[f"v{ch}_{k}"] = base + rng.integers(-300, 300, n)
    for name in ("e01", "e02", "e12"):
        t[name] = rng.integers(-200, 1, n)
    return t


@pytest.mark.parametrize("modes", ["linear,xshading,xshading",      # the default scene's
                                   pytest.param("exact,xshading", marks=pytest.mark.long)])
def test_narrow_row_engine_keeps_the_contract(modes):
    """``row_narrow=21``: block floating point (docs/quadratic.md, "The narrow row engine"):
    the setup chooses per triangle, from its derived bound, the narrow engine (21-bit
    mantissas, every product one MULT18X18D) or the wide one on one multiplier. Smooth
    triangles (most of them narrow) interleaved with random ones and the hard cases (wide),
    so rows switch engines often, under backpressure: the same fragments in the same order
    within the same bound as the wide engine's, the culled count, and the latency stated."""
    from flows.bfp import built_share
    params = {**SMALL, "channels": len(modes.split(",")), "modes": modes, "row_narrow": 21}
    unit = make_unit("raster", spec=True, **params)
    p = unit.params
    rng = np.random.default_rng(21)
    smooth, rand = _smooth(rng, 24, p), random_triangles(rng, 24, **p, size=24)
    mixed = {k: np.stack([smooth[k], rand[k]], 1).reshape(-1) for k in smooth}
    # both engines in use: the float model's choice (the setup's, within rounding)
    share = lambda t: built_share(t, 21, p["screen_bits"], p["sub_bits"],
                                  modes.split(","))[0]
    assert share(smooth) > 0.5 and share(rand) < 0.5, (share(smooth), share(rand))
    hard, labels = raster_hard_cases(**p)
    inputs = {k: np.concatenate([mixed[k], hard[k]]) for k in hard}
    out, info = stream("raster", inputs, "amaranth", params, p_valid=0.8, p_ready=0.7, seed=21)
    check(inputs, out, p)
    assert info["culled"] == raster.culled(inputs)
    k = labels.index("whole screen")
    _, info = stream("raster", {f: hard[f][k:k + 1] for f in hard}, "amaranth", params)
    assert info["latency"] == unit.latency


OVERLAPPED = [
    {"modes": "exact,xshading,linear", "setup_ii": 12, "setup_mults": 4, "setup_narrow": 3},
    {"modes": "linear,xshading,xshading", "setup_ii": 24, "setup_mults": 1, "setup_narrow": 2}]


@pytest.mark.parametrize("simulator,params", [
    # on Amaranth's simulator (ii12 the same as on Verilator below; ii24 a knob issue 49
    # retires) in make soak
    *(pytest.param("amaranth", p, id=f"amaranth-ii{p['setup_ii']}", marks=pytest.mark.long)
      for p in OVERLAPPED),
    *(pytest.param(c.values[0], OVERLAPPED[0], id=f"{c.id}-ii12",
                   marks=[*c.marks, pytest.mark.long])       # issue 49's knobs: make soak
      for c in per_simulator(["raster"], only=("verilator",)))])
def test_overlapped_setup_keeps_the_contract(simulator, params):
    """The setup overlapping triangles: one every 12 clocks on four wide multipliers and
    three 18 x 18 ones (the products of coordinates, Widths.wpos), its edge divisions (14
    quotient bits at 64 x 64) on two dividers in turn; or one every 24 on one wide and two
    narrow, whose shifter reads the shift amount from two copies (alpha's two products 24
    clocks apart or more). Its results go through a queue with credits. The same fragments
    within the same bound under backpressure, the culled count, and the latency its schedule
    states; back to back, small triangles come through at the interval (a cycle count, not a
    timing test)."""
    ii = params["setup_ii"]
    params = {**SMALL, "channels": 3, **params}
    unit = make_unit("raster", spec=True, **params)
    assert unit.timing[0] == ii
    p = unit.params
    hard, labels = raster_hard_cases(**p)
    extra = random_triangles(np.random.default_rng(9), 12, **p)
    inputs = {k: np.concatenate([hard[k], extra[k]]) for k in hard}
    out, info = stream("raster", inputs, simulator, params, p_valid=0.8, p_ready=0.7, seed=4)
    check(inputs, out, p)
    assert info["culled"] == raster.culled(inputs)
    k = labels.index("whole screen")
    one = {f: hard[f][k:k + 1] for f in hard}
    _, info = stream("raster", one, simulator, params)
    assert info["latency"] == unit.latency
    # 40 triangles that cover no pixel (between two rows' centres: no row, no span): each
    # costs the setup its interval and the walker a clock, so 40 take latency + 40 ii
    tiny = random_triangles(np.random.default_rng(2), 40, **p, size=1)
    for c in ("y0", "y1", "y2"):
        tiny[c][:] = 2 * (1 << p["sub_bits"]) + np.arange(3)[("y0", "y1", "y2").index(c)]
    out, info = stream("raster", tiny, simulator, params)
    check(tiny, out, p)
    assert info["cycles"] <= unit.latency + 40 * ii + 2, (info["cycles"], unit.latency)


@pytest.mark.parametrize("simulator,name", list(per_simulator(["raster"], only=("verilator",))))
def test_edge_constant_groups(simulator, name):
    """Channels in two groups, each with its own per-edge constants (a vector's components
    share theirs, seed 000 section 2), X-shading and exact mid-edges: the groups' constants
    differ on every triangle, so the channel that took group 0's would leave the 1-LSB
    bound (the fenney_xz scenes run three groups of three channels). With flat words (one
    model for this test and the next)."""
    params = GROUPS
    p = make_unit("raster", spec=True, **params).params
    assert [f.name for f in make_unit("raster", spec=True, **params).inputs][6:12] == \
        ["e01", "e02", "e12", "e01_1", "e02_1", "e12_1"]
    hard, _ = raster_hard_cases(**p)
    extra = random_triangles(np.random.default_rng(7), 40, **p)
    inputs = {k: np.concatenate([hard[k], extra[k]]) for k in hard}
    out, _ = stream("raster", inputs, simulator, params)
    check(inputs, out, p)


@pytest.mark.parametrize("simulator,name", list(per_simulator(["raster"], only=("verilator",))))
def test_flat_words_across_empty_triangles(simulator, name):
    """Flat words (a triangle's constants, fenney_polar's k1 k2 k3 Q) reach every fragment of
    their triangle exactly, across runs of triangles that cover no pixel (sub-pixel, culled,
    off screen: 0, 1, 40 and 300 in a row) with stalls on both sides: the sequence that hung
    the queue that once met the constants beside the raster (16 deep)."""
    params = GROUPS
    p = make_unit("raster", spec=True, **params).params
    rng = np.random.default_rng(11)
    parts = []
    for run in (0, 1, 40, 300, 2):
        parts.append(random_triangles(rng, 3, **p, size=20))            # some pixels
        empty = random_triangles(rng, run, **p, size=1)                # at most a pixel
        c = rng.integers(0, 64 * 16, (run, 1)) // 16 * 16 + 1          # inside one pixel,
        for a in ("x", "y"):                                           # off its centre
            for k in range(3):
                empty[f"{a}{k}"] = (c[:, 0] + rng.integers(0, 6, run)).astype(np.int64)
        parts.append(empty)
    inputs = {k: np.concatenate([q[k] for q in parts]) for k in parts[0]}
    out, _ = stream(name, inputs, simulator, params, p_valid=0.8, p_ready=0.5, seed=4)
    want = MODELS["raster"].run(inputs, **p)
    assert len(set(want["tri"])) < len(inputs["x0"]) - 300        # the empty runs are empty
    check(inputs, out, p)


def test_back_to_back_triangles_one_channel():
    """One channel: the row engine takes a row every 5 clocks, so a row of the next triangle
    (another Omega, another shift) starts while the last row of this one is in the shifter.
    These six triangles once caught the shifter reading the next row's shift amount (89 LSB
    on a one-pixel row)."""
    params = {**SMALL, "channels": 1}
    p = make_unit("raster", spec=True, **params).params
    inputs = random_triangles(np.random.default_rng(5), 6, **p)
    out, _ = stream("raster", inputs, "amaranth", params)
    check(inputs, out, p)


coords = st.integers(-2 * 32 * 16, 2 * 32 * 16 - 1)


@settings(max_examples=8)
@given(st.lists(st.tuples(*[coords] * 6, *[st.integers(-32768, 0)] * 3,
                          *[st.integers(-16384, 16384)] * 6), min_size=1, max_size=6),
       st.sampled_from(["xshading", "exact"]))
def test_property_no_triangle_breaks_the_bound(rows, modes):
    """Any triangle the input format holds (screen 32 x 32, vertices up to a screen outside
    it): the coverage rule, and values within one LSB."""
    names = ["x0", "y0", "x1", "y1", "x2", "y2", "e01", "e02", "e12"] + \
        [f"v{c}_{k}" for c in range(2) for k in range(3)]
    inputs = {n: np.array([r[i] for r in rows], np.int64) for i, n in enumerate(names)}
    params = {"screen_bits": 5, "modes": modes}
    out, _ = stream("raster", inputs, "amaranth", params)
    check(inputs, out, make_unit("raster", spec=True, **params).params)


@pytest.mark.parametrize("params,message", [
    ({"modes": "xshading,linear,exact"}, "modes names 3 channel(s) but channels=2"),
    ({"modes": "phong"}, "modes must be one of 'xshading', 'exact', 'linear' (one per channel), "
                         "not 'phong'"),
    ({"recip": "magic"}, "recip must be one of 'newton', 'divide', not 'magic'"),
    ({"screen_bits": 11}, "screen_bits must be in 4..10"),      # docs/quadratic.md: widths
    ({"channels": 3, "groups": "0,2,2"}, "groups must be numbered 0, 1, ... without gaps"),
    ({"groups": "0,0,1"}, "groups names 3 channel(s) but channels=2"),
    ({"channels": 1, "modes": "linear", "row_mults": 5},
     "row_mults must be at most the row engine's 4 products a row"),   # u, v, Phi's two
    ({"setup_mults": 0}, "setup_mults must be in 1..6"),
    ({"row_mults": 2, "row_serial": 3}, "row_mults=2 and row_serial=3: the row engine is one"),
    ({"row_serial": 10}, "row_serial must be in 0..9"),
    ({"setup_serial": 1}, "setup_serial=1 needs row_serial > 0"),
    ({"row_narrow": 10}, "row_narrow=10: mantissas of 18 to 24 bits, with the channels together"),
    ({"row_narrow": 25}, "row_narrow must be in 0..24"),
    ({"row_narrow": 21, "row_serial": 3}, "row_narrow=21: mantissas of 18 to 24 bits, with the "
                                          "channels together (row_serial=0, setup_serial=0)"),
    ({"setup_serial": 1, "row_serial": 3, "modes": "exact,linear"},
     "setup_serial=1 needs row_serial > 0 (its jobs read the channels' constants in turn), "
     "setup_ii=0 and no exact channel"),
    # 52 products: Omega 2, the edges' numerators 6, two Newton steps 4, the numerator
    # tracks 16, alpha 2, and 11 for each X-shading channel (a, b, c 3; Pu, Pv, P0, 2A 8)
    # of those, 30 fit 18 x 18: Omega 2, the edges' 6, the tracks' 16 and a, b, c 3 each
    ({"setup_ii": 16, "setup_narrow": 1}, "setup_ii=16 is too short: the 30 of the setup's "
                                           "products that fit 18 x 18 on setup_narrow=1 take "
                                           "at least 30 clocks"),
    ({"setup_ii": 8}, "setup_ii=8 is too short: the setup's 52 products on setup_mults=1 wide "
                      "multiplier(s) take at least 52 clocks; at this interval they need "
                      "setup_mults=7, more than the 6 allowed"),
])
def test_bad_parameters_are_named(params, message):
    with pytest.raises(ParamError, match=message.replace("(", r"\(").replace(")", r"\)")):
        make_unit("raster", **params)
