"""The FT231X's UART at the bit level: 8 data bits, no parity, one stop bit, LSB first.

``divisor`` is clocks per bit (the core clock over the baud rate). The receiver finds a start
bit's falling edge, checks it is still low half a bit later, then samples each bit at its
middle; a low stop bit is a framing error, counted and the byte dropped. A byte that arrives
while the previous one still waits (``o.valid & ~o.ready``) is an overrun, counted: the link
above never lets that happen (docs/board.md, "Flow control").
"""
from amaranth.hdl import Module, Signal
from amaranth.lib import stream, wiring
from amaranth.lib.cdc import FFSynchronizer
from amaranth.lib.wiring import In, Out

__all__ = ["UARTRx", "UARTTx", "check_divisor"]


def check_divisor(divisor):
    if not isinstance(divisor, int) or divisor < 4:
        raise ValueError(f"the UART divisor (clocks a bit) must be an integer of 4 or more, "
                         f"not {divisor!r}")
    return divisor


class UARTRx(wiring.Component):
    rx: In(1, init=1)
    o: Out(stream.Signature(8))
    framing: Out(16)            # bytes with a low stop bit, dropped
    overrun: Out(16)            # bytes that found the last one still waiting, dropped

    def __init__(self, divisor):
        self.divisor = check_divisor(divisor)
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        rx = Signal(init=1)
        m.submodules.sync_rx = FFSynchronizer(self.rx, rx, init=1)
        timer = Signal(range(self.divisor))
        bit = Signal(range(10))
        shift = Signal(8)
        with m.If(self.o.ready):
            m.d.sync += self.o.valid.eq(0)
        with m.FSM():
            with m.State("IDLE"):
                with m.If(~rx):
                    m.d.sync += timer.eq(self.divisor // 2 - 1)
                    m.next = "START"
            with m.State("START"):
                m.d.sync += timer.eq(timer - 1)
                with m.If(timer == 0):
                    with m.If(rx):                     # a glitch, not a start bit
                        m.next = "IDLE"
                    with m.Else():
                        m.d.sync += [timer.eq(self.divisor - 1), bit.eq(0)]
                        m.next = "DATA"
            with m.State("DATA"):
                m.d.sync += timer.eq(timer - 1)
                with m.If(timer == 0):
                    m.d.sync += [timer.eq(self.divisor - 1), bit.eq(bit + 1)]
                    with m.If(bit == 8):               # the stop bit's middle
                        with m.If(~rx):
                            m.d.sync += self.framing.eq(self.framing + 1)
                            m.next = "BREAK"
                        with m.Else():
                            with m.If(self.o.valid & ~self.o.ready):
                                m.d.sync += self.overrun.eq(self.overrun + 1)
                            with m.Else():
                                m.d.sync += [self.o.payload.eq(shift), self.o.valid.eq(1)]
                            m.next = "IDLE"
                    with m.Else():
                        m.d.sync += shift.eq((shift >> 1) | (rx << 7))
            with m.State("BREAK"):                     # wait for the line to go high again
                with m.If(rx):
                    m.next = "IDLE"
        return m


class UARTTx(wiring.Component):
    i: In(stream.Signature(8))
    tx: Out(1, init=1)

    def __init__(self, divisor):
        self.divisor = check_divisor(divisor)
        super().__init__()

    def elaborate(self, platform):
        m = Module()
        timer = Signal(range(self.divisor))
        bits = Signal(10)                 # start, 8 data, stop; bit 0 on the line
        left = Signal(range(11))
        m.d.comb += self.i.ready.eq(left == 0)
        with m.If(self.i.valid & self.i.ready):
            m.d.sync += [bits.eq((1 << 9) | (self.i.payload << 1)), left.eq(10),
                         timer.eq(self.divisor - 1), self.tx.eq(0)]
        with m.Elif(left != 0):
            m.d.sync += timer.eq(timer - 1)
            with m.If(timer == 0):
                m.d.sync += [timer.eq(self.divisor - 1), bits.eq(bits >> 1),
                             left.eq(left - 1), self.tx.eq(bits[1] | (left == 1))]
        return m
