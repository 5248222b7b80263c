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
    """P(X, C): 3 multipliers and 5 add/subtracts, one result per clock, latency 4."""
    NAME = "fenney_power"
    DOC = "Fenney quadratic power approximation (US 6,819,319)"
    inputs = (Field("x", u(10, 10)), Field("c", u(8, 8)))
    outputs = (Field("p", u(10, 10)),)
    latency = 4

    def datapath(self, p, v):
        v = dict(v)
        x, c = v.pop("x"), v.pop("c")
        v = p.stage({**v, "c": c, "t": (c + 8) * (ONE - x)})        # k * (1023 - X)
        t = v.pop("t")
        big = (t >> 3) > ONE
        v = p.stage({**v, "l": Mux(big, 0, ONE - (t >> 3))[:10]})   # L
        v = p.stage({**v, "q": (v["l"] * v["l"]) >> 10})             # Q
        l, q, c = v.pop("l"), v.pop("q"), v.pop("c")
        return p.stage({**v, "p": (l + ((c * (q - l)) >> 8))[:10]})  # P
