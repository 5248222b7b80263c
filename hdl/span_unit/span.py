"""The span engine (seeds 000, 001): edge walking, span-start evaluation, forward differences.

Three parts, each a stream stage with backpressure:

- ``walker``: holds one triangle from the setup unit and emits one row per clock, from the
  first row whose centre is at or below the top vertex to the last one above the bottom vertex
  (clipped to the screen). Each edge is a DDA in exact integers: column ``i = ceil(x / S -
  1/2)`` of the edge's crossing and the remainder ``r = i den - num``; a row step adds the
  quotient and remainder of ``2 S dx / (2 S dy)`` and carries once. The long edge runs top to
  bottom; the short one top to middle, then middle to bottom from the middle vertex's row.
  Columns ``[left, right)`` are the pixels whose centres lie inside (top-left rule).
- ``row_eval`` (pipelined): at the span's first pixel centre, the exact numerators
  nu = X y2 - Y x2, nv = Y x1 - X y1 (eq 18-20, sub-pixel units) times the reciprocal give
  (u, v); then per channel Phi(u, v) (eq 17) and its first difference along x,
  alpha_u dPhi/du + alpha_v dPhi/dv + A. The start is corrected for the sub-pixel position by
  construction, and rounding never accumulates across rows.
- ``stepper``: one fragment per clock, two additions per quadratic channel per pixel:
  Phi += d, d += 2A (one for a linear channel, whose 2A is 0).
"""
from amaranth.hdl import Mux, Signal

from ..setup_unit.formats import VALUE

__all__ = ["Link", "walker", "row_eval", "stepper"]


class Link:
    """The handshake of an internal stream (valid/ready), for :class:`hdl.unit.Pipeline`."""

    def __init__(self, name):
        self.valid = Signal(name=f"{name}_valid")
        self.ready = Signal(name=f"{name}_ready")


def _step(i, r, q, d, n):
    """One row of an edge DDA: (i + q, r - d), carrying once when r - d < 0."""
    rr = r - d
    return Mux(rr < 0, i + q + 1, i + q), Mux(rr < 0, rr + n, rr)


TRIANGLE_KEEP = ("tri", "xt", "yt", "x1", "y1", "x2", "y2", "r", "sh", "neg", "au", "av")


def walker(m, w, channels, src, src_valid, src_ready, out_link, culled):
    """Rows from triangles. ``src``: the setup unit's output values; returns the row values."""
    size = 1 << w.screen_bits
    have = Signal()
    j, j1, jm = Signal(w.wrow), Signal(w.wrow), Signal(w.wrow)
    left_long = Signal()
    keep = list(TRIANGLE_KEEP) + [f"c{ch}_{k}" for ch in range(channels)
                                  for k in ("a", "b", "c", "d", "e", "f", "a2")]
    held = {k: Signal.like(src[k], name=f"w_{k}") for k in keep}
    edge = {}
    for e in ("l", "s", "t"):
        edge[e] = {k: Signal.like(src[f"{e}_{k}"], name=f"w_{e}_{k}") for k in "irqdn"}
    accept = have & out_link.ready
    last = j + 1 == j1
    load = src_valid & (~have | (accept & last))
    m.d.comb += [src_ready.eq(~have | (accept & last)), out_link.valid.eq(have)]

    def init(e):     # the walker's remainder i den - num from the setup's floor remainder
        return {"i": src[f"{e}_i"], "r": src[f"{e}_n"] - 1 - src[f"{e}_r"],
                "q": src[f"{e}_q"], "d": src[f"{e}_d"], "n": src[f"{e}_n"]}

    with m.If(load):
        rows = ~src["cull"] & (src["j0"] < src["j1"])
        m.d.sync += [have.eq(rows), j.eq(src["j0"]), j1.eq(src["j1"]), jm.eq(src["jm"]),
                     left_long.eq(src["left_long"])]
        m.d.sync += [held[k].eq(src[k]) for k in keep]
        first_short = Mux(src["j0"] >= src["jm"], 1, 0)
        for e in ("l", "t"):
            m.d.sync += [edge[e][k].eq(val) for k, val in init(e).items()]
        s_init, t_init = init("s"), init("t")
        m.d.sync += [edge["s"][k].eq(Mux(first_short, t_init[k], s_init[k])) for k in "irqdn"]
        with m.If(src["cull"]):
            m.d.sync += culled.eq(culled + 1)
    with m.Elif(accept):
        m.d.sync += j.eq(j + 1)
        with m.If(last):
            m.d.sync += have.eq(0)
        li, lr = _step(*(edge["l"][k] for k in "irqdn"))
        m.d.sync += [edge["l"]["i"].eq(li), edge["l"]["r"].eq(lr)]
        si, sr = _step(*(edge["s"][k] for k in "irqdn"))
        with m.If(j + 1 == jm):
            m.d.sync += [edge["s"][k].eq(edge["t"][k]) for k in "irqdn"]
        with m.Else():
            m.d.sync += [edge["s"]["i"].eq(si), edge["s"]["r"].eq(sr)]
    clamp = lambda i: Mux(i < 0, 0, Mux(i > size, size, i))
    xl = Mux(left_long, edge["l"]["i"], edge["s"]["i"])
    xr = Mux(left_long, edge["s"]["i"], edge["l"]["i"])
    return {"j": j, "xs": clamp(xl), "xe": clamp(xr), **held}


def row_eval(p, w, channels, v):
    """Phi and its first difference at each span's first pixel centre (pipelined)."""
    S = 1 << w.sub_bits
    v = dict(v)
    X = v["xs"] * S + S // 2 - v.pop("xt")
    Y = v["j"] * S + S // 2 - v.pop("yt")
    x1, y1, x2, y2 = (v.pop(k) for k in ("x1", "y1", "x2", "y2"))
    v = p.stage(v, nu=X * y2 - Y * x2, nv=Y * x1 - X * y1)
    neg, r, sh = v.pop("neg"), v.pop("r"), v.pop("sh")
    nu, nv = v.pop("nu"), v.pop("nv")
    v = p.stage(v, su=Mux(neg, -(nu * r), nu * r) >> sh, sv=Mux(neg, -(nv * r), nv * r) >> sh)
    cu = w.FC + w.R - w.FI                     # coefficient x u -> FI fraction bits
    up = w.FI - w.FC
    new = {}
    for ch in range(channels):
        a, b, c = (v[f"c{ch}_{k}"] for k in "abc")
        new.update({f"_au{ch}": (a * v["su"]) >> cu, f"_cv{ch}": (c * v["sv"]) >> cu,
                    f"_bv{ch}": (b * v["sv"]) >> cu, f"_cu{ch}": (c * v["su"]) >> cu})
    v = p.stage(v, **new)
    new = {}
    for ch in range(channels):
        for k in ("a", "b", "c"):
            v.pop(f"c{ch}_{k}")
        au, cv, bv, cu_ = (v.pop(f"_{k}{ch}") for k in ("au", "cv", "bv", "cu"))
        d, e = v.pop(f"c{ch}_d") << up, v.pop(f"c{ch}_e") << up
        new.update({f"_pu{ch}": 2 * au + cv + d, f"_pv{ch}": 2 * bv + cu_ + e,
                    f"_t1{ch}": d + au + cv, f"_t2{ch}": e + bv})
    v = p.stage(v, **new)
    new = {}
    for ch in range(channels):
        new.update({f"_ut{ch}": (v["su"] * v.pop(f"_t1{ch}")) >> w.R,
                    f"_vt{ch}": (v["sv"] * v.pop(f"_t2{ch}")) >> w.R,
                    f"_dpu{ch}": (v["au"] * v.pop(f"_pu{ch}")) >> w.FA,
                    f"_dpv{ch}": (v["av"] * v.pop(f"_pv{ch}")) >> w.FA})
    v.pop("su"), v.pop("sv")
    v = p.stage(v, **new)
    new = {}
    for ch in range(channels):
        new[f"phi{ch}"] = (v.pop(f"c{ch}_f") << up) + v.pop(f"_ut{ch}") + v.pop(f"_vt{ch}")
        new[f"d{ch}"] = v.pop(f"_dpu{ch}") + v.pop(f"_dpv{ch}") + (v[f"c{ch}_a2"] >> 1)
    v.pop("au"), v.pop("av")
    return p.stage(v, **new)


ROW_EVAL_STAGES = 6


def stepper(m, w, channels, rows, row_link, o):
    """One fragment per clock from the rows: Phi += d, d += 2A per pixel and channel."""
    acc_bits = w.FI + 16                       # Phi and d wrap modulo 2**acc_bits: only
    cur = Signal()                              # emitted values must fit, and they do
    x, xe, y = Signal(w.screen_bits + 1), Signal(w.screen_bits + 1), Signal(w.screen_bits)
    tri = Signal.like(rows["tri"], name="st_tri")
    phi = [Signal(acc_bits, name=f"st_phi{ch}") for ch in range(channels)]
    d = [Signal(acc_bits, name=f"st_d{ch}") for ch in range(channels)]
    a2 = [Signal(acc_bits, name=f"st_a2_{ch}") for ch in range(channels)]
    last = x + 1 == xe
    take = ~cur | (o.ready & last)
    m.d.comb += [row_link.ready.eq(take), o.valid.eq(cur)]
    with m.If(take & row_link.valid):
        m.d.sync += [cur.eq(rows["xs"] < rows["xe"]), x.eq(rows["xs"]), xe.eq(rows["xe"]),
                     y.eq(rows["j"]), tri.eq(rows["tri"])]
        for ch in range(channels):
            m.d.sync += [phi[ch].eq(rows[f"phi{ch}"]), d[ch].eq(rows[f"d{ch}"]),
                         a2[ch].eq(rows[f"c{ch}_a2"])]
    with m.Elif(cur & o.ready):
        with m.If(last):
            m.d.sync += cur.eq(0)
        m.d.sync += x.eq(x + 1)
        for ch in range(channels):
            m.d.sync += [phi[ch].eq(phi[ch] + d[ch]), d[ch].eq(d[ch] + a2[ch])]
    shift = w.FI - VALUE.frac_bits
    m.d.comb += [o.payload["tri"].eq(tri), o.payload["x"].eq(x), o.payload["y"].eq(y)]
    for ch in range(channels):
        val = (phi[ch].as_signed() + (1 << (shift - 1))) >> shift
        m.d.comb += o.payload[f"v{ch}"].eq(Mux(val > VALUE.max, VALUE.max,
                                               Mux(val < VALUE.min, VALUE.min, val)))
    return cur
