"""The depth-tested framebuffer: the pipeline's last stage on the board.

Each fragment (x, y, depth, r, g, b) is tested against the depth plane and, where it is
nearer (a larger depth, scene/prepare.py's convention), written to the colour plane: one
fragment a clock. Planes, ``width2 x height`` words (``width2`` the image's width rounded
up to a power of two, so an address is ``y`` beside ``x``, with no multiplier):

- colour, RGB565: 16 bits a pixel, so 128 x 128 takes 16 DP16KD (RGB888 would take 24, and
  bump_polar's pipeline leaves 36 of the 25F's 56); written in the core clock, read by the
  scan-out in the pixel clock (a dual-clock block RAM);
- depth: the channel's raw 16 bits (s16, 14 fraction bits), 16 DP16KD at 128 x 128.

A clear writes the background and the depth ``CLEAR`` (the least s16) to every word, a word a
clock. A fragment's depth is clamped to ``CLEAR + 1`` or more, so it always beats the clear;
the model (scene/framebuffer.py) clamps the same.

**Read-modify-write.** A fragment's depth is read in the clock it is taken, registered in the
next (the block RAM's output is slow), tested in the third and written in the fourth. So the
three fragments ahead of it write after its read: where one of them shares its pixel, its test
takes that write's depth instead, the newest first (forwarding). All but the newest write's
enable and the read are known a clock ahead, so the pixel matches and three of the four depth
compares are registers, and the test is the read's compare and a select.
Fragments outside the image are counted (``outside``) and dropped.
"""
from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

__all__ = ["Framebuffer", "CLEAR", "MAX_WORDS", "MUTANTS", "fragment_layout", "plane_width"]

CLEAR = -(1 << 15)
MAX_WORDS = {"ulx3s-25f": 128 * 128, "ulx3s-85f": 256 * 256}
# the forwarding's mutants, each one enable dropped or one priority swapped; the tests show
# each caught (tests/test_board.py). Never built otherwise
MUTANTS = {
    "w_enable": "the newest write's pixel match taken without its enable",
    "h1_enable": "the older write h1's pixel match taken without its enable",
    "h2_enable": "the oldest write h2's pixel match taken without its enable",
    "h_priority": "h2's depth preferred to h1's, the newer, where both hold the pixel",
    "w_priority": "the older writes' depths preferred to the newest's",
}


def plane_width(width):
    return 1 << max(width - 1, 0).bit_length()


def fragment_layout(x_bits, y_bits):
    return data.StructLayout({"x": x_bits, "y": y_bits, "depth": signed(16),
                              "r": 8, "g": 8, "b": 8})


class Framebuffer(wiring.Component):
    """``i``: fragments; ``clear`` (a pulse) with ``colour`` (RGB565); ``busy`` while a
    fragment is in flight or a clear runs; ``rd_addr``/``rd_data``: the scan-out's port, in
    the ``pixel`` domain, one clock of latency. ``mutant``: one of ``MUTANTS``, for the
    tests only."""

    def __init__(self, width, height, x_bits, y_bits, read_domain="pixel", mutant=None):
        if mutant is not None and mutant not in MUTANTS:
            raise ValueError(f"mutant: one of {', '.join(MUTANTS)}, not {mutant!r}")
        self.mutant = mutant
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

        # the fragment moves one stage a clock: 1 (its depth read out of the block RAM), 2
        # (registered: the block's 5.8 ns clock-to-out leaves no time for the test after it),
        # 3 (tested), then written in the clock after the test
        take = self.i.valid & self.i.ready
        depth = Mux(f.depth > CLEAR, f.depth, CLEAR + 1)
        stage = []
        for k in (1, 2):
            st = (Signal(name=f"v{k}"), Signal(range(self.words), name=f"a{k}"),
                  Signal(signed(16), name=f"d{k}"), Signal(16, name=f"c{k}"))
            src = (take & inside, addr, depth, Cat(f.b[3:], f.g[2:], f.r[3:])) if k == 1 \
                else stage[-1]
            m.d.sync += [dst.eq(x) for dst, x in zip(st, src)]
            stage.append(st)
        (v1, a1, d1, c1), (v2, a2, d2, c2) = stage
        read = Signal(signed(16))
        m.d.sync += read.eq(z_rd.data)               # stage 1's depth, in stage 2
        with m.If(take & ~inside):
            m.d.sync += self.outside.eq(self.outside + 1)
        # the writes stage 2's read missed: the one being made now (w) and the two before
        # (h1, h2), the newest first where they share its pixel. Everything but stage 2's
        # read and whether w writes is known a clock ahead (stage 1 against what will be w, h1
        # and h2: w, h1 and h1's predecessor), so it is registered there: whether h1 or h2
        # holds the pixel (the newer of the two) and the compares with their depths. The test is then one
        # compare (with the read) and a select of registers: the block RAM's read into w_en
        # stays short
        w = (Signal(name="w_en"), Signal(range(self.words), name="w_addr"),
             Signal(signed(16), name="w_depth"), Signal(16, name="w_rgb"))
        h1 = (Signal(name="h1_en"), Signal(range(self.words), name="h1_addr"),
              Signal(signed(16), name="h1_depth"))
        same_w, in_h, near_w, near_h = (Signal(name=n) for n in
                                        ("same_w", "in_h", "near_w", "near_h"))
        mutant = self.mutant
        hit1 = (mutant == "h1_enable" or w[0]) & (a1 == w[1])   # what will be h1 holds
        hit2 = (mutant == "h2_enable" or h1[0]) & (a1 == h1[1])  # stage 1's pixel; h2
        m.d.sync += [same_w.eq(a1 == a2), near_w.eq(d1 > d2), in_h.eq(hit1 | hit2),
                     near_h.eq(Mux(hit2, d1 > h1[2], d1 > w[2]) if mutant == "h_priority"
                               else Mux(hit1, d1 > w[2], d1 > h1[2]))]
        in_w = same_w if mutant == "w_enable" else w[0] & same_w
        if mutant == "w_priority":
            win = v2 & Mux(in_h, near_h, Mux(in_w, near_w, d2 > read))
        else:
            win = v2 & Mux(in_w, near_w, Mux(in_h, near_h, d2 > read))
        m.d.sync += [w[0].eq(win), w[1].eq(a2), w[2].eq(d2), w[3].eq(c2),
                     *[x.eq(y) for x, y in zip(h1, w[:3])]]
        with m.If(win):
            m.d.sync += self.written.eq(self.written + 1)

        with m.If(clearing):
            m.d.comb += [c_wr.addr.eq(ptr), c_wr.data.eq(self.colour), c_wr.en.eq(1),
                         z_wr.addr.eq(ptr), z_wr.data.eq(CLEAR), z_wr.en.eq(1)]
            m.d.sync += ptr.eq(ptr + 1)
            with m.If(ptr == self.words - 1):
                m.d.sync += clearing.eq(0)
        with m.Else():
            m.d.comb += [c_wr.addr.eq(w[1]), c_wr.data.eq(w[3]), c_wr.en.eq(w[0]),
                         z_wr.addr.eq(w[1]), z_wr.data.eq(w[2]), z_wr.en.eq(w[0])]
        with m.If(self.clear & ~clearing):
            m.d.sync += [clearing.eq(1), ptr.eq(0)]
        m.d.comb += self.busy.eq(clearing | v1 | v2 | w[0])
        return m
