"""Arithmetic shared by the units: sliced products, normalisation, the reciprocal and
reciprocal square root seeds, and the pipelined reciprocal square root.

The pipelined functions take a :class:`hdl.unit.Pipeline` ``p`` and the dict ``v`` of values
at the current stage, add stages, and return the dict at the last one (values ride along).
The setup's reciprocal runs on a schedule instead (``hdl/setup_unit/setup.py``).
"""
import functools

import numpy as np
from amaranth.hdl import Cat, Const, Mux, signed, unsigned

from .fixed import u
from .lut import build_lut, rom

__all__ = ["products", "leading_one", "leading_zeros", "normalise", "recip_seed", "rsqrt_seed",
           "rsqrt_addr", "rsqrt_stages", "rsqrt"]


def products(p, v, jobs, port=18):
    """``v[out] = v[a] * v[b]`` for jobs ``{out: (a, b)}`` (operands consumed), in two stages:
    ``b`` cut into ``port``-bit slices, each slice's product alone in the first stage (one
    DSP each, registered on both sides), the shifted partial products summed in the second."""
    v = dict(v)
    parts, sums = {}, {}
    for out, (a, b) in jobs.items():
        x, y = v.pop(a), v.pop(b)
        terms = []
        for k, lo in enumerate(range(0, len(y), port)):
            piece = y[lo:lo + port]
            if lo + port >= len(y) and y.shape().signed:
                piece = piece.as_signed()
            parts[f"_{out}_{k}"] = x * piece
            terms.append((f"_{out}_{k}", lo))
        sums[out] = terms
    v = p.stage(v, **parts)
    return p.stage(v, **{out: sum((v.pop(key) << lo for key, lo in terms), Const(0, 1))
                         for out, terms in sums.items()})


def leading_one(value, width):
    """The position of the highest set bit of an unsigned value (0 for 0)."""
    pos = Const(0, range(width))
    for k in range(width):
        pos = Mux(value[k], k, pos)
    return pos


def leading_zeros(value, width):
    """``width - 1 - leading_one(value)``: the shift that normalises ``value``."""
    shamt = Const(width - 1, range(width))
    for k in range(width):
        shamt = Mux(value[k], width - 1 - k, shamt)
    return shamt


def normalise(value, width):
    """``(n, s)`` with ``value = n * 2**(s - width + 1)``, ``n`` in ``[2**(width-1), 2**width)``
    (a mantissa in [1, 2) with ``width - 1`` fraction bits) for nonzero ``value``."""
    return (value << leading_zeros(value, width))[:width], leading_one(value, width)


@functools.lru_cache(maxsize=None)
def recip_seed(seed_bits, frac):
    """1/m over m in [1, 2), ``seed_bits`` address bits (the mantissa's top fraction bits)."""
    return build_lut(lambda m: 1 / m, seed_bits, u(frac + 1, frac), domain=(1.0, 2.0))


@functools.lru_cache(maxsize=None)
def rsqrt_seed(seed_bits, frac):
    """1/sqrt(m) over m in [1, 4): the even/odd exponent bit, then ``seed_bits - 1`` bits."""
    half = 1 << (seed_bits - 1)
    edges = np.concatenate([1 + np.arange(half) / half, 2 + 2 * np.arange(half) / half, [4.0]])
    return build_lut(lambda m: 1 / np.sqrt(m), seed_bits, u(frac + 1, frac), edges=edges)


def rsqrt_addr(n, width, seed_bits):
    """``rsqrt_seed``'s address for ``m = n / 2**(width-2)`` in [1, 4): the exponent's parity
    (the top bit), then the ``seed_bits - 1`` bits below the leading one."""
    k = seed_bits - 1
    return Cat(Mux(n[width - 1], n[width - 1 - k:width - 1], n[width - 2 - k:width - 2]),
               n[width - 1])


def rsqrt_stages(iters):
    return 2 + 5 * iters


def rsqrt(p, v, key, width, frac, iters=2, seed_bits=8, out="g"):
    """``v[out]`` ~ 2**frac / sqrt(m) for ``m = v[key] / 2**(width-2)`` in [1, 4) (``v[key]``
    has ``width`` bits, top two bits not both 0): Newton-Raphson y' = y (3 - m y^2) / 2.
    The seed's output registered twice; per step y^2, m y^2 (``m`` in 18-bit slices),
    3 - m y^2 (below 4: the seed is within 2**-7), and the product, each in its own stage."""
    lut = rsqrt_seed(seed_bits, frac)
    v = p.stage(v, **{out: rom(lut, rsqrt_addr(v[key], width, seed_bits), "rsqrt_seed")})
    v = p.stage(v)                                      # the table's output
    for _ in range(iters):
        y = v[out]
        v = p.stage(v, _y2=((y * y) >> frac)[:frac + 1])
        v = products(p, {**v, "_rsq_m": v[key]}, {"_my": ("_y2", "_rsq_m")})
        v = p.stage(v, _t=(Const(3 << frac, unsigned(frac + 3))
                           - (v.pop("_my") >> (width - 2)))[:frac + 2])
        v = p.stage(v, **{out: ((v[out] * v.pop("_t")) >> (frac + 1))[:frac + 1]})
    return v
