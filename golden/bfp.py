"""Per-triangle block floating point (issue 49), bit for bit in Python's integers: the setup's
conversion of a channel's constants to M-bit mantissas with shared exponents, and the narrow
row engine's arithmetic at a span's first pixel (``hdl.span_unit.span._channel_narrow``).
Written from docs/quadratic.md ("The narrow row engine"), not from the RTL; the tests hold the
RTL to it exactly, and both to the float model within :func:`narrow_bound`.

Fixed-point inputs are integers: a..f, Pu, Pv with FO fraction bits, P0, 2A, Phi and d with FI
fraction bits, the numerators in sub-pixel units squared.
"""
__all__ = ["exponent", "mantissa", "quantised", "recip_mantissa", "amounts", "row",
           "narrow_bound", "AMOUNT_BITS"]

AMOUNT_BITS = 6          # a shift amount into FI, clamped to 2**6 - 1


def _wrap(x, bits):
    """``x`` modulo 2**bits, signed."""
    x &= (1 << bits) - 1
    return x - (1 << bits) if x >> (bits - 1) else x


def exponent(values, frac):
    """The least e with every |x| < 2**e (x: integers with ``frac`` fraction bits): the bit
    length of the OR of the magnitudes, less ``frac``."""
    top = 0
    for x in values:
        top |= abs(int(x))
    return top.bit_length() - frac


def mantissa(x, e, frac, M):
    """``x`` (``frac`` fraction bits) as an M-bit signed mantissa at exponent ``e``:
    x 2**(M-1-e), rounded half up, the one value that rounds up to 2**(M-1) saturated."""
    s = frac + e - (M - 1)
    x = int(x)
    q = (x + (1 << (s - 1))) >> s if s > 0 else x << -s
    return min(q, (1 << (M - 1)) - 1)


def recip_mantissa(omega, M):
    """The narrow engine's reciprocal: 2**(M-2+sh) / Omega rounded half up, sh the position
    of |Omega|'s leading one (so |rs| is in (2**(M-3), 2**(M-2)]); and sh."""
    sh = abs(int(omega)).bit_length() - 1
    num, den = 1 << (M - 2 + sh), int(omega)
    q = (2 * num + abs(den)) // (2 * abs(den))          # round half up of the magnitude
    return (q if den > 0 else -q), sh


def amounts(e0, e1, linear, FI, M, left):
    """The shifts of a channel's products into FI: Phi's (u t1 + v t2 at 2 M - 5 - e0
    fraction bits, u d + v e at 2 M - 3 - e0 for a linear channel) and d's (Pu u + Pv v at
    2 M - 3 - e1), each ``(p << left) >> amount``, clamped to [0, 2**AMOUNT_BITS - 1]."""
    top = (1 << AMOUNT_BITS) - 1
    clamp = lambda a: min(max(a, 0), top)
    phi = left - (FI - 2 * M + (3 if linear else 5) + e0)
    return clamp(phi), clamp(left - (FI - 2 * M + 3 + e1))


def row(nu, nv, rs, sh, ch, M, FI, FO, left, linear):
    """Phi and d at FI of one channel at a span's first pixel, as the narrow engine computes
    them. ``ch``: the channel's mantissas ``a..e``, ``pu``, ``pv``, its fixed-point ``f``
    (FO) and ``p0`` (FI), and its amounts ``sphi``, ``sd``."""
    frac = M - 2
    mant = lambda n: _wrap((n << frac) >> sh, M)                      # floor, M bits
    rnd_uv = lambda p: _wrap((p + (1 << (M - 3))) >> frac, M)
    u, v = rnd_uv(mant(nu) * rs), rnd_uv(mant(nv) * rs)
    shift = lambda p, a: (p << left) >> a
    if linear:
        t1, t2 = ch["d"], ch["e"]
    else:
        t = lambda base, x: _wrap(((base << frac) + x + (1 << (M - 1))) >> M, M)
        t1 = t(ch["d"], ch["a"] * u + ch["c"] * v)
        t2 = t(ch["e"], ch["b"] * v)
    phi = (ch["f"] << (FI - FO)) + shift(u * t1, ch["sphi"]) + shift(v * t2, ch["sphi"])
    if linear:
        return phi, ch["p0"]
    return phi, ch["p0"] + shift(ch["pu"] * u, ch["sd"]) + shift(ch["pv"] * v, ch["sd"])


def narrow_bound(M, e0, e1, FI):
    """The narrow engine's errors at a span's first pixel against the float model of the same
    exact constants, in the constants' units: ``(Phi, d)``; after i steps Phi is off by at
    most Phi's + i d's. They are ``flows.bfp.bound``'s terms, derived for M - 1 bits (so each
    coefficient's rounding, e(e) at M bits or 2 e(e) where it saturates, is within e(e) at
    M - 1), with u and v off by 3 r (5 r at M bits: ``hdl.span_unit.span._uv_narrow``) and
    P0 exact, plus a floor to FI for each of the two shifted products (2**-FI each)."""
    m, rs = M - 1, 3
    eps = lambda x: 2.0 ** (x - m)
    grow = 1 + rs * 2.0 ** -(m - 3)            # the products of two roundings
    floors = 2 * 2.0 ** -FI
    return ((7 + 12 * rs) * eps(e0) * grow + floors, (3 + 4 * rs) * eps(e1) * grow + floors)


def quantised(values, frac, M):
    """A group's exponent and each value's mantissa (``mantissa``)."""
    e = exponent(values, frac)
    return e, [mantissa(x, e, frac, M) for x in values]
