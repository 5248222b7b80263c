"""640 x 480 at 60 Hz (the VESA/CEA timing DVI sinks all take): 800 x 525 clocks a frame at
25 MHz (25.175 nominal; 25.0 is within what monitors lock to), negative syncs.

The framebuffer is scaled by the largest integer ``factor`` that fits and centred, with black
around it. Counters only: the scaled column steps every ``factor`` clocks, so no multiplier
and no divider. The colour plane is read one clock ahead of its pixel (its read port's
latency), RGB565 is widened to 8 bits a channel by repeating its top bits, and three TMDS
encoders make the lanes: lane 0 blue with (c1, c0) = (vsync, hsync), lanes 1 and 2 green
and red with zero control bits (DVI 1.0 §3.2).
"""
from dataclasses import dataclass

from amaranth.hdl import Cat, Module, Mux, Signal
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

from .tmds import TMDSEncoder

__all__ = ["Timing", "VGA", "Video", "placement", "expand565"]


@dataclass(frozen=True)
class Timing:
    active: int
    front: int
    sync: int
    back: int

    @property
    def total(self):
        return self.active + self.front + self.sync + self.back


VGA = (Timing(640, 16, 96, 48), Timing(480, 10, 2, 33))     # (horizontal, vertical)


def placement(width, height, timing=VGA):
    """The integer scale and the top-left corner of the picture on the screen."""
    h, v = timing
    factor = min(h.active // width, v.active // height)
    if factor < 1:
        raise ValueError(f"image.width and image.height: {width} x {height} is larger than "
                         f"the {h.active} x {v.active} screen")
    return factor, (h.active - factor * width) // 2, (v.active - factor * height) // 2


def expand565(word):
    """RGB565 to (r, g, b), 8 bits each, the top bits repeated below (0 -> 0, 31 -> 255)."""
    r, g, b = (word >> 11) & 31, (word >> 5) & 63, word & 31
    return (r << 3) | (r >> 2), (g << 2) | (g >> 4), (b << 3) | (b >> 2)


class Video(wiring.Component):
    """In the ``pixel`` domain: ``rd_addr``/``rd_data`` to the colour plane; ``symbols``,
    three lanes of 10 bits; ``first`` is high with the symbols of the frame's first clock
    (the top-left of the active picture's line 0, column 0)."""

    def __init__(self, width, height, plane_width, timing=VGA):
        self.width, self.height, self.w2 = width, height, plane_width
        self.timing = timing
        self.factor, self.x0, self.y0 = placement(width, height, timing)
        words = plane_width * height
        super().__init__({"rd_addr": Out(range(words)), "rd_data": In(16),
                          "symbols": Out(30), "first": Out(1)})

    @property
    def latency(self):
        return 1 + TMDSEncoder.latency

    def elaborate(self, platform):
        m = Module()
        h, v = self.timing
        hx, vy = Signal(range(h.total)), Signal(range(v.total))
        end_h = hx == h.total - 1
        m.d.pixel += hx.eq(Mux(end_h, 0, hx + 1))
        with m.If(end_h):
            m.d.pixel += vy.eq(Mux(vy == v.total - 1, 0, vy + 1))
        # the scaled picture: column and row of the plane, and the clocks within a pixel
        f = self.factor
        sx, sy = Signal(range(self.w2)), Signal(range(self.height + 1))
        kx, ky = Signal(range(f)), Signal(range(f))
        in_x = (hx >= self.x0) & (hx < self.x0 + f * self.width)
        in_y = (vy >= self.y0) & (vy < self.y0 + f * self.height)
        with m.If(in_x & in_y):
            m.d.pixel += [kx.eq(Mux(kx == f - 1, 0, kx + 1)),
                          sx.eq(Mux(kx == f - 1, sx + 1, sx))]
        with m.If(end_h):
            m.d.pixel += [sx.eq(0), kx.eq(0)]
            with m.If(in_y):
                m.d.pixel += [ky.eq(Mux(ky == f - 1, 0, ky + 1)),
                              sy.eq(Mux(ky == f - 1, sy + 1, sy))]
            with m.If(vy == v.total - 1):
                m.d.pixel += [sy.eq(0), ky.eq(0)]
        w_bits = (self.w2 - 1).bit_length()
        m.d.comb += self.rd_addr.eq(Cat(sx[:w_bits], sy) if w_bits else sy)

        # one clock for the read: the controls follow
        de = (hx < h.active) & (vy < v.active)
        hs = ~((hx >= h.active + h.front) & (hx < h.active + h.front + h.sync))
        vs = ~((vy >= v.active + v.front) & (vy < v.active + v.front + v.sync))
        de1, hs1, vs1, pic1, first1 = Signal(), Signal(), Signal(), Signal(), Signal()
        m.d.pixel += [de1.eq(de), hs1.eq(hs), vs1.eq(vs), pic1.eq(in_x & in_y),
                      first1.eq((hx == 0) & (vy == 0))]
        rgb = [Mux(pic1, c, 0) for c in expand565(self.rd_data)]
        lanes = [rgb[2], rgb[1], rgb[0]]                     # blue, green, red
        for k, lane in enumerate(lanes):
            enc = TMDSEncoder()
            m.submodules[f"tmds{k}"] = enc = wiring_domain(enc)
            m.d.comb += [enc.data.eq(lane), enc.de.eq(de1),
                         enc.c.eq(Cat(hs1, vs1) if k == 0 else 0),
                         self.symbols[10 * k:10 * k + 10].eq(enc.symbol)]
        first2 = Signal()
        m.d.pixel += [first2.eq(first1), self.first.eq(first2)]
        return m


def wiring_domain(unit):
    from amaranth.hdl import DomainRenamer
    return DomainRenamer("pixel")(unit)
