"""X/Z bump texel decode (US 6,819,319, second embodiment).

The patent's decode, bit-exact for valid texels::

    BumpX = (TexelX - 127) * 2      INT9
    BumpZ = (TexelZ - 127) * 2      INT9
    BumpY = 255 - |BumpX| - |BumpZ| UINT8

The vector is scaled so that ``|x| + |y| + |z| = 255`` (an L1 unit vector times 255), not to unit
length. The patent guards invalid texels but says no more; our policy (docs/fenney.md):

- a code of 255 (``(255-127)*2 = 256`` does not fit INT9) decodes as 254, the nearest valid
  code, so ``x`` and ``z`` stay within -254..254;
- ``y = max(0, 255 - |x| - |z|)``: past the diamond ``|x| + |z| = 255`` the vector lies on the
  horizon in the direction of (x, z), and ``y`` never wraps;
- ``invalid`` is raised for either case. Bilinear filtering can push valid texels past the
  diamond; they decode by the same rule.
"""
from amaranth.hdl import Mux

from ..fixed import Field, s, u
from ..unit import Unit

L1 = 255  # |x| + |y| + |z| of every valid decoded texel


class TexelDecode(Unit):
    """16-bit X/Z texel to bump vector (x, y, z), one per clock, latency 2."""
    NAME = "texel_decode"
    DOC = "Fenney X/Z texel decode (US 6,819,319, second embodiment)"
    inputs = (Field("texel_x", u(8, unit="code")), Field("texel_z", u(8, unit="code")))
    outputs = (Field("x", s(9, unit="1/255")), Field("y", u(8, unit="1/255")),
               Field("z", s(9, unit="1/255")), Field("invalid", u(1, unit="flag")))
    latency = 2

    def datapath(self, p, v):
        v = dict(v)
        tx, tz = v.pop("texel_x"), v.pop("texel_z")
        new = {"bad": (tx == 255) | (tz == 255)}
        for k, code in (("x", tx), ("z", tz)):
            c = Mux(code == 255, 254, code)
            new[k] = ((c - 127) * 2)[:9].as_signed()
            new[f"_a{k}"] = Mux(c >= 127, c - 127, 127 - c)[:7] << 1           # |Bump|
        v = p.stage(v, **new)
        l1_xz = v.pop("_ax") + v.pop("_az")
        return p.stage(v, y=Mux(l1_xz > L1, 0, L1 - l1_xz)[:8],
                       invalid=v.pop("bad") | (l1_xz > L1))
