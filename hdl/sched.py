"""A static schedule: one job's operations (a triangle's setup, a row's start values) at fixed
clock offsets from the job's start, on a few shared multipliers.

Each operation is placed, in program order, at the first offset where its operands are ready
(and, for a product, where a multiplier is free). Offsets are a one-hot delay line of the
start pulse, so several jobs may be in flight. With ``ii``, jobs start only on every ``ii``-th
clock (``aligned``, a free-running count), the multipliers are reserved modulo ``ii``, and a
register read more than ``ii`` offsets after it was written is read from a copy (``late``),
so the next job never overwrites a value before its last read (:meth:`Schedule.check`);
with ``ram_copies``, a value of more than 4 bits that would take two copies or more is read
instead from a 16-deep LUT RAM written as it lands, at the job's slot (a RAM's address, 4
bits, always from registers: :meth:`Schedule._ram_copy`);
a division takes ``ceil((q_bits + 1) / ii)`` dividers in turn. The copies of one
multiplier's products share registers where their lives (write to last read) do not
overlap (:meth:`Schedule._pool`): a copy is the product's sum register, so a shared one needs
no multiplexer, only its write enables ORed.
Everything advances with one enable, so a stalled schedule holds every value. The schedule
sees which registers a value reads, and rebuilds it with late copies, through its record of
operands (:mod:`hdl.term`): its registers are terms, and so is every value built from them.

A product: operands are registered (the DSP's input registers), the four 18 x 18 partial
products of two 35-bit signed operands registered (one MULT18X18D each), their sum registered;
the middle two summed, then added to the outer two (which do not overlap), each registered;
the result is written at ``issue + MUL_LAT`` (one more with ``mux_groups``) and readable one
clock later.
"""
from amaranth.hdl import Cat, Const, Mux, Signal, Value, signed, unsigned
from amaranth.lib.memory import Memory

from .bram import table_slice
from .dsp import mult18, mult_narrow
from .term import Term, term

__all__ = ["Schedule", "OPERAND", "MUL_LAT"]

OPERAND = 35          # signed operand bits: an 18-bit signed top slice, a 17-bit unsigned low one
NARROW = 18           # a narrow multiplier's signed operand bits: one MULT18X18D, two clocks less
CAPTURE_SHARE = 256   # enables per copy of a capture enable (``Schedule.inputs``)
MUL_LAT = 4           # issue (operands muxed) -> operand regs -> partial products -> two adds


def _deps(value):
    return term(value).leaves()


def _reg(x):
    """A register, given as itself or as its term."""
    return x.reg if isinstance(x, Term) else x


class _Regs:
    """Registers to values, by identity (Amaranth values are not hashable)."""

    def __init__(self):
        self._d = {}

    def __setitem__(self, reg, value):
        reg = _reg(reg)
        self._d[id(reg)] = (reg, value)

    def __getitem__(self, reg):
        return self._d[id(_reg(reg))][1]

    def get(self, reg, default=None):
        hit = self._d.get(id(_reg(reg)))
        return default if hit is None else hit[1]

    def __contains__(self, reg):
        reg = _reg(reg)
        return reg is not None and id(reg) in self._d

    def items(self):
        return list(self._d.values())

    def setdefault(self, reg, value):
        if reg not in self:
            self[reg] = value
        return self[reg]


class Schedule:
    def __init__(self, m, name, en, ii=None, mults=1, shift=None, mux_groups=None,
                 platform=None, narrow=0, host=None, share=True, narrow_bits=NARROW,
                 ram_copies=False):
        """``shift = (amount, left)``: products asked for ``shifted`` come out as
        ``(a * b << left) >> amount``, two clocks later (one two-stage shifter per multiplier
        that has such products; ``amount`` must be steady over the job). ``platform``: the
        multipliers' blocks are instantiated with their registers on ECP5 (:mod:`hdl.dsp`).
        ``narrow``: multipliers of one 18 x 18 block each, for the products whose operands
        fit ``narrow_bits`` signed bits (all of those, when there are any narrow ones): 18, one
        MULT18X18D two clocks less than a wide one, or 19-24 (:func:`hdl.dsp.mult_narrow`: the
        block and its low bits' partial products in logic, as many clocks as a wide one).
        ``host``: ``(schedule, index)``, a schedule whose multiplier ``index`` is this one's
        first: this one's operands join that multiplier's multiplexer, and its products come
        from that sum register. Finish this one first; the caller keeps their products apart
        in time (this one's jobs run only while the host issues none). ``share=False``: each
        product copy keeps a register of its own (:meth:`_pool`). ``ram_copies`` (with
        ``ii``): values read two copies or more after their write come from LUT RAM
        (:meth:`_ram_copy`), not from chains of registers."""
        self.m, self.name, self.en, self.ii, self.shift = m, name, en, ii, shift
        self.platform = platform
        # with many operations per multiplier: the operand multiplexer in two registered
        # levels (groups of ``mux_groups`` operations, then the groups), one clock more
        self.mux_groups, self.lat = mux_groups, MUL_LAT + (1 if mux_groups else 0)
        self.start = Signal(name=f"{name}_start")      # the caller drives it: a job starts
        self.phase = [self.start]
        self.ready = _Regs()                             # register -> first offset it is valid
        self.written = _Regs()                           # register -> offset written
        self.reads = _Regs()                             # register -> last offset read
        self.mults = [[] for _ in range(mults)]          # per multiplier: (offset, a, b)
        self.narrow = [[] for _ in range(narrow)]        # the same, narrow_bits square
        self.nbits = narrow_bits
        self.fits = 0                                    # products a narrow one can take
        self.length = 1                                  # offsets used
        self.outputs = _Regs()                           # read by the next stage, not here
        self.pooled = []                                 # (register, value, offset): _pool
        self.host, self.guests = host, {}                # guests: index -> operand terms
        self.share = share
        self.ram_copies, self._rams = ram_copies and ii is not None, {}

    def at(self, k):
        """The phase bit of offset ``k``: high while the job that started ``k`` clocks ago is
        at offset ``k``."""
        while len(self.phase) <= k:
            r = Signal(name=f"{self.name}_ph{len(self.phase)}")
            with self.m.If(self.en):
                self.m.d.sync += r.eq(self.phase[-1])
            self.phase.append(r)
        return self.phase[k]

    def busy(self):
        """High while a job is at an offset past its first (1 .. length - 1), from a register:
        the OR of the phase bits one offset earlier, captured with them (exact, since they
        shift with ``en``). Call after :meth:`finish`."""
        r = Signal(name=f"{self.name}_busy")
        with self.m.If(self.en):
            self.m.d.sync += r.eq(_or_tree([self.at(k) for k in range(self.length - 1)]))
        return r

    def when(self, *values, after=0):
        k = after
        for v in values:
            for s in _deps(v):
                k = max(k, self.ready.get(s, 0))
        return k

    def read(self, k, *values):
        for v in values:
            for s in _deps(v):
                if s in self.ready:
                    self.reads[s] = max(self.reads.get(s, 0), k)

    def _write(self, name, value, k, shape=None, en=None, pool=False):
        value = Value.cast(value)
        reg = Signal(shape or value.shape(), name=f"{self.name}_{name}", reset_less=True)
        if pool:                                        # a register of its pool's: _pool
            self.pooled.append((reg, value, k))
        else:
            with self.m.If(self.en & self.at(k) if en is None else en):
                self.m.d.sync += reg.eq(value)
        self.ready[reg], self.written[reg] = k + 1, k
        self.length = max(self.length, k + 1)
        return self._leaf(reg)

    def _leaf(self, reg):
        """The one term of a register of this schedule's (so that copies compare by ``is``)."""
        if not hasattr(self, "_leaves"):
            self._leaves = _Regs()
        return self._leaves.setdefault(reg, Term.leaf(reg))

    def input(self, name, value, shape=None, en=None):
        """``value`` (stable while ``start`` is high) captured at the job's start; or, with
        ``en``, whenever ``en`` is high: a register, high at every start and never while an
        earlier job may still read the input (the unit's ready, or ``aligned``), so that the
        capture enables wait on no handshake. ``en`` may be one of several copies
        (:meth:`aligned_copy`), each driving a share of the enables."""
        return self._write(name, value, 0, shape, en)

    def inputs(self, values, copy=None, share=CAPTURE_SHARE):
        """:meth:`input` of each of ``values`` (a dict); with ``copy`` (a function that makes
        a copy of a capture enable, such as :meth:`aligned_copy`), each copy captures about
        ``share`` bits. Returns the registers."""
        out, en, bits = {}, None, share
        for name, value in values.items():
            if copy is not None and bits >= share:
                en, bits = copy(), 0
            out[name] = self.input(name, value, en=en)
            bits += len(out[name])
        return out

    def let(self, name, value, shape=None, after=0):
        """A register of ``value``, written as soon as its operands are ready."""
        k = self.when(value, after=after)
        value = self.late_at(value, k)
        self.read(k, value)
        return self._write(name, value, k, shape)

    def apply(self, name, fn, *regs, after=0):
        """``let(name, fn(*regs))``, each register read from a copy still valid then."""
        k = self.when(*regs, after=after)
        return self.let(name, fn(*(self.late(r, k) for r in regs)), after=k)

    def lets(self, after=0, **values):
        """Several registers written at one offset (the latest operand's)."""
        k = self.when(*values.values(), after=after)
        values = {n: self.late_at(v, k) for n, v in values.items()}
        self.read(k, *values.values())
        return {n: self._write(n, v, k) for n, v in values.items()}

    def mul(self, name, a, b, post=None, shape=None, after=0, shifted=False):
        """``post(a * b)`` in a register (``a``, ``b``: signed, at most OPERAND bits).
        ``shifted``: True, the product shifted by the schedule's ``shift``; or a register, its
        own amount with the schedule's ``left`` (``(a * b << left) >> amount``)."""
        # an operand with logic in it (a negation, a sum) is registered first: the operand
        # multiplexer's inputs are wiring only, so no carry chain runs into it
        a, b = (term(x) if _wiring(x) else self.let(f"{name}_{s}", x)
                for x, s in ((a, "a"), (b, "b")))
        natural = len(a) + len(b)
        for x in (a, b):
            if len(x) + (0 if x.shape().signed else 1) > OPERAND:
                raise ValueError(f"{self.name}.{name}: operand of {len(x)} bits")
        k = self.when(a, b, after=after)
        fits = (shifted is not True
                and all(len(x) + (0 if x.shape().signed else 1) <= self.nbits for x in (a, b)))
        lat = self.lat - 2 if fits and self.narrow and self.nbits == NARROW else self.lat
        if shifted is not False:          # its amount is registered a clock before the sum
            k = max(k, self.when(self.shift[0] if shifted is True else shifted) + 1 - lat)
        self.fits += fits
        units = ([(True, i, u) for i, u in enumerate(self.narrow)] if fits and self.narrow
                 else [(False, i, u) for i, u in enumerate(self.mults)])
        while True:
            for narrow, idx, unit in units:
                used = [o for o, _, _ in unit]
                if self.ii is None:
                    free = k not in used
                else:
                    free = k % self.ii not in {o % self.ii for o in used}
                if free:
                    unit.append((k, a, b))
                    break
            else:
                k += 1
                if self.ii is not None and k > self.length + self.ii:
                    raise ValueError(f"{self.name}: more products than {len(units)} "
                                     f"multipliers take every {self.ii} clocks")
                continue
            break
        if self.ii is not None:
            a, b = self.late_at(a, k), self.late_at(b, k)
            unit[-1] = (k, a, b)
        self.read(k, a, b)
        total = self._total(idx, narrow)
        if shifted is not False:          # the amount is registered as the product's sum is
            amount = self.late(self.shift[0] if shifted is True else shifted, k + lat - 1)
            total = self._shifted(idx, amount, k + lat, narrow)
            self.read(k + lat - 1, amount)
            lat += 2
            natural = len(total)                    # the product shifted left, then right
        self.length = max(self.length, k + lat + 1)
        if post:
            return self._write(name, post(total), k + lat, shape, pool=True)
        return self._write(name, total, k + lat, shape or signed(natural), pool=True)

    def _shifted(self, idx, amount, at, narrow=False):
        """Multiplier ``idx``'s shifter, shifting at offset ``at`` by ``amount``, read a clock
        earlier into the shifter's own register (with ``ii``, its products may read it from
        different copies: the phase picks, see finish)."""
        if not hasattr(self, "_shifters"):
            self._shifters = {}
        key = (narrow, idx)
        if key not in self._shifters:
            left = self.shift[1]
            total = self._total(idx, narrow)
            n = f"{self.name}_{'n' if narrow else 'm'}{idx}"
            coarse = Signal(signed(len(total) + left), name=f"{n}_coarse", reset_less=True)
            reg = Signal(signed(len(total) + left), name=f"{n}_shifted", reset_less=True)
            low = Signal(3, name=f"{n}_low", reset_less=True)
            amt = Signal(len(amount), name=f"{n}_amount", reset_less=True)
            self._shifters[key] = [], (total << left, amt, coarse, low, reg)
        self._shifters[key][0].append((at, amount))
        return self._shifters[key][1][4]

    def _build_shifters(self):
        """The shifters: the amount registered (no LUT RAM copy or multiplexer of copies on
        the shifter's path), then two stages, by its high bits, then its low ones."""
        for reads, (value, amt, coarse, low, reg) in getattr(self, "_shifters", {}).values():
            copies = []
            for at, amount in reads:
                if not any(amount is c for _, c in copies):
                    copies.append((at, amount))
            if len(copies) == 1:
                amount = copies[0][1]
            else:                         # one copy per read offset: a one-hot AND-OR
                amount = _or_tree([Mux(_or_tree([self.at(at - 1) for at, c in reads
                                                 if c is amount]), amount, 0)
                                   for _, amount in copies])
            with self.m.If(self.en):
                self.m.d.sync += [amt.eq(amount),
                                  coarse.eq(value >> Cat(Const(0, 3), amt[3:])),
                                  low.eq(amt[:3]), reg.eq(coarse >> low)]

    def _total(self, idx, narrow=False):
        """A multiplier's product: a register (wide), or the block's output (narrow)."""
        if self.host and not narrow and idx == 0:
            return self.host[0]._total(self.host[1])
        if not hasattr(self, "_totals"):
            self._totals = [Signal(signed(2 * OPERAND), name=f"{self.name}_m{n}_sum",
                                   reset_less=True) for n in range(len(self.mults))]
            self._ntotals = [Signal(signed(2 * self.nbits), name=f"{self.name}_n{n}_p")
                             for n in range(len(self.narrow))]
        return (self._ntotals if narrow else self._totals)[idx]

    def rom(self, name, lut, addr):
        """``lut[addr]``: a synchronous read, then the RAM's output register (``hdl.bram``:
        the block's own on ECP5, in 18-bit slices), so its clock to output is never in series
        with logic; a register of the schedule's, written a clock after the address."""
        k = self.when(addr)
        addr = self.late_at(addr, k)
        self.read(k, addr)
        width = lut.fmt.width
        raw = [int(v) & ((1 << width) - 1) for v in lut.contents]
        outs = [table_slice(self.m, f"{self.name}_{name}_rom{lo // 18}", len(raw),
                            min(18, width - lo), [(v >> lo) & ((1 << min(18, width - lo)) - 1)
                                                  for v in raw],
                            [addr], self.en & self.at(k), self.platform,
                            out_en=self.en & self.at(k + 1))[0]
                for lo in range(0, width, 18)]
        reg = Signal(lut.fmt.shape, name=f"{self.name}_{name}")
        self.m.d.comb += reg.eq(Cat(*outs))
        self.ready[reg], self.written[reg] = k + 2, k + 1
        self.length = max(self.length, k + 2)
        return self._leaf(reg)

    def divide(self, name, num, den, q_bits):
        """Unsigned restoring division, one quotient bit per clock: ``(q, r)`` registers with
        ``num = q den + r``, ``0 <= r < den``, for ``num < den 2**q_bits`` (the caller's).
        With ``ii``: ``ceil((q_bits + 1) / ii)`` dividers, each job taking the next in turn,
        each with its own copy of ``den``; with more than one, the finished divider's result
        is copied to a register of its own."""
        k = self.when(num, den)
        n = f"{self.name}_{name}"
        if self.ii is None:
            self.read(k + q_bits, den)
            q, rem = self._divider(n, num, den, self.at(k), self.at(k + q_bits), q_bits)
            done = k + q_bits
            self.ready[q] = self.ready[rem] = done + 1
            self.written[q] = self.written[rem] = done
            self.length = max(self.length, done + 1)
            return self._leaf(q), self._leaf(rem)[:len(den)]
        num, den = self.late_at(num, k), self.late_at(den, k)
        self.read(k, num, den)
        copies = -(-(q_bits + 1) // self.ii)
        if copies == 1:                 # valid until the next job loads it, ii clocks on
            q, rem = self._divider(n, num, den, self.at(k), self.at(k + q_bits), q_bits, True)
            self.ready[q] = self.ready[rem] = k + q_bits + 1
            self.written[q] = self.written[rem] = k
            self.length = max(self.length, k + q_bits + 1)
            return self._leaf(q), self._leaf(rem)[:len(den)]
        # one-hot turns: the divider the next job loads, the one that finishes next
        turn = [Signal(name=f"{n}_turn{c}", init=c == 0) for c in range(copies)]
        fin = [Signal(name=f"{n}_fin{c}", init=c == 0) for c in range(copies)]
        for ring, at in ((turn, self.at(k)), (fin, self.at(k + q_bits + 1))):
            with self.m.If(self.en & at):
                self.m.d.sync += [ring[c].eq(ring[c - 1]) for c in range(copies)]
        outs = [self._divider(f"{n}{c}", num, den, self.at(k) & turn[c],
                              self.at(k + q_bits) & fin[c], q_bits, True)
                for c in range(copies)]
        done = k + q_bits + 1
        q, rem = (self._write(f"{name}_{x}", _or_tree([Mux(fin[c], o[j], 0)
                                                        for c, o in enumerate(outs)]), done)
                  for j, x in enumerate(("qo", "ro")))
        return q, rem[:len(den)]

    def _divider(self, n, num, den, load, stop, q_bits, own_den=False):
        """One divider: loaded at ``load``, a quotient bit a clock until ``stop``."""
        num, den = Value.cast(num), Value.cast(den)        # hardware: no term needed
        rem = Signal(len(den) + 1, name=f"{n}_rem", reset_less=True)
        low = Signal(q_bits, name=f"{n}_low", reset_less=True)
        q = Signal(q_bits, name=f"{n}_q", reset_less=True)
        run = Signal(name=f"{n}_run")      # offsets k+1 .. k+q_bits, a register
        if own_den:
            held = Signal.like(den, name=f"{n}_den", reset_less=True)
            with self.m.If(self.en & load):
                self.m.d.sync += held.eq(den)
            den = held
        with self.m.If(self.en):
            self.m.d.sync += run.eq(load | (run & ~stop))
        with self.m.If(self.en):
            with self.m.If(load):
                self.m.d.sync += [rem.eq(num >> q_bits), low.eq(num[:q_bits]), q.eq(0)]
            with self.m.Elif(run):
                trial = Cat(low[-1], rem)                    # 2 rem + the next bit
                ok = trial >= den
                self.m.d.sync += [rem.eq(Mux(ok, trial - den, trial)), low.eq(low << 1),
                                  q.eq(Cat(ok, q))]
        return q, rem

    def late(self, reg, k):
        """``reg`` (a term), or a copy of it that is still valid at offset ``k`` (with
        ``ii``)."""
        reg = term(reg)
        if self.ii is None or reg not in self.written or k <= self.written[reg] + self.ii:
            return reg
        c = max(k - self.ii, self.ready[reg])
        if self.ram_copies and c > self.written[reg] + self.ii and len(reg) > 4:
            return self._ram_copy(reg, k)
        if not hasattr(self, "_late"):
            self._late = _Regs()
        copies = self._late.setdefault(reg, {})
        if c not in copies:
            src = self.late(reg, c)
            self.read(c, src)
            copies[c] = self._write(f"{reg.reg.name[len(self.name) + 1:]}_at{c}", src, c)
        return copies[c]

    def _ram_copy(self, reg, k):
        """``reg`` as the job reading at offset ``k`` wrote it: a LUT RAM of 16 words (a job's
        slot, 4 bits, counts its starts; at most 16 jobs in flight, :meth:`finish`) written
        at the offset ``reg`` is first valid, read at ``k`` (asynchronously, as a register
        would be). One per register and read offset, each a read port."""
        key = (id(reg.reg), k)
        if key not in self._rams:
            if not hasattr(self, "_slot"):
                ptr = Signal(4, name=f"{self.name}_rptr")
                with self.m.If(self.en & self.start):
                    self.m.d.sync += ptr.eq(ptr + 1)
                self._slot = self.input("rslot", ptr)
            w = self.ready[reg]
            mem = Memory(shape=reg.shape(), depth=16, init=[])
            name = f"{reg.reg.name}_ram{k}"
            self.m.submodules[name] = mem
            wr, rd = mem.write_port(), mem.read_port(domain="comb")
            at_w, at_k = self.late(self._slot, w), self.late(self._slot, k)
            self.read(w, reg, at_w)
            self.read(k, at_k)
            out = Signal(reg.shape(), name=name)
            self.m.d.comb += [wr.addr.eq(at_w), wr.data.eq(reg), wr.en.eq(self.en & self.at(w)),
                              rd.addr.eq(at_k), out.eq(rd.data)]
            self._rams[key] = Term.leaf(out)
        return self._rams[key]

    def late_at(self, value, k):
        """``value`` with each register replaced by its copy still valid at offset ``k``."""
        if self.ii is None:
            return value
        return term(value).map(lambda reg: self.late(reg, k))

    @property
    def aligned(self):
        """With ``ii``: a job may start: ``ii`` clocks after the last start, or any time when
        no job is in flight."""
        if not hasattr(self, "_aligned"):
            self._aligned = [Signal(name=f"{self.name}_aligned", init=1)]
        return self._aligned[0]

    def aligned_copy(self):
        """A copy of ``aligned``, to drive a share of the enables of the inputs it captures.
        One flop cannot drive a thousand enables in a clock (on ECP5 the routing alone takes
        7-8 ns); copies can, but Yosys merges flops with equal inputs, so each copy is a state
        machine of its own, with its own slot count: equal in value, never in structure."""
        self.aligned                                        # the first is the start's
        self._aligned.append(Signal(name=f"{self.name}_aligned{len(self._aligned)}", init=1))
        return self._aligned[-1]

    def _align(self):
        """``aligned``, a register: the next clock's slot count is 0, or no job will be in
        flight then, so that nothing lies between it and the start it allows."""
        # no job in flight next clock: none starts now, none is at 1 .. length - 2 (from a
        # register: the OR of the phase bits an offset earlier, as in ``busy``), so that each
        # copy of ``aligned`` is two LUTs from registers
        inflight = Signal(name=f"{self.name}_inflight")
        with self.m.If(self.en):
            self.m.d.sync += inflight.eq(_or_tree([self.at(k) for k in range(self.length - 2)]))
        idle = ~self.start & ~inflight
        for n, aligned in enumerate(self._aligned):
            count = Signal(range(self.ii), name=f"{self.name}_slot{n}")
            nxt = Mux(self.start, 1 % self.ii, Mux(count == self.ii - 1, 0, count + 1))
            with self.m.If(self.en):
                self.m.d.sync += [count.eq(nxt), aligned.eq(~nxt.any() | idle)]  # no "== 0"

    @property
    def last_issue(self):
        """The last offset at which a job issues a product (-1: none)."""
        return max((k for unit in self.mults + self.narrow for k, _, _ in unit), default=-1)

    def keep(self, *values):
        """The registers in ``values`` are read by the next stage, after the job: never
        shared (call before :meth:`finish`)."""
        for v in values:
            for reg in _deps(v):
                self.outputs[reg] = True

    def finish(self):
        if self._rams and -(-self.length // self.ii) > 16:
            raise ValueError(f"{self.name}: more than 16 jobs in flight for its LUT RAM copies")
        if self.ii is not None:
            self._align()
        self._multipliers()
        self._build_shifters()
        self._pool()

    def _pool(self):
        """The product copies' registers: those of one value (the same multiplier's sum, the
        same ``post``) share a physical register where their lives do not overlap. A copy
        written at offset w and last read at r holds (w, r]; with ``ii``, at those offsets
        modulo ``ii`` (jobs in flight start a multiple of ``ii`` apart, and no register lives
        longer than ``ii``: :meth:`check`). First fit in write order: without ``ii`` it is
        left-edge allocation, the fewest registers for intervals. A copy that is never read
        here, or is an output, keeps its own."""
        pools = {}
        for reg, value, w in self.pooled:
            r = None if reg in self.outputs or not self.share else self.reads.get(reg)
            pools.setdefault(_key(value), (value, []))[1].append((w, r, reg))
        self.shared = 0                                  # registers saved (for reports)
        for value, regs in pools.values():
            phys = []                                    # [offsets held, members]
            for w, r, reg in sorted(regs, key=lambda x: x[0]):
                live = None if r is None else set(range(w + 1, r + 1))
                if live is not None and self.ii is not None:
                    live = {k % self.ii for k in live}
                slot = next((p for p in phys if live is not None and p[0] is not None
                             and not (live & p[0]) and (self.ii is not None
                                                        or max(p[0]) <= w)), None)
                if slot is None:
                    slot = [set(), []]
                    phys.append(slot)
                slot[0] = None if live is None else slot[0] | live
                slot[1].append((w, reg))
            self.shared += len(regs) - len(phys)
            for members in (p[1] for p in phys):
                width = max(len(reg) for _, reg in members)
                p = Signal(width, name=f"{members[0][1].name}_p", reset_less=True)
                with self.m.If(self.en & _or_tree([self.at(w) for w, _ in members])):
                    self.m.d.sync += p.eq(value[:width])
                self.m.d.comb += [reg.eq(p) for _, reg in members]

    def _multipliers(self):
        """The multipliers: each operand a one-hot AND-OR over its distinct operands, registered;
        four partial products registered; the middle two summed beside the outer two
        (concatenated: they do not overlap), then one addition. A narrow one: one block, its
        operands and product registered in it."""
        for narrow, units in ((False, self.mults), (True, self.narrow)):
            bits = self.nbits if narrow else OPERAND
            for idx, unit in enumerate(units):
                guests = [] if narrow else self.guests.get(idx, [])
                if not unit and not guests:
                    continue
                n = f"{self.name}_{'n' if narrow else 'm'}{idx}"
                opa, opb = _operands(self, n, unit, bits)
                if self.host and not narrow and idx == 0:      # the host's multiplier
                    host, at = self.host
                    host.guests.setdefault(at, []).append((opa, opb))
                    continue
                for ga, gb in guests:
                    opa, opb = opa + ga, opb + gb
                if self.mux_groups:
                    opa, opb = (self._grouped(f"{n}_{x}", terms, bits)
                                for x, terms in (("a", opa), ("b", opb)))
                opa, opb = _or_tree(opa), _or_tree(opb)
                ra = Signal(signed(bits), name=f"{n}_a")         # registered in the blocks
                rb = Signal(signed(bits), name=f"{n}_b")
                self.m.d.comb += [ra.eq(opa), rb.eq(opb)]
                if narrow:
                    if self.nbits == NARROW:
                        p = mult18(self.m, f"{n}_x", ra, rb, self.en, self.platform)
                    else:
                        p = mult_narrow(self.m, f"{n}_x", ra, rb, self.en, self.platform,
                                        self.nbits)
                    self.m.d.comb += self._total(idx, True).eq(p)
                    continue
                lo = OPERAND - 18
                xs = {"h": (ra[lo:].as_signed(), rb[lo:].as_signed()),
                      "l": (ra[:lo], rb[:lo])}
                part = {pa + pb: mult18(self.m, f"{n}_{pa}{pb}", xs[pa][0], xs[pb][1], self.en,
                                        self.platform) for pa in "hl" for pb in "hl"}
                mid = Signal(signed(38), name=f"{n}_mid", reset_less=True)
                outer = Signal(signed(2 * OPERAND), name=f"{n}_outer", reset_less=True)
                with self.m.If(self.en):
                    self.m.d.sync += [mid.eq(part["hl"] + part["lh"]),
                                      outer.eq(Cat(part["ll"][:2 * lo], part["hh"]))]
                    self.m.d.sync += self._total(idx).eq(outer + (mid << lo))

    def _grouped(self, name, terms, bits=OPERAND):
        """The first level of a two-level operand multiplexer: each group's OR registered."""
        out = []
        for g, at in enumerate(range(0, len(terms), self.mux_groups)):
            reg = Signal(signed(bits), name=f"{name}_g{g}", reset_less=True)
            with self.m.If(self.en):
                self.m.d.sync += reg.eq(_or_tree(terms[at:at + self.mux_groups]))
            out.append(reg)
        return out

    def check(self):
        """With ``ii``: every register's last read comes before the next job's write."""
        if self.ii is None:
            return
        for reg, w in self.written.items():
            r = self.reads.get(reg, w)
            if r > w + self.ii and reg not in self.outputs:
                raise AssertionError(f"{reg.name}: written at {w}, read at {r}, ii {self.ii}")


def _wiring(value):
    """``value`` is registers and constants, sliced, concatenated, cast or shifted by
    constants: no logic (its term says)."""
    return term(value).wiring


def _key(value):
    """Structural identity of an operand (names may repeat; the signals themselves do not)."""
    return repr(value), tuple(sorted(id(s) for s in _deps(value)))


def _operands(sc, n, unit, bits=OPERAND):
    """Each side's multiplexer terms: one per distinct operand, selected by the OR of the
    phase bits of the products that use it. A product's operands are swapped where that lets
    a side reuse an operand it already has (a b = b a): fewer, narrower AND-OR trees."""
    sides = ({}, {})                                       # key -> [value, phase bits]
    for k, a, b in unit:
        ka, kb = _key(a), _key(b)
        if not (ka in sides[0] or kb in sides[1]) and (kb in sides[0] or ka in sides[1]):
            (a, ka), (b, kb) = (b, kb), (a, ka)
        for side, key, value in ((0, ka, a), (1, kb, b)):
            sides[side].setdefault(key, [value, []])[1].append(k)
    terms = ([], [])
    for side, name in enumerate("ab"):
        for j, (value, ks) in enumerate(sides[side].values()):
            sig = Signal(signed(bits), name=f"{n}_{name}{j}")
            sc.m.d.comb += sig.eq(value)
            if min(ks) > 0:     # the select a register: the OR of the phase bits a clock early
                sel = Signal(name=f"{n}_{name}{j}_sel")
                with sc.m.If(sc.en):
                    sc.m.d.sync += sel.eq(_or_tree([sc.at(k - 1) for k in ks]))
            else:
                sel = _or_tree([sc.at(k) for k in ks])
            terms[side].append(Mux(sel, sig, 0))
    return terms


def _or_tree(terms):
    while len(terms) > 1:
        terms = [terms[i] | terms[i + 1] if i + 1 < len(terms) else terms[i]
                 for i in range(0, len(terms), 2)]
    return terms[0]
