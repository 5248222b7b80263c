"""Per-triangle block floating point (issue 49), bit for bit in Python's integers: the setup's
conversion of a channel's constants to M-bit mantissas with shared exponents, and the narrow
row engine's arithmetic at a span's first pixel (``hdl.span_unit.span._channel_narrow``).
Written from docs/quadratic.md ("The narrow row engine"), not from the RTL; the tests hold the
RTL to it exactly, and both to the float model within :func:`narrow_bound`.

Fixed-point inputs are integers: a..f, Pu, Pv with FO fraction bits, P0, 2A, Phi and d with FI
fraction bits, the numerators in sub-pixel units squared.
"""
__all__ = ["exponent", "mantissa", "quantised", "recip_mantissa", "amounts", "row",
           "narrow_bound", "narrow_ok", "other_terms", "rs_mantissa", "choice",
           "choice_tables", "AMOUNT_BITS", "BUDGET"]

from hdl.setup_unit.choice import BUDGET, choice_tables, other_terms
from hdl.span_unit.span import AMOUNT_BITS       # a shift amount into FI, clamped to 2**6 - 1


def _wrap(x, bits):
    """``x`` modulo 2**bits, signed."""
    x &= (1 << bits) - 1
    return x - (1 << bits) if x >> (bits - 1) else x


def exponent(values, frac, M):
    """A group's exponent e: every x has -2**e <= x < 2**e (x: integers with ``frac``
    fraction bits), from the bit length of the OR of the values' one's-complement
    magnitudes (x, or -x - 1 = ~x for a negative one: no negation in the setup), at least
    M - 1 bits (smaller groups' mantissas are then exact, and no shift is to the left)."""
    top = 0
    for x in values:
        x = int(x)
        top |= ~x if x < 0 else x
    return max(top.bit_length(), M - 1) - frac


def mantissa(x, e, frac, M):
    """``x`` (``frac`` fraction bits) as an M-bit signed mantissa at exponent ``e``:
    x 2**(M-1-e), floored (within [-2**(M-1), 2**(M-1)), so never saturated)."""
    return int(x) >> (frac + e - (M - 1))


def rs_mantissa(rcp, neg, R, M):
    """The narrow engine's reciprocal from the setup's: ``rcp`` ~ 2**R / m (m = |Omega| /
    2**sh in [1, 2)) rounded half up to M - 1 fraction bits, saturated at 2**(M-1) - 1, and
    negated for a negative Omega."""
    q = min((int(rcp) + (1 << (R - M))) >> (R - M + 1), (1 << (M - 1)) - 1)
    return -q if neg else q


def recip_mantissa(omega, M):
    """The narrow engine's reciprocal: 2**(M-1+sh) / Omega rounded half up and saturated at
    2**(M-1) - 1, sh the position of |Omega|'s leading one; and sh."""
    sh = abs(int(omega)).bit_length() - 1
    num, den = 1 << (M - 1 + sh), abs(int(omega))
    q = min((2 * num + den) // (2 * den), (1 << (M - 1)) - 1)
    return (q if omega > 0 else -q), sh


def amounts(e0, e1, linear, FI, M, left):
    """The shifts of a channel's products into FI: Phi's (u t1 + v t2 at 2 M - 4 - e0
    fraction bits, u d + v e at 2 M - 2 - e0 for a linear channel) and d's (Pu u + Pv v at
    2 M - 2 - e1), each ``(p << left) >> amount``, clamped to [0, 2**AMOUNT_BITS - 1]."""
    top = (1 << AMOUNT_BITS) - 1
    clamp = lambda a: min(max(a, 0), top)
    phi = left - (FI - 2 * M + (2 if linear else 4) + e0)
    return clamp(phi), clamp(left - (FI - 2 * M + 2 + e1))


def row(nu, nv, rs, sh, ch, M, FI, FO, left, linear):
    """Phi and d at FI of one channel at a span's first pixel, as the narrow engine computes
    them. ``ch``: the channel's mantissas ``a..e``, ``pu``, ``pv``, its fixed-point ``f``
    (FO) and ``p0`` (FI), and its amounts ``sphi``, ``sd``."""
    top = (1 << (M - 1)) - 1
    sat = lambda x: _wrap(min(x, top), M)
    # N = nu / 2**sh to M - 2 fraction bits, rounded: floor at M - 1 bits, then half of it
    mant = lambda n: sat((_wrap((n << (M - 1)) >> sh, M + 1) + 1) >> 1)
    rnd_uv = lambda p: sat((p + (1 << (M - 3))) >> (M - 2))         # M - 1 fraction bits
    u, v = rnd_uv(mant(nu) * rs), rnd_uv(mant(nv) * rs)
    shift = lambda p, a: (p << left) >> a
    if linear:
        t1, t2 = ch["d"], ch["e"]
    else:                                      # at exponent e0 + 2: M + 1 bits below the sum
        t = lambda base, x: _wrap(((base << (M - 1)) + x + (1 << M)) >> (M + 1), M)
        t1 = t(ch["d"], ch["a"] * u + ch["c"] * v)
        t2 = t(ch["e"], ch["b"] * v)
    phi = (ch["f"] << (FI - FO)) + shift(u * t1, ch["sphi"]) + shift(v * t2, ch["sphi"])
    if linear:
        return phi, ch["p0"]
    return phi, ch["p0"] + shift(ch["pu"] * u, ch["sd"]) + shift(ch["pv"] * v, ch["sd"])


def narrow_bound(M, e0, e1, FI, recip_err=0.0):
    """The narrow engine's errors at a span's first pixel against the float model of the same
    exact constants, in the constants' units: ``(Phi, d)``; after i steps Phi is off by at
    most Phi's + i d's. With e = 2**(e0 - M), each coefficient's mantissa is off by at most
    2 e (floored), u and v by eps = k 2**-M, k = 5 + 2**(M+1) ``recip_err`` (the numerator's
    and the reciprocal's roundings, 2 each, the product's 1, and the reciprocal's relative
    error: ``hdl.span_unit.span._uv_narrow``), and u, v >= 0, u + v <= 1 at the first pixel
    (docs/quadratic.md, "The narrow row engine"):
    - t1 = d + a u + c v: 2 e (1 + u + v) + 2**e0 2 eps <= (4 + 2 k) e, then its rounding at
      exponent e0 + 2, 4 e: (8 + 2 k) e. t2 = e + b v: (8 + k) e.
    - Phi = f + u t1 + v t2: (u + v) (8 + 2 k) e, and eps (|t1| + |t2|) <= eps 2**(e0+2) =
      4 k e: (8 + 6 k) e (38 e at k = 5). d = P0 + Pu u + Pv v (P0 exact): 2 e1' (u + v) +
      2**e1 2 eps = (2 + 2 k) e1', e1' = 2**(e1 - M).
    Products of two errors add under a factor 1 + 2**-(M-5); each shifted product's floor to
    FI adds 2**-FI."""
    k = 5 + 2.0 ** (M + 1) * recip_err
    grow = 1 + 2.0 ** -(M - 5)
    floors = 2 * 2.0 ** -FI
    return ((8 + 6 * k) * 2.0 ** (e0 - M) * grow + floors,
            (2 + 2 * k) * 2.0 ** (e1 - M) * grow + floors)


def narrow_ok(M, FI, channels, n, recip_err=0.0):
    """The narrow engine's errors on a triangle within ``BUDGET`` (:func:`narrow_bound` after
    ``n`` steps, and :func:`other_terms`), so that the raster's bound of 2**-(p+1) +
    2**-15.37 + 2**-(p+6) holds on it as on the wide engine. ``channels``: per channel
    (linear, e0, e1); a linear channel's Phi is off by at most (2 + 2 k) e (2 e (u + v) and
    eps 2**(e0+1)) and its d, P0, is exact. Works on arrays."""
    k = 5 + 2.0 ** (M + 1) * recip_err
    ok = True
    for linear, e0, e1 in channels:
        phi, d = narrow_bound(M, e0, e1, FI, recip_err)
        if linear:
            phi, d = (2 + 2 * k) * 2.0 ** (e0 - M) * (1 + 2.0 ** -(M - 5)) + 2 * 2.0 ** -FI, 0.0
        ok = ok & (phi + n * d + other_terms(n) <= BUDGET)
    return ok


def choice(M, FI, FO, sub_bits, screen_bits, recip_err, sh, ly, channels):
    """The setup's choice of the narrow engine for a triangle, as its RTL makes it from its
    tables (``hdl.setup_unit.choice``; ``tests/test_row_narrow.py`` holds them to
    :func:`narrow_ok`): :func:`narrow_ok` with n bounded by 2**kn (|Omega| < 2**(sh+1), y2 >= 2**ly sub-pixel
    units, so the widest chord W < 2**(sh+1-ly-sub_bits) pixels, and a span at most
    2**screen_bits), n (n - 1) / 2 by 2**(2 kn - 1), and each term rounded up to a 64th of
    the budget (:func:`choice_tables`). ``channels``: per channel (linear, bl0, bl1), the
    groups' clamped bit lengths (e0 = bl0 - FO). True where every channel's sum is within
    the budget."""
    kn = min(max(sh + 1 - ly - sub_bits, 0), screen_bits)
    for linear, bl0, bl1 in channels:
        start, steps, own = choice_tables(M, FI, FO, screen_bits, recip_err, linear)
        total = start[bl0 - (M - 1)] + own[kn]
        if not linear:
            total += steps[bl1 - (M - 1) + kn]
        if total > 64:
            return False
    return True


def quantised(values, frac, M):
    """A group's exponent and each value's mantissa (``mantissa``)."""
    e = exponent(values, frac, M)
    return e, [mantissa(x, e, frac, M) for x in values]
