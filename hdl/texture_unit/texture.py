"""Texel fetch: a bump map's texels in ROM, addressed by texture coordinates that the raster
interpolates (linear channels, ``VALUE``: tiles, 14 fraction bits), wrapping at every tile.

- A texel is two codes of ``bits`` bits each, ``hi`` above ``lo``: S and R for fenney_polar,
  TexelX and TexelZ for fenney_xz (8 bits each), theta and phi for angular (angle bits). The map is ``2**b`` texels a side, row t
  after row t - 1, each row along s.
- ``nearest``: the texel holding the coordinate, its index the top ``b`` fraction bits.
- ``bilinear`` (each code filtered on its own, as the patent's texels are; defined here in
  integers, and ``golden.bump.bilinear`` is the same definition in numpy):
  - u = c - half a texel; texels i0 = floor(u), i1 = i0 + 1 (wrapping), weight f the next
    ``F = weight_bits(b)`` bits of u, likewise along t;
  - each row: a = code(i0) 2**F + (code(i1) - code(i0)) f_s; then
    r = a(j0) 2**F + (a(j1) - a(j0)) f_t; the code is (r + 2**(2F-1)) >> 2F;
  - the 2 x 2 texels come from four ROM banks by the parities of s and t, one texel from
    each, so a fragment a clock needs no more ports than one read each;
  - three multipliers per code (two rows, one column), each alone in its stage.
  A filtered X/Z texel can leave the valid diamond |X| + |Z| <= 255: texel_decode's guard
  meets it downstream.
"""
import numpy as np
from amaranth.hdl import Cat, Mux

from ..fixed import u
from ..lut import build_lut, rom
from ..setup_unit.formats import VALUE

FILTERS = ("nearest", "bilinear")
MAX_TEXTURE = 1024            # texels a side (20 address bits)
CODES = ("hi", "lo")


def weight_bits(b):
    """Fraction bits of a bilinear weight: what the coordinate holds below the texel index,
    at most 6."""
    return min(6, VALUE.frac_bits - b)


def texture_lut(texels, bits=8, bank=None):
    """A texture ROM: ``texels`` (size x size, row t, column s), each ``hi << bits | lo``, as
    data (the scene's encoder makes them); ``bank`` (a, b): only the texels whose s and t have
    those parities."""
    texels = np.asarray(texels, np.int64)
    if bank is not None:
        texels = texels[bank[1]::2, bank[0]::2]
    texels = texels.ravel()
    return build_lut(lambda a: texels[a.astype(int)], (len(texels) - 1).bit_length(),
                     u(2 * bits))


def fetch_latency(filter):
    """:func:`fetch`'s stages: nearest 2 (the ROM's read register, its output registered),
    bilinear 7."""
    return 2 if filter == "nearest" else 7


def fetch(p, v, s, t, texels, filter, bits=8):
    """Texel codes at the coordinates ``s``, ``t`` (keys, consumed): ``_hi`` and ``_lo``, in
    ``fetch_latency(filter)`` stages. ``texels``: the map (see :func:`texture_lut`)."""
    b = len(texels).bit_length() - 1
    top = VALUE.frac_bits
    if filter == "nearest":
        addr = Cat(v.pop(s)[top - b:top], v.pop(t)[top - b:top])
        lut = texture_lut(texels, bits)
        v = p.stage(p.stage(v, _texel=rom(lut, addr, "texels")))
        texel = v.pop("_texel")
        return {**v, "_hi": texel[bits:2 * bits], "_lo": texel[:bits]}
    F = weight_bits(b)
    half = 1 << (top - b - 1)
    new = {}
    for axis, key in (("s", s), ("t", t)):
        c = (v.pop(key) - half)[:top]                       # u, modulo one tile
        i0 = c[top - b:top]
        new.update({f"_{axis}0": i0, f"_{axis}1": (i0 + 1)[:b],
                    f"_f{axis}": c[top - b - F:top - b]})
    v = p.stage(v, **new)
    # bank (a, c) holds the texels of s parity a and t parity c: one of the four each
    reads = {}
    for a in (0, 1):
        sa = Mux(v["_s0"][0] == a, v["_s0"], v["_s1"])
        for c in (0, 1):
            tc = Mux(v["_t0"][0] == c, v["_t0"], v["_t1"])
            lut = texture_lut(texels, bank=(a, c))
            reads[f"_b{a}{c}"] = rom(lut, Cat(sa[1:], tc[1:]), f"bank{a}{c}")
    par = {"_ps": v.pop("_s0")[0], "_pt": v.pop("_t0")[0]}
    v.pop("_s1"), v.pop("_t1")
    v = p.stage(v, **reads, **par)
    v = p.stage(v)                                          # the banks' outputs
    ps, pt = v.pop("_ps"), v.pop("_pt")
    bank = {(a, c): v.pop(f"_b{a}{c}") for a in (0, 1) for c in (0, 1)}

    def texel(di, dj):            # the footprint's texel (i0 + di, j0 + dj): its bank
        sel = lambda a, c: bank[a, c]
        return Mux(ps ^ di, Mux(pt ^ dj, sel(1, 1), sel(1, 0)),
                   Mux(pt ^ dj, sel(0, 1), sel(0, 0)))
    new = {}
    for k, code in enumerate(CODES):
        part = lambda x: x[8:16] if code == "hi" else x[:8]
        for dj in (0, 1):
            c0, c1 = part(texel(0, dj)), part(texel(1, dj))
            new[f"_{code}0{dj}"] = c0
            new[f"_{code}d{dj}"] = (c1 - c0)[:9].as_signed()
    v = p.stage(v, **new)
    fs, ft = v.pop("_fs"), v.pop("_ft")
    v = p.stage(v, **{f"_{code}a{dj}": (v.pop(f"_{code}0{dj}") << F) + v.pop(f"_{code}d{dj}") * fs
                      for code in CODES for dj in (0, 1)}, _ft2=ft)
    ft = v.pop("_ft2")
    v = p.stage(v, **{f"_{code}r0": v[f"_{code}a0"] << F for code in CODES},
                **{f"_{code}m": (v.pop(f"_{code}a1") - v.pop(f"_{code}a0")) * ft
                   for code in CODES})
    v = p.stage(v, **{f"_{code}": ((v.pop(f"_{code}r0") + v.pop(f"_{code}m")
                                   + (1 << (2 * F - 1))) >> (2 * F))[:8] for code in CODES})
    return v
