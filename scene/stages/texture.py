"""The texture stage: the bump map's texel codes at the raster's texture coordinates (``s``,
``t``, linear channels), nearest or bilinear, read through the texel cache from the texture
memory port (``tex_req``, ``tex_resp``; ``hdl/texture_unit``). The texels are data: the
driver encodes them from the scene's map (``golden.bump``) into the memory image, which the
harness's memory holds; the hardware depends only on the map's size, the filter and the
cache."""
from amaranth.lib.wiring import In, Out

from golden import bump as bumps
from hdl.texture_unit import (CACHE_LATENCY, MAX_TEXTURE, address_stages, banks, filter_stages,
                              filtered, lines, memory_image, request_fields, response_fields,
                              texel_cache)
from hdl.unit import Pipeline

from ..stage import Link, Stage, raw

ANGLE_BITS = 12               # angular: every angle in turns * 2**12 (the rotation's default)


CACHE = ("cache_lines", "cache_line", "cache_ways", "tex_queue", "bank_ports")


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
        out = dict(kind=self.kind, bump_size=q["bump_size"], filter=q["filter"],
                   bits=self.bits, **{k: q[k] for k in CACHE})
        return out

    @property
    def port_names(self):
        """``[(request, response)]``: one port shared by the banks, or one per bank."""
        n = banks(self.q["filter"]) if self.q["bank_ports"] else 1
        return [("tex_req", "tex_resp")] if n == 1 else \
            [(f"tex_req{k}", f"tex_resp{k}") for k in range(n)]

    @property
    def ports(self):
        out = {}
        for req, resp in self.port_names:
            out.update({req: (Out, request_fields()),
                        resp: (In, response_fields(2 * self.bits))})
        return out

    @property
    def why(self):
        return (f"bump.method = {self.q['bump']}: {self.kind} texels, {self.q['filter']}, "
                f"{self.q['bump_size']} a side, through the texel cache")

    def validate(self, q):
        for k in ("cache_lines", "cache_line", "cache_ways", "tex_queue"):
            if q[k] & (q[k] - 1):
                raise ValueError(f"{k}: must be a power of two, not {q[k]}")
        if q["cache_ways"] > q["cache_lines"]:
            raise ValueError(f"cache_ways: must be at most cache_lines ({q['cache_lines']}), "
                             f"not {q['cache_ways']}")
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
        """With every texel in the cache and nothing waiting: the address stages, the cache,
        the filter's stages."""
        f = self.q["filter"]
        return address_stages(f) + CACHE_LATENCY + filter_stages(f)

    def build(self, m, i, o, v, uni, ports):
        """The line addresses (a pipeline), the cache (its own handshakes: its latency
        varies), the filter (a pipeline)."""
        q, f = self.q, self.q["filter"]
        size, n = q["bump_size"], banks(f)
        a_out, c_out = Link(), Link()
        p1 = Pipeline(m, i, a_out)
        v = lines(p1, v, "s", "t", size, f, q["cache_line"])
        m.d.comb += a_out.valid.eq(p1.valid)
        v, busy = texel_cache(m, a_out, v, c_out, [ports[r] for r, _ in self.port_names],
                              [ports[r] for _, r in self.port_names],
                              banks=n, lines=q["cache_lines"], line=q["cache_line"],
                              ways=q["cache_ways"], bank_texels=size * size // n,
                              texel_bits=2 * self.bits, depth=q["tex_queue"])
        p2 = Pipeline(m, c_out, o)
        v = filtered(p2, v, f, self.bits, size)
        m.d.comb += o.valid.eq(p2.valid)
        for valid in p1.valids + p2.valids:
            busy = busy | valid
        return v, busy

    def image(self, prep):
        """The texture memory's words (``hdl.texture_unit.memory_image``'s layout)."""
        hi, lo = prep["bump"]["texels"]
        return memory_image(hi, lo, self.bits, self.q["filter"])

    def model(self, prep, frag, ch, bound):
        """The codes ``_hi``, ``_lo`` (``golden.bump.fetch``: nearest, or the bilinear filter
        bit for bit). ``bound``: ``ds``, ``dt`` added to the raw texture coordinates."""
        hi, lo = prep["bump"]["texels"]
        rs, rt = raw(ch["s"]) + bound.get("ds", 0), raw(ch["t"]) + bound.get("dt", 0)
        return {**ch, "_hi": bumps.fetch(hi, rs, rt, self.q["filter"]),
                "_lo": bumps.fetch(lo, rs, rt, self.q["filter"])}
