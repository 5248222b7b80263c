"""The narrow row engine (issue 49's block floating point: every product of M-bit mantissas on
one MULT18X18D) alone: rows of random triangles, from slivers to screen-sized ones, and
constants from 2**-20 to their format's top, driven into ``span.row_engine(narrow=M)``
under random credit; each output bit for bit against ``golden.bfp.row`` (an integer model
written from docs/quadratic.md, not from the RTL), and each within ``golden.bfp.narrow_bound``
of the float model of the same exact constants."""
import random
from types import SimpleNamespace

import pytest
from amaranth.hdl import Elaboratable, Module, Signal
from amaranth.sim import Simulator

from golden import bfp
from hdl.setup_unit.formats import VALUE
from hdl.setup_unit.setup import Widths
from hdl.span_unit.span import narrow_left, narrow_row_fields, row_engine, row_products

MODES = ("xshading", "linear", "exact")
QUAD_KEYS = ("a", "b", "c", "d", "e")
BOUNDS = {"a": 4, "b": 4, "c": 12, "d": 8, "e": 8, "pu": 64, "pv": 64}


class _Engine(Elaboratable):
    def __init__(self, w, M, modes, shapes):
        self.w, self.M, self.modes = w, M, modes
        self.rows = {k: Signal(s, name=f"in_{k}") for k, s in shapes.items()}
        self.link = SimpleNamespace(valid=Signal(), ready=Signal())
        self.space = Signal()

    def elaborate(self, platform):
        m = Module()
        mults = len(self.modes) + 1
        writes, self.started, self.written, self.t = row_engine(
            m, self.w, self.modes, self.rows, self.link, self.space, mults=mults,
            narrow=self.M)
        self.late = {name: (vals, en) for name, vals, en, _ in writes}
        return m


def _triangle(rng, w):
    """Relative vertices (sub-pixel units) at a random scale, Omega != 0."""
    top = 1 << (w.screen_bits + w.sub_bits)
    while True:
        scale = 2 ** rng.uniform(0, w.screen_bits + w.sub_bits)
        x1, y1, x2, y2 = (int(rng.uniform(-1, 1) * min(scale, top)) for _ in range(4))
        y1, y2 = abs(y1), abs(y2)
        if rng.random() < 0.2:                                   # slivers
            x2, y2 = x1 + rng.randint(-2, 2), y1 + rng.randint(-2, 2)
        omega = x1 * y2 - x2 * y1
        if omega:
            return x1, y1, x2, y2, omega


def _point(rng, x1, y1, x2, y2, omega):
    """A point (integer sub-pixel offsets) inside the triangle, and its numerators."""
    xs, ys = (0, x1, x2), (0, y1, y2)
    for _ in range(200):
        X = rng.randint(min(xs), max(xs))
        Y = rng.randint(min(ys), max(ys))
        nu, nv = X * y2 - Y * x2, Y * x1 - X * y1
        if 0 <= nu * (1 if omega > 0 else -1) and 0 <= nv * (1 if omega > 0 else -1) \
                and abs(nu) + abs(nv) <= abs(omega):
            return nu, nv
    return 0, 0                                                 # the top vertex


def _constants(rng, w, M, mode):
    """A channel's fixed-point constants at a random scale, and its engine inputs."""
    left = narrow_left(w, M)
    scale = 2.0 ** -rng.choice([0, 0, 1, 3, 8, 20])
    fixed = {k: int(rng.uniform(-1, 1) * b * scale * 2 ** w.FO) for k, b in BOUNDS.items()}
    fixed["f"] = int(rng.uniform(-2, 2) * 2 ** w.FO)
    fixed["p0"] = int(rng.uniform(-1, 1) * 2 ** (w.FI + 3))
    linear = mode == "linear"
    group = ("d", "e") if linear else QUAD_KEYS
    e0, mants = bfp.quantised([fixed[k] for k in group], w.FO, M)
    e1, pmants = bfp.quantised([fixed["pu"], fixed["pv"]], w.FO, M)
    sphi, sd = bfp.amounts(e0, e1, linear, w.FI, M, left)
    ch = {**dict(zip(group, mants)), "f": fixed["f"], "p0": fixed["p0"], "sphi": sphi,
          "sd": sd}
    if not linear:
        ch.update(pu=pmants[0], pv=pmants[1])
    return fixed, ch, e0, e1


def _model(w, M, modes, tri):
    """Per channel: the model's (Phi, d) at FI and the float model's, and the bounds."""
    left = narrow_left(w, M)
    out = []
    for ch, mode in enumerate(modes):
        fixed, c, e0, e1 = tri["ch"][ch]
        linear = mode == "linear"
        phi, d = bfp.row(tri["nu"], tri["nv"], tri["rs"], tri["sh"], c, M, w.FI, w.FO, left,
                         linear)
        u, v = tri["nu"] / tri["omega"], tri["nv"] / tri["omega"]
        f = {k: x / 2 ** w.FO for k, x in fixed.items() if k not in ("p0",)}
        if linear:
            exact_phi, exact_d = f["f"] + u * f["d"] + v * f["e"], fixed["p0"] / 2 ** w.FI
        else:
            t1, t2 = f["d"] + f["a"] * u + f["c"] * v, f["e"] + f["b"] * v
            exact_phi = f["f"] + u * t1 + v * t2
            exact_d = fixed["p0"] / 2 ** w.FI + f["pu"] * u + f["pv"] * v
        out.append((phi, d, exact_phi, exact_d, bfp.narrow_bound(M, e0, e1, w.FI)))
    return out


def _rows(rng, w, M, modes, n):
    rows = []
    for k in range(n):
        x1, y1, x2, y2, omega = _triangle(rng, w)
        nu, nv = _point(rng, x1, y1, x2, y2, omega)
        rs, sh = bfp.recip_mantissa(omega, M)
        border = rng.random() < 0.3                   # the span starts at column 0: B track
        xl = -rng.randint(1, 50) if border else rng.randint(0, (1 << w.screen_bits) + 20)
        tri = {"nu": nu, "nv": nv, "omega": omega, "rs": rs, "sh": sh,
               "ch": [_constants(rng, w, M, mode) for mode in modes]}
        junk = lambda: rng.randrange(1 << w.wn)
        track = {"E_u": nu, "E_v": nv, "B_u": junk(), "B_v": junk()}
        if border:
            track = {"B_u": nu, "B_v": nv, "E_u": junk(), "E_v": junk()}
        fields = {"j": k % (1 << w.wrow), "tri": k, "xl": xl, "xr": xl + rng.randint(-3, 40),
                  **{t: x & ((1 << w.wn) - 1) for t, x in track.items()}, "rsm": rs, "sh": sh}
        for ch, (fixed, c, _, _) in enumerate(tri["ch"]):
            fields.update({f"c{ch}_{'n' if key not in ('f', 'p0', 'sphi', 'sd') else ''}{key}": x
                           for key, x in c.items()})
            fields[f"c{ch}_a2"] = rng.randrange(-1 << 40, 1 << 40)
        rows.append((fields, tri))
    return rows


def _run(w, M, modes, rows, rng):
    dut = _Engine(w, M, modes, narrow_row_fields(w, M, modes))
    got = []

    async def drive(ctx):
        for fields, _ in rows:
            ctx.set(dut.link.valid, 1)
            for key, x in fields.items():
                ctx.set(dut.rows[key], x)
            while True:
                ctx.set(dut.space, rng.random() < 0.7)
                await ctx.delay(1e-9)
                if ctx.get(dut.link.ready):
                    await ctx.tick()
                    break
                await ctx.tick()
            ctx.set(dut.link.valid, 0)
            for _ in range(rng.choice([0, 0, 0, 1, 7])):
                await ctx.tick()
        for _ in range(dut.t["length"] + 10):
            await ctx.tick()

    async def watch(ctx):
        vals, en = dut.late["late"]
        early, early_en = dut.late["early"]
        pending = []
        async for state in ctx.tick().sample(en, early_en, *vals.values(), *early.values()):
            _, _, e, ee, *rest = state
            late, first = dict(zip(vals, rest[:len(vals)])), dict(zip(early, rest[len(vals):]))
            if ee:
                pending.append(first)
            if e:
                got.append((pending.pop(0), late))

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(drive)
    sim.add_testbench(watch, background=True)
    sim.run()
    return got


@pytest.mark.parametrize("M", [18, 20, 21, 22])
def test_narrow_row_engine_against_its_model_and_the_float_model(M):
    rng = random.Random(49 + M)
    w = Widths(10, 4)
    rows = _rows(rng, w, M, MODES, 300)
    got = _run(w, M, MODES, rows, rng)
    assert len(got) == len(rows)
    half = 1 << (w.FI - VALUE.frac_bits - 1)              # the output's rounding (p = 14)
    acc = w.acc(VALUE.frac_bits)
    worst = [0.0, 0.0]
    for (fields, tri), (early, late) in zip(rows, got):
        assert early["tri"] == fields["tri"]
        size = 1 << w.screen_bits
        xs = min(max(fields["xl"], 0), size)
        xe = min(max(fields["xr"], 0), size)
        assert (late["xs"], late["xe"], late["some"], late["one"]) == \
            (xs, xe, xs < xe, xs + 1 == xe)
        for ch, (phi, d, exact_phi, exact_d, (b_phi, b_d)) in \
                enumerate(_model(w, M, MODES, tri)):
            # modulo 2**acc, the bits the stepper keeps (``Widths.acc``)
            assert late[f"phi{ch}"] == (phi + half) % (1 << acc), (fields["tri"], ch)
            got_d = early[f"d{ch}"] if MODES[ch] == "linear" else late[f"d{ch}"]
            assert got_d == d % (1 << acc), (fields["tri"], ch)
            e_phi = abs(phi / 2 ** w.FI - exact_phi)
            e_d = abs(d / 2 ** w.FI - exact_d)
            assert e_phi <= b_phi and e_d <= b_d, (fields["tri"], ch, e_phi, b_phi, e_d, b_d)
            worst = [max(worst[0], e_phi / b_phi), max(worst[1], e_d / b_d)]
    # the bound is not slack beyond reason: the worst row spends a good share of it
    print("worst share of the bound (Phi, d):", worst)
    assert worst[0] > 0.05, worst


def test_narrow_row_engine_takes_no_wide_multiplier():
    """Its products are all narrow: channels + 1 multipliers of one MULT18X18D each, a row
    every ceil(products / multipliers) clocks, as the wide engine."""
    w = Widths(10, 4)
    dut = _Engine(w, 20, MODES, narrow_row_fields(w, 20, MODES))
    from amaranth.hdl import Fragment
    Fragment.get(dut, None)
    assert dut.t["ii"] == -(-row_products(MODES) // (len(MODES) + 1))


def test_the_setups_mantissas_shifts_and_choice_bit_for_bit():
    """The setup's side of block floating point (``Setup._narrow_channel``): each triangle's
    exponents, M-bit mantissas of a..e and Pu, Pv, the shifts into FI, the narrow reciprocal
    and the choice of engine, bit for bit against ``golden.bfp`` applied to the same
    triangle's wide constants (smooth triangles, mostly narrow, and random ones, mostly
    wide; both choices must occur)."""
    import numpy as np
    from golden import random_triangles
    from golden.raster import sorted_triangles
    from hdl.fixed import layout
    from hdl.setup_unit.formats import triangle_fields
    from hdl.span_unit.plan import RasterPlan
    from hdl.span_unit.setup_engine import SetupEngine
    from .test_raster_rtl import _smooth
    M, modes = 21, ("linear", "xshading", "exact")
    plan = RasterPlan.from_params(screen_bits=6, channels=3, modes=",".join(modes),
                                  row_narrow=M)
    p, w = plan.params(), plan.setup.w
    rng = np.random.default_rng(7)
    tris = [_smooth(rng, 30, p), random_triangles(rng, 30, **p, size=24)]
    inputs = {k: np.concatenate([t[k] for t in tris]) for k in tris[0]}
    n = len(inputs["x0"])
    dut = SetupEngine(plan, layout(triangle_fields(6, p["sub_bits"], 3, 1)))
    got = []

    async def bench(ctx):
        ctx.set(dut.o.ready, 1)
        for t in range(n):
            ctx.set(dut.i.valid, 1)
            for k in inputs:
                ctx.set(getattr(dut.i.payload, k), int(inputs[k][t]))
            await ctx.tick().until(dut.i.ready)
        ctx.set(dut.i.valid, 0)
        for _ in range(400):
            await ctx.tick()

    async def watch(ctx):
        async for _, _, valid, *vals in ctx.tick().sample(
                dut.o.valid, *(getattr(dut.o, k) for k in dut.fields)):
            if valid:
                got.append(dict(zip(dut.fields, vals)))

    sim = Simulator(dut)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    sim.add_testbench(watch, background=True)
    sim.run()
    st = sorted_triangles(inputs, 3, p["sub_bits"])
    drawn = [t for t in range(n) if st["x1"][t] * st["y2"][t] != st["x2"][t] * st["y1"][t]]
    got = [g for g in got if not g["cull"]]
    assert len(got) == len(drawn)
    left = narrow_left(w, M)
    choices = []
    for t, g in zip(drawn, got):
        rs = g["rs"]
        assert g["rsm"] == bfp.rs_mantissa(abs(rs), rs < 0, w.R, M)
        chans = []
        for ch, mode in enumerate(modes):
            linear = mode == "linear"
            group = ("d", "e") if linear else ("a", "b", "c", "d", "e")
            e0, mants = bfp.quantised([g[f"c{ch}_{k}"] for k in group], w.FO, M)
            assert [g[f"c{ch}_n{k}"] for k in group] == mants, (t, ch)
            e1 = 0
            if not linear:
                e1, pm = bfp.quantised([g[f"c{ch}_pu"], g[f"c{ch}_pv"]], w.FO, M)
                assert [g[f"c{ch}_npu"], g[f"c{ch}_npv"]] == pm, (t, ch)
            sphi, sd = bfp.amounts(e0, e1, linear, w.FI, M, left)
            assert g[f"c{ch}_sphi"] == sphi and (linear or g[f"c{ch}_sd"] == sd), (t, ch)
            chans.append((linear, e0 + w.FO, e1 + w.FO))
        ly = int(st["y2"][t]).bit_length() - 1
        want = bfp.choice(M, w.FI, w.FO, w.sub_bits, w.screen_bits, plan.setup.recip_err,
                          g["sh"], ly, chans)
        assert g["narrow"] == want, t
        choices.append(want)
    assert 0 < sum(choices) < len(choices), sum(choices)


@pytest.mark.parametrize("M", [18, 21, 24])
def test_the_choice_tables_keep_the_derived_bound(M):
    """Every sum the setup's tables allow (``hdl.setup_unit.choice``: each channel's start,
    its steps and the setup's own terms, in 64ths of the budget) is within the budget by the
    float bound (``golden.bfp.narrow_ok``, n = 2**kn steps), for every bit length and kn; and
    the tables are not empty (the default torus's exponents pass)."""
    from hdl.setup_unit.choice import choice_tables
    w = Widths(10, 4)
    for linear in (False, True):
        start, steps, own = choice_tables(M, w.FI, w.FO, w.screen_bits, 7.2e-9, linear)
        allowed = 0
        for s0 in range(len(start)):
            for kn in range(len(own)):
                for s1 in range(len(steps) - kn):
                    if start[s0] + own[kn] + (0 if linear else steps[s1 + kn]) > 64:
                        continue
                    allowed += 1
                    e0, e1 = s0 + M - 1 - w.FO, s1 + M - 1 - w.FO
                    assert bfp.narrow_ok(M, w.FI, [(linear, e0, e1)], 2 ** kn, 7.2e-9), \
                        (linear, s0, s1, kn)
        assert allowed > 0


@pytest.mark.parametrize("t, s_bits, g_bits", [(8, 22, 14), (9, 22, 14), (10, 23, 13)])
def test_the_seed_and_slope_reciprocal_is_within_its_derived_bound(t, s_bits, g_bits):
    """Issue 66's reciprocal for the narrow raster (``flows.bfp.recip_seed_slope``): a word
    of seed and slope (36 bits: a DP16KD holds 512) for each of 2^t intervals and one 18 x 18
    product. Over every 24-bit mantissa its relative error is within the bound derived from
    the minimax line (h^2 / 8) and the three roundings, and the 1,024-word table is within
    2^-21, the narrow engine's unit at M = 21."""
    from flows.bfp import recip_seed_slope
    err, bound = recip_seed_slope(t, s_bits, g_bits)
    assert err <= bound
    if t == 10:
        assert err < 2.0 ** -21
