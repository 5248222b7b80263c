"""The host link: frames of host-port rows (docs/host.md) over a byte stream.

A frame, little-endian::

    A5 5A | kind u8 | seq u8 | length u16 | payload (length bytes) | CRC-16 u16

The CRC is CRC-16/CCITT-FALSE (polynomial 0x1021, initial 0xFFFF, MSB first) over kind, seq,
length and payload. Kinds (``KINDS``): triangles (records of the raster's fields, packed LSB
first, ``tri_bytes`` each), writes (records of addr u24, data u32), clear (the background as
RGB565 u16) and status (no payload).

A frame is stored whole, checked, and only then applied, so a bad one is never half-applied:

- a wrong CRC, an unknown kind, or a length that is not a whole number of records: rejected;
- a frame longer than the buffer: rejected at its header, the rest of it dropped until the
  line is quiet (``timeout`` clocks without a byte);
- a frame cut short: rejected when the line is quiet for ``timeout`` clocks inside it;
- bytes outside a frame (noise): counted and dropped until the next sync;
- a write to an address that the pipeline's map does not name: counted, and not sent on;
- a triangle that ``reject`` marks (the top's test: every vertex beyond one edge of the
  image, so it covers no pixel of it): counted (``offscreen``), and not sent on.

Every frame that got as far as its header is answered on ``tx`` with a reply (``REPLY``):
its seq, its result (``RESULTS``) and the counters. A good frame is answered once its last
row has entered the pipeline, so a host that waits for the reply before the next frame (one
credit) can never overrun the buffer. Bytes that arrive while a frame is checked, applied or
answered are counted (``dropped``); their frame goes unanswered, and the host sends it again.
"""
import binascii

from amaranth.hdl import Cat, Const, Module, Mux, Signal
from amaranth.lib import data, stream, wiring
from amaranth.lib.memory import Memory
from amaranth.lib.wiring import In, Out

__all__ = ["SYNC", "KINDS", "RESULTS", "COUNTERS", "REPLY_BYTES", "WRITE_BYTES", "Link",
           "crc16"]

SYNC = (0xA5, 0x5A)
KINDS = {"triangles": 1, "writes": 2, "clear": 3, "status": 4}
RESULTS = ("ok", "crc", "cut", "long", "kind")
# the reply's counters (u16 each, after magic, seq and result)
COUNTERS = ("good", "crc", "cut", "long", "kind", "unknown", "offscreen", "noise", "dropped")
REPLY_MAGIC = 0xC3
REPLY_BYTES = 3 + 2 * len(COUNTERS)
WRITE_BYTES = 7                               # addr u24, data u32
CLEAR_BYTES = 2


def crc16(payload):
    """CRC-16/CCITT-FALSE of ``payload`` (the standard library's, not ours)."""
    return binascii.crc_hqx(bytes(payload), 0xFFFF)


def _crc_step(m, crc, byte):
    """One byte into the CRC register, MSB first (combinational; a signal a bit step, so the
    Verilog does not double at each)."""
    c = crc ^ (byte << 8)
    for k in range(8):
        nxt = Signal(16, name=f"crc_bit{k}")
        m.d.comb += nxt.eq((c << 1)[:16] ^ Mux(c[15], 0x1021, 0))
        c = nxt
    return c


def row_layout(tri_bits):
    return data.StructLayout({"tri": tri_bits, "cmd": 1, "addr": 24, "data": 32})


class Link(wiring.Component):
    """``i``: bytes from the UART; ``o``: host-port rows; ``tx``: reply bytes; ``clear``: a
    pulse with ``colour`` when a clear frame applies, after ``drained`` (nothing in the
    pipeline or the framebuffer); ``reject``: the top's verdict on the triangle that ``o``
    holds (combinational, from ``o.payload``)."""

    def __init__(self, tri_bits, known, buffer=2048, timeout=1 << 16):
        self.tri_bits = tri_bits
        self.tri_bytes = (tri_bits + 7) // 8
        self.known = tuple(known)              # (base, size) of every address the map names
        if buffer < max(self.tri_bytes, WRITE_BYTES) or buffer > 65535:
            raise ValueError(f"the link's buffer must hold a record and at most 65535 bytes, "
                             f"not {buffer}")
        self.buffer, self.timeout = buffer, timeout
        super().__init__({
            "i": In(stream.Signature(8)),
            "o": Out(stream.Signature(row_layout(tri_bits))),
            "tx": Out(stream.Signature(8)),
            "drained": In(1), "clear": Out(1), "colour": Out(16), "reject": In(1),
            "counters": Out(data.ArrayLayout(16, len(COUNTERS))),
            "frames": Out(16),                 # replies sent
        })

    def elaborate(self, platform):
        m = Module()
        n = {name: self.counters[k] for k, name in enumerate(COUNTERS)}
        m.submodules.buf = buf = Memory(shape=8, depth=self.buffer, init=[])
        wr, rd = buf.write_port(), buf.read_port()

        kind, seq, length = Signal(8), Signal(8), Signal(16)
        crc, got = Signal(16, init=0xFFFF), Signal(16)
        ptr = Signal(16)                           # header byte, payload byte or read pointer
        gap = Signal(range(self.timeout + 1))
        result = Signal(range(len(RESULTS)))
        rec_bytes = max(self.tri_bytes, WRITE_BYTES)
        rec, nb = Signal(8 * rec_bytes), Signal(range(rec_bytes + 1))
        part = Signal(range(rec_bytes))          # payload bytes past the last whole record
        rejected, unknown = Signal(), Signal()    # the record's verdicts (JUDGE)
        got_byte = Signal(8)
        byte = self.i.payload
        take = self.i.valid                         # the input is never stalled
        m.d.comb += self.i.ready.eq(1)
        m.d.sync += gap.eq(Mux(take, 0, Mux(gap == self.timeout, gap, gap + 1)))
        drained = Signal()          # registered: the pipeline's busy is a wide OR, far away
        m.d.sync += drained.eq(self.drained)
        quiet = gap == self.timeout

        crc_next = _crc_step(m, crc, byte)
        is_tri = kind == KINDS["triangles"]
        size = Mux(is_tri, self.tri_bytes, WRITE_BYTES)
        reply_idx = Signal(range(REPLY_BYTES + 1))

        def reply(code):
            m.d.sync += [result.eq(code), reply_idx.eq(0)]
            if code != 0:
                m.d.sync += n[RESULTS[code]].eq(n[RESULTS[code]] + 1)
            else:
                m.d.sync += n["good"].eq(n["good"] + 1)
            m.next = "REPLY"

        def receiving(state_body):
            """A state inside a frame: a byte goes to ``state_body``, silence cuts it."""
            with m.If(take):
                state_body()
            with m.Elif(quiet):
                reply(RESULTS.index("cut"))

        addr, wdata = rec[:24], rec[24:56]
        known = Const(0)
        for base, count in self.known:
            known = known | ((addr >= base) & (addr < base + count))

        # the row: the record as it stands (offered in EMIT only)
        m.d.comb += [self.o.payload.cmd.eq(~is_tri), self.o.payload.tri.eq(rec[:self.tri_bits]),
                     self.o.payload.addr.eq(addr), self.o.payload.data.eq(wdata)]
        with m.FSM() as fsm:
            with m.State("HUNT"):
                with m.If(take):
                    with m.If(byte == SYNC[0]):
                        m.next = "SYNC1"
                    with m.Else():
                        m.d.sync += n["noise"].eq(n["noise"] + 1)
            with m.State("SYNC1"):
                with m.If(take):
                    with m.If(byte == SYNC[1]):
                        m.d.sync += [crc.eq(0xFFFF), ptr.eq(0)]
                        m.next = "HEAD"
                    with m.Elif(byte != SYNC[0]):
                        m.d.sync += n["noise"].eq(n["noise"] + 2)
                        m.next = "HUNT"
                with m.Elif(quiet):
                    m.next = "HUNT"
            with m.State("HEAD"):
                def head():
                    m.d.sync += [crc.eq(crc_next), ptr.eq(ptr + 1)]
                    with m.Switch(ptr):
                        with m.Case(0):
                            m.d.sync += kind.eq(byte)
                        with m.Case(1):
                            m.d.sync += seq.eq(byte)
                        with m.Case(2):
                            m.d.sync += length[:8].eq(byte)
                        with m.Case(3):
                            full = Cat(length[:8], byte)
                            m.d.sync += [length[8:].eq(byte), ptr.eq(0), part.eq(0)]
                            with m.If(full > self.buffer):
                                m.next = "DISCARD"
                            with m.Elif(full == 0):
                                m.next = "CRC0"
                            with m.Else():
                                m.next = "BODY"
                receiving(head)
            with m.State("BODY"):
                def body():
                    m.d.comb += [wr.addr.eq(ptr), wr.data.eq(byte), wr.en.eq(1)]
                    m.d.sync += [crc.eq(crc_next), ptr.eq(ptr + 1),
                                 part.eq(Mux(part + 1 == size, 0, part + 1))]
                    with m.If(ptr < CLEAR_BYTES):
                        m.d.sync += self.colour.word_select(ptr[0], 8).eq(byte)
                    with m.If(ptr + 1 == length):
                        m.next = "CRC0"
                receiving(body)
            with m.State("CRC0"):
                def crc0():
                    m.d.sync += got[:8].eq(byte)
                    m.next = "CRC1"
                receiving(crc0)
            with m.State("CRC1"):
                def crc1():
                    m.d.sync += [got[8:].eq(byte), ptr.eq(0), nb.eq(0)]
                    m.next = "CHECK"
                receiving(crc1)
            with m.State("CHECK"):
                whole = part == 0
                with m.If(got != crc):
                    reply(RESULTS.index("crc"))
                with m.Elif(((kind == KINDS["triangles"]) | (kind == KINDS["writes"]))
                            & whole):
                    m.next = "READ"
                with m.Elif((kind == KINDS["clear"]) & (length == CLEAR_BYTES)):
                    m.next = "CLEAR"
                with m.Elif((kind == KINDS["status"]) & (length == 0)):
                    reply(0)
                with m.Else():
                    reply(RESULTS.index("kind"))
            with m.State("READ"):
                with m.If(ptr == length):
                    reply(0)
                with m.Else():
                    m.d.comb += rd.addr.eq(ptr)
                    m.d.sync += ptr.eq(ptr + 1)
                    m.next = "TAKE"
            with m.State("TAKE"):                   # the block RAM's output, registered
                m.d.sync += got_byte.eq(rd.data)     # (5.8 ns from its clock)
                m.next = "PUT"
            with m.State("PUT"):
                m.d.sync += [rec.word_select(nb, 8).eq(got_byte), nb.eq(nb + 1)]
                with m.If(nb + 1 == size):
                    m.next = "JUDGE"
                with m.Else():
                    m.next = "READ"
            with m.State("JUDGE"):           # the record's verdicts, registered
                m.d.sync += [rejected.eq(is_tri & self.reject), unknown.eq(~is_tri & ~known)]
                m.next = "EMIT"
            with m.State("EMIT"):
                m.d.sync += nb.eq(0)
                with m.If(rejected):
                    m.d.sync += n["offscreen"].eq(n["offscreen"] + 1)
                    m.next = "READ"
                with m.Elif(~unknown):
                    m.d.comb += self.o.valid.eq(1)
                    with m.If(self.o.ready):
                        m.next = "READ"
                with m.Else():
                    m.d.sync += n["unknown"].eq(n["unknown"] + 1)
                    m.next = "READ"
            with m.State("CLEAR"):
                with m.If(drained):
                    m.d.comb += self.clear.eq(1)
                    m.next = "CLEARING"
            with m.State("CLEARING"):                # drained is a clock late: skip its
                m.next = "CLEARED"                   # view of the clock before the pulse
            with m.State("CLEARED"):
                with m.If(drained):
                    reply(0)
            with m.State("DISCARD"):
                with m.If(quiet):
                    reply(RESULTS.index("long"))
            with m.State("REPLY"):
                words = [REPLY_MAGIC, seq, result] + [
                    self.counters[k].word_select(j, 8)
                    for k in range(len(COUNTERS)) for j in range(2)]
                with m.Switch(reply_idx):
                    for k, w in enumerate(words):
                        with m.Case(k):
                            m.d.comb += self.tx.payload.eq(w)
                m.d.comb += self.tx.valid.eq(1)
                with m.If(self.tx.ready):
                    m.d.sync += reply_idx.eq(reply_idx + 1)
                    with m.If(reply_idx == REPLY_BYTES - 1):
                        m.d.sync += self.frames.eq(self.frames + 1)
                        m.next = "HUNT"
        # bytes that arrive while a frame is checked, applied or answered: not taken
        applying = Cat(*(fsm.ongoing(s) for s in ("CHECK", "READ", "TAKE", "PUT", "JUDGE",
                                                  "EMIT", "CLEAR", "CLEARING", "CLEARED",
                                                  "REPLY"))).any()
        with m.If(take & applying):
            m.d.sync += n["dropped"].eq(n["dropped"] + 1)
        return m
