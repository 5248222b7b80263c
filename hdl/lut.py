"""The one LUT builder: contents from a numpy function, with the error they carry.

Every table in the project (trigonometric, reciprocal square root, ...) comes from
:func:`build_lut`, so its rounding and its address quantisation are derived in one place and
the tests can state their bounds from ``Lut.max_error``.
"""
from dataclasses import dataclass
import functools
import operator

import numpy as np
from amaranth.hdl import Cat, Mux, Value

from .bram import table_slice
from .fixed import Fixed

__all__ = ["Lut", "build_lut", "blank_lut", "rom", "read_roms", "WriteBus"]


@dataclass(frozen=True, eq=False)
class Lut:
    """Table contents (raw integers of ``fmt``) and what they cost in accuracy.

    ``max_error`` is the largest ``|fn(x) - entry|`` in LSBs of ``fmt`` over every input ``x``
    that an entry stands for: rounding alone (at most 0.5) when addresses are exact inputs,
    rounding plus the function's change across a bin when an address covers an interval.
    """
    contents: np.ndarray
    fmt: Fixed
    max_error: float
    domain: tuple | None
    errors: np.ndarray        # each entry's own largest error, over its bin
    edges: np.ndarray | None  # bin edges, for interval addressing

    def error_over(self, lo, hi):
        """The largest entry error over the bins that inputs in ``[lo, hi]`` address
        (vectorised; inputs past the table's ends address its end bins)."""
        if self.edges is None:
            a_lo = np.clip(np.floor(lo), 0, self.depth - 1).astype(np.int64)
            a_hi = np.clip(np.ceil(hi), 0, self.depth - 1).astype(np.int64)
        else:
            a_lo = np.clip(np.searchsorted(self.edges, lo, "right") - 1, 0, self.depth - 1)
            a_hi = np.clip(np.searchsorted(self.edges, hi, "right") - 1, 0, self.depth - 1)
        # a wide range (more than 64 bins) takes the table's overall largest error
        wide = (a_hi - a_lo) > 64
        a_hi = np.where(wide, a_lo, a_hi)
        span = int((a_hi - a_lo).max()) if np.size(a_lo) else 0
        idx = np.minimum(a_lo[..., None] + np.arange(span + 1), a_hi[..., None])
        return np.where(wide, self.max_error, self.errors[idx].max(axis=-1))

    @property
    def depth(self):
        return len(self.contents)

    def address_of(self, x):
        """The address a real input falls in (numpy), for models that mimic the addressing."""
        if self.domain is None:
            return np.asarray(x, dtype=np.int64)
        lo, hi = self.domain
        a = np.floor((np.asarray(x, dtype=float) - lo) * self.depth / (hi - lo))
        return np.clip(a, 0, self.depth - 1).astype(np.int64)


def build_lut(fn, addr_bits, fmt, *, domain=None, depth=None, edges=None, oversample=65):
    """Tabulate ``fn`` (a vectorised numpy function) into ``2**addr_bits`` entries of ``fmt``.

    ``fn`` returns values in the format's unit (the builder scales by ``2**fmt.frac_bits``).
    With ``domain=None`` the address is the input itself (``x = a``). With ``domain=(lo, hi)``
    address ``a`` stands for ``x`` in ``[lo + a*step, lo + (a+1)*step)`` and holds ``fn`` at the
    bin's centre; the error is then measured on ``oversample`` points across each bin.
    ``depth`` overrides ``2**addr_bits`` (a quarter-wave table with both end points, say).
    ``edges`` (``depth + 1`` increasing values) gives each address its own bin
    ``[edges[a], edges[a+1])``, for non-uniform addressing (``float_bins``).
    Entries outside ``fmt`` are an error, never saturated.
    """
    addr_bits = operator.index(addr_bits)
    if not 1 <= addr_bits <= 20:
        raise ValueError(f"LUT address width must be 1..20 bits, not {addr_bits}")
    if not isinstance(fmt, Fixed):
        raise TypeError(f"LUT output format must be a Fixed, not {fmt!r}")
    depth = 1 << addr_bits if depth is None else operator.index(depth)
    if not 1 <= depth <= 1 << addr_bits:
        raise ValueError(f"LUT depth {depth} does not fit {addr_bits} address bits")
    scale = 2.0 ** fmt.frac_bits
    if edges is not None:
        edges = np.asarray(edges, float)
        depth = len(edges) - 1
        if depth > 1 << addr_bits or not np.all(np.diff(edges) > 0):
            raise ValueError("LUT edges must increase and fit the address width")
    a = np.arange(depth)
    if edges is not None:
        x_entry = (edges[:-1] + edges[1:]) / 2
        x_check = edges[:-1, None] + np.linspace(0.0, 1.0, oversample)[None, :] \
            * np.diff(edges)[:, None]
        lo, hi = edges[0], edges[-1]
    elif domain is None:
        x_entry = a.astype(float)
        x_check = x_entry[:, None]
    else:
        lo, hi = map(float, domain)
        if not hi > lo:
            raise ValueError(f"LUT domain must be increasing, not {domain!r}")
        step = (hi - lo) / depth
        x_entry = lo + (a + 0.5) * step
        x_check = lo + (a[:, None] + np.linspace(0.0, 1.0, oversample)[None, :]) * step
    exact = np.asarray(fn(x_entry), dtype=float) * scale
    if not np.all(np.isfinite(exact)):
        raise ValueError("LUT function returned a non-finite value")
    contents = np.rint(exact).astype(np.int64)
    if contents.min() < fmt.min or contents.max() > fmt.max:
        raise ValueError(f"LUT entries {contents.min()}..{contents.max()} do not fit "
                         f"{'s' if fmt.signed else 'u'}{fmt.width}")
    err = np.abs(np.asarray(fn(x_check), dtype=float) * scale - contents[:, None]).max(axis=1)
    if edges is None and domain is not None:
        edges = lo + np.arange(depth + 1) * step
    return Lut(contents, fmt, float(err.max()),
               None if domain is None and edges is None else (lo, hi), err, edges)


def blank_lut(depth, fmt):
    """A table's shape alone (``depth`` entries of ``fmt``, all zero): a RAM that the host
    loads (the on-chip texture), whose contents are data."""
    zero = np.zeros(depth, np.int64)
    return Lut(zero, fmt, 0.0, None, zero.astype(float), None)


class WriteBus:
    """A host's writes into one loaded table: ``en`` (this table's), ``addr``, ``data``
    (the entry's raw bits at the bottom)."""

    def __init__(self, en, addr, data):
        self.en, self.addr, self.data = en, Value.cast(addr), Value.cast(data)


class RomRead:
    """A table read, to be placed in a :meth:`hdl.unit.Pipeline.stage`: the stage's register
    is the block RAM's own read register (see :func:`read_roms`)."""

    def __init__(self, lut, addr, name, load=None):
        self.lut, self.addr, self.name, self.load = lut, Value.cast(addr), name, load


def rom(lut, addr, name, load=None):
    """A read of ``lut`` at ``addr``, for ``p.stage(v, out=rom(...))``, then a plain stage
    (``v = p.stage(v)``), whose register is the RAM's output register (``hdl.bram``): the
    value is there, two registers after the address, and the RAM's clock-to-output is never
    in series with logic. Logic on it in between is an error (it is not a value yet).
    ``name`` is made unique within the module.

    ``load``: the table is scene data (a power table's shininess), named so. Where the
    pipeline has a host bus of that name (``p.host[load]``, a :class:`WriteBus`) the table is
    a RAM, empty after configuration, that the host writes; elsewhere (a unit on its own) it
    is a ROM of ``lut``'s contents. Either way ``lut`` gives its depth and format."""
    return RomRead(lut, addr, name, load)


def slice_width(depth):
    """Bits per memory slice: the widest ECP5 DP16KD shape (16 kbit) at least ``depth`` deep
    (512 x 36 ... 16384 x 1). A table cut into such slices by width maps one RAM to each, and
    Yosys never cascades it by depth, whose output mux would stand between the RAM and its
    register."""
    for d, w in ((512, 36), (1024, 18), (2048, 9), (4096, 4), (8192, 2)):
        if depth <= d:
            return w
    return 1


def read_roms(p, reads):
    """Build ``{key: RomRead}`` in pipeline ``p``: each read registered twice while the stage
    is enabled, the RAM's read register and its output register (``hdl.bram.table_slice``: on
    ECP5 the block's own), so the value is the next stage's register. Two reads of one table
    share a memory (a block RAM has two ports); each table is cut by width into slices one
    RAM deep (``slice_width``), so nothing stands between a RAM and its register: a table of
    ``2**k + 1`` entries (both ends of a quarter wave) takes RAMs ``2**(k+1)`` deep rather
    than a mux for its last entry. Returns ``{key: output register}``."""
    groups = {}
    host = getattr(p, "host", {})
    for key, r in reads.items():
        bus = host.get(r.load) if r.load else None
        # a loaded table: a RAM of its own per read, its one write port the host's (a
        # block RAM has two ports: one write, one read)
        groups.setdefault(id(r) if bus else id(r.lut), []).append((key, r))
    out = {}
    for group in groups.values():
        for at in range(0, len(group), 2):
            pair = group[at:at + 2]
            lut = pair[0][1].lut
            bus = host.get(pair[0][1].load) if pair[0][1].load else None
            stored = np.asarray(lut.contents, np.int64)
            raw = stored & ((1 << lut.fmt.width) - 1)            # two's complement bits
            # deeper than one RAM (a texture): one memory, which Yosys cascades itself
            step = slice_width(len(stored)) if len(stored) <= 16384 else lut.fmt.width
            name = p.unique("_".join(r.name for _, r in pair))
            slices = []
            for k, lo in enumerate(range(0, lut.fmt.width, step)):
                bits = min(step, lut.fmt.width - lo)
                init = [] if bus else [int(v) for v in (raw >> lo) & ((1 << bits) - 1)]
                write = (bus.en, bus.addr, bus.data[lo:lo + bits]) if bus else None
                slices.append(table_slice(p.m, name if lut.fmt.width <= step else
                                          f"{name}_{k}", len(stored), bits, init,
                                          [r.addr for _, r in pair], p.en, p.platform,
                                          write))
            for j, (key, r) in enumerate(pair):
                value = Cat(*(s[j] for s in slices))
                out[key] = value.as_signed() if lut.fmt.signed else value
    return out


def float_bins(exp_lo, exp_hi, mant_bits):
    """Bin edges of a floating-point address over [0, 2**exp_hi): ``2**mant_bits`` uniform bins
    below ``2**-exp_lo``, then ``2**mant_bits`` per octave up to ``2**exp_hi``
    (``float_address`` computes the address in hardware)."""
    m = 1 << mant_bits
    below = np.arange(m) * 2.0 ** -exp_lo / m
    octaves = [2.0 ** e * (1 + np.arange(m) / m) for e in range(-exp_lo, exp_hi)]
    return np.concatenate([below, *octaves, [2.0 ** exp_hi]])


def float_address(value, frac_bits, exp_lo, exp_hi, mant_bits):
    """The address of ``float_bins`` for an unsigned fixed-point ``value`` (``frac_bits``
    fraction bits): a leading-one search and a shift; values past the top saturate."""
    width = len(Value.cast(value))
    m = 1 << mant_bits
    top = (exp_lo + exp_hi + 1) * m - 1
    base = frac_bits - exp_lo                       # bit position of 2**-exp_lo
    if base < mant_bits:
        raise ValueError("float_address needs at least mant_bits bits below 2**-exp_lo")
    addr = (value >> (base - mant_bits))[:mant_bits]                      # below 2**-exp_lo
    for pos in range(base, width):                                         # leading one
        seg = pos - base + 1
        here = top if seg > exp_lo + exp_hi else seg * m + (value >> (pos - mant_bits))[:mant_bits]
        addr = Mux(value[pos], here, addr)
    return addr


@functools.lru_cache(maxsize=None)
def quarter_cos_lut(frac_bits, steps=256):
    """cos over a quarter turn, both ends included: entry a is cos(a/steps * 90 deg).

    One table serves sine (``T[steps - a]``) and cosine (``T[a]``), and, folded by quadrant,
    the cosine of any binary angle. Unsigned, ``frac_bits + 1`` bits so that 1.0 is exact.
    """
    return build_lut(lambda a: np.cos(a * (np.pi / 2) / steps), (steps).bit_length(),
                     Fixed(frac_bits + 1, False, frac_bits), depth=steps + 1)
