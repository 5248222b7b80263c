"""Triangle setup (seeds 001, 002) as a schedule on one shared multiplier (``hdl.sched``).

sort by (y, x) -> relative coordinates (seed 002 eq 9-12) -> Omega = x1 y2 - x2 y1 (eq 47),
orientation, cull of Omega = 0 -> the reciprocal of |Omega| (normalised mantissa, Newton-Raphson
or a divider) -> per channel the ortho-normalised coefficients a..f (seed 001 eq 16/32, seed 000
eq 24-26) -> alpha_u, alpha_v per pixel step (eq 20) and, per channel, the constants of the
span's first difference -> the edge walkers' DDAs (six floor divisions, one bit per clock) and
the exact integer numerators of (u, v) at the first row of each left edge and of the screen's
left border, and their steps per row.

The row engine (``hdl.span_unit.span``) turns a row's numerators into (u, v) with one product
each, and Phi and its first difference from them. Why these widths: ``Widths`` and
docs/quadratic.md.
"""
from dataclasses import dataclass

from amaranth.hdl import Const, signed

from .. import arith
from ..fixed import Field, s, u
from ..sched import OPERAND, Schedule, _or_tree
from ..term import Cat, Mux, Term, term
from .formats import EXACT_G_MAX, VALUE, coord, edge_names, parse_groups, parse_modes

RSQRT_ITERS = 2    # Newton-Raphson steps of the exact mid-edges' 1/sqrt (seed error 2**-9)
G_FRAC = 30        # fraction bits of g = 1/||Ni + Nj|| while it is computed (27 kept)

__all__ = ["Widths", "Setup"]


def _or(values):
    out = values[0]
    for x in values[1:]:
        out = out | x
    return out


def _and(values):
    out = values[0]
    for x in values[1:]:
        out = out & x
    return out


def _halves(a, b):
    """``a < b`` and ``a == b`` of each half (the high one by its sign): two short carry
    chains in place of one long one."""
    h = len(a) // 2
    hi = lambda x: x[h:].as_signed() if x.shape().signed else x[h:]
    return {"lt_hi": hi(a) < hi(b), "eq_hi": hi(a) == hi(b), "lt_lo": a[:h] < b[:h],
            "eq_lo": a[:h] == b[:h]}


@dataclass(frozen=True)
class Widths:
    """Fraction bits, derived in docs/quadratic.md ("Widths from analysis") for spans of up to
    2**screen_bits pixels and an internal error of at most half an output LSB (2**-15).
    Multiplier operands are 35-bit signed (two 18 x 18 slices each way)."""
    screen_bits: int
    sub_bits: int
    R: int = 28        # reciprocal mantissa (1/m in (1/2, 1])
    FC: int = 29       # coefficients a..f, exact (products of VALUE and EDGE: 14 + 15)
    FO: int = 28       # a..f, Pu, Pv, t as operands: s(35, 28), [-64, 64)
    FA: int = 34       # alpha_u, alpha_v per pixel as operands: s(35, 34), saturated to [-1, 1)
    FQ: int = 32       # u, v at a span's start as operands: s(35, 32), modulo 4
    FT: int = 27       # t1 = d + a u + c v and t2 = e + b v as operands: s(35, 27)

    @property
    def FI(self):                      # Phi, its first difference and 2A in the stepper
        return 2 * self.screen_bits + 20

    def fi(self, precision):
        """FI for a channel rounded to ``precision`` fraction bits (FI at VALUE's 14): the
        row queue and the stepper keep Phi, d and 2A floored to it, 2 screen_bits + p + 6
        bits, which adds at most 2**-(p + 6) over a span of 2**screen_bits pixels
        (docs/quadratic.md "A channel's precision")."""
        return self.FI - (VALUE.frac_bits - precision)

    def acc(self, precision):
        """The bits the stepper keeps of Phi, d and 2A at :meth:`fi`: it steps them modulo
        2**acc, as only emitted values must fit (|Phi| < 128: 7 bits and a sign, and one for
        the rounding half); so the row engine and its queue keep no more."""
        return self.fi(precision) + 9

    @property
    def wc(self):                      # vertex coordinate width (sub-pixel units)
        return self.screen_bits + 2 + self.sub_bits

    @property
    def wrel(self):                    # relative coordinates
        return self.wc + 1

    @property
    def womega(self):                  # |Omega|, sub-pixel units squared
        return 2 * self.wrel

    @property
    def wpos(self):                    # offsets of pixel centres from the top vertex (X, Y),
        # the edges' numerator factors and row steps in sub-pixel units: |x| < 2**(wc + 1)
        return self.wc + 2             # (so at every screen a product of two is 18 x 18)

    @property
    def wn(self):                      # (u, v) numerators, tracked modulo 2**wn
        return 2 * self.wrel + 2

    @property
    def wi(self):                      # an edge's pixel column (signed, within +-2**(sb+2))
        return self.screen_bits + 4

    @property
    def wden(self):                    # 2 S dy
        return self.wrel + self.sub_bits + 1

    @property
    def qstep(self):                   # |floor(dx / dy)| bits
        return self.wrel + 1

    @property
    def wrow(self):
        return self.screen_bits + 1


def operand(frac):
    return s(OPERAND, frac)


EDGES = ("l", "s", "t")   # the long edge (top-bottom), the short ones (top-mid, mid-bottom)
TRACKS = ("e0", "s0", "s1", "e1", "t0", "t1", "b0", "bs")   # numerator pairs, see Setup


def channel_fields(w, ch):
    """Per channel: a..f, Pu, Pv (operands), P0 and 2A (FI fraction bits)."""
    f = [Field(f"c{ch}_{k}", operand(w.FO)) for k in ("a", "b", "c", "d", "e", "f", "pu", "pv")]
    return f + [Field(f"c{ch}_{k}", s(w.FI + 9, w.FI)) for k in ("p0", "a2")]


class Setup:
    """The setup program; ``Raster`` runs it (``program``) on its own schedule."""

    def __init__(self, screen_bits, sub_bits, channels, modes, recip, recip_iters, groups="0",
                 narrow=0):
        self.w = Widths(screen_bits, sub_bits)
        self.channels = channels
        self.modes = parse_modes(modes, channels)
        self.groups = parse_groups(groups, channels)
        self.recip, self.recip_iters = recip, recip_iters
        self.narrow = narrow       # the narrow row engine's mantissa bits (0: none)

    def sort(self, sc, v):
        """Ranks by (y, x, index) (registered) -> vertices top/mid/bottom, edges and values in
        sorted labels."""
        x = [v.pop(f"x{k}") for k in range(3)]
        y = [v.pop(f"y{k}") for k in range(3)]

        # Vertex a before b (a < b): y_a < y_b, or equal y and x_a <= x_b (the index breaks
        # ties); b before a is the complement. Each compare is split into its two halves,
        # registered alone next to their short carry chains; "a before b" from them a clock
        # later, and the ranks a clock after that.
        pairs = ((0, 1), (0, 2), (1, 2))
        cmp = sc.lets(**{f"{n}{a}{b}_{k}": val for a, b in pairs
                         for n, val in (("y", _halves(y[a], y[b])), ("x", _halves(x[a], x[b])))
                         for k, val in val.items()})
        lt = {}
        for a, b in pairs:
            c = {f"{n}{k}": cmp[f"{n}{a}{b}_{k}"] for n in "xy"
                 for k in ("lt_hi", "eq_hi", "lt_lo", "eq_lo")}
            ylt = c["ylt_hi"] | (c["yeq_hi"] & c["ylt_lo"])
            yeq = c["yeq_hi"] & c["yeq_lo"]
            xle = c["xlt_hi"] | (c["xeq_hi"] & (c["xlt_lo"] | c["xeq_lo"]))
            lt[a, b] = sc.let(f"lt{a}{b}", ylt | (yeq & xle))
            lt[b, a] = ~lt[a, b]
        rank = sc.lets(**{f"rank{k}": sum((lt[o, k] for o in range(3) if o != k),
                                              term(Const(0, 2)))
                          for k in range(3)})
        rank = [rank[f"rank{k}"] for k in range(3)]

        def pick(slot, vals):
            out = vals[2]
            for k in (1, 0):
                hit = ~rank[k].any() if slot == 0 else rank[k] == slot   # no "x == 0": lint
                out = Mux(hit, vals[k], out)
            return out
        out = {f"{n}{slot}": pick(slot, vals) for slot in range(3)
               for n, vals in (("x", x), ("y", y))}
        for g in range(max(self.groups) + 1):
            e01, e02, e12 = edge_names(g)
            opp = [v.pop(e12), v.pop(e02), v.pop(e01)]          # the edge opposite vertex k
            sfx = e01[3:]
            out.update({f"e12{sfx}": pick(2, opp), f"e13{sfx}": pick(1, opp),
                        f"e23{sfx}": pick(0, opp)})
        for ch in range(self.channels):
            vals = [v.pop(f"v{ch}_{k}") for k in range(3)]
            out.update({f"i{ch}_{slot}": pick(slot, vals) for slot in range(3)})
        return out

    def rows(self, y):
        """ceil(y / S - 1/2): the first row whose centre is at or below y (exact shifts)."""
        S = 1 << self.w.sub_bits
        return (2 * y + S - 1) >> (self.w.sub_bits + 1)

    def program(self, sc, v, in_turn=False):
        """The setup of one triangle on schedule ``sc`` from the input registers ``v``;
        returns the walker's values (registers). ``in_turn``: the channels are left to
        :meth:`channel_job` (``setup_engine.channel_engine``); instead of their constants, the values
        its jobs read: each channel's sorted ``i{ch}_0..2``, each group's ``e12 e13 e23``, and
        ``au``, ``av``."""
        w, S = self.w, 1 << self.w.sub_bits
        size = 1 << w.screen_bits
        pos = lambda x: x[:w.wpos].as_signed()                         # see Widths.wpos
        tri = v["tri"]
        v = sc.lets(**self.sort(sc, dict(v)))                                       # sort
        xt, yt = v["x0"], v["y0"]
        clamp = lambda j: Mux(j < 0, 0, Mux(j > size, size, j))
        j = sc.lets(**{f"_j{k}": self.rows(v[f"y{k}"]) for k in range(3)})
        j = sc.lets(**{f"j{k}": clamp(j[f"_j{k}"]) for k in range(3)})
        r = sc.lets(x1=v["x1"] - xt, y1=v["y1"] - yt, x2=v["x2"] - xt, y2=v["y2"] - yt,
                    j0=j["j0"], jm=j["j1"], j1=j["j2"])   # sorted by y, and rows() and
        # the clamp are monotonic: j0 <= j1 <= j2, the middle vertex's row is the middle one
        x1, y1, x2, y2 = r["x1"], r["y1"], r["x2"], r["y2"]
        out = {"tri": tri, "xt": xt, "yt": yt, "j0": r["j0"]}
        # the walker counts down the rows after its current one to j1 and to jm; it starts
        # from these, and from their tests for zero (its first row is the last, or jm's)
        left = sc.lets(to_j1=r["j1"] - r["j0"] - 1, to_jm=r["jm"] - r["j0"] - 1)
        out.update(left, **sc.lets(last0=~left["to_j1"].any(), at_jm0=~left["to_jm"].any()))
        om = sc.let("omega", sc.mul("x1y2", x1, y2) - sc.mul("x2y1", x2, y1))
        # each edge's first column: ceil(((2 px - S) dy + (2 S j + S - 2 py) dx) / (2 S dy))
        # (the row's crossing minus half a pixel), a floor division of num + den - 1
        ends = {"l": ("x0", "y0", "x2", "y2", "j0"), "s": ("x0", "y0", "x1", "y1", "j0"),
                "t": ("x1", "y1", "x2", "y2", "jm")}
        div_jobs = []
        for e, (px, py, qx, qy, j) in ends.items():
            d = sc.lets(**{f"{e}_dx": v[qx] - v[px], f"{e}_dy": v[qy] - v[py]})
            dx, dy = d[f"{e}_dx"], d[f"{e}_dy"]
            den = sc.let(f"{e}_n", Mux(dy.any(), 2 * S * dy, 1)[:w.wden])
            fac = sc.lets(**{f"{e}_fx": pos(2 * v[px] - S), f"{e}_fy": pos(2 * S * r[j] + S
                                                                             - 2 * v[py])})
            # two sums of two operands, each in a clock of its own: the three in one, after
            # the route from a pooled product copy, closed at 118.7 MHz (setup_ii=24)
            part = sc.let(f"{e}_nd", sc.mul(f"{e}_ndy", fac[f"{e}_fx"], dy)
                          + sc.let(f"{e}_n1", den - 1))
            num = sc.let(f"{e}_num", part + sc.mul(f"{e}_ndx", fac[f"{e}_fy"], dx))
            div_jobs += [(e, "i", num, den, w.wi - 1), (e, "q", 2 * S * dx, den, w.qstep)]
            out[f"{e}_n"] = den
        # orientation, cull, |Omega| normalised: n in [2**(W-1), 2**W) and sh
        W = w.womega
        flags = sc.lets(cull=~om.any(), neg=om < 0, left_long=om > 0, mag=abs(om)[:W])
        out.update(cull=flags["cull"], left_long=flags["left_long"],
                   # the walker has rows to walk: registered here, not compared on its load
                   rows=sc.let("rows", ~flags["cull"] & (r["j0"] < r["j1"])))
        norm = sc.lets(sh=Term.call(arith.leading_one, flags["mag"], W))
        norm["lz"] = sc.let("lz", W - 1 - norm["sh"], shape=range(W))
        sh = norm["sh"]
        sc.shift = self.shift(sh)
        n = sc.let("n", (flags["mag"] << norm["lz"])[:W])
        rcp = self._reciprocal(sc, n, W)
        rs = sc.let("rs", Mux(flags["neg"], -rcp, rcp))           # the sign of 1/Omega in it
        out.update(rs=rs, sh=sh)
        if self.narrow:
            out.update(self._narrow_triangle(sc, rcp, flags["neg"], sh, y2))
        for e, kind, num, den, bits in div_jobs:
            q, rem = self._floor_divide(sc, f"{e}_{kind}", num, den, bits)
            out[f"{e}_{kind}"] = q
            out[f"{e}_{'r' if kind == 'i' else 'd'}"] = rem
        for e in EDGES:      # the walker's start values (it holds r - d and n - d: span.py)
            n, rem, d = out[f"{e}_n"], out[f"{e}_r"], out[f"{e}_d"]
            n0 = out[f"{e}_n0"] = sc.let(f"{e}_n0", n - d)
            # n - 1 - rem - d = n0 + ~rem (-1 - rem = ~rem): two operands, not three
            out[f"{e}_r0"] = sc.let(f"{e}_r0", n0 + ~Cat(rem, Const(0, 1)).as_signed())
        # alpha per pixel step: S y2 / Omega, -S y1 / Omega (eq 20), s(35, 34) saturated;
        # with the channels in turn, ahead of the tracks, for the channels' jobs to start
        lo, hi = -(1 << w.FA), (1 << w.FA) - 1
        if not in_turn:
            out.update(self._tracks(sc, r, out, xt, yt))
        # the saturation's compares (46-bit carry chains), then its multiplexer, each in a
        # clock of its own: both in one, after the route from a shared product copy, closed
        # at 107 MHz
        raw = {k: sc.mul(f"{k}_raw", val, rs, shifted=True) for k, val in (("au", y2),
                                                                          ("av", -y1))}
        over = sc.lets(**{f"{k}_{n}": test for k, x in raw.items()
                          for n, test in (("hi", x > hi), ("lo", x < lo))})
        alpha = {k: sc.let(k, Mux(over[f"{k}_hi"], hi, Mux(over[f"{k}_lo"], lo, x))
                           .as_signed()[:OPERAND].as_signed(), after=sc.when(*over.values()))
                 for k, x in raw.items()}
        if in_turn:
            out.update(self._tracks(sc, r, out, xt, yt))
            return {**out, **{k: {**v, **alpha}[k] for k in self.job_inputs}}
        g = self._exact_mid_edges(sc, v) if "exact" in self.modes else {}
        oks = []
        for ch, mode in enumerate(self.modes):
            coef = self._channel(sc, v, g, ch, mode)
            span = self._span(sc, coef, alpha, ch, mode == "linear")
            out.update({f"c{ch}_{k}": val for k, val in span.items()})
            if self.narrow:
                fields, ok = self._narrow_channel(sc, span, ch, mode == "linear", out["kn"])
                out.update(fields)
                oks.append(ok)
        if self.narrow:                 # the narrow engine holds every channel's bound
            out["narrow"] = sc.let("narrow", _and(oks))
            del out["kn"]
        return out

    @property
    def job_inputs(self):
        """What :meth:`channel_job`'s jobs read of ``program(..., in_turn=True)``'s values."""
        return (["au", "av"] + [f"i{ch}_{k}" for ch in range(self.channels) for k in range(3)]
                + [f"{e}{self.suffix(ch)}" for ch in range(self.channels)
                   for e in ("e12", "e13", "e23")])

    def suffix(self, ch):
        """The suffix of channel ``ch``'s group's edge constants."""
        return edge_names(self.groups[ch])[0][3:]

    def channel_job(self, sc, v):
        """One channel's constants on a schedule of its own (``setup_engine.channel_engine``: the
        channels in turn): a..f by X-shading (seed 001 eq 32), then the span's constants
        (eq 22), from the job's inputs: ``i0_0..2``, the edge constants of channel 0's group's
        names (0 for a linear channel: then a = b = c = 0 and every other sum is a linear
        channel's, bit for bit) and ``au``, ``av``."""
        return self._span(sc, self._channel(sc, v, {}, 0, "xshading"), v, 0, False)

    def _narrow_triangle(self, sc, rcp, neg, sh, y2):
        """The narrow row engine's reciprocal ``rsm`` (``golden.bfp.rs_mantissa``: 1/m to
        M - 1 fraction bits, rounded, saturated, signed) and ``kn``, a bound on the steps
        along a span: |Omega| < 2**(sh+1) and y2 >= 2**ly, so the widest chord is below
        2**(sh+1-ly-sub_bits) pixels (``golden.bfp.choice``)."""
        M, R, w = self.narrow, self.w.R, self.w
        top = (1 << (M - 1)) - 1
        q = sc.let("rsm_q", (rcp + (1 << (R - M))) >> (R - M + 1))
        mag = sc.let("rsm_mag", Mux(q > top, top, q)[:M - 1])
        rsm = sc.let("rsm", Mux(neg, -mag, mag), shape=signed(M))
        ly = sc.let("ly", Term.call(arith.leading_one, y2[:w.wrel], w.wrel))
        k = sc.let("kn_raw", sh + 1 - ly - w.sub_bits, shape=signed(8))
        kn = sc.let("kn", Mux(k < 0, 0, Mux(k > w.screen_bits, w.screen_bits, k)),
                    shape=range(w.screen_bits + 1))
        return {"rsm": rsm, "kn": kn}

    def _narrow_channel(self, sc, span, ch, linear, kn):
        """One channel's constants for the narrow row engine (issue 49's block floating
        point, ``golden.bfp``): the exponents of (a..e) and of (Pu, Pv) from the bit length of
        the OR of their one's-complement magnitudes (at least M - 1), the M-bit mantissas
        (each value times 2**(33 - s) on the setup's multiplier, then its top bits: x floored
        by s, the group's bit length less M - 1; a shifter each would cost 200 LUT4), the
        shifts of the engine's products into FI (``sphi``, ``sd``), and whether the channel's
        derived bound on this triangle is within the raster's budget: three small tables
        (its start, its steps, the setup's own terms) in 64ths of the budget, summed
        (``golden.bfp.choice``)."""
        from ..span_unit.span import narrow_left
        from .choice import choice_tables
        M, w, n = self.narrow, self.w, f"c{ch}"
        FO, W = w.FO, OPERAND
        group = ("d", "e") if linear else ("a", "b", "c", "d", "e")
        ones = lambda x: Mux(x[-1], ~x, x)                  # ~x for a negative x: |x| - 1
        bits = {}
        for g, names in (("0", group), ("1", () if linear else ("pu", "pv"))):
            if not names:
                continue
            top = sc.let(f"{n}_or{g}", _or([ones(span[k]).as_unsigned() for k in names]))
            # the bit length less M - 1, at least 0: only the bits from M - 1 up count, so
            # the leading one is found among those (a 35-bit chain of the search was the
            # narrow raster's critical path, 8.7 ns)
            high = top[M - 1:]
            pos = sc.let(f"{n}_lo{g}", Term.call(arith.leading_one, high, len(high)))
            s_ = sc.let(f"{n}_s{g}", Mux(high.any(), pos + 1, 0), shape=range(W - M + 2))
            bits[g] = s_
            scale = sc.let(f"{n}_p{g}", term(Const(1 << 33, signed(W))) >> s_)
            for k in names:
                bits[k] = sc.mul(f"{n}_n{k}", span[k], scale,
                                 post=lambda p: (p >> 33)[:M].as_signed())
        left = narrow_left(w, M)
        c_phi = left - w.FI + 2 * M + FO - (2 if linear else 4) - (M - 1)
        fields = {f"{n}_n{k}": bits[k] for k in group + (() if linear else ("pu", "pv"))}
        if linear:                              # a = b = c = 0: nothing stored or carried
            fields.update({f"{n}_n{k}": Const(0, 1) for k in ("a", "b", "c", "pu", "pv")},
                          **{f"{n}_sd": Const(0, 1)})
        fields[f"{n}_sphi"] = sc.let(f"{n}_sphi", (c_phi - bits["0"])[:6], shape=6)
        if not linear:
            c_d = left - w.FI + 2 * M + FO - 2 - (M - 1)
            fields[f"{n}_sd"] = sc.let(f"{n}_sd", (c_d - bits["1"])[:6], shape=6)
        start, steps, own = choice_tables(M, w.FI, FO, w.screen_bits, self.recip_err,
                                          linear)
        look = lambda values, i: _or_tree([Mux(i == k, v, 0) for k, v in enumerate(values)
                                           if v])
        parts = {f"{n}_cp": look(start, bits["0"]), f"{n}_ck": look(own, kn)}
        if not linear:
            parts[f"{n}_cd"] = look(steps, bits["1"] + kn)
        parts = sc.lets(**parts)
        ok = sc.let(f"{n}_ok", sum(parts.values(), term(Const(0, 9))) <= 64)
        return fields, ok

    @property
    def recip_err(self):
        """The reciprocal's relative error (docs/quadratic.md, "The reciprocal": every 16-bit
        mantissa through the seed and its Newton-Raphson steps; a restoring divider truncates
        at 2**-R)."""
        if self.recip == "divide":
            return 2.0 ** -self.w.R
        return (1.95e-3, 3.8e-6, 7.2e-9, 7.2e-9)[self.recip_iters]

    def shift(self, sh):
        """The schedule's shift: alpha = y2 r 2**(sub_bits + FA - R - sh)."""
        return sh, self.w.sub_bits + self.w.FA - self.w.R

    def _reciprocal(self, sc, n, W):
        """~ 2**R / m for the mantissa m = n / 2**(W-1): a table seed and Newton-Raphson steps
        r' = r (2 - m r), or a restoring divider (truncating)."""
        R = self.w.R
        if self.recip == "divide":
            q, _ = sc.divide("recip", Const(1 << (R + W - 1)), n, R + 1)
            return q
        rcp = sc.rom("recip_seed", arith.recip_seed(8, R), n[W - 9:W - 1])
        nop = n[W - OPERAND + 1:] if W >= OPERAND else n                 # operand-wide m
        drop = max(0, W - OPERAND + 1)
        for k in range(self.recip_iters):
            mr = sc.mul(f"mr{k}", nop, rcp, post=lambda p: (p >> (W - 1 - drop))[:R + 2])
            t = sc.let(f"t{k}", (term(Const(2 << R, signed(R + 3))) - mr)[:R + 2])    # in (0, 2)
            rcp = sc.mul(f"r{k}", rcp, t, post=lambda p: (p >> R)[:R + 1])
        return rcp

    @staticmethod
    def _floor_divide(sc, name, num, den, bits):
        """Signed floor division: q = floor(num / den), r = num - q den in [0, den), through
        M = -num - 1 for negative numerators: q = -q(M) - 1, r = den - 1 - r(M)."""
        pre = sc.lets(**{f"{name}_neg": num < 0,
                         f"{name}_m": Mux(num < 0, -num - 1, num).as_unsigned()[:len(num)],
                         f"{name}_dm1": den - 1})          # so r's fix-up is one subtract
        neg = pre[f"{name}_neg"]
        q, r = sc.divide(name, pre[f"{name}_m"], den, bits)
        post = sc.lets(**{f"{name}_q": Mux(neg, -(q + 1), q + Const(0, signed(2))),
                          f"{name}_r": Mux(neg, pre[f"{name}_dm1"] - r, r)[:len(den)]})
        return post[f"{name}_q"], post[f"{name}_r"]

    def _tracks(self, sc, r, out, xt, yt):
        """Exact (u, v) numerators nu = X y2 - Y x2, nv = Y x1 - X y1 (eq 18-20, sub-pixel
        units, X and Y from the top vertex to a pixel centre) for the row engine, and their
        steps: ``e0`` at the first left edge's first pixel, ``s0``/``s1`` its steps per row
        without and with the DDA's carry, ``e1``, ``t0``, ``t1`` the same for the lower short
        edge (from row jm), ``b0`` at column 0 of the first row, ``bs`` its step."""
        w, S = self.w, 1 << self.w.sub_bits
        x1, y1, x2, y2 = r["x1"], r["y1"], r["x2"], r["y2"]
        wn = w.wn
        mod = lambda x: x[:wn].as_signed() if len(x) > wn else x     # modulo 2**wn, signed
        # the first left edge's column and step: a compare, then a mux, then an add, each
        # in its own clock (registers between, so none of them is in series with another)
        first_short = sc.let("first_short", r["j0"] >= r["jm"])
        sel = sc.lets(**{f"sel_{k}": Mux(out["left_long"], out[f"l_{k}"],
                                         Mux(first_short, out[f"t_{k}"], out[f"s_{k}"]))
                         for k in ("i", "q")})
        # each within +-2**(wc + 1) (Widths.wpos); a step quotient too, on an edge that is
        # walked (dy > 0: |dx / dy| < 2**wc; a flat edge's is never read)
        pos = sc.lets(**{k: x[:w.wpos].as_signed() for k, x in (
            ("X0", S // 2 - xt), ("Y0", S * r["j0"] + S // 2 - yt),
            ("Ym", S * r["jm"] + S // 2 - yt), ("Xe", S * sel["sel_i"] + S // 2 - xt),
            ("Xt", S * out["t_i"] + S // 2 - xt), ("qe", sel["sel_q"]), ("qt", out["t_q"]))})
        tr = {"fs": {"first_short": first_short}}      # the walker's choice at its load too

        def pair(name, X, Y):
            tr[name] = sc.lets(**{f"{name}_u": mod(sc.mul(f"{name}_xy2", X, y2)
                                                - sc.mul(f"{name}_yx2", Y, x2)),
                                  f"{name}_v": mod(sc.mul(f"{name}_yx1", Y, x1)
                                                   - sc.mul(f"{name}_xy1", X, y1))})
        pair("b0", pos["X0"], pos["Y0"])
        pair("e0", pos["Xe"], pos["Y0"])
        pair("e1", pos["Xt"], pos["Ym"])
        for name, q in (("s", pos["qe"]), ("t", pos["qt"])):
            qy2, qy1 = sc.mul(f"{name}_qy2", q, y2), sc.mul(f"{name}_qy1", q, y1)
            tr[f"{name}0"] = sc.lets(**{f"{name}0_u": mod(S * (qy2 - x2)),
                                        f"{name}0_v": mod(S * (x1 - qy1))})
            st = tr[f"{name}0"]
            tr[f"{name}1"] = sc.lets(**{f"{name}1_u": mod(st[f"{name}0_u"] + S * y2),
                                        f"{name}1_v": mod(st[f"{name}0_v"] - S * y1)})
        tr["bs"] = sc.lets(bs_u=mod(-S * x2), bs_v=mod(S * x1))
        return {k: val for d in tr.values() for k, val in d.items()}

    def _exact_mid_edges(self, sc, v):
        """g_ij = 1 / (2 sqrt(1 + e_ij)) (= 1/||Ni + Nj||), clamped at EXACT_G_MAX, by
        Newton-Raphson y' = y (3 - m y^2) / 2 from a table seed on the mantissa m of 1 + e in
        [1, 4); kept with G_FRAC - 3 fraction bits (an operand)."""
        Wm, FG = 19, G_FRAC
        lut = arith.rsqrt_seed(8, FG)
        gmax = int(EXACT_G_MAX) << (FG - 3)
        g = {}
        exact = {g for g, m in zip(self.groups, self.modes) if m == "exact"}
        for e in (f"{e}{edge_names(g)[0][3:]}" for g in sorted(exact)
                  for e in ("e12", "e13", "e23")):
            # 1 + e (15 fraction bits), its normalising shift (even, top bit at 17/18), the
            # shift: each in its own clock
            x = sc.let(f"{e}_1e", (v[e] + (1 << 15)).as_unsigned()[:17])
            sh = Const(0, 5)
            for k in range(17):
                sh = Mux(x[k], (18 - k) & ~1, sh)
            sh = sc.lets(**{f"{e}_nsh": sh, f"{e}_z": ~x.any()})
            pre = {**sh, **sc.lets(**{f"{e}_x": (x << sh[f"{e}_nsh"])[:Wm]})}
            pre[f"{e}_sh"] = pre[f"{e}_nsh"]
            m = pre[f"{e}_x"]
            k = 7
            addr = Cat(Mux(m[Wm - 1], m[Wm - 1 - k:Wm - 1], m[Wm - 2 - k:Wm - 2]), m[Wm - 1])
            y = sc.rom(f"rsqrt_seed_{e}", lut, addr)
            for it in range(RSQRT_ITERS):
                y2 = sc.mul(f"{e}_yy{it}", y, y, post=lambda p: (p >> FG)[:FG + 1])
                my = sc.mul(f"{e}_my{it}", y2, m, post=lambda p: p >> (Wm - 2))
                t = sc.let(f"{e}_t{it}", (term(Const(3 << FG, signed(FG + 4))) - my)[:FG + 2])
                y = sc.mul(f"{e}_y{it}", y, t, post=lambda p: (p >> (FG + 1))[:FG + 1])
            gg = sc.let(f"{e}_gg", (y << (pre[f"{e}_sh"] >> 1)) >> 5)  # y 2**(sh/2-2), FG-3
            g[f"g{e[1:]}"] = sc.let(f"g{e[1:]}", Mux(pre[f"{e}_z"] | (gg > gmax), gmax,
                                                     gg)[:OPERAND - 1])
        return g

    def _channel(self, sc, v, g, ch, mode):
        """a..f of one channel, FC fraction bits (exact except the exact mode's mid-edges)."""
        w = self.w
        I1, I2, I3 = (v[f"i{ch}_{k}"] for k in range(3))
        up = w.FC - VALUE.frac_bits
        n = f"c{ch}"
        sfx = self.suffix(ch)                                         # its group's constants
        if mode == "linear":
            z = Const(0, 1)
            return {"a": z, "b": z, "c": z, "d": (I2 - I1) << up, "e": (I3 - I1) << up,
                    "f": I1 << up}
        sums = sc.lets(**{f"{n}_s12": I1 + I2, f"{n}_s13": I1 + I3, f"{n}_s23": I2 + I3})
        if mode == "xshading":                                        # seed 001 eq 32
            # I2 - I1, I3 - I1 and a + b registered ahead, so that d, e, c are one
            # subtraction each once their last product is ready (two in series: 116 MHz)
            diff = sc.lets(**{f"{n}_d21": I2 - I1, f"{n}_d31": I3 - I1})
            a = sc.mul(f"{n}_a", sums[f"{n}_s12"], v[f"e12{sfx}"])
            b = sc.mul(f"{n}_b", sums[f"{n}_s13"], v[f"e13{sfx}"])
            ab = sc.let(f"{n}_ab", a + b)
            c = ab - sc.mul(f"{n}_c3", sums[f"{n}_s23"], v[f"e23{sfx}"])
            return {"a": a, "b": b, "c": c, "d": (diff[f"{n}_d21"] << up) - a,
                    "e": (diff[f"{n}_d31"] << up) - b, "f": I1 << up}
        lo, hi = VALUE.min << up, VALUE.max << up                       # exact: eq 4-6, 16
        shift = VALUE.frac_bits + G_FRAC - 3 - w.FC

        # the mid-edge values' products, their saturation's compares, its multiplexer, then
        # a, b, c, then d, e: each in its own clock (a product's compares, multiplexer and
        # three sums in one clock closed at 67 MHz)
        mids = {}
        for k in ("12", "13", "23"):
            m = sc.mul(f"{n}_m{k}", sums[f"{n}_s{k}"], g[f"g{k}{sfx}"],
                       post=lambda p: (p + (1 << (shift - 1))) >> shift)
            cmp = sc.lets(**{f"{n}_hi{k}": m > hi, f"{n}_lo{k}": m < lo})
            mids[f"{n}_I{k}"] = sc.let(f"{n}_I{k}", Mux(cmp[f"{n}_hi{k}"], hi,
                                                        Mux(cmp[f"{n}_lo{k}"], lo, m)))
        I12, I13, I23 = (mids[f"{n}_I{k}"] for k in ("12", "13", "23"))
        L, M, N = I1 << up, I2 << up, I3 << up
        abc = sc.lets(**{f"{n}_xa": 2 * (L + M - 2 * I12), f"{n}_xb": 2 * (L + N - 2 * I13),
                         f"{n}_xc": 4 * (L + I23 - I13 - I12)})
        a, b, c = (abc[f"{n}_x{k}"] for k in "abc")
        return {"a": a, "b": b, "c": c, "d": M - L - a, "e": N - L - b, "f": L}

    def _span(self, sc, coef, alpha, ch, linear):
        """The row engine's constants of one channel: a..f as operands, and the first
        difference along x at a span's start, d = Pu u + Pv v + P0, with Pu = 2 a au + c av,
        Pv = 2 b av + c au, P0 = d au + e av + A, and 2A = 2 (au (a au + c av) + av (b av))
        (eq 22). A linear channel (a = b = c = 0) needs only P0 = d au + e av."""
        w, n = self.w, f"c{ch}"
        op = lambda x: x.as_signed()[:OPERAND].as_signed()
        # P0 and 2A as the stepper keeps them, modulo 2**(FI + 9) (its sums wrap there)
        acc = lambda x: x[:w.FI + 9].as_signed()
        zero = Const(0, 1)
        if linear:                     # a = b = c = 0: constants, nothing stored or carried
            coef = {k: coef[k] for k in "def"}
        c = sc.lets(**{f"{n}_{k}": op(val >> (w.FC - w.FO)) for k, val in coef.items()})
        d, e = c[f"{n}_d"], c[f"{n}_e"]
        au, av = alpha["au"], alpha["av"]
        FP = w.FO + w.FA                                     # fraction bits of a product
        if linear:
            p0 = sc.let(f"{n}_p0", acc((sc.mul(f"{n}_dau", d, au)
                                        + sc.mul(f"{n}_eav", e, av)) >> (FP - w.FI)))
            return {"a": zero, "b": zero, "c": zero, "d": d, "e": e, "f": c[f"{n}_f"],
                    "pu": zero, "pv": zero, "p0": p0, "a2": zero}
        a, b, cc = (c[f"{n}_{k}"] for k in "abc")
        aau, cav, bav = (sc.mul(f"{n}_{k}", x, y) for k, x, y in
                         (("aau", a, au), ("cav", cc, av), ("bav", b, av)))
        cau, dau, eav = (sc.mul(f"{n}_{k}", x, y) for k, x, y in
                         (("cau", cc, au), ("dau", d, au), ("eav", e, av)))
        t = sc.lets(**{f"{n}_t": op((aau + cav) >> w.FA), f"{n}_bv": op(bav >> w.FA),
                       f"{n}_pu": op((2 * aau + cav) >> w.FA),
                       f"{n}_pv": op((2 * bav + cau) >> w.FA)})
        a2 = sc.let(f"{n}_a2", (sc.mul(f"{n}_ut", au, t[f"{n}_t"])
                                + sc.mul(f"{n}_vb", av, t[f"{n}_bv"])) >> (FP - w.FI - 1))
        de = sc.let(f"{n}_de", (dau + eav) >> (FP - w.FI))
        p0 = sc.let(f"{n}_p0", acc(de + (a2 >> 1)))
        return {**{k: c[f"{n}_{k}"] for k in "abcdef"}, "pu": t[f"{n}_pu"],
                "pv": t[f"{n}_pv"], "p0": p0, "a2": acc(a2)}
