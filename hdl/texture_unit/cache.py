"""The texel cache in front of the texture memory port: in order, non-blocking, any memory
latency (the prefetching design of Igehy, Eldridge and Proudfoot, "Prefetching in a Texture
Cache Architecture", Graphics Hardware 1998).

The port (``REQUEST``, ``response``): a request is the texel address of a line, aligned to the
line; the memory answers each request with ``line`` responses, the line's texels in order, in
the order of the requests, with any latency and with backpressure on both streams.

- ``banks`` caches side by side, one per bank of the map (one for nearest; four for bilinear,
  one per parity of s and t, so a 2 x 2 footprint reads one texel from each), each with
  ``lines`` lines of ``line`` texels in ``lines / ways`` sets of ``ways`` ways; a line's set is
  the low bits of its line number in its bank, its tag the rest.
- **Look-up** (a miss a clock): the fragment's lines are looked up in the tags (distributed
  RAM, read at once); a bank that misses takes its set's next way (round robin), its tag is
  written at once (so the next fragment hits the line on its way) and its request goes to the
  port. With a port a bank, the fragment, with its lines' slots and which of them missed,
  enters the **queue** (``depth`` fragments: the latency it hides) when its last miss goes
  out (or at once, if every bank hits). With one port shared, it enters at once and its
  misses go out after it, one a clock, before the next look-up: so the memory need never
  hold more than one request before it answers. A fragment takes a clock, or one per miss.
- **Head**: the fragment at the queue's head takes its missed lines' texels from the port, in
  order, and writes them into the data arrays (one block RAM read port and one write port per
  bank); when it has them all it reads its texels (transparent to the write of the same
  clock) and leaves. A line is written only when the fragment that missed it is at the head,
  so every fragment before it has read the line it replaces: nothing is overwritten before it
  is read, whatever the latency, and nothing waits on anything behind it.
- After a reset the tags are cleared, a set a clock (``sets`` clocks), before the first
  look-up.
"""
from amaranth.hdl import Cat, Const, Mux, Signal, unsigned
from amaranth.lib.fifo import SyncFIFOBuffered
from amaranth.lib.memory import Memory

from ..fixed import Field, u

__all__ = ["ADDR", "request_fields", "response_fields", "texel_cache", "CACHE_LATENCY"]

ADDR = u(24, unit="texel")       # a texel's address in the texture memory
CACHE_LATENCY = 3                # look-up to queue (1), the queue's read (1), the head (1)


def request_fields():
    return [Field("addr", ADDR)]


def response_fields(texel_bits):
    return [Field("data", u(texel_bits))]


def _log2(n):
    return n.bit_length() - 1


def texel_cache(m, i, v, o, reqs, resps, *, banks, lines, line, ways, bank_texels,
                texel_bits, depth):
    """The cache between the handshakes ``i`` (in: values ``v`` at its register, among them
    ``_ln<k>`` and ``_off<k>``, bank k's line number and the texel's place in the line) and
    ``o`` (out; ``o.ready`` is driven by the caller). ``reqs``, ``resps``: the memory ports'
    streams, one shared by every bank or one per bank. Returns ``(values, busy)``: ``v``
    without the line keys, with ``_tex<k>`` (bank k's texel) from the output register."""
    shared = len(reqs) == 1
    sets = lines // ways
    sb, wb, lb = _log2(sets), _log2(ways), _log2(line)
    tag_bits = max(1, _log2(bank_texels) - lb - sb)
    slot_bits = max(1, _log2(lines))
    v = dict(v)
    lnum = [v.pop(f"_ln{k}")[:_log2(bank_texels) - lb] for k in range(banks)]
    offs = [v.pop(f"_off{k}", Const(0, 1)) for k in range(banks)]

    # ---- tags: a memory per bank and way, (valid, tag) per set; cleared after a reset
    clearing = Signal(init=1, name="tc_clearing")
    sweep = Signal(max(1, sb), name="tc_sweep")
    with m.If(clearing):
        m.d.sync += sweep.eq(sweep + 1)
        with m.If(sweep == sets - 1):
            m.d.sync += clearing.eq(0)
    rr = [Signal(max(1, wb), name=f"tc_rr{k}") for k in range(banks)]
    missed = Signal(banks)
    hit, hit_way, issue = [], [], []
    for k in range(banks):
        set_k = lnum[k][:sb] if sb else Const(0, 1)
        tag_k = lnum[k][sb:sb + tag_bits]
        match = []
        for w in range(ways):
            mem = Memory(shape=unsigned(tag_bits + 1), depth=sets, init=[])
            m.submodules[f"tags{k}_{w}"] = mem
            rd, wr = mem.read_port(domain="comb"), mem.write_port()
            m.d.comb += rd.addr.eq(set_k)
            match.append(rd.data[0] & (rd.data[1:] == tag_k))
            wr_here = Signal(name=f"tc_wr{k}_{w}")
            m.d.comb += [wr.addr.eq(Mux(clearing, sweep, set_k)),
                         wr.data.eq(Mux(clearing, 0, Cat(Const(1, 1), tag_k))),
                         wr.en.eq(clearing | wr_here)]
            issue.append((k, w, wr_here))
        h = Cat(*match).any()
        hit.append(h)
        way = Const(0, max(1, wb))
        for w in reversed(range(ways)):
            way = Mux(match[w], w, way)
        hit_way.append(way)
    remaining = Cat(*(~h for h in hit))
    line_addr = [Cat(Const(0, lb), lnum[k], Const(k, max(1, _log2(banks))) if banks > 1
                     else Const(0, 0)) for k in range(banks)]

    # ---- the queue: the fragment's values, each bank's slot and offset, and which missed
    riding = list(v.items())
    width = sum(len(x) for _, x in riding) + banks * (slot_bits + lb + 1)
    m.submodules.tex_queue = fifo = SyncFIFOBuffered(width=width, depth=depth)
    if shared:
        # The fragment enters the queue at its look-up, each missing bank's tag written and
        # its request noted (``pend``); the port sends them after, one a clock, the lowest
        # bank first, and the look-up waits until they are out. (Sent before it entered,
        # the fragment's requests would need a memory that takes all of them before it
        # gives a response: with one that holds two, four misses hung. flows/texjoin.py.)
        pend = Signal(banks, name="tc_pend")
        pend_addr = [Signal(ADDR.width, name=f"tc_pend_addr{k}") for k in range(banks)]
        ready = i.valid & ~clearing & ~pend.any()
        push = ready & fifo.w_rdy
        send = [push & remaining[k] for k in range(banks)]       # noted, sent after
        first = [pend[k] & ~(pend[:k].any() if k else Const(0)) for k in range(banks)]
        addr = Const(0, ADDR.width)
        for k in reversed(range(banks)):
            addr = Mux(first[k], pend_addr[k], addr)
        req = reqs[0]
        m.d.comb += [req.valid.eq(pend.any()), req.payload.addr.eq(addr)]
        gone = Cat(*(req.ready & first[k] for k in range(banks)))
        m.d.sync += pend.eq((pend & ~gone) | Mux(push, remaining, 0))
        for k in range(banks):
            with m.If(send[k]):
                m.d.sync += pend_addr[k].eq(line_addr[k])
        waiting = pend.any()
    else:                      # every missing bank's at once, each on its own port; the
        #                        fragment enters when its last one is out
        ready = i.valid & ~clearing
        send = []
        for k, req in enumerate(reqs):
            m.d.comb += [req.valid.eq(ready & remaining[k]), req.payload.addr.eq(line_addr[k])]
            send.append(req.valid & req.ready)
        push = ready & fifo.w_rdy
        for k in range(banks):
            push = push & (~remaining[k] | send[k])
        waiting = Const(0)
    for k, w, wr_here in issue:
        m.d.comb += wr_here.eq(send[k] & (rr[k] == w if ways > 1 else 1))
    for k in range(banks):
        with m.If(send[k]):
            m.d.sync += rr[k].eq(rr[k] + 1)
    m.d.comb += [i.ready.eq(push), fifo.w_en.eq(push)]
    with m.If(push):
        m.d.sync += missed.eq(0)
    with m.Else():
        m.d.sync += missed.eq(missed | Cat(*send))
    per_bank = []
    for k in range(banks):
        way = Mux(send[k], rr[k], hit_way[k])                # a miss sent now: its victim's
        slot = Cat(way[:wb], lnum[k][:sb]) if wb else lnum[k][:sb]
        per_bank += [slot[:slot_bits], offs[k][:lb], missed[k] | send[k]]
    m.d.comb += fifo.w_data.eq(Cat(*(x for _, x in riding), *per_bank))

    # ---- the head: the missed lines from the port, then the texels
    at = 0
    head = {}
    for name, x in riding:
        n = len(x)
        head[name] = fifo.r_data[at:at + n].as_signed() if x.shape().signed \
            else fifo.r_data[at:at + n]
        at += n
    slot, off, miss = [], [], []
    for k in range(banks):
        slot.append(fifo.r_data[at:at + slot_bits])
        off.append(fifo.r_data[at + slot_bits:at + slot_bits + lb] if lb else Const(0, 1))
        miss.append(fifo.r_data[at + slot_bits + lb])
        at += slot_bits + lb + 1
    served = Signal(banks)
    need = Cat(*(miss[k] & ~served[k] for k in range(banks))) & \
        Cat(*([fifo.r_rdy] * banks))
    out_valid = Signal(name="tc_out_valid")
    en = ~out_valid | o.ready
    # each bank's writes: from the shared port, the lowest bank that needs its line; else
    # from its own port. A bank's line is complete with its last texel.
    if shared:
        cur = [need[k] & ~(need[:k].any() if k else Const(0)) for k in range(banks)]
        m.d.comb += resps[0].ready.eq(need.any())
        got = resps[0].valid & resps[0].ready
        counts = [Signal(max(1, lb), name="tc_count")] * banks
        writes = [got & cur[k] for k in range(banks)]
        datas = [resps[0].payload.data] * banks
    else:
        for k, resp in enumerate(resps):
            m.d.comb += resp.ready.eq(need[k])
        counts = [Signal(max(1, lb), name=f"tc_count{k}") for k in range(banks)]
        writes = [resp.valid & resp.ready for resp in resps]
        datas = [resp.payload.data for resp in resps]
    ends = [(c == line - 1) if lb else Const(1) for c in counts]
    go = fifo.r_rdy & en
    for k in range(banks):
        go = go & (~need[k] | (writes[k] & ends[k]))
    # one counter shared (any bank's write moves it), or one a bank
    groups = [(counts[0], Cat(*writes).any(), ends[0])] if shared else \
        list(zip(counts, writes, ends))
    for count, moved, end in groups:
        with m.If(moved):
            m.d.sync += count.eq(Mux(end, 0, count + 1))
    for k in range(banks):
        with m.If(go):
            m.d.sync += served[k].eq(0)
        with m.Elif(writes[k] & ends[k]):
            m.d.sync += served[k].eq(1)
    m.d.comb += fifo.r_en.eq(go)
    out = {}
    for k in range(banks):
        data = Memory(shape=unsigned(texel_bits), depth=lines * line, init=[])
        m.submodules[f"texels{k}"] = data
        wr = data.write_port()
        rd = data.read_port(transparent_for=(wr,))
        m.d.comb += [wr.addr.eq(Cat(counts[k][:lb], slot[k]) if lb else slot[k]),
                     wr.data.eq(datas[k]), wr.en.eq(writes[k]),
                     rd.addr.eq(Cat(off[k][:lb], slot[k]) if lb else slot[k]), rd.en.eq(en)]
        out[f"_tex{k}"] = rd.data
    with m.If(en):
        m.d.sync += out_valid.eq(go)
    for name, x in head.items():
        reg = Signal(x.shape(), name=f"tc_{name}", reset_less=True)
        with m.If(en):
            m.d.sync += reg.eq(x)
        out[name] = reg
    m.d.comb += o.valid.eq(out_valid)
    busy = i.valid | (fifo.level != 0) | out_valid | clearing | waiting
    return out, busy
