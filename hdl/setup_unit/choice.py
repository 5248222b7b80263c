"""The setup's choice of the narrow row engine (issue 49's block floating point): the
constants of its tables, derived from the narrow engine's bound (docs/quadratic.md, "The
narrow row engine"; ``golden.bfp.narrow_bound``) and the setup's own terms ("Widths from
analysis"), within the raster's whole budget. ``Setup._narrow_channel`` looks them up and
sums them; ``tests/test_row_narrow.py`` holds every sum the tables allow within
``golden.bfp.narrow_ok``."""
import math

from ..sched import OPERAND

__all__ = ["BUDGET", "other_terms", "choice_tables"]

BUDGET = 2.0 ** -15.37     # the raster's arithmetic, all terms (docs/quadratic.md, "Widths")


def other_terms(n):
    """What the setup's fixed-point arithmetic spends on a triangle whose spans step at most
    ``n`` times, beside the row engine's (docs/quadratic.md, "Widths from analysis", terms
    1, 4, 6 and 7 and the floors to FI, at G = 168): the reciprocal's 2**-19.7, alpha floored
    to 2**-34 n G, 2A's floors summed twice n (n - 1) / 2 2**-36, the exact mid-edges'
    2**-24 and the FI floors' 2**-21."""
    return (2.0 ** -19.7 + 2.0 ** -24 + 2.0 ** -21 + n * 168 * 2.0 ** -34
            + n * (n - 1) / 2 * 2.0 ** -36)


def choice_tables(M, FI, FO, screen_bits, recip_err, linear):
    """The setup's choice in 64ths of ``BUDGET`` (``golden.bfp.choice``), each entry rounded
    up and 65 where the term alone is over: ``start[s0]``, a channel's error at a span's
    first pixel (``golden.bfp.narrow_bound``'s, or a linear channel's) for the group (a..e)
    of bit length
    M - 1 + s0; ``steps[s1 + kn]``, its first difference's over 2**kn steps for (Pu, Pv) of
    bit length M - 1 + s1; ``own[kn]``, :func:`other_terms` and the floors to FI over
    2**kn steps. The exponent e is the bit length less FO (``Widths.FO``)."""
    k = 5 + 2.0 ** (M + 1) * recip_err
    grow = 1 + 2.0 ** -(M - 5)
    part = lambda x: min(math.ceil(x / BUDGET * 64), 65)
    lengths = range(OPERAND - M + 2)                  # s = bit length - (M - 1)
    start = [part((2 + 2 * k if linear else 8 + 6 * k) * grow
                  * 2.0 ** (s + M - 1 - FO - M)) for s in lengths]
    steps = [part((2 + 2 * k) * grow * 2.0 ** (s + M - 1 - FO - M)) for s in
             range(len(lengths) + screen_bits + 1)]
    own = [part(other_terms(2 ** kn) + (2 + 2 * 2 ** kn) * 2.0 ** -FI)
           for kn in range(screen_bits + 1)]
    return start, steps, own
