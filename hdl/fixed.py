"""Numeric formats, stated once.

A :class:`Fixed` is a two's-complement (or unsigned) integer of ``width`` bits whose value is
``raw / 2**frac_bits`` in ``unit``. A :class:`Field` names one. Every port of every unit, every
npz column and every LUT output is described by one of these, and ``python -m sim units --json``
prints them.
"""
from dataclasses import dataclass
import operator

import numpy as np
from amaranth.hdl import signed, unsigned
from amaranth.lib import data

__all__ = ["Fixed", "Field", "layout", "FieldError", "check_arrays", "align"]


class FieldError(ValueError):
    """A user-supplied array does not fit a field (missing, out of range, not integral)."""


@dataclass(frozen=True)
class Fixed:
    width: int
    signed: bool = False
    frac_bits: int = 0
    unit: str = "1"

    def __post_init__(self):
        width = operator.index(self.width)
        if width < 1:
            raise ValueError(f"width must be a positive integer, not {self.width!r}")
        operator.index(self.frac_bits)

    @property
    def shape(self):
        return signed(self.width) if self.signed else unsigned(self.width)

    @property
    def min(self):
        return -(1 << (self.width - 1)) if self.signed else 0

    @property
    def max(self):
        return (1 << (self.width - 1)) - 1 if self.signed else (1 << self.width) - 1

    @property
    def lsb(self):
        """The value of one raw step, in ``unit``."""
        return 2.0 ** -self.frac_bits

    def describe(self):
        return {"width": self.width, "signed": self.signed, "frac_bits": self.frac_bits,
                "unit": self.unit}


def u(width, frac_bits=0, unit="1"):
    return Fixed(width, False, frac_bits, unit)


def s(width, frac_bits=0, unit="1"):
    return Fixed(width, True, frac_bits, unit)


def align(value, frac_from, frac_to):
    """A fixed-point value of ``frac_from`` fraction bits with ``frac_to``: shifted left, or
    right (truncated)."""
    return value << (frac_to - frac_from) if frac_to >= frac_from else \
        value >> (frac_from - frac_to)


def binary_angle(bits):
    """An angle of ``bits`` bits in turns: raw / 2**bits of a full turn, wrapping."""
    return Fixed(bits, False, bits, "turn")


@dataclass(frozen=True)
class Field:
    name: str
    fmt: Fixed

    def describe(self):
        return {"name": self.name, **self.fmt.describe()}


def layout(fields):
    """The ``StructLayout`` of a list of fields, first field in the least significant bits."""
    return data.StructLayout({f.name: f.fmt.shape for f in fields})


def check_arrays(fields, arrays, *, where="input"):
    """Validate user arrays against ``fields``; return ``{name: int64 array}`` and extra names.

    Rejects, naming the field: a missing field, rows of unequal length, non-finite or
    non-integral values, and values outside the field's range. Nothing is truncated.
    """
    out, n = {}, None
    for f in fields:
        if f.name not in arrays:
            raise FieldError(f"{where}: field {f.name!r} is missing "
                             f"(expected {', '.join(g.name for g in fields)})")
        a = np.asarray(arrays[f.name])
        if a.ndim != 1:
            raise FieldError(f"{where}: field {f.name!r} must be a 1-D array, has shape {a.shape}")
        if a.dtype.kind == "f":
            bad = ~np.isfinite(a)
            if bad.any():
                raise FieldError(f"{where}: field {f.name!r} has a non-finite value "
                                 f"({a[bad][0]}) at row {int(np.flatnonzero(bad)[0])}")
            frac = a != np.round(a)
            if frac.any():
                raise FieldError(f"{where}: field {f.name!r} holds raw integers, but row "
                                 f"{int(np.flatnonzero(frac)[0])} is {a[frac][0]!r}")
        elif a.dtype.kind not in "iub":
            raise FieldError(f"{where}: field {f.name!r} has dtype {a.dtype}, not integers")
        bad = (a < f.fmt.min) | (a > f.fmt.max)             # in the user's own dtype
        if bad.any():
            row = int(np.flatnonzero(bad)[0])
            kind = "s" if f.fmt.signed else "u"
            raise FieldError(f"{where}: field {f.name!r} ({kind}{f.fmt.width}, range "
                             f"{f.fmt.min}..{f.fmt.max}) has {a[row].item()!r} at row {row}")
        a = a.astype(np.int64)
        if n is not None and len(a) != n:
            raise FieldError(f"{where}: field {f.name!r} has {len(a)} rows, others have {n}")
        n = len(a)
        out[f.name] = a
    extra = sorted(set(arrays) - {f.name for f in fields})
    return out, extra
