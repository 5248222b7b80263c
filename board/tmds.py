"""The DVI 1.0 TMDS encoder (DVI 1.0 §3.2.2, its flow chart): 8 data bits to a 10-bit
transition-minimised, DC-balanced symbol while DE is high; one of four control tokens while
it is low. Bit 0 of a symbol is the first sent.

The disparity ``cnt`` of the symbols sent since the last blanking is what the encoder
tracks (each branch below adds exactly its symbol's ones minus zeros), and it stays in
[-8, 8]: with cnt > 0 no branch adds to it, with cnt < 0 none takes from it, and one step
moves it by at most 10 from an even value of the other sign (tests/test_board.py checks the
bound on the stream itself).
"""
from amaranth.hdl import Cat, Module, Mux, Signal, signed
from amaranth.lib import wiring
from amaranth.lib.wiring import In, Out

__all__ = ["CONTROL", "TMDSEncoder", "encode", "decode", "disparity"]

# the control tokens by (c1, c0), bit 0 first sent (DVI 1.0 table 3-3, written MSB first there)
CONTROL = (0b1101010100, 0b0010101011, 0b0101010100, 0b1010101011)


class TMDSEncoder(wiring.Component):
    """One lane: ``data`` (8), ``c`` (c1 c0) and ``de`` in, ``symbol`` out two clocks later."""
    data: In(8)
    c: In(2)
    de: In(1)
    symbol: Out(10)

    latency = 2

    def elaborate(self, platform):
        m = Module()
        d = self.data
        n1d = sum(d[i] for i in range(8))
        xnor = (n1d > 4) | ((n1d == 4) & ~d[0])
        qm = [d[0]]
        for i in range(1, 8):             # each bit a signal: an expression would double
            q = Signal(name=f"qm{i}")
            m.d.comb += q.eq(qm[-1] ^ d[i] ^ xnor)
            qm.append(q)
        # stage 1: q_m, its ones count, and the control path's inputs
        q_m, q8, n1 = Signal(8), Signal(), Signal(4)
        de1, c1 = Signal(), Signal(2)
        m.d.sync += [q_m.eq(Cat(*qm)), q8.eq(~xnor), de1.eq(self.de), c1.eq(self.c)]
        m.d.comb += n1.eq(sum(Cat(*qm)[i] for i in range(8)))
        n1r = Signal(4)
        m.d.sync += n1r.eq(n1)
        # stage 2: the disparity choice (N1 - N0 = 2 N1 - 8)
        cnt = Signal(signed(5))
        diff = Signal(signed(5))
        m.d.comb += diff.eq((n1r << 1) - 8)
        with m.If(~de1):
            m.d.sync += [self.symbol.eq(Mux(c1[1], Mux(c1[0], CONTROL[3], CONTROL[2]),
                                            Mux(c1[0], CONTROL[1], CONTROL[0]))),
                         cnt.eq(0)]
        with m.Elif((cnt == 0) | (diff == 0)):
            m.d.sync += [self.symbol.eq(Cat(Mux(q8, q_m, ~q_m), q8, ~q8)),
                         cnt.eq(cnt + Mux(q8, diff, -diff))]
        with m.Elif(((cnt > 0) & (diff > 0)) | ((cnt < 0) & (diff < 0))):
            m.d.sync += [self.symbol.eq(Cat(~q_m, q8, 1)),
                         cnt.eq(cnt + Mux(q8, 2, 0) - diff)]
        with m.Else():
            m.d.sync += [self.symbol.eq(Cat(q_m, q8, 0)),
                         cnt.eq(cnt - Mux(q8, 0, 2) + diff)]
        return m


# ---- the model (written from the specification's flow chart, not from the RTL) --------------

def _bits(v, n):
    return [(v >> i) & 1 for i in range(n)]


def encode(data, c, de):
    """The symbols for sequences ``data``, ``c`` (c1 c0) and ``de``, from a cleared encoder."""
    out, cnt = [], 0
    for d, cc, e in zip(data, c, de):
        if not e:
            out.append(CONTROL[cc])
            cnt = 0
            continue
        D = _bits(int(d), 8)
        n1 = sum(D)
        q = [D[0]]
        use_xnor = n1 > 4 or (n1 == 4 and D[0] == 0)
        for i in range(1, 8):
            q.append(1 - (q[i - 1] ^ D[i]) if use_xnor else q[i - 1] ^ D[i])
        q8 = 0 if use_xnor else 1
        ones = sum(q)
        zeros = 8 - ones
        if cnt == 0 or ones == zeros:
            word = q if q8 else [1 - b for b in q]
            bits = word + [q8, 1 - q8]
            cnt += (ones - zeros) if q8 else (zeros - ones)
        elif (cnt > 0 and ones > zeros) or (cnt < 0 and zeros > ones):
            bits = [1 - b for b in q] + [q8, 1]
            cnt += 2 * q8 + zeros - ones
        else:
            bits = q + [q8, 0]
            cnt += -2 * (1 - q8) + ones - zeros
        out.append(sum(b << i for i, b in enumerate(bits)))
    return out


def decode(symbol):
    """A symbol back to ``("data", byte)`` or ``("control", c1c0)``; ``("error", symbol)`` for
    a symbol that is neither a token nor a valid data character."""
    s = int(symbol)
    if s in CONTROL:
        return "control", CONTROL.index(s)
    q = _bits(s, 10)
    w = [1 - b for b in q[:8]] if q[9] else q[:8]
    d = [w[0]] + [(w[i] ^ w[i - 1]) if q[8] else 1 - (w[i] ^ w[i - 1]) for i in range(1, 8)]
    return "data", sum(b << i for i, b in enumerate(d))


def disparity(symbol):
    """Ones minus zeros of a 10-bit symbol."""
    ones = bin(int(symbol) & 0x3FF).count("1")
    return 2 * ones - 10
