"""Bump vector dotted with an interpolated light, weighted: seed 004 eq 1, ``(1-h) + h*(N.L)``.

Formats (all exact integers, the unit in the field names the scale):

- bump ``x z`` s9, ``y`` u8: the decoded texel, ``|x| + |y| + |z| = 255`` (texel_decode);
- light ``lx ly lz`` s8: a unit vector times 127, linearly interpolated upstream, so its
  length may fall below 127 (the patent accepts that loss);
- ``h`` u8: the weight h times 255 (255 is exactly 1);
- out ``x`` u10: ``(1-h) + h*d`` as a 10-bit fraction (value/1024, saturated to 0..1023), the
  ``X`` that fenney_power takes.

The dot product ``d`` is, with ``D = x*lx + y*ly + z*lz``:

- ``normalize=False`` (the patent's): ``d = D / (255*127)``. The bump vector has L1 length 1, so
  its Euclidean length lies between 1/sqrt(3) and 1 and diagonal normals shade darker.
- ``normalize=True``: ``d = D / (127 * max(|b|, 128))``, the bump vector renormalised by a
  reciprocal-square-root table addressed by ``n2 = |b|^2`` (``rsqrt_bits`` address bits over
  0..65535; n2 >= 65536, from invalid texels only, is shifted down two bits and the result
  scaled by 1/2, which is exact). Vectors shorter than 128/255, which texel_decode never
  produces, are renormalised as if 128/255 long.

Fixed point: ``d`` is carried as ``dq = round(D * g / 2**15)``, ``d * 2**14``, with ``g`` the
table entry ``2**29 / (127 * |b|)``. Then ``M = (255 - h) * 2**14 + h * dq`` and
``out = round(M * 1024 / (255 * 2**14)) = round(M / 4080)``, done as ``M * K >> 36``. The bound
these roundings give against the float model is derived in ``golden.fenney.dot_bound``.
"""
import functools

import numpy as np
from amaranth.hdl import Mux

from ..fixed import Field, s, u
from ..lut import build_lut, rom
from ..unit import Unit

G_FRAC = 29                  # g = 2**29 / (127 * |b|)
D_FRAC = 14                  # dq = d * 2**14
DIV_SHIFT = 36               # M / 4080 as M * K >> 36
DIV_K = round(2**DIV_SHIFT / 4080)
assert DIV_K == 257 * 65537         # 0x1010101: the datapath multiplies by it with two adds
MIN_LEN = 128                # shortest |b| (of 255) the table renormalises exactly
G_PLAIN = round(2**G_FRAC / (127 * 255))
assert G_PLAIN == 2**14 + 2**7 + 2**6 + 2


@functools.lru_cache(maxsize=None)
def rsqrt_lut(addr_bits):
    """g(n2) = 2**29 / (127 * sqrt(max(n2, 128**2))) over n2 in [0, 65536)."""
    return build_lut(lambda n2: 2.0**G_FRAC / (127 * np.sqrt(np.maximum(n2, MIN_LEN**2))),
                     addr_bits, u(16), domain=(0, 65536))


class FenneyDot(Unit):
    """(1-h) + h * (bump . light), one result per clock; latency 10, or 12 when renormalising."""
    NAME = "fenney_dot"
    DOC = "Fenney bump . light dot product, weighted by h (US 6,819,319 eq 1)"
    PARAMS = {"normalize": False, "rsqrt_bits": 12}
    RANGES = {"rsqrt_bits": (4, 16)}
    inputs = (Field("x", s(9, unit="1/255")), Field("y", u(8, unit="1/255")),
              Field("z", s(9, unit="1/255")),
              Field("lx", s(8, unit="1/127")), Field("ly", s(8, unit="1/127")),
              Field("lz", s(8, unit="1/127")), Field("h", u(8, unit="1/255")))
    outputs = (Field("x", u(10, 10)),)

    @property
    def latency(self):
        return 12 if self.params["normalize"] else 10

    @property
    def lut(self):
        return rsqrt_lut(self.params["rsqrt_bits"]) if self.params["normalize"] else None

    def datapath(self, p, v):
        return dot_lanes(p, v, "x", "y", "z", [("lx", "ly", "lz", "h", "x")],
                         self.params["normalize"], self.params["rsqrt_bits"])


def dot_lanes(p, v, bx, by, bz, lanes, normalize=False, rsqrt_bits=12):
    """(1-h) + h (b.l) for one bump vector (``bx by bz`` keys) against several lights side by
    side: ``lanes`` of ``(lx, ly, lz, h, out)`` keys (10 stages, 12 renormalising). The
    vector's length and its table read are shared by every lane; each lane has its own three
    products, its weight and its divider. Every multiplier alone in its stage, registered on
    both sides; the table's output registered before it is used. The inputs are consumed."""
    v = dict(v)
    x, y, z = v.pop(bx), v.pop(by), v.pop(bz)
    n = range(len(lanes))
    prods = {}
    for k, (lx, ly, lz, _, _) in enumerate(lanes):
        prods.update({f"_px{k}": x * v.pop(lx), f"_py{k}": y * v.pop(ly),
                      f"_pz{k}": z * v.pop(lz)})
    if normalize:
        prods.update(_qx=x * x, _qy=y * y, _qz=z * z)
    v = p.stage(v, **prods)
    # |D| <= 256*128 + 255*128 + 256*128 = 98,176 for any inputs: s18, one multiplier port
    new = {f"_dot{k}": (v.pop(f"_px{k}") + v.pop(f"_py{k}") + v.pop(f"_pz{k}"))[:18]
           .as_signed() for k in n}                                            # D
    if normalize:
        new["_n2"] = v.pop("_qx") + v.pop("_qy") + v.pop("_qz")
    v = p.stage(v, **new)
    dq = {}
    if normalize:
        n2 = v.pop("_n2")
        big = n2 >= 65536
        n2_16 = Mux(big, n2 >> 2, n2)[:16]
        v = p.stage(v, _big=big, _addr=n2_16 >> (16 - rsqrt_bits))
        v = p.stage(v, _g=rom(rsqrt_lut(rsqrt_bits), v.pop("_addr"), "rsqrt"))
        v = p.stage(v)                                                 # the table's output
        g = v.pop("_g")
        v = p.stage(v, **{f"_prod{k}": v.pop(f"_dot{k}") * g for k in n})
        big = v.pop("_big")
        for k in n:
            prod = v.pop(f"_prod{k}")
            dq[k] = Mux(big, (prod + (1 << 15)) >> 16, (prod + (1 << 14)) >> 15)
    else:
        # D * G_PLAIN by wiring and adds (G_PLAIN = 2**14 + 2**7 + 2**6 + 2): a 19-bit
        # operand would take two chained MULT18X18Ds
        new = {}
        for k in n:
            dot = v.pop(f"_dot{k}")
            new.update({f"_a{k}": (dot << 14) + (dot << 7), f"_b{k}": (dot << 6) + (dot << 1)})
        v = p.stage(v, **new)
        v = p.stage(v, **{f"_prod{k}": v.pop(f"_a{k}") + v.pop(f"_b{k}") for k in n})
        dq = {k: (v.pop(f"_prod{k}") + (1 << 14)) >> 15 for k in n}
    # |d| <= |l| / 127 <= sqrt(3) (two of the table's bins' error over that): |dq| < 2**16
    v = p.stage(v, **{f"_dq{k}": dq[k][:17].as_signed() for k in n})       # d * 2**14
    new = {}
    for k, (_, _, _, h, _) in enumerate(lanes):
        hk = v.pop(h)
        new.update({f"_keep{k}": (255 - hk) << D_FRAC, f"_hd{k}": hk * v.pop(f"_dq{k}")})
    v = p.stage(v, **new)
    v = p.stage(v, **{f"_m{k}": v.pop(f"_keep{k}") + v.pop(f"_hd{k}") for k in n})      # M
    # round(M / 4080) as (M * K + 2**35) >> 36 with K = 0x1010101 = 257 * 65537, by wiring
    # and adds: s = 257 M, then (s + (s >> 16) + 2**19) >> 20 (s's low 16 bits never carry)
    v = p.stage(v, **{f"_s{k}": v[f"_m{k}"] + (v.pop(f"_m{k}") << 8) for k in n})
    v = p.stage(v, **{f"_q{k}": (v[f"_s{k}"] + (v.pop(f"_s{k}") >> 16)
                                 + (1 << (DIV_SHIFT - 17))) >> (DIV_SHIFT - 16) for k in n})
    out = {}
    for k, (_, _, _, _, key) in enumerate(lanes):
        q = v.pop(f"_q{k}")
        out[key] = Mux(q < 0, 0, Mux(q > 1023, 1023, q))[:10]
    return p.stage(v, **out)
