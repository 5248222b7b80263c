"""The texel_decode stage (seed 004, second embodiment): the X/Z codes to the bump vector."""
import numpy as np

from golden import fenney
from hdl.illum_unit.texel_decode import TexelDecode as Unit

from ..stage import Stage


class TexelDecode(Stage):
    bump = True
    name = "texel_decode"
    why = "bump.method = fenney_xz"
    when = {"bump": "fenney_xz"}

    @property
    def latency(self):
        return Unit.spec().latency

    def rtl(self, p, v, uni):
        v["texel_x"], v["texel_z"] = v.pop("_hi"), v.pop("_lo")
        v = Unit.spec().datapath(p, v)
        v.pop("invalid")             # decoded by the guard's rule (docs/bump.md)
        return v

    format_group = "texels"

    def convert(self, ch, ideal):
        """The decoded vector: L1 length 255 (the model's) or 1 (the ideal's)."""
        if not all(a in ch for a in "xyz"):
            return ch
        return {**ch, **{a: ch[a] / 255.0 if ideal else ch[a] * 255.0 for a in "xyz"}}

    def ideal(self, prep, frag, ch):
        """The normal as the patent's X/Z texel holds it, unrounded: in its axes (x along T,
        y out, z along B), of L1 length 1."""
        ch = dict(ch)
        n = ch.pop("_n")[:, [0, 2, 1]]
        n = n / np.abs(n).sum(-1, keepdims=True)
        return {**ch, **{a: n[:, k] for k, a in enumerate("xyz")}}

    def model(self, prep, frag, ch, bound):
        out = fenney.texel_decode(ch.pop("_hi"), ch.pop("_lo"))
        return {**ch, **{k: out[k] for k in "xyz"}}
