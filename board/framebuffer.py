"""The depth-tested framebuffer: the pipeline's last stage on the board.

Each fragment (x, y, depth, r, g, b) is tested against the depth plane and, where it is
nearer (a larger depth, scene/driver.py's convention), written to the colour plane: one
fragment a clock. Planes, ``width2 x height`` words (``width2`` the image's width rounded
up to a power of two, so an address is ``y`` beside ``x``, with no multiplier):

- colour, RGB565: 16 bits a pixel, so 128 x 128 takes 16 DP16KD (RGB888 would take 24, and
  bump_polar's pipeline leaves 36 of the 25F's 56); written in the core clock, read by the
  scan-out in the pixel clock (a dual-clock block RAM);
- depth: the channel's raw 16 bits (s16, 14 fraction bits), 16 DP16KD at 128 x 128.

A clear writes the background and the depth ``CLEAR`` (the least s16) to every word, a word a
clock. A fragment's depth is clamped to ``CLEAR + 1`` or more, so it always beats the clear;
the model (scene/framebuffer.py) clamps the same.

**Read-modify-write.** A fragment's depth is read in the clock it is taken and tested and
written in the next. The fragment behind it reads in that same clock, before the write lands,
so its test takes the written depth instead wherever the two share a pixel (``forward``).
Fragments outside the image are counted (``outside``) and dropped.
"""
from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

__all__ = ["Framebuffer", "CLEAR", "MAX_WORDS", "fragment_layout", "plane_width"]

CLEAR = -(1 << 15)
MAX_WORDS = {"ulx3s-25f": 128 * 128, "ulx3s-85f": 256 * 256}


def plane_width(width):
    return 1 << max(width - 1, 0).bit_length()


def fragment_layout(x_bits, y_bits):
    return data.StructLayout({"x": x_bits, "y": y_bits, "depth": signed(16),
                              "r": 8, "g": 8, "b": 8})


class Framebuffer(wiring.Component):
    """``i``: fragments; ``clear`` (a pulse) with ``colour`` (RGB565); ``busy`` while a
    fragment is in flight or a clear runs; ``rd_addr``/``rd_data``: the scan-out's port, in
    the ``pixel`` domain, one clock of latency."""

    def __init__(self, width, height, x_bits, y_bits, read_domain="pixel"):
        self.width, self.height = width, height
        self.w2 = plane_width(width)
        self.words = self.w2 * height
        self.read_domain = read_domain
        super().__init__({
            "i": In(stream.Signature(fragment_layout(x_bits, y_bits))),
            "clear": In(1), "colour": In(16), "busy": Out(1),
            "rd_addr": In(range(self.words)), "rd_data": Out(16),
            "outside": Out(32), "written": Out(32),
        })

    def elaborate(self, platform):
        m = Module()
        m.submodules.rgb = rgb = Memory(shape=16, depth=self.words, init=[])
        m.submodules.z = z = Memory(shape=signed(16), depth=self.words, init=[])
        c_wr, z_wr, z_rd = rgb.write_port(), z.write_port(), z.read_port()
        c_rd = rgb.read_port(domain=self.read_domain)
        m.d.comb += [c_rd.addr.eq(self.rd_addr), self.rd_data.eq(c_rd.data)]

        clearing, ptr = Signal(), Signal(range(self.words))
        f = self.i.payload
        m.d.comb += self.i.ready.eq(~clearing)
        inside = (f.x < self.width) & (f.y < self.height)
        addr = Cat(f.x[:(self.w2 - 1).bit_length()], f.y) if self.w2 > 1 else f.y
        m.d.comb += z_rd.addr.eq(addr)

        # stage 1: the fragment whose depth is being read
        v1, a1, d1, c1 = Signal(), Signal(range(self.words)), Signal(signed(16)), Signal(16)
        take = self.i.valid & self.i.ready
        depth = Mux(f.depth > CLEAR, f.depth, CLEAR + 1)
        m.d.sync += [v1.eq(take & inside), a1.eq(addr), d1.eq(depth),
                     c1.eq(Cat(f.b[3:], f.g[2:], f.r[3:]))]
        with m.If(take & ~inside):
            m.d.sync += self.outside.eq(self.outside + 1)
        # the last clock's write, for the fragment behind it
        fw, fa, fd = Signal(), Signal(range(self.words)), Signal(signed(16))
        stored = Mux(fw & (fa == a1), fd, z_rd.data)
        win = v1 & (d1 > stored)
        m.d.sync += [fw.eq(win), fa.eq(a1), fd.eq(d1)]
        with m.If(win):
            m.d.sync += self.written.eq(self.written + 1)

        with m.If(clearing):
            m.d.comb += [c_wr.addr.eq(ptr), c_wr.data.eq(self.colour), c_wr.en.eq(1),
                         z_wr.addr.eq(ptr), z_wr.data.eq(CLEAR), z_wr.en.eq(1)]
            m.d.sync += ptr.eq(ptr + 1)
            with m.If(ptr == self.words - 1):
                m.d.sync += clearing.eq(0)
        with m.Else():
            m.d.comb += [c_wr.addr.eq(a1), c_wr.data.eq(c1), c_wr.en.eq(win),
                         z_wr.addr.eq(a1), z_wr.data.eq(d1), z_wr.en.eq(win)]
        with m.If(self.clear & ~clearing):
            m.d.sync += [clearing.eq(1), ptr.eq(0)]
        m.d.comb += self.busy.eq(clearing | v1)
        return m
