"""The board's design in two layers.

- :class:`BoardCore`: everything clocked, in two domains, ``sync`` (the core clock) and
  ``pixel``: the link, the scene's pipeline, the framebuffer and the scan-out, with the
  link's bytes as ports. The whole-frame simulation runs this (``board/sim.py``).
- :class:`BoardTop`: the ULX3S: the PLL, the UART on the FT231X's pins, the symbols across
  to the TMDS clock through an ``AsyncFIFO``, and the serialisers (``ODDRX1F`` through
  ``lib.io.DDRBuffer``).

Clocks (one ``EHXPLLL``, VCO 500 MHz from the 25 MHz oscillator): TMDS 125 MHz (CLKOP, two
bits a clock through ``ODDRX1F``: a 10-bit symbol every 5), pixel 25 MHz (CLKOS), core 100 MHz
(CLKOS2): the pipelines alone placed at 110.9-126 MHz (docs/fpga.md); on the board, beside the
framebuffer and the link, their routes are longer (docs/board.md).
"""
from amaranth.hdl import Cat, ClockDomain, ClockSignal, Instance, Module, Mux, Signal, Value
from amaranth.lib import io, stream, wiring
from amaranth.lib.cdc import ResetSynchronizer
from amaranth.lib.fifo import AsyncFIFO
from amaranth.lib.wiring import In, Out

from scene.pipeline import ScenePipeline

from .framebuffer import MAX_WORDS, Framebuffer, plane_width
from .link import COUNTERS, Link
from .protocol import known_ranges
from .uart import UARTRx, UARTTx
from .video import Video

__all__ = ["BoardCore", "BoardTop", "CLOCKS", "BAUD", "check_size"]

# MHz: (the PLL's output, its divider from the 500 MHz VCO)
VCO_MHZ = 500
CLOCKS = {"tmds": (125.0, 4), "pixel": (25.0, 20), "sync": (100.0, 5)}
BAUD = 3_000_000                     # the FT231X's fastest
QUIET_S = 0.01


def divisor(baud=BAUD):
    return round(CLOCKS["sync"][0] * 1e6 / baud)


def check_size(width, height, board="ulx3s-25f"):
    words = plane_width(width) * height
    if words > MAX_WORDS[board]:
        raise ValueError(f"image.width and image.height: {width} x {height} needs "
                         f"{words} words a plane (the width rounded up to a power of two); "
                         f"the {board}'s block RAM holds {MAX_WORDS[board]}")
    return width, height


class BoardCore(wiring.Component):
    """The pipeline for ``params`` (``scene.driver.pipeline_params``) at ``width`` x
    ``height``, behind the link, in front of the framebuffer and the scan-out."""

    def __init__(self, params, width, height, board="ulx3s-25f", buffer=2048, timeout=None):
        if params.get("bump", "none") != "none" and params.get("texture") != "onchip":
            raise ValueError("texture: the board has no texture memory port; the bump map "
                             "must be on chip (texture = \"onchip\")")
        self.params, self.board = params, board
        self.width, self.height = check_size(width, height, board)
        self.pipe = ScenePipeline.spec(**params)
        self.tri_bits = sum(f.fmt.width for f in self.pipe.raster.unit.inputs)
        # the line quiet for 10 ms ends a frame: within a frame the FT231X's bytes come back
        # to back but for its USB refills (a millisecond frame), so gaps inside a frame are
        # shorter; a host waits 0.5 s for a reply
        self.timeout = timeout or round(CLOCKS["sync"][0] * 1e6 * QUIET_S)
        self.buffer = buffer
        super().__init__({
            "rx_valid": In(1), "rx_data": In(8),
            "tx_valid": Out(1), "tx_data": Out(8), "tx_ready": In(1),
            "symbols": Out(30), "first": Out(1),
            "frames": Out(16), "busy": Out(1), "fragments": Out(32), "outside": Out(32),
            "counters": Out(16 * len(COUNTERS)),
        })

    def elaborate(self, platform):
        m = Module()
        m.submodules.pipe = pipe = ScenePipeline(**self.params)
        m.submodules.link = link = Link(self.tri_bits, known_ranges(self.pipe),
                                        self.buffer, self.timeout)
        m.d.comb += [link.i.valid.eq(self.rx_valid), link.i.payload.eq(self.rx_data),
                     self.tx_valid.eq(link.tx.valid), self.tx_data.eq(link.tx.payload),
                     link.tx.ready.eq(self.tx_ready)]
        # link rows -> two slots -> the pipeline's host port (its ready is a wide OR of the
        # stages' busy bits: the slots keep it out of the link's state machine and off the
        # rows' registers)
        rows = stream.Signature(link.o.payload.shape()).create()
        in_slice = two_slots(m, link.o, rows)
        m.d.comb += link.reject.eq(self._offscreen(self._fields(link.o.payload.tri)))
        fields = self._fields(rows.payload.tri)
        m.d.comb += [pipe.i.payload[name].eq(v) for name, v in fields.items()]
        m.d.comb += [pipe.i.payload.cmd.eq(rows.payload.cmd),
                     pipe.i.payload.addr.eq(rows.payload.addr),
                     pipe.i.payload.data.eq(rows.payload.data), pipe.i.valid.eq(rows.valid),
                     rows.ready.eq(pipe.i.ready)]
        # fragments -> the depth test
        xb = pipe.o.payload.x.shape().width
        yb = pipe.o.payload.y.shape().width
        m.submodules.fb = fb = Framebuffer(self.width, self.height, xb, yb)
        for name in ("x", "y", "depth", "r", "g", "b"):
            m.d.comb += fb.i.payload[name].eq(pipe.o.payload[name])
        m.d.comb += [fb.i.valid.eq(pipe.o.valid), pipe.o.ready.eq(fb.i.ready),
                     fb.clear.eq(link.clear), fb.colour.eq(link.colour),
                     link.drained.eq(~pipe.busy & ~fb.busy & ~in_slice)]
        with m.If(fb.i.valid & fb.i.ready):
            m.d.sync += self.fragments.eq(self.fragments + 1)
        # scan-out, in the pixel domain
        m.submodules.video = video = Video(self.width, self.height, fb.w2)
        m.d.comb += [fb.rd_addr.eq(video.rd_addr), video.rd_data.eq(fb.rd_data),
                     self.symbols.eq(video.symbols), self.first.eq(video.first),
                     self.frames.eq(link.frames), self.outside.eq(fb.outside),
                     self.counters.eq(link.counters.as_value()),
                     self.busy.eq(pipe.busy | fb.busy | link.o.valid | in_slice)]
        return m


    def _fields(self, flat):
        """A triangle record's raster fields, in their order, from its flat bits."""
        out, shift = {}, 0
        for f in self.pipe.raster.unit.inputs:
            out[f.name] = flat[shift:shift + f.fmt.width].as_signed() if f.fmt.signed \
                else flat[shift:shift + f.fmt.width]
            shift += f.fmt.width
        return out

    def _offscreen(self, tri):
        """Every vertex beyond one edge of the image: no pixel centre of it is covered (a
        centre x + 1/2 inside the triangle is at least its least vertex x)."""
        S = 1 << self.params["sub_bits"]
        xs = [tri[f"x{k}"] for k in range(3)]
        ys = [tri[f"y{k}"] for k in range(3)]
        beyond = lambda vs, test: test(vs[0]) & test(vs[1]) & test(vs[2])
        return (beyond(xs, lambda v: v < 0) | beyond(ys, lambda v: v < 0)
                | beyond(xs, lambda v: v >= self.width * S)
                | beyond(ys, lambda v: v >= self.height * S))


def two_slots(m, src, dst):
    """``src`` to ``dst`` through two registers written from the source side only: a slot
    loads when the source offers an item and a slot is free (both registers), and the sink's
    ready only moves a one-bit read pointer and the count. So a late ready (a pipeline's busy
    OR) drives three flip-flops, not a register of every payload bit as a skid buffer's
    enables do. One item a clock; returns busy (an item held)."""
    width = len(Value.cast(src.payload))
    slots = [Signal(width, name=f"slot{k}", reset_less=True) for k in (0, 1)]
    wp, rp, count = Signal(), Signal(), Signal(range(3))
    put = src.valid & src.ready
    get = dst.valid & dst.ready
    m.d.comb += [src.ready.eq(count != 2), dst.valid.eq(count != 0),
                 dst.payload.eq(Mux(rp, slots[1], slots[0]))]
    with m.If(put):
        for k in (0, 1):
            with m.If(wp == k):
                m.d.sync += slots[k].eq(src.payload)
        m.d.sync += wp.eq(~wp)
    with m.If(get):
        m.d.sync += rp.eq(~rp)
    m.d.sync += count.eq(count + put - get)
    return count != 0


class BoardTop(wiring.Component):
    """The ULX3S top: ``platform.build(BoardTop(core))``."""

    def __init__(self, core):
        self.core = core
        super().__init__({})

    def elaborate(self, platform):
        m = Module()
        clk25 = platform.request("clk25", dir="-")
        m.submodules.clk25 = clk_in = io.Buffer("i", clk25)
        locked = Signal()
        clocks = {name: Signal(name=f"pll_{name}") for name in CLOCKS}
        div = {name: d for name, (_, d) in CLOCKS.items()}
        m.submodules.pll = Instance(
            "EHXPLLL",
            a_FREQUENCY_PIN_CLKI="25", a_FREQUENCY_PIN_CLKOP="125",
            a_FREQUENCY_PIN_CLKOS="25", a_FREQUENCY_PIN_CLKOS2=f"{CLOCKS['sync'][0]:.3f}",
            a_ICP_CURRENT="12", a_LPF_RESISTOR="8", a_MFG_ENABLE_FILTEROPAMP="1",
            a_MFG_GMCREF_SEL="2",
            p_PLLRST_ENA="DISABLED", p_INTFB_WAKE="DISABLED", p_STDBY_ENABLE="DISABLED",
            p_DPHASE_SOURCE="DISABLED", p_OUTDIVIDER_MUXA="DIVA", p_OUTDIVIDER_MUXB="DIVB",
            p_OUTDIVIDER_MUXC="DIVC", p_OUTDIVIDER_MUXD="DIVD",
            p_CLKI_DIV=1, p_CLKFB_DIV=5, p_FEEDBK_PATH="CLKOP",    # 25 x 5 = CLKOP
            p_CLKOP_ENABLE="ENABLED", p_CLKOP_DIV=div["tmds"], p_CLKOP_CPHASE=div["tmds"] - 1,
            p_CLKOP_FPHASE=0,
            p_CLKOS_ENABLE="ENABLED", p_CLKOS_DIV=div["pixel"],
            p_CLKOS_CPHASE=div["pixel"] - 1, p_CLKOS_FPHASE=0,
            p_CLKOS2_ENABLE="ENABLED", p_CLKOS2_DIV=div["sync"],
            p_CLKOS2_CPHASE=div["sync"] - 1, p_CLKOS2_FPHASE=0,
            i_CLKI=clk_in.i, i_CLKFB=clocks["tmds"], i_RST=0, i_STDBY=0,
            i_PHASESEL0=0, i_PHASESEL1=0, i_PHASEDIR=1, i_PHASESTEP=1, i_PHASELOADREG=1,
            i_PLLWAKESYNC=0, i_ENCLKOP=0,
            o_CLKOP=clocks["tmds"], o_CLKOS=clocks["pixel"], o_CLKOS2=clocks["sync"],
            o_LOCK=locked)
        for name, clk in clocks.items():
            m.domains += ClockDomain(name)
            m.d.comb += ClockSignal(name).eq(clk)
            m.submodules[f"rst_{name}"] = ResetSynchronizer(~locked, domain=name)
        # no constraint of ours on the PLL's outputs: nextpnr derives each from the
        # oscillator's 25 MHz and the dividers (its log: "Derived frequency constraint")

        m.submodules.core = core = self.core
        # the UART (the FT231X's, the board's uart resource)
        uart = platform.request("uart", 0)
        m.submodules.rx = rx = UARTRx(divisor())
        m.submodules.tx = tx = UARTTx(divisor())
        m.d.comb += [rx.rx.eq(uart.rx.i), uart.tx.o.eq(tx.tx),
                     core.rx_valid.eq(rx.o.valid), core.rx_data.eq(rx.o.payload),
                     rx.o.ready.eq(1),
                     tx.i.valid.eq(core.tx_valid), tx.i.payload.eq(core.tx_data),
                     core.tx_ready.eq(tx.i.ready)]
        m.d.comb += platform.request("uart_tx_enable", 0).o.eq(1)
        # the LEDs: busy, a frame answered (toggles), each rejection count's bit 0, locked
        leds = [core.busy, core.frames[0]] + [core.counters[16 * k] for k in range(1, 6)] \
            + [locked]
        for k, bit in enumerate(leds):
            m.d.comb += platform.request("led", k).o.eq(bit)

        # symbols: pixel -> TMDS clock through an AsyncFIFO; a symbol every 5 TMDS clocks
        m.submodules.cross = fifo = AsyncFIFO(width=30, depth=8, r_domain="tmds",
                                              w_domain="pixel")
        m.d.comb += [fifo.w_data.eq(core.symbols), fifo.w_en.eq(1)]
        phase = Signal(range(5))
        shift = [Signal(10, name=f"shift{k}") for k in range(4)]      # 3 lanes, the clock
        started = Signal()
        m.d.tmds += phase.eq(Mux(phase == 4, 0, phase + 1))
        with m.If(phase == 0):
            m.d.comb += fifo.r_en.eq(started | (fifo.r_level >= 4))
            with m.If(fifo.r_rdy & (started | (fifo.r_level >= 4))):
                m.d.tmds += started.eq(1)
            m.d.tmds += [shift[k].eq(fifo.r_data[10 * k:10 * k + 10]) for k in range(3)]
            m.d.tmds += shift[3].eq(0b0000011111)
        with m.Else():
            m.d.tmds += [s.eq(s >> 2) for s in shift]
        hdmi = platform.request("hdmi", 0, dir={"d": "-", "clk": "-"})
        m.submodules.ddr_d = ddr_d = io.DDRBuffer("o", hdmi.d, o_domain="tmds")
        m.submodules.ddr_clk = ddr_clk = io.DDRBuffer("o", hdmi.clk, o_domain="tmds")
        m.d.comb += [ddr_d.o[0].eq(Cat(*(s[0] for s in shift[:3]))),
                     ddr_d.o[1].eq(Cat(*(s[1] for s in shift[:3]))),
                     ddr_clk.o[0].eq(shift[3][0]), ddr_clk.o[1].eq(shift[3][1])]
        return m

