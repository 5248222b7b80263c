"""Issue 49's per-triangle block floating point, measured before it is built: how many
mantissa bits the row engine's products need for each channel to stay within its bound of
the float model, when each triangle's values share an exponent per group.

The row engine (docs/quadratic.md) computes per row, at the span's first pixel (u, v):
Phi = f + u t1 + v t2 with t1 = d + a u + c v and t2 = e + b v (seed 000 eq 17), and the
first difference dd = P0 + Pu u + Pv v; the stepper then adds dd and 2A per pixel (eq 22).
Here every product's operands are rounded to M-bit signed mantissas: u and v with M - 2
fraction bits (they lie in [0, 1] at a pixel inside the triangle), and each group of
coefficients, (a..e), (P0, Pu, Pv) and 2A, at the exponent of its largest magnitude on that
triangle, and a row's t1, t2 at theirs. f, only added, keeps its fixed point. Products and
sums are exact (the accumulators are adders, as wide as the bound needs). ``bound`` derives
each triangle's error from its exponents and its widest chord, so a setup can choose per
triangle: within half an LSB, the narrow path (each product one 18 x 18 block); beyond it,
wide products. The first table gives the share on the narrow path and checks the bound
against the emulation; the second counts the MULT18X18D that issue 49's rates need on each
mesh, today and with the narrow path (``blocks``). The error at each fragment is against the same float model's Phi, in LSBs of
the output (2^-14); the tests' bound is one LSB after rounding, so half an LSB is what the
arithmetic may spend.

Why the exponent can be per triangle: along x, the barycentric u changes by y2 / Omega a
pixel and v by y1 / Omega, both at most 1 / W, W = |Omega| / y2 the triangle's widest
horizontal chord (at the middle vertex's row); so dd scales as 1 / W and 2A as 1 / W^2,
while a span is at most W + 1 pixels long. A triangle with W < 1 (a sliver across the rows)
has spans of one pixel: its dd and 2A are never used.

A third table weighs the other direction, row starts by additions (forward differences
along the left edge): per mesh, the rows and fragments a triangle brings, which set how many
products a row engine spends per triangle against a setup's, and K, how far the (u, v) of a
triangle's fragments move from its first fragment's along x and y before they cancel
(|du/dx X| + |du/dy Y| + |dv/dx X| + |dv/dy Y|, X and Y in pixels): an affine map stepped by
additions has its relative error multiplied by K, where the numerators the RTL steps today
are exact.

    python -m flows.bfp      (a minute: the driver and numpy only)"""
import numpy as np

from golden import raster as R, random_triangles, TYPICAL_SIZE
from golden import quadratic as q
from hdl.setup_unit.formats import VALUE, parse_modes
from scene import driver as S
from sim.verilog import SCENES

MESHES = [("default torus, 12 x 12 segments", "default", None),
          ("wuson (OBJ)", "wuson", None),
          ("torus, 64 x 64 segments, 256 x 256", "default", [64, 64])]

MANTISSAS = (18, 20, 22, 25)
BUILT = (18, 20)                # the narrow engine's mantissas: mult18's, mult20's
# issue 49's targets: fragments per clock on each mesh, and the raster's MULT18X18D
TARGETS = dict(zip((label for label, _, _ in MESHES), (0.95, 0.75, 0.75)))
WIDE = 4                       # a product of 35-bit operands: four 18 x 18 blocks (or passes)


def _quant(x, exp, m):
    """``x`` rounded to an m-bit signed mantissa at the exponent ``exp`` (|x| < 2^exp)."""
    step = 2.0 ** (exp - (m - 1))
    with np.errstate(invalid="ignore"):                  # culled triangles: NaN
        return np.rint(x / step) * step


def _exp(*groups):
    """The group's exponent per triangle: the least e with every |x| < 2^e."""
    top = np.max(np.abs(np.stack(groups)), 0)
    return np.floor(np.log2(np.maximum(top, 2.0 ** -60))) + 1


def errors(inputs, m, screen_bits, sub_bits, modes, recip=False):
    """Per fragment, |Phi emulated - Phi float| in LSBs (2^-14), the worst quadratic channel;
    per triangle the widest chord W and the derived bound (:func:`bound`, LSBs, the worst
    quadratic channel); and each fragment's triangle. ``recip``: u and v made as a narrow
    row engine would, from m-bit mantissas of the numerator (at Omega's exponent) and of the
    reciprocal of Omega's mantissa, the product rounded again: each of the three roundings
    at most r (below), so the bound takes 3 r."""
    channels = len(modes)
    x, y = R._vertices(inputs)
    tri, px, py = R.coverage(x, y, sub_bits, screen_bits)
    st = R.sorted_triangles(inputs, channels, sub_bits)
    with np.errstate(divide="ignore", invalid="ignore"):    # culled triangles: Omega = 0
        omega = q.omega(st["x1"], st["y1"], st["x2"], st["y2"])
        width = np.abs(omega) / st["y2"]
        ux, vx = st["y2"] / omega, -st["y1"] / omega          # du/dx, dv/dx a pixel
    # each row's first fragment (the RTL's span start), its (u, v), and each pixel's offset
    first = np.r_[True, (tri[1:] != tri[:-1]) | (py[1:] != py[:-1])]
    start = np.maximum.accumulate(np.where(first, np.arange(len(tri)), 0))
    i = px - px[start]
    X0 = px[start] + 0.5 - st["x0"][tri]
    Y0 = py[start] + 0.5 - st["y0"][tri]
    g = {k: st[k][tri] for k in ("x1", "y1", "x2", "y2")}
    with np.errstate(divide="ignore", invalid="ignore"):
        u, v = q.uv_of(g["x1"], g["y1"], g["x2"], g["y2"], X0, Y0)
        ue, ve = q.uv_of(g["x1"], g["y1"], g["x2"], g["y2"], px + 0.5 - st["x0"][tri],
                         py + 0.5 - st["y0"][tri])
    rnd = lambda x, f: np.rint(x * 2.0 ** f) * 2.0 ** -f
    if recip:
        with np.errstate(divide="ignore", invalid="ignore"):
            sh = np.floor(np.log2(np.abs(omega)))                 # |Omega| = M 2^sh
            rm = rnd(2.0 ** sh / np.abs(omega), m - 1)[tri]       # 1/M in (1/2, 1]
            scale = np.abs(omega)[tri] * 2.0 ** -sh[tri]         # M, in [1, 2)
            # the numerator at Omega's exponent, nu sign(Omega) / 2^sh = u M, in [0, 2)
            uq, vq = (rnd(rnd(w * scale, m - 2) * rm, m - 2) for w in (u, v))
    else:
        uq, vq = (rnd(w, m - 2) for w in (u, v))
    out, bounds = [], [np.zeros(len(omega))]
    for ch, mode in enumerate(modes):
        if mode == "linear":
            continue
        I = [st["values"][ch][:, k] for k in range(3)]
        coef = R.channel_uv(mode, I, st["e"])                       # (n, 6): a..f
        a, b, c, d, e, f = coef.T
        with np.errstate(invalid="ignore"):
            A = a * ux * ux + b * vx * vx + c * ux * vx
            Pu, Pv, P0 = 2 * a * ux + c * vx, 2 * b * vx + c * ux, A + d * ux + e * vx
        e0, e1, e2 = _exp(a, b, c, d, e), _exp(P0, Pu, Pv), _exp(2 * A)
        bounds.append(bound(m, e0, e1, e2, width, 3 if recip else 1))
        qa, qb, qc, qd, qe = (_quant(z, e0, m)[tri] for z in (a, b, c, d, e))
        t1 = qd + qa * uq + qc * vq
        t2 = qe + qb * vq
        et = _exp(t1, t2)                                  # a row's: at most e0 + 2
        phi0 = f[tri] + uq * _quant(t1, et, m) + vq * _quant(t2, et, m)
        dd = (_quant(P0, e1, m)[tri] + _quant(Pu, e1, m)[tri] * uq
              + _quant(Pv, e1, m)[tri] * vq)
        phi = phi0 + i * dd + i * (i - 1) / 2 * _quant(2 * A, e2, m)[tri]
        exact = q.eval_uv(coef[tri], ue, ve)
        out.append(np.abs(phi - exact) / VALUE.lsb)
    err = np.max(out, 0) if out else np.zeros(len(tri))
    return tri, err, width, np.max(bounds, 0)


def bound(m, e0, e1, e2, width, rs=1):
    """The error at a triangle's fragments, derived from its exponents, in LSBs (2^-14):
    what a setup could test to pick the narrow path. e(x) = 2^(x - m) is half a mantissa's
    step at exponent x, r = 2^-(m-1) the rounding of u and v, and u, v >= 0, u + v <= 1 at a
    span's first pixel centre:
    - f is added, never multiplied: exact.
    - t1 = d + a u + c v: d is off by e(e0), a u by e(e0) u + |a| r <= 3 e(e0), c v too;
      |t1| <= 2^e0 (1 + u + v) < 2^(e0+2), so its rounding is 4 e(e0): 11 e(e0) in all.
      t2 = e + b v: 8 e(e0).
    - u t1 + v t2: u, v times those, at most 11 e(e0); and (uq - u) t1, (vq - v) t2 with
      |t1|, |t2| <= 2^(e0+1), r 2^(e0+1) = 4 e(e0) each: Phi at the start 19 e(e0).
    - The first difference P0 + Pu u + Pv v: e(e1) + 2 (e(e1) + 2^e1 r) = 7 e(e1); 2A e(e2).
      After i steps: i 7 e(e1) + i (i - 1) / 2 e(e2), i <= floor(W): a row has at most
      floor(W) + 1 pixel centres, W the widest chord.
    The products of two roundings are below a factor 1 + 2^-(m-3) of the sum. ``rs``: u and
    v off by rs r, not r (``errors``' ``recip``)."""
    eps = lambda x: 2.0 ** (x - m)
    with np.errstate(invalid="ignore"):
        n = np.floor(np.nan_to_num(width, nan=0.0, posinf=0.0))
    with np.errstate(invalid="ignore"):            # the terms in r are 12 e(e0), 4 e(e1)
        total = ((7 + 12 * rs) * eps(e0) + (3 + 4 * rs) * n * eps(e1)
                 + n * (n - 1) / 2 * eps(e2))
    return total * (1 + rs * 2.0 ** -(m - 3)) / VALUE.lsb


def additions(inputs, screen_bits, sub_bits, channels):
    """Per triangle drawn: K (above) and W; and the fragments, rows and triangles in."""
    x, y = R._vertices(inputs)
    tri, px, py = R.coverage(x, y, sub_bits, screen_bits)
    st = R.sorted_triangles(inputs, channels, sub_bits)
    with np.errstate(divide="ignore", invalid="ignore"):
        omega = q.omega(st["x1"], st["y1"], st["x2"], st["y2"])
        ux, uy, vx, vy = (st["y2"] / omega, -st["x2"] / omega, -st["y1"] / omega,
                          st["x1"] / omega)
        width = np.abs(omega) / st["y2"]
    first = np.r_[True, tri[1:] != tri[:-1]]
    start = np.maximum.accumulate(np.where(first, np.arange(len(tri)), 0))
    X, Y = (px - px[start]).astype(float), (py - py[start]).astype(float)
    k = (np.abs(ux[tri] * X) + np.abs(uy[tri] * Y) + np.abs(vx[tri] * X)
         + np.abs(vy[tri] * Y))
    per = np.zeros(len(ux))
    np.maximum.at(per, tri, k)
    drawn = np.unique(tri)
    rows = len(np.unique(tri.astype(np.int64) * (2 << screen_bits) + py))
    return per[drawn], width[drawn], len(tri), rows, len(st["x1"])


def blocks(inputs, m, screen_bits, sub_bits, modes, rate, recip=False):
    """The 18 x 18 blocks a raster needs to draw ``inputs`` at ``rate`` fragments a clock,
    counting block-clocks per triangle in: today (the setup's products that fit 18 x 18 one
    block-clock, the rest and every row product ``WIDE``), and with a narrow path (every
    setup product one, assumed: its exponents are not measured; a row's products one on a
    triangle whose derived bound at m bits is within half an LSB, ``WIDE`` passes on the
    others; ``recip``: u and v from the reciprocal, as :func:`errors`). Returns (narrow
    share of rows, blocks today, blocks with the path)."""
    from hdl.span_unit.plan import RasterPlan
    from hdl.span_unit.span import row_products
    plan = RasterPlan.from_params(screen_bits=screen_bits, sub_bits=sub_bits,
                                  channels=len(modes), modes=",".join(modes))
    setup, fits = plan.setup_products
    per_row = row_products(modes)
    tri, _, _, bnd = errors(inputs, m, screen_bits, sub_bits, modes, recip)
    x, y = R._vertices(inputs)
    _, _, py = R.coverage(x, y, sub_bits, screen_bits)
    rows = np.unique(tri.astype(np.int64) * (2 << screen_bits) + py) // (2 << screen_bits)
    n = len(x)
    narrow = bnd[rows] <= 0.5
    clocks = len(tri) / rate                                    # all triangles' share
    today = (n * (fits + WIDE * (setup - fits)) + len(rows) * per_row * WIDE) / clocks
    path = (n * setup + per_row * (narrow.sum() + WIDE * (~narrow).sum())) / clocks
    return narrow.mean(), int(np.ceil(today)), int(np.ceil(path))


def built_share(inputs, m, screen_bits, sub_bits, modes):
    """The narrow engine's share of the triangles drawn and of their rows
    (:func:`narrow_triangles`)."""
    x, y = R._vertices(inputs)
    tri, _, py = R.coverage(x, y, sub_bits, screen_bits)
    ok = narrow_triangles(inputs, m, screen_bits, sub_bits, modes)
    drawn = np.unique(tri)
    rows = np.unique(tri.astype(np.int64) * (2 << screen_bits) + py) // (2 << screen_bits)
    return ok[drawn].mean(), ok[rows].mean()


def narrow_triangles(inputs, m, screen_bits, sub_bits, modes):
    """The narrow engine as built (``span.row_engine(narrow=m)``): per triangle in, whether
    the setup chooses it (``golden.bfp.choice``: its derived bound, with the setup's own
    terms, within the raster's budget, from the bit lengths of its constants, of |Omega| and
    of y2), here from the float model's constants at the setup's 28 fraction bits."""
    from hdl.setup_unit.choice import choice_tables
    from hdl.setup_unit.setup import Widths
    FO = Widths.FO
    st = R.sorted_triangles(inputs, len(modes), sub_bits)
    with np.errstate(divide="ignore", invalid="ignore"):
        omega = q.omega(st["x1"], st["y1"], st["x2"], st["y2"])
        ux, vx = st["y2"] / omega, -st["y1"] / omega
        log2 = lambda v: np.floor(np.log2(np.maximum(np.abs(v), 1)))
        kn = np.clip(log2(omega) + 1 - log2(st["y2"]) - sub_bits, 0, screen_bits)
    kn = np.nan_to_num(kn).astype(int)
    ok = np.ones(len(omega), bool)
    for ch, mode in enumerate(modes):
        I = [st["values"][ch][:, k] for k in range(3)]
        a, b, c, d, e, _ = R.channel_uv(mode, I, st["e"]).T
        with np.errstate(invalid="ignore"):
            Pu, Pv = 2 * a * ux + c * vx, 2 * b * vx + c * ux
        start, steps, own = choice_tables(m, 2 * screen_bits + 20, FO, screen_bits, 7.2e-9,
                                          mode == "linear")
        with np.errstate(invalid="ignore"):       # culled triangles' NaN: never chosen
            s0, s1 = ((np.nan_to_num(_exp(*g)) + FO - (m - 1)).clip(0, None).astype(int)
                      for g in ((a, b, c, d, e), (Pu, Pv)))
        total = np.take(start, s0.clip(0, len(start) - 1)) + np.take(own, kn)
        if mode != "linear":
            total = total + np.take(steps, (s1 + kn).clip(0, len(steps) - 1))
        ok &= total <= 64
    return ok


def recip_seed_slope(t, s_bits, g_bits, m_bits=24, d_bits=18):
    """1/x for a mantissa x in [1, 2) from a table of 2^t words and one product, as issue 66
    asks of the narrow raster (pico-gs's ``raster_recip_area``): the top t fraction bits of x
    pick the word, the seed s (``s_bits`` fraction bits) and slope g (``g_bits``) of the
    minimax line of 1/x on that interval [a, a + 2^-t), and r = s - g d, d = x - a floored to
    ``d_bits`` below 2^-t (one 18 x 18 product). Returns (the largest |r x - 1| over every
    ``m_bits``-bit mantissa, its derived bound): the line's own error h^2 / 8 (h = 2^-t, the
    chord's h^2 f''/8 halved by the shift), the seed's rounding 2^-(s_bits+1), the slope's
    2^-(g_bits+1) times d < h, d's floor 2^-(t+d_bits), each doubled to a relative error
    (x < 2)."""
    n = np.arange(1 << (m_bits - 1), 1 << m_bits, dtype=np.int64)
    x = n / 2.0 ** (m_bits - 1)
    i = (n >> (m_bits - 1 - t)) & ((1 << t) - 1)
    a = 1 + np.arange(1 << t) / 2.0 ** t
    g = 1 / (a * (a + 2.0 ** -t))                         # the chord's slope, |f'| between
    mid = np.sqrt(a * (a + 2.0 ** -t))                    # where the chord is furthest above
    seed = 1 / a - ((1 / a - g * (mid - a)) - 1 / mid) / 2
    sq = np.rint(seed * 2.0 ** s_bits) / 2.0 ** s_bits
    gq = np.rint(g * 2.0 ** g_bits) / 2.0 ** g_bits
    d = np.floor((x - a[i]) * 2.0 ** (t + d_bits)) / 2.0 ** (t + d_bits)
    err = np.abs((sq[i] - gq[i] * d) * x - 1).max()
    bound = 2.0 ** -(2 * t + 3) + 2 * (2.0 ** -(s_bits + 1) + 2.0 ** -(g_bits + 1 + t)
                                       + 2.0 ** -(t + d_bits))
    return float(err), bound


def _scene_inputs(name, segments):
    scene = S.load(SCENES / f"{name}.toml")
    if segments:
        scene["mesh"]["segments"] = segments
    prep = S.prepare(scene)
    p = prep["pipeline"].raster.params
    return prep["inputs"], p["screen_bits"], p["sub_bits"], parse_modes(p["modes"],
                                                                         p["channels"])


def main():
    cases = [(label, *_scene_inputs(name, seg)) for label, name, seg in MESHES]
    for bits in (8, 10):               # random triangles as the raster's tests draw them
        rand = random_triangles(np.random.default_rng(49), 3000, screen_bits=bits,
                                sub_bits=4, channels=2, size=TYPICAL_SIZE)
        cases.append((f"random, {1 << bits} x {1 << bits} (golden.random_triangles)", rand,
                      bits, 4, ("xshading", "xshading")))
        big = random_triangles(np.random.default_rng(50), 300, screen_bits=bits, sub_bits=4,
                               channels=2)
        cases.append((f"random screen-sized, {1 << bits} x {1 << bits}", big, bits, 4,
                      ("xshading", "xshading")))
    print("| triangles | drawn | W < 1 (slivers) | "
          + " | ".join(f"{m} bits: max error (LSB), narrow path" for m in MANTISSAS)
          + " | worst error / bound |")
    print("| --- | --- | --- | " + " | ".join("---" for _ in MANTISSAS) + " | --- |")
    for label, inputs, sb, sub, modes in cases:
        cells, ratio = [], 0.0
        for m in MANTISSAS:
            tri, err, width, bnd = errors(inputs, m, sb, sub, modes)
            drawn = np.unique(tri)
            narrow = (bnd[drawn] <= 0.5).mean() * 100     # the arithmetic's half LSB
            cells.append(f"{err.max():.3g}, {narrow:.1f} %")
            ratio = max(ratio, (err / np.maximum(bnd[tri], 1e-300)).max())
        slivers = f"{(width[drawn] < 1).mean() * 100:.1f} %"
        print(f"| {label} | {len(drawn):,} | {slivers} | " + " | ".join(cells)
              + f" | {ratio:.3f} |")
    print("\n| triangles | " + " | ".join(f"narrow engine, M = {m}: triangles, rows"
                                       for m in BUILT) + " |")
    print("| --- | " + " | ".join("---" for _ in BUILT) + " |")
    for label, inputs, sb, sub, modes in cases:
        got = [built_share(inputs, m, sb, sub, modes) for m in BUILT]
        print(f"| {label} | " + " | ".join(f"{t * 100:.1f} %, {r * 100:.1f} %" for t, r in got)
              + " |", flush=True)
    narrow = ((18, False), (20, False), (20, True), (22, True))
    print("\n| mesh | target (fragments / clock) | MULT18X18D today | "
          + " | ".join(f"{m} bits{', u and v from 1/Omega' if r else ''}: rows on the narrow "
                       f"path, MULT18X18D" for m, r in narrow) + " |")
    print("| --- | --- | --- | " + " | ".join("---" for _ in narrow) + " |")
    for label, inputs, sb, sub, modes in cases[:len(MESHES)]:
        got = [blocks(inputs, m, sb, sub, modes, TARGETS[label], r) for m, r in narrow]
        print(f"| {label} | {TARGETS[label]} | {got[0][1]} | "
              + " | ".join(f"{s * 100:.1f} %, {b}" for s, _, b in got) + " |")
    print("\n| reciprocal: table words (DP16KD) | seed, slope bits | max relative error, every "
          "24-bit mantissa | derived bound |")
    print("| --- | --- | --- | --- |")
    for t, sb, gb in ((8, 22, 14), (9, 22, 14), (10, 23, 13)):
        err, bnd = recip_seed_slope(t, sb, gb)
        print(f"| {1 << t} x 36 ({max(1, (1 << t) // 512)}) | {sb}, {gb} | 2^{np.log2(err):.2f} "
              f"| 2^{np.log2(bnd):.2f} |")
    print("\n| triangles | in | fragments / triangle in | rows / triangle in | K median | "
          "K p99 | K max | K > 64 |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for label, inputs, sb, sub, modes in cases:
        k, _, frags, rows, n = additions(inputs, sb, sub, len(modes))
        print(f"| {label} | {n:,} | {frags / n:.1f} | {rows / n:.2f} | {np.median(k):.1f} | "
              f"{np.percentile(k, 99):.0f} | {k.max():.0f} | {(k > 64).mean() * 100:.1f} % |")


if __name__ == "__main__":
    main()
