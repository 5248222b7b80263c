"""Cosine of a binary angle from a quarter-wave table: magnitude and sign bit.

A binary angle of ``bits`` bits is ``raw / 2**bits`` turns. The table (``quarter_cos_lut``)
holds cos over 0..90 deg in ``steps`` + 1 entries, ``steps`` a power of two of at least a
quarter turn's codes. Folding: cos(a) = -cos(a - 180 deg) and |cos(180 deg - a)| = |cos a|.
"""
from amaranth.hdl import Mux

from .lut import rom


def cos_address(lut, angle, bits):
    """``(address, negative)`` of cos(angle) in ``lut``: the fold and the sign bit, logic only
    (register them before the read, so that the adds and the fold are not on the table's
    address path)."""
    steps = lut.depth - 1
    quarter = 1 << (bits - 2)
    if steps < quarter or steps % quarter:
        raise ValueError(f"a {steps}-step quarter table cannot index {bits}-bit angles")
    a = angle[:bits]
    half_angle = a[:bits - 1]                                  # a mod 180 deg
    fold = Mux(half_angle > quarter, (1 << (bits - 1)) - half_angle, half_angle)[:bits - 1]
    negative = (a > quarter) & (a < 3 * quarter)
    return fold * (steps // quarter), negative


def cos_lookup(lut, angle, bits, name):
    """``(magnitude, negative)`` of cos(angle): an asynchronous ROM read and its sign bit."""
    addr, negative = cos_address(lut, angle, bits)
    return rom(lut, addr, name), negative


def signed_cos(magnitude, negative):
    return Mux(negative, -magnitude, magnitude)
