"""Texel fetch: a bump map's texels in the texture memory, read through the texel cache
(``cache.py``) at texture coordinates that the raster interpolates (linear channels,
``VALUE``: tiles, 14 fraction bits), wrapping at every tile.

- A texel is two codes of ``bits`` bits each, ``hi`` above ``lo``: S and R for fenney_polar,
  TexelX and TexelZ for fenney_xz (8 bits each), theta and phi for angular (12 bits each): 16
  or 24 bits. The map is ``2**b`` texels a side.
- **Memory layout** (``memory_image``), texel addresses from 0 (the map's base):
  - nearest: one bank, row t after row t - 1, each row along s: ``t * size + s``;
  - bilinear: four banks, bank ``k = 2 (t & 1) + (s & 1)`` at ``k * (size / 2)**2``, each a
    quarter map, row ``t >> 1`` after row ``(t >> 1) - 1``: ``k (size/2)**2 + (t >> 1)
    (size / 2) + (s >> 1)``. A 2 x 2 footprint has one texel in each bank.
- ``nearest``: the texel holding the coordinate, its index the top ``b`` fraction bits.
- ``bilinear`` (each code filtered on its own, as the patent's texels are; defined here in
  integers, and ``golden.bump.fetch`` is the same definition in numpy):
  - u = c - half a texel; texels i0 = floor(u), i1 = i0 + 1 (wrapping), weight f the next
    ``F = weight_bits(b)`` bits of u, likewise along t;
  - each row: a = code(i0) 2**F + (code(i1) - code(i0)) f_s; then
    r = a(j0) 2**F + (a(j1) - a(j0)) f_t; the code is (r + 2**(2F-1)) >> 2F;
  - three products per code (two rows, one column), each in logic as two halves
    (``hdl.dsp.soft_halves``), a clock for the halves and one for their sum.
  A filtered X/Z texel can leave the valid diamond |X| + |Z| <= 255: texel_decode's guard
  meets it downstream.
"""
import numpy as np
from amaranth.hdl import Cat, Mux

from ..dsp import soft_halves
from ..setup_unit.formats import VALUE

__all__ = ["FILTERS", "MAX_TEXTURE", "banks", "memory_image", "lines", "filtered",
           "address_stages", "filter_stages", "weight_bits"]

FILTERS = ("nearest", "bilinear")
MAX_TEXTURE = 1024            # texels a side (20 address bits; ADDR has 24)
CODES = ("hi", "lo")


def weight_bits(b):
    """Fraction bits of a bilinear weight: what the coordinate holds below the texel index,
    at most 6."""
    return min(6, VALUE.frac_bits - b)


def banks(filter):
    return 1 if filter == "nearest" else 4


def memory_image(hi, lo, bits, filter):
    """The map's texels (``hi``, ``lo``: size x size codes, row t, column s) as the texture
    memory holds them (the layout above): one word per texel, ``hi << bits | lo``."""
    words = (np.asarray(hi, np.int64) << bits) | np.asarray(lo, np.int64)
    if filter == "nearest":
        return words.ravel()
    return np.concatenate([words[c::2, a::2].ravel() for c in (0, 1) for a in (0, 1)])


def address_stages(filter):
    return 1 if filter == "nearest" else 2


def filter_stages(filter):
    return 1 if filter == "nearest" else 7


def lines(p, v, s, t, size, filter, line):
    """Each bank's line number ``_ln<k>`` and the texel's place in it ``_off<k>`` (none for
    lines of one texel) at the
    coordinates ``s``, ``t`` (keys, consumed), in ``address_stages(filter)`` stages; with
    bilinear, the weights ``_fs``, ``_ft`` and the footprint's parities ``_ps``, ``_pt``."""
    b, lb = size.bit_length() - 1, line.bit_length() - 1
    top = VALUE.frac_bits
    place = lambda k, c: {f"_off{k}": c[:lb]} if lb else {}    # a line of one: no place
    if filter == "nearest":
        si, ti = v.pop(s)[top - b:top], v.pop(t)[top - b:top]
        return p.stage(v, _ln0=Cat(si[lb:], ti), **place(0, si))
    F = weight_bits(b)
    half = 1 << (top - b - 1)
    new = {}
    for axis, key in (("s", s), ("t", t)):
        c = (v.pop(key) - half)[:top]                       # u, modulo one tile
        i0 = c[top - b:top]
        new.update({f"_{axis}0": i0, f"_{axis}1": (i0 + 1)[:b],
                    f"_f{axis}": c[top - b - F:top - b]})
    v = p.stage(v, **new)
    # bank 2c + a holds the texels of s parity a and t parity c: one of the four each
    new = {}
    for c in (0, 1):
        tc = Mux(v["_t0"][0] == c, v["_t0"], v["_t1"])[1:]
        for a in (0, 1):
            sa = Mux(v["_s0"][0] == a, v["_s0"], v["_s1"])[1:]
            new[f"_ln{2 * c + a}"] = Cat(sa[lb:], tc)
            new.update(place(2 * c + a, sa))
    new.update(_ps=v.pop("_s0")[0], _pt=v.pop("_t0")[0])
    v.pop("_s1"), v.pop("_t1")
    return p.stage(v, **new)


def filtered(p, v, filter, bits, size):
    """The codes ``_hi`` and ``_lo`` from the banks' texels ``_tex<k>`` (the cache's output
    register), in ``filter_stages(filter)`` stages."""
    if filter == "nearest":
        v = p.stage(v)                               # the data array's output registered
        texel = v.pop("_tex0")
        return {**v, "_hi": texel[bits:2 * bits], "_lo": texel[:bits]}
    F = weight_bits(size.bit_length() - 1)
    v = p.stage(v)                                   # the banks' outputs registered
    ps, pt = v.pop("_ps"), v.pop("_pt")
    bank = {(a, c): v.pop(f"_tex{2 * c + a}") for a in (0, 1) for c in (0, 1)}

    def texel(di, dj):            # the footprint's texel (i0 + di, j0 + dj): its bank
        sel = lambda a, c: bank[a, c]
        return Mux(ps ^ di, Mux(pt ^ dj, sel(1, 1), sel(1, 0)),
                   Mux(pt ^ dj, sel(0, 1), sel(0, 0)))
    new = {}
    for code in CODES:
        part = lambda x: x[8:16] if code == "hi" else x[:8]
        for dj in (0, 1):
            c0, c1 = part(texel(0, dj)), part(texel(1, dj))
            new[f"_{code}0{dj}"] = c0
            new[f"_{code}d{dj}"] = (c1 - c0)[:9].as_signed()
    v = p.stage(v, **new)
    # Each product by a weight (F <= 6 bits) is logic, not a MULT18X18D: two soft halves in
    # one clock, summed in the next (hdl.dsp.soft_halves). The six would otherwise take six
    # of the 25F's 28 blocks, which fenney_xz's pipeline needs for its raster.
    fs = v.pop("_fs")
    new = {}
    for code in CODES:
        for dj in (0, 1):
            lo, hi, k = soft_halves(fs, v.pop(f"_{code}d{dj}"))
            new.update({f"_{code}l{dj}": lo, f"_{code}h{dj}": hi})
    v = p.stage(v, **new)
    v = p.stage(v, **{f"_{code}a{dj}": (v.pop(f"_{code}0{dj}") << F) + v.pop(f"_{code}l{dj}")
                      + (v.pop(f"_{code}h{dj}") << k) for code in CODES for dj in (0, 1)})
    v = p.stage(v, **{f"_{code}r0": v[f"_{code}a0"] << F for code in CODES},
                **{f"_{code}ad": v.pop(f"_{code}a1") - v.pop(f"_{code}a0") for code in CODES})
    ft = v.pop("_ft")
    new = {}
    for code in CODES:
        lo, hi, k = soft_halves(ft, v.pop(f"_{code}ad"))
        new.update({f"_{code}ml": lo, f"_{code}mh": hi})
    v = p.stage(v, **new)
    v = p.stage(v, **{f"_{code}": ((v.pop(f"_{code}r0") + v.pop(f"_{code}ml")
                                   + (v.pop(f"_{code}mh") << k)
                                   + (1 << (2 * F - 1))) >> (2 * F))[:8] for code in CODES})
    return v
