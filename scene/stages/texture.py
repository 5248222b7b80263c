"""The texture stage: the bump map's texel codes at the raster's texture coordinates (``s``,
``t``, linear channels), nearest or bilinear, from one of two texture memories
(``texture``):

- ``external``: read through the texel cache from the texture memory port (``tex_req``,
  ``tex_resp``; ``hdl/texture_unit``), for maps up to 1024 x 1024;
- ``onchip``: a texture RAM in the top (a block RAM per bank), which the host loads through
  its port (``scene/host.py``); a fixed latency, no cache. At most ``ONCHIP_MAX`` texels a
  side: 128 x 128 texels of 16 bits take 16 of the ECP5-25F's 56 DP16KD.

The texels are data: the driver encodes them from the scene's map (``golden.bump``) into the
memory image, in one layout for both (``hdl.texture_unit.memory_image``); the hardware depends
only on the map's size, the filter, the memory and the cache."""
import math

import numpy as np
from amaranth.lib import stream
from amaranth.lib.wiring import In, Out

from golden import bump as bumps
from hdl.fixed import Field, layout, u
from hdl.setup_unit.formats import VALUE
from hdl.lut import WriteBus, blank_lut, rom
from hdl.texture_unit import (ADDR, CACHE_LATENCY, FILTERS, MAX_TEXTURE, address_stages, banks, filter_stages,
                              filtered, lines, memory_image, request_fields, response_fields,
                              texel_cache)
from hdl.unit import Pipeline

from ..host import equals
from ..mesh import tangent_frames, texcoords
from ..stage import Link, SceneError, Stage, Sweep, raw

ANGLE_BITS = 12               # angular: every angle in turns * 2**12 (the rotation's default)
MEMORIES = ("external", "onchip")
ONCHIP_MAX = 128              # texels a side of the on-chip texture RAM (the ECP5-25F's fit)
ONCHIP_LATENCY = 1            # the RAM's read register
ANGLES = ("sr", "polar")      # texel kinds that hold angles (golden.bump.KINDS): nearest only

# The on-chip texture's side where the 128 x 128 of ONCHIP_MAX cannot fit beside the rest:
# angular's rotation and illumination tables take 52 of the 56 DP16KD, and 32 x 32 texels of
# 24 bits take 2 more (128 x 128 would take 24).
BOARD_TEXTURE = {"angular": 32}


def board_form(params, texture="onchip"):
    """A scene pipeline's parameters as a board builds it: a bump pipeline's texture in the
    on-chip RAM (``texture = "onchip"``, the default for FPGA builds), at most
    ``ONCHIP_MAX`` texels a side, loaded at run time like the rest of the scene's data; or
    ``external``, the memory port, as the renders take it."""
    if params.get("bump", "none") == "none" or texture == "external":
        return dict(params)
    return {**params, "texture": "onchip",
            "bump_size": min(params["bump_size"], BOARD_TEXTURE.get(params["bump"], ONCHIP_MAX))}


CACHE = ("cache_lines", "cache_line", "cache_ways", "tex_queue", "bank_ports")


class Texture(Stage):
    bump = True
    name = "texture"
    format_group = "texels"
    scene_keys = {"bump": {"map": ("bricks", ("str",)), "size": (256, ("int", 16, 4096)),
                           "repeat": ([8.0, 2.0], ("vec", 2, 1e-6, math.inf)),
                           "depth": (1.0, ("num", 0.0, math.inf)),
                           "filter": ("nearest", ("choice", FILTERS))}}
    channels = (("s", "linear", 0), ("t", "linear", 0))
    # the map's size and filter (the scene's), the memory and the texel cache (per bank:
    # lines, texels a line, ways), its queue, and a memory port per bank (bilinear: 4) or one
    build_params = {"bump_size": (256, (16, MAX_TEXTURE)), "texture": (MEMORIES[0], MEMORIES),
                    "filter": (FILTERS[0], FILTERS), "cache_lines": (64, (2, 1024)),
                    "cache_line": (1, (1, 64)), "cache_ways": (2, (1, 8)),
                    "tex_queue": (64, (4, 512)), "bank_ports": (True, None)}

    @classmethod
    def wanted(cls, q):
        return q["bump"] != "none"

    @classmethod
    def sweeps(cls):
        """The filter: the whole fenney_xz pipeline (the texture is not a unit of its own)."""
        return [Sweep("filter", f, scene="bump_xz", hardware={"filter": f}, build="pipeline",
                      default=f == "bilinear") for f in FILTERS]

    @property
    def kind(self):
        return bumps.KINDS[self.q["bump"]]

    @property
    def bits(self):
        return ANGLE_BITS if self.kind == "polar" else 8

    @property
    def label(self):
        return self.q["filter"]

    @property
    def onchip(self):
        return self.q["texture"] == "onchip"

    @property
    def params(self):
        q = self.q
        return dict(kind=self.kind, bump_size=q["bump_size"], filter=q["filter"],
                    bits=self.bits, texture=q["texture"],
                    **({} if self.onchip else {k: q[k] for k in CACHE}))

    @property
    def uniforms(self):
        """External memory: the map's base address, a register (the memory may hold many)."""
        return [] if self.onchip else [Field("tex_base", ADDR)]

    def uniform_values(self, scene, L, H):
        return {} if self.onchip else {"tex_base": 0}

    @property
    def tables(self):
        """The on-chip texture RAM: every bank's words, one after another."""
        size = self.q["bump_size"]
        return {"texture": blank_lut(size * size, u(2 * self.bits))} if self.onchip else {}

    @property
    def port_names(self):
        """``[(request, response)]``: one port shared by the banks, or one per bank."""
        n = banks(self.q["filter"]) if self.q["bank_ports"] else 1
        return [("tex_req", "tex_resp")] if n == 1 else \
            [(f"tex_req{k}", f"tex_resp{k}") for k in range(n)]

    @property
    def ports(self):
        if self.onchip:
            return {}
        out = {}
        for req, resp in self.port_names:
            out.update({req: (Out, request_fields()),
                        resp: (In, response_fields(2 * self.bits))})
        return out

    @property
    def why(self):
        return (f"bump.method = {self.q['bump']}: {self.kind} texels, {self.q['filter']}, "
                f"{self.q['bump_size']} a side, " + (
                    "from the on-chip texture RAM" if self.onchip else "through the texel cache"))

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
        if q["texture"] == "onchip" and size > ONCHIP_MAX:
            raise ValueError(f"bump.size: {size} x {size} texels exceed the on-chip texture RAM "
                             f"(at most {ONCHIP_MAX} x {ONCHIP_MAX}, what an ECP5-25F holds "
                             f"beside the pipeline); use --texture external (the memory "
                             f"port) or a smaller map")
        if self.kind in ANGLES and q["filter"] != "nearest":
            vectors = [m for m, k in bumps.KINDS.items() if k not in ANGLES]
            raise ValueError(f"bump.filter: {q['bump']} filters nearest only (its texels are "
                             f"angles, which do not interpolate across their wrap); bilinear "
                             f"is for {', '.join(vectors)}")

    @property
    def latency(self):
        """With every texel in the cache and nothing waiting: the address stages, the cache,
        the filter's stages."""
        f = self.q["filter"]
        memory = ONCHIP_LATENCY if self.onchip else CACHE_LATENCY
        return address_stages(f) + memory + filter_stages(f)

    def build(self, m, i, o, v, uni, ports, host, platform=None):
        """The line addresses (a pipeline), the cache (its own handshakes: its latency
        varies), the filter (a pipeline); or, on chip, one pipeline through the RAM."""
        q, f = self.q, self.q["filter"]
        size, n = q["bump_size"], banks(f)
        if self.onchip:
            return self.build_onchip(m, i, o, v, host["texture"])
        a_out, c_out = Link(), Link()
        p1 = Pipeline(m, i, a_out)
        v = lines(p1, v, "s", "t", size, f, q["cache_line"])
        m.d.comb += a_out.valid.eq(p1.valid)
        reqs = []                     # the cache's requests, the map's base added on the way out
        for r, _ in self.port_names:
            inner = stream.Signature(layout(request_fields())).create(path=(f"_{r}",))
            m.d.comb += [ports[r].valid.eq(inner.valid), inner.ready.eq(ports[r].ready),
                         ports[r].payload.addr.eq(inner.payload.addr + uni["tex_base"])]
            reqs.append(inner)
        v, busy = texel_cache(m, a_out, v, c_out, reqs, [ports[r] for _, r in self.port_names],
                              banks=n, lines=q["cache_lines"], line=q["cache_line"],
                              ways=q["cache_ways"], bank_texels=size * size // n,
                              texel_bits=2 * self.bits, depth=q["tex_queue"])
        p2 = Pipeline(m, c_out, o)
        v = filtered(p2, v, f, self.bits, size)
        m.d.comb += o.valid.eq(p2.valid)
        for valid in p1.valids + p2.valids:
            busy = busy | valid
        return v, busy

    def build_onchip(self, m, i, o, v, bus):
        """The texel addresses, a read of each bank's RAM (the host's writes land by the
        memory image's address: bank, then word), the filter: one shared-enable pipeline."""
        q, f = self.q, self.q["filter"]
        size, n = q["bump_size"], banks(f)
        depth = size * size // n
        bb = depth.bit_length() - 1
        p = Pipeline(m, i, o)
        p.host = {f"texture{k}": WriteBus(bus.en & equals(bus.addr[bb:], k), bus.addr[:bb],
                                          bus.data) for k in range(n)}
        shape = blank_lut(depth, u(2 * self.bits))
        v = lines(p, v, "s", "t", size, f, 1)
        v = p.stage(v, **{f"_tex{k}": rom(shape, v.pop(f"_ln{k}")[:bb], f"texture{k}",
                                          load=f"texture{k}") for k in range(n)})
        v = filtered(p, v, f, self.bits, size)
        if p.stages != self.latency:
            raise AssertionError(f"texture has {p.stages} stages, its latency says "
                                 f"{self.latency}")
        m.d.comb += o.valid.eq(p.valid)
        busy = 0
        for valid in p.valids:
            busy = busy | valid
        return v, busy

    def prepare(self, scene, view, data):
        """The map's texels (``golden.bump.bump_texels``), whose size sets ``bump_size``; each
        drawn triangle's texture coordinates and its vertices' tangent frames.

        A vertex's (s, t) is taken within half a period of the first vertex's (so a triangle
        across the mesh's seam does not run back over the whole texture), then every vertex
        is shifted by the same whole tiles so that the least lies in [0, 1): the texture
        repeats every tile, so the shift changes nothing but keeps the values in the
        raster's [-2, 2). A triangle may span less than one tile."""
        b = scene["bump"]
        try:
            hi, lo, normals = bumps.bump_texels(self.kind, b["map"], b["size"], b["depth"],
                                                ANGLE_BITS)
        except bumps.BumpError as e:           # its message names bump.map
            raise SceneError(str(e)) from None
        size = hi.shape[0]
        if hi.shape[0] != hi.shape[1] or size & (size - 1) or size > MAX_TEXTURE:
            raise SceneError(f"bump.map: {b['map']!r} is {hi.shape[1]} x {hi.shape[0]} "
                             f"texels; a texture ROM needs a square power of two up to "
                             f"{MAX_TEXTURE}")
        self.q["bump_size"] = size
        period = np.array(b["repeat"], float)
        uv, periodic = texcoords(scene)
        st = uv[view.drawn]                                                   # (n, 3, 2)
        st = np.where(periodic, st[:, :1] + np.mod(st - st[:, :1] + period / 2, period)
                      - period / 2, st)
        st -= np.floor(st.min(axis=1, keepdims=True))
        span = st.max(axis=1) - st.min(axis=1)
        if len(span) and span.max() >= 1.0 - VALUE.lsb:
            k = int(np.argmax(span.max(axis=1)))
            raise SceneError(
                f"bump.repeat: a triangle spans {span.max():.3g} tiles of the bump map (along "
                f"{'st'[int(np.argmax(span[k]))]}); the raster carries texture coordinates in "
                f"[-2, 2), so a triangle may span less than one tile: " + (
                    "use more mesh.segments or a smaller repeat"
                    if scene["mesh"]["shape"] != "obj" else
                    "give the OBJ finer texture coordinates, or a smaller repeat (without "
                    "them, the cylindrical projection wraps whole turns around the triangles "
                    "at the ends of its axis)"))
        return {"st": st, "lanes": self.lanes, "normals": normals, "size": size,
                "frames": [f[view.drawn] for f in tangent_frames(scene)],     # (n, 3, 3) each
                "filter": b["filter"], "texels": (hi, lo)}

    def vertex_values(self, data):
        return {"s": data["st"][..., 0], "t": data["st"][..., 1]}

    def memory_image(self, data):
        """The texture memory's words (``hdl.texture_unit.memory_image``'s layout)."""
        hi, lo = data["texels"]
        return memory_image(hi, lo, self.bits, self.q["filter"])

    def ideal(self, prep, frag, ch):
        """The map's exact normal (tangent frame, before any texel encoding) at the texture
        coordinates, nearest or bilinear as the texels (``golden.bump.sample``)."""
        b = prep["data"]
        st = np.stack([ch["s"], ch["t"]], -1)
        return {**ch, "_n": bumps.sample(b["normals"], st, self.q["filter"])}

    def model(self, prep, frag, ch, bound):
        """The codes ``_hi``, ``_lo`` (``golden.bump.fetch``: nearest, or the bilinear filter
        bit for bit). ``bound``: ``ds``, ``dt`` added to the raw texture coordinates."""
        hi, lo = prep["data"]["texels"]
        rs, rt = raw(ch["s"]) + bound.get("ds", 0), raw(ch["t"]) + bound.get("dt", 0)
        return {**ch, "_hi": bumps.fetch(hi, rs, rt, self.q["filter"]),
                "_lo": bumps.fetch(lo, rs, rt, self.q["filter"])}
