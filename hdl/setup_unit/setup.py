"""Triangle setup (seeds 001, 002): one triangle per clock, fully pipelined.

sort by (y, x) -> relative coordinates (seed 002 eq 9-12) -> Omega = x1 y2 - x2 y1 (eq 47),
orientation, cull of Omega = 0 -> the reciprocal of |Omega| (normalised mantissa, Newton-Raphson
or a divider) -> per channel the ortho-normalised coefficients a..f (seed 001 eq 16/32, seed 000
eq 24-26) -> alpha_u, alpha_v per pixel step (eq 20) and each channel's second difference
2A = 2 (a au^2 + b av^2 + c au av) (eq 22) -> the edge walkers' start values and steps.

The span engine evaluates Phi(u, v) and its first difference at the start of each span from u
and v (exact integer numerators times the reciprocal), then steps along the span with two
additions per pixel. Why these widths: ``Widths`` and docs/quadratic.md.
"""
from dataclasses import dataclass

from amaranth.hdl import Const, Mux

from .. import arith
from ..fixed import Field, s, u
from .formats import EXACT_G_MAX, VALUE, coord, parse_modes

RSQRT_ITERS = 2    # Newton-Raphson steps of the exact mid-edges' 1/sqrt (seed error 2**-9)
G_FRAC = 30        # fraction bits of g = 1/||Ni + Nj||

__all__ = ["Widths", "Setup"]


@dataclass(frozen=True)
class Widths:
    """Fraction bits, derived in docs/quadratic.md ("Widths from analysis") for spans of up to
    2**screen_bits pixels and an internal error of at most half an output LSB (2**-15)."""
    screen_bits: int
    sub_bits: int
    R: int = 28        # reciprocal mantissa (1/m in (1/2, 1]); also u and v's fraction bits
    FC: int = 29       # coefficients a..f (exact products of VALUE and EDGE: 14 + 15)
    FA: int = 36       # alpha_u, alpha_v per pixel, saturated to [-2, 2)
    FI: int = 40       # Phi, its first difference and 2A in the span engine

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


def coef_fmt(w):
    return s(w.FC + 7, w.FC)          # |a..f| < 64 covers every mode (docs: |c| <= 32)


def a2_fmt(w):
    return s(w.FI + 13, w.FI)         # |2A| <= 2 (16 + 16 + 32) 16 with |alpha| < 4


def alpha_fmt(w):
    return s(w.FA + 3, w.FA)


EDGES = ("l", "s", "t")   # the long edge (top-bottom), the short ones (top-mid, mid-bottom)


def setup_fields(w, channels):
    """The coefficient stream from the setup unit to the span engine."""
    c, rel = coord(w.screen_bits, w.sub_bits), s(w.wrel, w.sub_bits, "px")
    f = [Field("tri", u(32)), Field("cull", u(1)), Field("left_long", u(1)),
         Field("neg", u(1)), Field("j0", u(w.wrow)), Field("jm", u(w.wrow)),
         Field("j1", u(w.wrow)), Field("xt", c), Field("yt", c)]
    f += [Field(n, rel) for n in ("x1", "y1", "x2", "y2")]
    f += [Field("r", u(w.R + 1, w.R)), Field("sh", u(len(range(w.womega)))),
          Field("au", alpha_fmt(w)), Field("av", alpha_fmt(w))]
    for e in EDGES:
        f += [Field(f"{e}_i", s(w.wi)), Field(f"{e}_r", u(w.wden)),
              Field(f"{e}_q", s(w.qstep + 1)), Field(f"{e}_d", u(w.wden)),
              Field(f"{e}_n", u(w.wden))]
    for ch in range(channels):
        f += [Field(f"c{ch}_{k}", coef_fmt(w)) for k in "abcdef"]
        f += [Field(f"c{ch}_a2", a2_fmt(w))]
    return f


def _round_shift(value, shift):
    """value / 2**shift, rounded half up (shift > 0)."""
    return (value + (1 << (shift - 1))) >> shift


def _saturate(value, fmt):
    return Mux(value > fmt.max, fmt.max, Mux(value < fmt.min, fmt.min, value))


class Setup:
    """The setup datapath; ``Raster`` runs it on its input pipeline."""

    def __init__(self, screen_bits, sub_bits, channels, modes, recip, recip_iters):
        self.w = Widths(screen_bits, sub_bits)
        self.channels = channels
        self.modes = parse_modes(modes, channels)
        self.recip, self.recip_iters = recip, recip_iters

    @property
    def latency(self):
        """Stages: sort, relative, Omega and edge numerators, normalise; the reciprocal; the
        edge divisions; the exact mid-edges' rsqrt (if a channel is exact); coefficients and
        alpha; alpha squared; 2A. The parts run one after another (values ride along): a
        longer latency, still one triangle per clock."""
        recip = arith.recip_stages(self.recip, self.recip_iters, self.w.R)
        exact = 3 * arith.rsqrt_stages(RSQRT_ITERS) + 2 if "exact" in self.modes else 0
        return 4 + recip + arith.divide_stages(self.w.qstep) + exact + 3

    def sort(self, v):
        """Ranks by (y, x, index) -> vertices top/mid/bottom, edges and values in sorted labels."""
        x = [v.pop(f"x{k}") for k in range(3)]
        y = [v.pop(f"y{k}") for k in range(3)]

        def lt(a, b):     # vertex a before vertex b
            later = (x[a] < x[b]) if a > b else (x[a] <= x[b])
            return (y[a] < y[b]) | ((y[a] == y[b]) & later)
        rank = [sum((lt(o, k) for o in range(3) if o != k), Const(0, 2)) for k in range(3)]

        def pick(slot, vals):
            out = vals[2]
            for k in (1, 0):
                hit = ~rank[k].any() if slot == 0 else rank[k] == slot   # no "x == 0": lint
                out = Mux(hit, vals[k], out)
            return out
        opp = [v.pop("e12"), v.pop("e02"), v.pop("e01")]        # the edge opposite vertex k
        out = {f"{n}{slot}": pick(slot, vals) for slot in range(3)
               for n, vals in (("x", x), ("y", y))}
        out.update(e12=pick(2, opp), e13=pick(1, opp), e23=pick(0, opp))
        for ch in range(self.channels):
            vals = [v.pop(f"v{ch}_{k}") for k in range(3)]
            out.update({f"i{ch}_{slot}": pick(slot, vals) for slot in range(3)})
        return {**v, **out}

    def rows(self, y):
        """ceil(y / S - 1/2): the first row whose centre is at or below y (exact shifts)."""
        S = 1 << self.w.sub_bits
        return (2 * y + S - 1) >> (self.w.sub_bits + 1)

    def datapath(self, p, v):
        w, S = self.w, 1 << self.w.sub_bits
        size = 1 << w.screen_bits
        v = p.stage(self.sort(dict(v)))                                          # 1: sort
        xt, yt = v["x0"], v["y0"]
        clamp = lambda j: Mux(j < 0, 0, Mux(j > size, size, j))
        j0, jm, j1 = (clamp(self.rows(v[f"y{k}"])) for k in range(3))
        new = {"x1": v["x1"] - xt, "y1": v["y1"] - yt, "x2": v["x2"] - xt, "y2": v["y2"] - yt,
               "xt": v.pop("x0"), "yt": v.pop("y0"), "xm": v.pop("x1"), "ym": v.pop("y1"),
               "xb": v.pop("x2"), "yb": v.pop("y2"),
               "j0": j0, "jm": Mux(jm < j0, j0, Mux(jm > j1, j1, jm)), "j1": j1}
        v = p.stage(v, **new)                                                    # 2: relative
        om = v["x1"] * v["y2"] - v["x2"] * v["y1"]
        ends = {"l": ("xt", "yt", "xb", "yb", "j0"), "s": ("xt", "yt", "xm", "ym", "j0"),
                "t": ("xm", "ym", "xb", "yb", "jm")}
        new = {"omega": om}
        for e, (px, py, qx, qy, j) in ends.items():
            dx, dy = v[qx] - v[px], v[qy] - v[py]
            den = Mux(dy.any(), 2 * S * dy, 1)[:w.wden]
            # i = ceil(((2 px - S) dy + (2 S j + S - 2 py) dx) / den): the row's crossing, minus
            # half a pixel, in pixels; as a floor division of num + den - 1
            new[f"{e}_num"] = (2 * v[px] - S) * dy + (2 * S * v[j] + S - 2 * v[py]) * dx + den - 1
            new[f"{e}_n"] = den
            new[f"{e}_dx2"] = 2 * S * dx
        for k in ("xm", "ym", "xb", "yb"):
            v.pop(k)
        v = p.stage(v, **new)                                                    # 3: Omega
        om = v.pop("omega")
        n, sh = arith.normalise(abs(om)[:w.womega], w.womega)
        v = p.stage(v, cull=~om.any(), neg=om < 0, left_long=om > 0, _n=n, sh=sh)  # 4
        v = arith.recip(p, v, "_n", w.womega, w.R, self.recip, self.recip_iters)
        v.pop("_n")
        jobs = [(f"{e}_num", f"{e}_n", w.wi - 1, f"{e}_i", f"{e}_r") for e in EDGES]
        jobs += [(f"{e}_dx2", f"{e}_n", w.qstep, f"{e}_q", f"{e}_d") for e in EDGES]
        v = arith.floor_divide(p, v, jobs)
        for e in EDGES:
            v.pop(f"{e}_num"), v.pop(f"{e}_dx2")
        if "exact" in self.modes:
            v = self._exact_mid_edges(p, v)
        return self._coefficients(p, v)

    def _exact_mid_edges(self, p, v):
        """g_ij = 1 / (2 sqrt(1 + e_ij)) (= 1/||Ni + Nj||), clamped at EXACT_G_MAX, by
        Newton-Raphson from a table seed on the mantissa of 1 + e in [1, 4)."""
        W, FG = 19, G_FRAC
        new = {}
        for e in ("e12", "e13", "e23"):
            x = (v[e] + (1 << 15)).as_unsigned()[:17]                 # 1 + e, 15 fraction bits
            sh = Const(0, 5)                                           # even, top bit at 17/18
            for k in range(17):
                sh = Mux(x[k], (18 - k) & ~1, sh)
            new[f"_x{e}"] = (x << sh)[:W]
            new[f"_s{e}"] = sh
            new[f"_z{e}"] = ~x.any()
        v = p.stage(v, **new)
        for e in ("e12", "e13", "e23"):
            v = arith.rsqrt(p, v, f"_x{e}", W, FG, RSQRT_ITERS, out=f"_g{e}")
        new = {}
        gmax = int(EXACT_G_MAX) << FG
        for e in ("e12", "e13", "e23"):
            v.pop(f"_x{e}")
            g = (v.pop(f"_g{e}") << (v.pop(f"_s{e}") >> 1)) >> 2      # y 2**(sh/2 - 2)
            new[f"g{e[1:]}"] = Mux(v.pop(f"_z{e}") | (g > gmax), gmax, g)
        return p.stage(v, **new)

    def _channel(self, v, ch, mode):
        """a..f of one channel, FC fraction bits (exact except the exact mode's mid-edges)."""
        w = self.w
        I1, I2, I3 = (v.pop(f"i{ch}_{k}") for k in range(3))
        up = w.FC - VALUE.frac_bits
        if mode == "linear":
            z = Const(0, 1)
            return {"a": z, "b": z, "c": z, "d": (I2 - I1) << up, "e": (I3 - I1) << up,
                    "f": I1 << up}
        if mode == "xshading":                                        # seed 001 eq 32
            a, b = (I1 + I2) * v["e12"], (I1 + I3) * v["e13"]
            c = a + b - (I2 + I3) * v["e23"]
            return {"a": a, "b": b, "c": c, "d": ((I2 - I1) << up) - a,
                    "e": ((I3 - I1) << up) - b, "f": I1 << up}
        lo, hi = VALUE.min << up, VALUE.max << up                       # exact: eq 4-6, 16

        def mid(Ia, Ib, g):
            m = _round_shift((Ia + Ib) * v[g], VALUE.frac_bits + G_FRAC - w.FC)
            return Mux(m < lo, lo, Mux(m > hi, hi, m))
        I12, I13, I23 = mid(I1, I2, "g12"), mid(I1, I3, "g13"), mid(I2, I3, "g23")
        L, M, N = I1 << up, I2 << up, I3 << up
        a, b = 2 * (L + M - 2 * I12), 2 * (L + N - 2 * I13)
        return {"a": a, "b": b, "c": 4 * (L + I23 - I13 - I12), "d": M - L - a, "e": N - L - b,
                "f": L}

    def _coefficients(self, p, v):
        w = self.w
        new = {}
        for ch, mode in enumerate(self.modes):
            new.update({f"c{ch}_{k}": val for k, val in self._channel(v, ch, mode).items()})
        for e in ("e12", "e13", "e23", "g12", "g13", "g23"):
            v.pop(e, None)
        # alpha per pixel step: S y2 / Omega, -S y1 / Omega (eq 20), saturated
        r, sh = v["r"], v["sh"]
        up = w.sub_bits + w.FA - w.R
        fmt = alpha_fmt(w)
        for name, val in (("au", v["y2"]), ("av", -v["y1"])):
            a = ((val * r) << up) >> sh
            new[name] = _saturate(Mux(v["neg"], -a, a), fmt)
        v = p.stage(v, **new)                                                    # coefficients
        au, av = v["au"], v["av"]
        sq = 2 * w.FA - w.FI
        v = p.stage(v, _uu=(au * au) >> sq, _vv=(av * av) >> sq, _uv=(au * av) >> sq)
        uu, vv, uv = v.pop("_uu"), v.pop("_vv"), v.pop("_uv")
        new = {}
        for ch in range(self.channels):
            a, b, c = (v[f"c{ch}_{k}"] for k in "abc")
            new[f"c{ch}_a2"] = (a * uu + b * vv + c * uv) >> (w.FC - 1)          # 2A, FI bits
        return p.stage(v, **new)

