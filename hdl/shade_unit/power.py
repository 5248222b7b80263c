"""``power_table``: the specular power max(0, s)^n from one table (the scene's ``power =
"table"``).

The table is addressed by t = 1 - s (s clamped to [0, 1]) in floating-point bins
(``hdl.lut.float_bins``): ``mant_bits`` bins per octave of t, uniform bins of one input LSB
below 2^-(14 - mant_bits). x^n is steep near x = 1, where t is small and the bins are fine, so
the error is about the same for every n: about e^-1 / 2^(mant_bits + 1) of full scale at most
(``Lut.max_error`` states it exactly). mant_bits = 6: 640 entries of 11 bits, one block RAM.
Latency 4: 1 - s, the address, the ROM's read register, its output registered again.
"""
import functools

import numpy as np
from amaranth.hdl import Mux

from ..fixed import Field
from ..lut import build_lut, float_address, float_bins, rom
from ..setup_unit.formats import VALUE
from ..unit import Unit
from .formats import ONE, POWER

EXP_HI = 1          # t reaches 1.0 (s <= 0): the top octave is [1, 2)


def power_bins(mant_bits):
    """The table's bins over t = 1 - s: (exp_lo, edges)."""
    exp_lo = VALUE.frac_bits - mant_bits
    return exp_lo, float_bins(exp_lo, EXP_HI, mant_bits)


@functools.lru_cache(maxsize=None)
def power_lut(shininess, mant_bits):
    _, edges = power_bins(mant_bits)
    return build_lut(lambda t: np.maximum(0.0, 1.0 - t) ** shininess,
                     (len(edges) - 2).bit_length(), POWER, edges=edges)


def power_lanes(p, v, lanes, shininess, mant_bits):
    """max(0, s)^n for several ``(s_key, p_key)`` side by side (4 stages); ``s`` is consumed.
    The table is scene data (``load="power"``): in a scene's pipeline the host loads it, and
    ``shininess`` gives its shape only."""
    lut = power_lut(float(shininess), mant_bits)
    exp_lo, _ = power_bins(mant_bits)
    ts = {}
    for s, _ in lanes:
        x = v.pop(s)
        t = ONE - Mux(x < 0, 0, Mux(x > ONE, ONE, x))                  # 1 - clamp(s, 0, 1)
        ts[f"_t_{s}"] = t.as_unsigned()[:VALUE.frac_bits + 1]
    v = p.stage(v, **ts)
    v = p.stage(v, **{f"_a_{s}": float_address(v.pop(f"_t_{s}"), VALUE.frac_bits, exp_lo,
                                                EXP_HI, mant_bits) for s, _ in lanes})
    v = p.stage(v, **{out: rom(lut, v.pop(f"_a_{s}"), "power", load="power") for s, out in lanes})
    return p.stage(v)                                                   # the table's output


class PowerTable(Unit):
    NAME = "power_table"
    DOC = "Specular power max(0, s)^n from one table in floating-point bins of 1 - s"
    PARAMS = {"shininess": 32.0, "mant_bits": 6}
    RANGES = {"shininess": (1.0, 1e9), "mant_bits": (3, 8)}
    inputs = (Field("s", VALUE),)
    outputs = (Field("p", POWER),)
    latency = 4

    def datapath(self, p, v):
        return power_lanes(p, v, [("s", "p")], self.params["shininess"],
                           self.params["mant_bits"])
