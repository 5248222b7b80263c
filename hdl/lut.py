"""The one LUT builder: contents from a numpy function, with the error they carry.

Every table in the project (trigonometric, reciprocal square root, ...) comes from
:func:`build_lut`, so its rounding and its address quantisation are derived in one place and
the tests can state their bounds from ``Lut.max_error``.
"""
from dataclasses import dataclass
import functools
import operator

import numpy as np
from amaranth.hdl import Value
from amaranth.lib.memory import Memory

from .fixed import Fixed

__all__ = ["Lut", "build_lut", "rom"]


@dataclass(frozen=True, eq=False)
class Lut:
    """Table contents (raw integers of ``fmt``) and what they cost in accuracy.

    ``max_error`` is the largest ``|fn(x) - entry|`` in LSBs of ``fmt`` over every input ``x``
    that an entry stands for: rounding alone (at most 0.5) when addresses are exact inputs,
    rounding plus the function's change across a bin when an address covers an interval.
    """
    contents: np.ndarray
    fmt: Fixed
    max_error: float
    domain: tuple | None

    @property
    def depth(self):
        return len(self.contents)

    def address_of(self, x):
        """The address a real input falls in (numpy), for models that mimic the addressing."""
        if self.domain is None:
            return np.asarray(x, dtype=np.int64)
        lo, hi = self.domain
        a = np.floor((np.asarray(x, dtype=float) - lo) * self.depth / (hi - lo))
        return np.clip(a, 0, self.depth - 1).astype(np.int64)


def build_lut(fn, addr_bits, fmt, *, domain=None, depth=None, oversample=65):
    """Tabulate ``fn`` (a vectorised numpy function) into ``2**addr_bits`` entries of ``fmt``.

    ``fn`` returns values in the format's unit (the builder scales by ``2**fmt.frac_bits``).
    With ``domain=None`` the address is the input itself (``x = a``). With ``domain=(lo, hi)``
    address ``a`` stands for ``x`` in ``[lo + a*step, lo + (a+1)*step)`` and holds ``fn`` at the
    bin's centre; the error is then measured on ``oversample`` points across each bin.
    ``depth`` overrides ``2**addr_bits`` (a quarter-wave table with both end points, say).
    Entries outside ``fmt`` are an error, never saturated.
    """
    addr_bits = operator.index(addr_bits)
    if not 1 <= addr_bits <= 20:
        raise ValueError(f"LUT address width must be 1..20 bits, not {addr_bits}")
    if not isinstance(fmt, Fixed):
        raise TypeError(f"LUT output format must be a Fixed, not {fmt!r}")
    depth = 1 << addr_bits if depth is None else operator.index(depth)
    if not 1 <= depth <= 1 << addr_bits:
        raise ValueError(f"LUT depth {depth} does not fit {addr_bits} address bits")
    scale = 2.0 ** fmt.frac_bits
    a = np.arange(depth)
    if domain is None:
        x_entry = a.astype(float)
        x_check = x_entry[:, None]
    else:
        lo, hi = map(float, domain)
        if not hi > lo:
            raise ValueError(f"LUT domain must be increasing, not {domain!r}")
        step = (hi - lo) / depth
        x_entry = lo + (a + 0.5) * step
        x_check = lo + (a[:, None] + np.linspace(0.0, 1.0, oversample)[None, :]) * step
    exact = np.asarray(fn(x_entry), dtype=float) * scale
    if not np.all(np.isfinite(exact)):
        raise ValueError("LUT function returned a non-finite value")
    contents = np.rint(exact).astype(np.int64)
    if contents.min() < fmt.min or contents.max() > fmt.max:
        raise ValueError(f"LUT entries {contents.min()}..{contents.max()} do not fit "
                         f"{'s' if fmt.signed else 'u'}{fmt.width}")
    err = np.abs(np.asarray(fn(x_check), dtype=float) * scale - contents[:, None])
    return Lut(contents, fmt, float(err.max()), None if domain is None else (lo, hi))


def rom(m, lut, addr, name):
    """Instantiate ``lut`` as a ROM with an asynchronous read port; returns the read data.

    The caller registers the result in the next pipeline stage, so Yosys can merge the register
    into a block RAM.
    """
    mem = Memory(shape=lut.fmt.shape, depth=lut.depth, init=[int(v) for v in lut.contents])
    m.submodules[name] = mem
    port = mem.read_port(domain="comb")
    m.d.comb += port.addr.eq(addr)
    return Value.cast(port.data)


@functools.lru_cache(maxsize=None)
def quarter_cos_lut(frac_bits, steps=256):
    """cos over a quarter turn, both ends included: entry a is cos(a/steps * 90 deg).

    One table serves sine (``T[steps - a]``) and cosine (``T[a]``), and, folded by quadrant,
    the cosine of any binary angle. Unsigned, ``frac_bits + 1`` bits so that 1.0 is exact.
    """
    return build_lut(lambda a: np.cos(a * (np.pi / 2) / steps), (steps).bit_length(),
                     Fixed(frac_bits + 1, False, frac_bits), depth=steps + 1)
