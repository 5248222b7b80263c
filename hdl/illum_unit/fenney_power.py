"""Fenney's quadratic power ("glossiness") approximation (US 6,819,319, col. 6-7).

Bit-exact to the patent, with X the dot product as a 10-bit fraction and C the concentration::

    k = C + 8                                 9 bits, 3 of them fractional
    L = max(0, 1023 - (k * (1023 - X) >> 3))  10-bit fraction
    Q = (L * L) >> 10                         10-bit fraction, Q <= L
    P = L + (C * (Q - L) >> 8)                signed: C * (Q - L) <= 0, >> floors

The patent prints ``P=L+C*(Q-L)>>8``; read with C precedence that shifts the sum, which would
scale P by 1/256. We follow the only reading that gives a 10-bit result (and the issue's).
"""
from amaranth.hdl import Mux

from ..fixed import Field, u
from ..unit import Unit

ONE = 1023  # full scale of a 10-bit fraction, as the patent uses it


class FenneyPower(Unit):
    """P(X, C): 3 multipliers and 5 add/subtracts, one result per clock, latency 7."""
    NAME = "fenney_power"
    DOC = "Fenney quadratic power approximation (US 6,819,319)"
    inputs = (Field("x", u(10, 10)), Field("c", u(8, 8)))
    outputs = (Field("p", u(10, 10)),)
    latency = 7

    def datapath(self, p, v):
        return power_lanes(p, v, [("x", "c", "p")])


def power_lanes(p, v, lanes):
    """P(X, C) for several ``(x_key, c_key, p_key)`` side by side on one pipeline (7 stages);
    the ``x`` and ``c`` values are consumed. Each multiplier has registers at its inputs and
    its output and nothing else in its stage (the MULT18X18D's own timing)."""
    v = dict(v)
    n = range(len(lanes))
    v = p.stage(v, **{f"_k{k}": v[c] + 8 for k, (_, c, _) in enumerate(lanes)},    # k
                **{f"_u{k}": ONE - v.pop(x) for k, (x, _, _) in enumerate(lanes)},
                **{f"_c{k}": v.pop(c) for k, (_, c, _) in enumerate(lanes)})
    v = p.stage(v, **{f"_t{k}": v.pop(f"_k{k}") * v.pop(f"_u{k}") for k in n})   # k (1023 - X)
    v = p.stage(v, **{f"_l{k}": Mux((v[f"_t{k}"] >> 3) > ONE, 0,                   # L
                                    ONE - (v.pop(f"_t{k}") >> 3))[:10] for k in n})
    v = p.stage(v, **{f"_q{k}": (v[f"_l{k}"] * v[f"_l{k}"]) >> 10 for k in n})       # Q
    v = p.stage(v, **{f"_d{k}": (v.pop(f"_q{k}") - v[f"_l{k}"])[:11].as_signed()    # Q - L,
                      for k in n})                                        # in [-1023, 0]
    v = p.stage(v, **{f"_m{k}": v.pop(f"_c{k}") * v.pop(f"_d{k}") for k in n})       # C (Q - L)
    return p.stage(v, **{key: (v.pop(f"_l{k}") + (v.pop(f"_m{k}") >> 8))[:10]         # P
                         for k, (_, _, key) in enumerate(lanes)})
