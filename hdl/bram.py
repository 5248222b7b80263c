"""One table slice in a block RAM, read through the block's own output register.

A table read is two registers: the RAM's read register (the address registered into the
block) and one more before any logic (``hdl.lut.rom``). Yosys (0.70) infers ECP5's DP16KD
without its output register (REGMODE=OUTREG, YosysHQ/yosys#5814), so the second register is
in the fabric and the block's clock-to-output (5.8 ns) is in series with a route into it: the
default pipeline's critical path on every seed (docs/fpga.md). On ECP5 a slice that fits one
DP16KD in its 1,024 x 18 form is therefore instantiated with REGMODE=OUTREG on its read
ports, the output register taking the second register's place; everywhere else (simulation,
iCE40, wider slices) the same two clocks are a ``Memory`` read port and a register. Both
forms are cycle-for-cycle the same: the read register loads while ``en`` is high, and so does
the output register.

The INITVAL packing is Yosys's own (``share/lattice/brams_map_16kd.v``): in the 18-bit form
entry k is bits [20 (k mod 16), +18) of INITVAL_(k div 16); tests/test_fpga.py checks it
against the DP16KD that Yosys infers for the same contents.
"""
from amaranth.hdl import ClockSignal, Const, Instance, Signal, Value
from amaranth.lib.memory import Memory

from .dsp import ecp5

__all__ = ["block_fits", "initvals", "table_slice"]

DEPTH, WIDTH = 1024, 18            # DP16KD's 18-bit form (DATA_WIDTH 18: address AD[13:4])


def block_fits(depth, bits):
    """A slice that one DP16KD holds in its 18-bit form."""
    return depth <= DEPTH and bits <= WIDTH


def initvals(words):
    """``{INITVAL_00..3F: 320-bit Const}`` of up to 1,024 words of up to 18 bits."""
    out = {}
    for row in range(64):
        v = 0
        for i, w in enumerate(words[row * 16:row * 16 + 16]):
            v |= int(w) << (20 * i)
        out[f"p_INITVAL_{row:02X}"] = Const(v, 320)
    return out


def _port(side, addr, en, oe, we=Const(0), data=Const(0, WIDTH), out=None, write=False):
    """Port ``side`` (A or B) in the 18-bit form: the word address on AD[13:4]; a write port
    sets both byte enables (AD[1:0]) and holds its output register still."""
    ad = Value.cast(addr)
    ports = {f"i_AD{side}{k}": Const(int(write) if k < 2 else 0) for k in range(4)}
    ports.update({f"i_AD{side}{k + 4}": ad[k] if k < len(ad) else Const(0) for k in range(10)})
    ports.update({f"i_DI{side}{k}": Value.cast(data)[k] if k < len(Value.cast(data))
                  else Const(0) for k in range(WIDTH)})
    ports.update({f"i_CS{side}{k}": Const(0) for k in range(3)})
    ports.update({f"i_CLK{side}": ClockSignal(), f"i_CE{side}": en, f"i_OCE{side}": oe,
                  f"i_WE{side}": we, f"i_RST{side}": Const(0)})
    if out is not None:
        ports.update({f"o_DO{side}{k}": out[k] for k in range(len(out))})
    return ports


def table_slice(m, name, depth, bits, init, addrs, en, platform, write=None, out_en=None):
    """A slice of ``bits`` x ``depth`` (``init``: its words, or empty for a loaded table) read
    at each of ``addrs`` (one or two): the read register loads while ``en`` is high, the
    output register while ``out_en`` is (``en`` by default: a pipeline's stage; a schedule's
    read loads it a clock after the address). ``write`` is ``(en, addr, data)``, the host's
    port of a loaded table (then one read). Returns the output registers, one per read."""
    if write is not None and len(addrs) != 1:
        raise ValueError(f"{name}: a loaded table has one read port beside its write port")
    if not 1 <= len(addrs) <= 2:
        raise ValueError(f"{name}: a block RAM has two ports, not {len(addrs)} reads")
    oe = en if out_en is None else out_en
    outs = [Signal(bits, name=f"{name}_q{k}" if len(addrs) > 1 else f"{name}_q",
                   reset_less=True) for k in range(len(addrs))]
    if ecp5(platform) and block_fits(depth, bits):
        params = dict(p_DATA_WIDTH_A=WIDTH, p_DATA_WIDTH_B=WIDTH, p_RESETMODE="SYNC",
                      p_ASYNC_RESET_RELEASE="SYNC", p_CSDECODE_A="0b000",
                      p_CSDECODE_B="0b000", p_WRITEMODE_A="NORMAL", p_WRITEMODE_B="NORMAL",
                      p_GSR="DISABLED", **initvals(init))
        if write is not None:                      # A writes, B reads
            we, wa, wd = write
            params.update(p_REGMODE_A="NOREG", p_REGMODE_B="OUTREG",
                          **_port("A", wa, Const(1), Const(1), we, wd, write=True),
                          **_port("B", addrs[0], en, oe, out=outs[0]))
        else:
            params.update(p_REGMODE_A="OUTREG", p_REGMODE_B="OUTREG",
                          **_port("A", addrs[0], en, oe, out=outs[0]),
                          **(_port("B", addrs[1], en, oe, out=outs[1]) if len(addrs) > 1
                             else _port("B", Const(0), Const(0), Const(0))))
        m.submodules[name] = Instance("DP16KD", **params)
        return outs
    mem = Memory(shape=bits, depth=depth, init=[int(w) for w in init])
    m.submodules[name] = mem
    if write is not None:
        wr = mem.write_port()
        m.d.comb += [wr.en.eq(write[0]), wr.addr.eq(write[1]), wr.data.eq(write[2])]
    for addr, q in zip(addrs, outs):
        port = mem.read_port(domain="sync")
        m.d.comb += [port.addr.eq(addr), port.en.eq(en)]
        with m.If(oe):
            m.d.sync += q.eq(port.data)               # the output register's place
    return outs
