"""The texture stage: the bump map's texel codes at the raster's texture coordinates (``s``,
``t``, linear channels), nearest or bilinear; the texels reach the hardware as data, encoded
here from the scene's map (``golden.bump``)."""
import functools

import numpy as np

from golden import bump as bumps
from hdl.setup_unit.formats import VALUE
from hdl.texture_unit import MAX_TEXTURE, fetch, fetch_latency

from ..stage import Stage

ANGLE_BITS = 12               # angular: every angle in turns * 2**12 (the rotation's default)


@functools.lru_cache(maxsize=4)
def texels(kind, bump_map, bump_size, bump_depth, bits):
    """The texture ROM's words (size x size, ``hi << bits | lo``) of a scene's bump map."""
    hi, lo, _ = bumps.bump_texels(kind, bump_map, bump_size, bump_depth, bits)
    return (hi.astype(np.int64) << bits) | lo


def raw(v):
    """A channel's real value as the raster's raw integer (``VALUE``)."""
    return np.rint(np.asarray(v) / VALUE.lsb).astype(np.int64)


class Texture(Stage):
    bump = True
    name = "texture"
    channels = (("s", "linear", 0), ("t", "linear", 0))

    @classmethod
    def wanted(cls, q):
        return q["bump"] != "none"

    @property
    def kind(self):
        return bumps.KINDS[self.q["bump"]]

    @property
    def bits(self):
        return ANGLE_BITS if self.kind == "polar" else 8

    @property
    def params(self):
        q = self.q
        out = dict(kind=self.kind, bump_map=q["bump_map"], bump_size=q["bump_size"],
                   bump_depth=q["bump_depth"], filter=q["filter"])
        if self.kind == "polar":
            out["bits"] = ANGLE_BITS
        return out

    @property
    def why(self):
        return f"bump.map = {self.q['bump_map']}: {self.kind} texels, {self.q['filter']}"

    def validate(self, q):
        size = q["bump_size"]
        if size & (size - 1) or size > MAX_TEXTURE:
            raise ValueError(f"bump.size: must be a power of two up to {MAX_TEXTURE} (the "
                             f"texture coordinates wrap by their bits), not {size}")
        if q["bump"] in ("fenney_polar", "angular") and q["filter"] != "nearest":
            raise ValueError(f"bump.filter: {q['bump']} filters nearest only (its texels are "
                             f"angles, which do not interpolate across their wrap); bilinear "
                             f"is for fenney_xz")

    @property
    def latency(self):
        return fetch_latency(self.q["filter"])

    def rtl(self, p, v, uni):
        q = self.q
        words = texels(self.kind, q["bump_map"], q["bump_size"], q["bump_depth"], self.bits)
        return fetch(p, v, "s", "t", words, q["filter"], self.bits)

    def model(self, prep, frag, ch, bound):
        """The codes ``_hi``, ``_lo`` (``golden.bump.fetch``: nearest, or the bilinear filter
        bit for bit). ``bound``: ``ds``, ``dt`` added to the raw texture coordinates."""
        hi, lo = prep["bump"]["texels"]
        rs, rt = raw(ch["s"]) + bound.get("ds", 0), raw(ch["t"]) + bound.get("dt", 0)
        return {**ch, "_hi": bumps.fetch(hi, rs, rt, self.q["filter"]),
                "_lo": bumps.fetch(lo, rs, rt, self.q["filter"])}
