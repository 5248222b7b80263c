"""The span engine (seeds 000, 001): edge walking, span-start evaluation, forward differences.

The row engines; the setup (``setup_engine.py``), the walker (``walker.py``), the row queue
and the stepper are components of their own.

- ``row_engine`` (a schedule on shared multipliers, a row every ``ii`` clocks): (u, v) from
  the numerators times the reciprocal, then per channel Phi(u, v) (eq 17) and its first
  difference along x, Pu u + Pv v + P0. Exact numerators: rounding never accumulates across
  rows.
"""
from amaranth.hdl import Const, Signal, Value, signed, unsigned
from amaranth.lib.memory import Memory

from ..sched import OPERAND, Schedule, _or_tree
from ..term import Cat, Mux, term
from ..setup_unit.formats import VALUE

AMOUNT_BITS = 6       # a narrow product's shift into FI (``golden.bfp.AMOUNT_BITS``)

__all__ = ["narrow_left", "narrow_row_fields", "plan_row_engine", "row_engine", "row_engine_serial", "row_products",
           "split_fields", "turns"]


def plan_row_engine(m, plan, w, rows, row_link, space, platform=None, flat=(), consts=None,
                    narrow=None, registered=True):
    """The plan's row engine: every channel a job (:func:`row_engine`, on the plan's
    ``row_multipliers``; ``narrow``: on M-bit mantissas;
    ``registered=False``: its row values a clock before their register, for ``RowPair``'s
    one register), or one channel a job (:func:`row_engine_serial`, ``row_serial``)."""
    mults = plan.row_multipliers
    if plan.row_serial:
        assert not narrow, "the narrow engine has every channel in a job"
        return row_engine_serial(m, w, plan.modes, rows, row_link, space, platform, flat,
                                 mults, consts, plan.precision)
    return row_engine(m, w, plan.modes, rows, row_link, space, platform, flat, mults, consts,
                      plan.precision, narrow, registered)


def row_engine(m, w, modes, rows, row_link, space, platform=None, flat=(), mults=None,
               consts=None, precision=None, narrow=None, registered=True):
    """Phi and its first difference at each span's first pixel centre, on ``channels + 1``
    shared multipliers, a row every ``ii`` clocks: u = nu r / 2**sh, v likewise (eq 18-20),
    then per channel Phi = f + u (d + a u + c v) + v (e + b v) (eq 17) and
    d = P0 + Pu u + Pv v: seven products, two for a linear channel (a = b = c = 0, so
    Phi = f + u d + v e and d = P0). The engine never stalls: a row starts only when
    ``space`` (a register of the row queue) promises a place for it. ``precision``: each
    channel's fraction bits out; its Phi, d and 2A go into the queue floored to ``w.fi`` of
    it. ``narrow``: mantissa bits M (at most 20), every product narrow (:func:`narrow_left`;
    the constants are then the setup's mantissas and shifts). ``registered=False``: the
    ``late`` write's values and enable a clock early, not registered. Returns what
    :func:`row_engine_serial` returns: the writes into the row queue
    (``late``, the row values computed, and ``early``, what the engine only carries, taken at
    the row's start), the row's start, its last write and the timing. ``consts`` is the
    serial engine's (the setup's channels in turn need it), so none here."""
    assert consts is None, "the channel-constant memory is read by the serial engine only"
    channels = len(modes)
    precision = precision or (VALUE.frac_bits,) * channels
    cut = [VALUE.frac_bits - p for p in precision]     # bits below the channel's FI
    mults = mults or channels + 1
    ii = -(-row_products(modes) // mults)
    out_valid = Signal(name="re_out_valid")
    if narrow:
        sc = Schedule(m, "re", Const(1), ii=ii, mults=0, narrow=mults, narrow_bits=narrow,
                      mux_groups=8, platform=platform, shift=(None, narrow_left(w, narrow)),
                      ram_copies=True)
    else:                     # in RowPair (not ``registered``), late values in LUT RAM too
        sc = Schedule(m, "re", Const(1), ii=ii, mults=mults, mux_groups=8, platform=platform,
                      ram_copies=not registered)
    m.d.comb += [sc.start.eq(row_link.valid & sc.aligned & space),
                 row_link.ready.eq(sc.aligned & space)]
    # what passes through unchanged (the row, the triangle's index and flat words, 2A, a
    # linear channel's d = P0) goes to the row queue as the row starts, not through a copy
    # for each row in flight (over the engine's length, 6 copies of each 2A at the default)
    early = {k: rows[k] for k in ("j", "tri", *flat)}
    acc = [w.acc(p) for p in precision]             # what the stepper keeps of them
    early.update({f"c{ch}_a2": (rows[f"c{ch}_a2"] >> cut[ch])[:acc[ch]]
                  for ch in range(channels)})
    early.update({f"d{ch}": (rows[f"c{ch}_p0"] >> cut[ch])[:acc[ch]]
                  for ch, mode in enumerate(modes) if mode == "linear"})
    carried = {"j", "tri", *flat, *(f"c{ch}_a2" for ch in range(channels)),
               *(f"c{ch}_p0" for ch, mode in enumerate(modes) if mode == "linear")}
    # what is read only at the end, f and a quadratic channel's P0: a memory per channel
    # written as the row starts, read at the offset of that end at the row's slot (a copy of
    # 4 bits, not of the 51-61 the values take; at most ceil(length / ii) < 16 rows in
    # flight, so no slot is written again before its row's read)
    ends = {ch: (f"c{ch}_f",) if mode == "linear" else (f"c{ch}_f", f"c{ch}_p0")
            for ch, mode in enumerate(modes)}
    carried.update(k for names in ends.values() for k in names)
    wptr = Signal(4, name="re_cptr")
    m.d.sync += wptr.eq(wptr + sc.start)
    slot = sc.input("cslot", wptr)

    def read_at(ch, k):
        """Channel ``ch``'s end values as the row at offset ``k`` wrote them: f at FI with
        the output's rounding half in it (``f_fi``; an addition on the way in, from the
        walker's registers), P0."""
        f = rows[f"c{ch}_f"]
        vals = {f"c{ch}_f_fi": (Value.cast(f) << (w.FI - w.FO)) + _half(w, precision[ch]),
                **{n: rows[n] for n in ends[ch][1:]}}
        mem = Memory(shape=unsigned(sum(len(x) for x in vals.values())), depth=16, init=[])
        m.submodules[f"row_ends{ch}"] = mem
        wr, rd = mem.write_port(), mem.read_port(domain="comb")
        addr = sc.late(slot, k)
        sc.read(k, addr)
        m.d.comb += [wr.addr.eq(wptr), wr.data.eq(Cat(*vals.values())), wr.en.eq(sc.start),
                     rd.addr.eq(addr)]
        return {n[len(f"c{ch}_"):]: x for n, x in split_fields(rd.data, vals).items()}
    # the inputs are captured at every slot a job may start in (``aligned``, not the start:
    # safe, since no job reads an input more than ``ii`` clocks after its start), from copies
    v = sc.inputs({k: x for k, x in rows.items() if k not in carried}, copy=sc.aligned_copy)
    u, vv = _uv_narrow(sc, w, v, narrow) if narrow else _uv(sc, w, v)
    fq = lambda x: x[:OPERAND].as_signed()
    FP = w.FO + w.FQ                                     # fraction bits of coefficient x u
    out = {}
    for ch, mode in enumerate(modes):
        c = {k: v.get(f"c{ch}_{k}") for k in ("a", "b", "c", "d", "e", "f", "pu", "pv", "p0")}
        if narrow:                                # the setup's mantissas and shifts
            c.update({k: v.get(f"c{ch}_n{k}") for k in ("a", "b", "c", "d", "e", "pu", "pv")})
            c.update({k: v.get(f"c{ch}_{k}") for k in ("sphi", "sd")})
        if narrow:
            uvt, puv = _channel_narrow(sc, narrow, ch, mode, c, u, vv)
        elif mode == "linear":           # t1 = d, t2 = e at FT fraction bits: a shift, no sum
            t1, t2 = (c[k] >> (w.FO - w.FT) for k in "de")
        else:
            au, cv, bv = sc.mul(f"au{ch}", c["a"], u), sc.mul(f"cv{ch}", c["c"], vv), \
                sc.mul(f"bv{ch}", c["b"], vv)
            pu, pv = sc.mul(f"pu{ch}", c["pu"], u), sc.mul(f"pv{ch}", c["pv"], vv)
            acv = sc.let(f"acv{ch}", au + cv)
            t1 = sc.apply(f"t1_{ch}", lambda d, x: fq(((d << w.FQ) + x) >> (FP - w.FT)),
                          c["d"], acv)
            t2 = sc.apply(f"t2_{ch}", lambda e, x: fq(((e << w.FQ) + x) >> (FP - w.FT)),
                          c["e"], bv)
        if not narrow:
            ut, vt = sc.mul(f"ut{ch}", u, t1), sc.mul(f"vt{ch}", vv, t2)
            uvt = sc.let(f"uvt{ch}", (ut + vt) >> (w.FQ + w.FT - w.FI))
            if mode != "linear":
                puv = sc.let(f"puv{ch}", (pu + pv) >> (FP - w.FI))
        if mode == "linear":          # d = P0: carried (``early``)
            k = sc.when(uvt)
            end_vals = read_at(ch, k)
        else:
            k = sc.when(uvt, puv)
            end_vals = read_at(ch, k)
            out[f"d{ch}"] = sc.let(f"d{ch}", ((term(end_vals["p0"]) + puv) >> cut[ch])
                                   [:acc[ch]], after=k)
        # Phi with its rounding half, floored to the channel's FI, the bits the stepper keeps
        out[f"phi{ch}"] = sc.let(f"phi{ch}", ((term(end_vals["f_fi"]) + uvt) >> cut[ch])
                                 [:acc[ch]], after=k)
    end = max(sc.ready[x] for x in out.values() if x in sc.ready)
    out = _outputs(sc, w, v, out, end, registered=registered)
    if registered:
        m.d.sync += out_valid.eq(sc.at(end))
    else:
        m.d.comb += out_valid.eq(sc.at(end))
    sc.finish()
    sc.check()
    writes = [("late", out, out_valid, None), ("early", early, sc.start, None)]
    return writes, sc.start, out_valid, {"ii": sc.ii, "length": sc.length, "busy": sc.busy(),
                                          "written": end + 1}


def row_engine_serial(m, w, modes, rows, row_link, space, platform=None, flat=(), mults=3,
                      consts=None, precision=None):
    """The row engine with its channels in turn: one datapath, on ``mults`` shared
    multipliers, evaluates one channel of one row per job, a job every ``ii`` clocks, so a
    further channel costs clocks per row (``ii`` each) and a share of the operand
    multiplexer, not multipliers or registers of its own. A job computes what
    :func:`row_engine` computes for one channel, in the same formats and order (u, v, then
    Phi and d, eq 17-20; a linear channel's zero a, b, c, Pu, Pv make the same sums), so the
    fragments are the same. Each job captures its inputs at its start (the row's values and
    its channel's constants, picked by a one-hot channel register) and recomputes u and v
    (nine products, four with no quadratic channel); the walker's row is taken at the last
    channel's start, so it and the triangle's constants stay steady while the jobs read
    them. ``consts``: the setup's channel-constant memory (``setup_engine.channel_engine``)
    as ``(index, fields, bits)``: the port that names the channel it reads, and its fields,
    read at the next job's channel in place of the walker's registers. ``precision``: as :func:`row_engine`'s (a job's rounding half is its
    channel's). Returns the writes into the row queue (``(name, values, enable, slot)``), the
    last job's start (the queue's credit), its write, and the timing."""
    channels = len(modes)
    precision = precision or (VALUE.frac_bits,) * channels
    cut = [VALUE.frac_bits - p for p in precision]
    quad = any(mode != "linear" for mode in modes)
    ii = -(-(9 if quad else 4) // mults)
    sc = Schedule(m, "rs", Const(1), ii=ii, mults=mults, mux_groups=8, platform=platform)
    sel, index, under = turns(m, sc, "rs", channels, row_link.valid & space)   # next job's
    slot = Signal(4, name="rs_next_slot")      # the next row's place in the row queue (4 bits
    #                                            wrap); each job captures it as ``rs_slot``
    m.d.comb += row_link.ready.eq(sc.aligned & sel[-1] & (under | space))
    with m.If(sc.start & sel[-1]):
        m.d.sync += slot.eq(slot + 1)
    # the row counts in the queue's credits from its last job's start, a start from
    # registers (with more than one channel): the first job's check of ``space`` holds a
    # place, as no other row starts before the last job and the queue only empties meanwhile
    started = Signal(name="rs_started")
    m.d.comb += started.eq(sc.aligned & sel[-1] if channels > 1 else sc.start)  # sel[-1]:
    # under, so this is sc.start & sel[-1], written so that no path runs from the walker
    keys = ("a", "b", "c", "d", "e", "f", "pu", "pv", "p0")
    if consts is None:
        pick = {k: _or_tree([Mux(sel[c], rows[f"c{c}_{k}"], 0) for c in range(channels)])
                for k in keys}
    else:
        port, fields, bits = consts
        m.d.comb += port.eq(index[:bits])
        pick = {k: fields[k] for k in keys}
    row_keys = ("xl", "xr", "E_u", "E_v", "B_u", "B_v", "rs", "sh")
    v = sc.inputs({**{k: rows[k] for k in row_keys}, **pick, "slot": slot, "sel": Cat(*sel)},
                  copy=sc.aligned_copy)
    u, vv = _uv(sc, w, v)
    fq = lambda x: x[:OPERAND].as_signed()
    FP = w.FO + w.FQ
    t1, t2 = (v[k] >> (w.FO - w.FT) for k in "de")
    if quad:
        au, cv, bv = sc.mul("au", v["a"], u), sc.mul("cv", v["c"], vv), sc.mul("bv", v["b"], vv)
        pu, pv = sc.mul("pu", v["pu"], u), sc.mul("pv", v["pv"], vv)
        acv = sc.let("acv", au + cv)
        t1 = sc.apply("t1", lambda d, x: fq(((d << w.FQ) + x) >> (FP - w.FT)), v["d"], acv)
        t2 = sc.apply("t2", lambda e, x: fq(((e << w.FQ) + x) >> (FP - w.FT)), v["e"], bv)
    ut, vt = sc.mul("ut", u, t1), sc.mul("vt", vv, t2)
    uvt = sc.let("uvt", (ut + vt) >> (w.FQ + w.FT - w.FI))
    d = (sc.apply("d", lambda p0, x: p0 + x, v["p0"], sc.let("puv", (pu + pv) >> (FP - w.FI)))
         if quad else v["p0"])
    phi = sc.apply("phi", lambda f, x: (f << (w.FI - w.FO)) + x, v["f"], uvt)
    end = sc.when(phi, d)
    halves = sorted(set(precision))
    half = (_half(w, halves[0]) if len(halves) == 1 else      # the job's channel's
            (v["sel"], lambda sel: _or_tree([Mux(sel[c], _half(w, p), 0)
                                             for c, p in enumerate(precision)])))
    out = _outputs(sc, w, v, {"phi": phi, "d": d}, end, {"phi": half})
    at = end + 1                               # the outputs' registers are valid
    addr, chan = sc.late(v["slot"], at), sc.late(v["sel"], at)
    sc.read(at, addr, chan)
    en = sc.at(at)
    acc = [w.acc(p) for p in precision]
    writes = [(f"c{c}", {f"phi{c}": (out["phi"] >> cut[c])[:acc[c]],
                         f"d{c}": (out["d"] >> cut[c])[:acc[c]]}, en & chan[c], addr)
              for c in range(channels)]
    last = Signal(name="rs_written")
    m.d.comb += last.eq(en & chan[-1])
    writes.append(("late", {k: out[k] for k in ("xs", "xe", "some", "one")}, last, addr))
    early = {k: rows[k] for k in ("j", "tri", *flat)}
    early.update({f"c{ch}_a2": (rows[f"c{ch}_a2"] >> cut[ch])[:acc[ch]]
                  for ch in range(channels)})
    writes.append(("early", early, started, slot))
    sc.finish()
    sc.check()
    busy = Signal(name="rs_busy")
    m.d.comb += busy.eq(sc.busy() | under)
    timing = {"ii": channels * ii, "length": (channels - 1) * ii + at, "busy": busy,
              "written": at}
    return writes, started, last, timing


def _start(sc, w, v):
    """A row's start in a row-engine schedule: the span clamped to the screen (``xs``,
    ``xe`` into ``v``) and the numerator track it starts on (column 0 when the left edge is
    off screen), ``nu``, ``nv`` into ``v``."""
    size = 1 << w.screen_bits

    def clamp(i):     # to [0, size]: i >= size (size a power of two) tests the bits above it,
        # where i > size was a carry chain (the default pipeline's critical path, placed)
        big = i[w.screen_bits:len(i) - 1].any() if len(i) - 1 > w.screen_bits else 0
        return Mux(i[-1], 0, Mux(big, size, i))
    border = v["xl"] < 0                          # the span starts at column 0: its track
    num = {f"n{a}": Mux(border, v[f"B_{a}"], v[f"E_{a}"])[:min(w.wn, OPERAND)].as_signed()
           for a in "uv"}                         # modulo 2**35: |nu| <= |Omega| < 2**33
    v.update(sc.lets(xs=clamp(v["xl"]), xe=clamp(v["xr"]), **num))
    v.update(sc.lets(some=v["xs"] < v["xe"], one=v["xs"] + 1 == v["xe"]))   # the span's tests


def _uv(sc, w, v):
    """:func:`_start`, then u = nu r / 2**sh, v likewise (eq 18-20). Returns (u, v)."""
    _start(sc, w, v)
    sc.shift = (v["sh"], w.FQ - w.R)
    fq = lambda x: x[:OPERAND].as_signed()
    return (sc.mul("u", v["nu"], v["rs"], post=fq, shifted=True),
            sc.mul("v", v["nv"], v["rs"], post=fq, shifted=True))


def narrow_row_fields(w, M, modes, flat=()):
    """The narrow engine's row fields (``{name: shape}``): the walker's row, the triangle's
    M-bit reciprocal ``rsm`` and its ``sh``, and per channel the M-bit mantissas of a..e
    (``na``..``ne``; d, e for a linear channel) and of Pu, Pv (``npu``, ``npv``), f as the
    wide engine has it, P0 and 2A at FI, and the shift amounts ``sphi``, ``sd``
    (``golden.bfp.amounts``)."""
    fields = {"j": unsigned(w.wrow), "tri": unsigned(16), **{k: unsigned(16) for k in flat},
              "xl": signed(w.wi), "xr": signed(w.wi),
              **{k: unsigned(w.wn) for k in ("E_u", "E_v", "B_u", "B_v")},
              "rsm": signed(M), "sh": unsigned(6)}
    for ch, mode in enumerate(modes):
        keys = ("d", "e") if mode == "linear" else ("a", "b", "c", "d", "e", "pu", "pv")
        fields.update({f"c{ch}_n{k}": signed(M) for k in keys})
        fields.update({f"c{ch}_f": signed(OPERAND), f"c{ch}_p0": signed(w.FI + 9),
                       f"c{ch}_a2": signed(w.FI + 9), f"c{ch}_sphi": unsigned(AMOUNT_BITS),
                       f"c{ch}_sd": unsigned(AMOUNT_BITS)})
    return fields


def narrow_left(w, M):
    """The narrow engine's left shift L: each product of M-bit mantissas is summed into FI as
    ``(p << L) >> amount``; L = FI - 2 M + 10 (at least 0) keeps every amount >= 0 for
    exponents up to 6 (a..e, |x| < 64) and 7 (Pu, Pv): see :func:`_channel_narrow`."""
    return max(w.FI - 2 * M + 10, 0)


def _uv_narrow(sc, w, v, M):
    """:func:`_start`, then (u, v) as M-bit mantissas with M - 1 fraction bits (in [0, 1] at
    a span's first pixel, eq 18-20): N = nu / 2**sh (|N| < 2, as |nu| <= |Omega| <
    2**(sh+1)) to M - 2 fraction bits, rounded, by two shifts, each a clock; times ``rs``
    (the setup's M - 1 fraction bits of 2**sh / Omega, rounded), rounded to M - 1 fraction
    bits. Each of the three saturates at 2**(M-1) - 1 (the one value that rounds past it).
    Off by at most 5 2**-M (docs/quadratic.md, "The narrow row engine")."""
    _start(sc, w, v)
    top = (1 << (M - 1)) - 1
    sat = lambda x: Mux(x > top, top, x)[:M].as_signed()
    coarse = sc.lets(**{f"{a}_hi": (v[f"n{a}"] << (M - 1)) >> Cat(Const(0, 3), v["sh"][3:])
                        for a in "uv"})
    fine = sc.lets(**{f"{a}_n2": (coarse[f"{a}_hi"] >> v["sh"][:3])[:M + 1].as_signed()
                      for a in "uv"})
    mant = sc.lets(**{f"{a}_m": sat((fine[f"{a}_n2"] + 1) >> 1) for a in "uv"})
    post = lambda p: sat((p + (1 << (M - 3))) >> (M - 2))
    return (sc.mul("u", mant["u_m"], v["rsm"], post=post),
            sc.mul("v", mant["v_m"], v["rsm"], post=post))


def _channel_narrow(sc, M, ch, mode, c, u, v):
    """One channel's products on M-bit mantissas (block floating point, issue 49): a..e
    share the channel's exponent e0 on the triangle, Pu and Pv its exponent e1; u, v have
    M - 1 fraction bits. t1 = d + a u + c v and t2 = e + b v (eq 17) are exact sums, then
    rounded to M bits at exponent e0 + 2 (|t1| < 2**(e0+1), with room for u and v's
    rounding); u t1 + v t2 and Pu u + Pv v go into FI through the multipliers' shifters by
    the setup's amounts (``sphi``: L - (FI - 2 M + 4 + e0), or L - (FI - 2 M + 2 + e0) for a
    linear channel, whose t1, t2 are d, e; ``sd``: L - (FI - 2 M + 2 + e1)), floored there.
    Returns (u t1 + v t2, Pu u + Pv v) at FI (None for a linear channel's second)."""
    if mode == "linear":
        t1, t2 = c["d"], c["e"]
    else:
        au, cv, bv = sc.mul(f"au{ch}", c["a"], u), sc.mul(f"cv{ch}", c["c"], v), \
            sc.mul(f"bv{ch}", c["b"], v)
        # Pu u, Pv v issued beside a u, c v, b v, as the wide engine's: their operands are
        # read early, so fewer copies of them are made for the rows in flight
        pu = sc.mul(f"pu{ch}", c["pu"], u, shifted=c["sd"])
        pv = sc.mul(f"pv{ch}", c["pv"], v, shifted=c["sd"])
        rnd = lambda x: ((x + (1 << M)) >> (M + 1))[:M].as_signed()
        acv = sc.let(f"acv{ch}", au + cv)
        t1 = sc.apply(f"t1_{ch}", lambda d, x: rnd((d << (M - 1)) + x), c["d"], acv)
        t2 = sc.apply(f"t2_{ch}", lambda e, x: rnd((e << (M - 1)) + x), c["e"], bv)
    ut = sc.mul(f"ut{ch}", u, t1, shifted=c["sphi"])
    vt = sc.mul(f"vt{ch}", v, t2, shifted=c["sphi"])
    uvt = sc.let(f"uvt{ch}", ut + vt)
    if mode == "linear":
        return uvt, None
    return uvt, sc.let(f"puv{ch}", pu + pv)


def _half(w, precision):
    """Half an LSB of a channel rounded to ``precision`` fraction bits, at FI."""
    return 1 << (w.FI - precision - 1)


def _outputs(sc, w, v, vals, end, halves=None, registered=True):
    """The row engine's outputs registered at ``end`` (or, not ``registered``, their values
    at ``end``, no logic in them); what the stepper would otherwise compute from the
    queue's RAM on its way into a register is computed here or before: the rounding half in
    each Phi (``halves``: a constant, or ``(register, function of it)``), and the span's
    tests (empty, one pixel, :func:`_start`)."""
    halves = halves or {}
    fns = {}
    for k, x in vals.items():
        half = halves.get(k, 0)
        if isinstance(half, tuple):
            reg, of = half
            fns[k] = ((lambda r, h, of=of: r + of(h)), x, reg)
        else:
            fns[k] = ((lambda r, h=half: r + h if h else r), x)
    fns.update({k: (lambda r: r, v[k]) for k in ("xs", "xe", "some", "one")})
    if not registered:
        assert all(sc.when(*regs) <= end for _, *regs in fns.values())
        late = {k: [sc.late(r, end) for r in regs] for k, (_, *regs) in fns.items()}
        sc.read(end, *(r for regs in late.values() for r in regs))
        return {k: Value.cast(fn(*late[k])) for k, (fn, *_) in fns.items()}
    out = {k: sc.apply(f"o_{k}", fn, *regs, after=end) for k, (fn, *regs) in fns.items()}
    sc.keep(*out.values())
    return out


def row_products(modes):
    """The row engine's products per row: u and v, then seven per quadratic channel and two
    per linear one."""
    return 2 + sum(2 if mode == "linear" else 7 for mode in modes)


def split_fields(data, like):
    """``data`` cut into the fields of ``like`` (a dict of values), in its order."""
    out, at = {}, 0
    for k, x in like.items():
        n = len(x)
        out[k] = data[at:at + n].as_signed() if x.shape().signed else data[at:at + n]
        at += n
    return out


def turns(m, sc, name, channels, first):
    """The channel of the next job of ``sc`` (a schedule with an interval), one-hot and as an
    index: a row's (or triangle's) jobs start with ``first`` and go on every ``ii`` clocks,
    one a channel. Returns ``(sel, index, under)``, ``under`` high between its first and its
    last job's start."""
    sel = [Signal(name=f"{name}_sel{c}", init=c == 0) for c in range(channels)]
    index = Signal(range(max(channels, 2)), name=f"{name}_index")
    under = ~sel[0]
    m.d.comb += sc.start.eq(sc.aligned & (under | first))
    with m.If(sc.start):
        m.d.sync += [sel[c].eq(sel[c - 1]) for c in range(channels)]
        m.d.sync += index.eq(Mux(sel[-1], 0, index + 1))
    return sel, index, under
