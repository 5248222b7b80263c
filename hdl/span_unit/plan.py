"""The raster's plan: its configuration as one typed, frozen object, validated once.

A :class:`RasterPlan` holds the screen and sub-pixel bits, each channel's interpolation mode,
edge-constant group and precision (:class:`Channel`), the reciprocal, the flat words, and the
architecture's knobs (``KNOBS``: the setup's and the row engine's multipliers, the setup's
interval, the channels in turn). It is checked when it is made, with errors that name the
knob; the raster (``hdl.span_unit.Raster``) and the scene's raster stage build it, and the
names and ranges of the knobs are stated here only (the raster's parameters, the scene
pipeline's and the CLI's ``--raster`` read them). ``params`` gives it back as the raster
unit's parameters (strings per channel), so that a plan and a unit's parameters name the
same Verilog.
"""
import functools
from dataclasses import dataclass
from typing import NamedTuple

from ..setup_unit.formats import MODES, VALUE, parse_groups, parse_modes, parse_precision

__all__ = ["Channel", "RasterPlan", "Timing", "KNOBS", "RECIPS", "RANGES", "ROW_MULTS"]

# the row engine's wide multipliers by default: issue 49's 18 MULT18X18D for the default
# pipeline, less its other units' 6 and the setup's 4, leave 8: two wide multipliers, a row
# every ceil(products / 2) clocks (docs/quadratic.md, "The row engine's multipliers")
ROW_MULTS = 2
# the architecture's knobs: name -> (default, range, what it is); the CLI's --raster help
# and docs/quadratic.md ("The knobs, and what they buy")
KNOBS = {
    "setup_mults": (1, (1, 6), "the setup's multipliers (35 x 35, four MULT18X18D each)"),
    "row_mults": (0, (0, 13), f"the row engine's, a row every ceil(products / row_mults) "
                              f"clocks; 0: {ROW_MULTS} (with row_narrow: one narrow a "
                              f"channel and one more)"),
    "setup_ii": (0, (0, 255), "clocks between triangles in the setup; 0: one at a time"),
    "setup_narrow": (0, (0, 6), "the setup's 18 x 18 multipliers (one MULT18X18D each)"),
    "row_serial": (0, (0, 9), ">0: the row engine's channels in turn on this many"),
    "setup_serial": (0, (0, 3), ">0: the setup's channels in turn on this many"),
    "row_narrow": (0, (0, 24), ">0: the narrow row engine's mantissa bits (18-24; block "
                               "floating point), the wide engine for the triangles it cannot "
                               "hold"),
}
RECIPS = ("newton", "divide")
# the sizes' ranges: a screen of 16 to 1,024 pixels a side, sub-pixel bits, channels,
# Newton-Raphson steps of the reciprocal, flat words
RANGES = {"screen_bits": (4, 10), "sub_bits": (1, 8), "channels": (1, 12),
          "recip_iters": (0, 3), "flat": (0, 8)}


@dataclass(frozen=True)
class Channel:
    """One interpolated channel: its mode (seed 001: X-shading, exact mid-edges, or linear),
    the group of edge constants it uses, and the fraction bits it is rounded to."""
    mode: str = MODES[0]
    group: int = 0
    precision: int = VALUE.frac_bits


class Timing(NamedTuple):
    """The raster's clocks, from its two schedules: the setup's clocks a triangle (its
    length, or ``setup_ii``), the row engine's clocks a row and its length, and the offset
    of the setup's last result (its last register, or its last write into the setup
    queue)."""
    setup_clocks: int
    row_ii: int
    row_clocks: int
    setup_end: int


@dataclass(frozen=True)
class RasterPlan:
    screen_bits: int = 10
    sub_bits: int = 4
    channels: tuple = (Channel(), Channel())
    recip: str = RECIPS[0]
    recip_iters: int = 2
    flat: int = 0
    setup_mults: int = KNOBS["setup_mults"][0]
    row_mults: int = KNOBS["row_mults"][0]
    setup_ii: int = KNOBS["setup_ii"][0]
    setup_narrow: int = KNOBS["setup_narrow"][0]
    row_serial: int = KNOBS["row_serial"][0]
    setup_serial: int = KNOBS["setup_serial"][0]
    row_narrow: int = KNOBS["row_narrow"][0]

    def __post_init__(self):
        self._check()

    @classmethod
    def from_params(cls, screen_bits=10, sub_bits=4, channels=2, modes="xshading", groups="0",
                    precision=str(VALUE.frac_bits), recip=RECIPS[0], recip_iters=2, flat=0,
                    **knobs):
        """A plan from the raster unit's parameters (``modes``, ``groups``, ``precision``:
        one per channel, comma-separated, or one for all)."""
        chans = tuple(Channel(m, g, p) for m, g, p in zip(
            parse_modes(modes, channels), parse_groups(groups, channels),
            parse_precision(precision, channels)))
        return cls(screen_bits, sub_bits, chans, recip, recip_iters, flat, **knobs)

    @property
    def modes(self):
        return tuple(c.mode for c in self.channels)

    @property
    def groups(self):
        """The number of groups of edge constants."""
        return max(c.group for c in self.channels) + 1

    @property
    def precision(self):
        return tuple(c.precision for c in self.channels)

    def params(self, defaults=True):
        """The raster unit's parameters; ``defaults=False``: only those that differ from its
        defaults (a scene's, so that a default knob keeps the Verilog's name)."""
        per = lambda xs: ",".join(map(str, xs))
        out = dict(screen_bits=self.screen_bits, sub_bits=self.sub_bits,
                   channels=len(self.channels), modes=per(self.modes),
                   recip=self.recip, recip_iters=self.recip_iters,
                   **{k: getattr(self, k) for k in KNOBS},
                   precision=per(self.precision), groups=per(c.group for c in self.channels),
                   flat=self.flat)
        if defaults:
            return out
        dropped = {**{k: d for k, (d, _, _) in KNOBS.items()}, "flat": 0}
        out = {k: v for k, v in out.items() if k not in dropped or v != dropped[k]}
        if min(self.precision) == VALUE.frac_bits:
            del out["precision"]
        if self.groups == 1:
            del out["groups"]
        return out

    @property
    def timing(self):
        """The plan's :class:`Timing`, from the setup's and the row engine's schedules built
        on their own (not the raster's elaboration)."""
        return _timing(self)

    @property
    def row_multipliers(self):
        """The row engine's multipliers: ``row_serial``'s, ``row_mults``, or by default
        ``ROW_MULTS`` wide ones (with ``row_narrow``: a narrow one a channel and one more)."""
        return (self.row_serial or self.row_mults
                or (len(self.channels) + 1 if self.row_narrow else ROW_MULTS))

    @property
    def latency(self):
        """From a triangle in to its first fragment out, when nothing waits: the setup (to
        its results' last register, or last queue write), the walker's load and its row
        buffer, the row engine, the row queue, the stepper's load, the output register."""
        t = self.timing
        return t.setup_end + 1 + 2 + t.row_clocks + 3

    @property
    def setup(self):
        from ..setup_unit.setup import Setup
        p = self.params()
        return Setup(self.screen_bits, self.sub_bits, len(self.channels), p["modes"],
                     self.recip, self.recip_iters, p["groups"], self.row_narrow)

    def _check(self):
        """The checks that tie the knobs together; each error names the knob."""
        from .span import row_products
        if not self.channels or not all(isinstance(c, Channel) for c in self.channels):
            raise TypeError(f"channels must be a tuple of Channel, not {self.channels!r}")
        for c in self.channels:
            if c.mode not in MODES:
                raise ValueError(f"unknown mode {c.mode!r}; modes are {', '.join(MODES)}")
            if not 1 <= c.precision <= VALUE.frac_bits:
                raise ValueError(f"precision must be fraction bits from 1 to "
                                 f"{VALUE.frac_bits}, not {c.precision}")
        sizes = {"screen_bits": self.screen_bits, "sub_bits": self.sub_bits,
                 "channels": len(self.channels), "recip_iters": self.recip_iters,
                 "flat": self.flat}
        for k, (_, (lo, hi), _) in KNOBS.items():
            sizes[k] = getattr(self, k)
        for k, v in sizes.items():
            lo, hi = RANGES[k] if k in RANGES else KNOBS[k][1]
            if not lo <= v <= hi:
                raise ValueError(f"{k} must be in {lo}..{hi}, not {v}")
        groups = sorted({c.group for c in self.channels})
        if groups != list(range(len(groups))):
            raise ValueError(f"groups must be numbered 0, 1, ... without gaps, not "
                             f"{[c.group for c in self.channels]}")
        if self.recip not in RECIPS:
            raise ValueError(f"recip must be one of {', '.join(RECIPS)}, not {self.recip!r}")
        if self.setup_serial and (not self.row_serial or self.setup_ii
                                  or "exact" in self.modes):
            raise ValueError(f"setup_serial={self.setup_serial} needs row_serial > 0 (its jobs "
                             f"read the channels' constants in turn), setup_ii=0 and no exact "
                             f"channel; here row_serial={self.row_serial}, setup_ii="
                             f"{self.setup_ii}, modes={','.join(self.modes)!r}")
        if self.row_serial and self.row_mults:
            raise ValueError(f"row_mults={self.row_mults} and row_serial={self.row_serial}: "
                             f"the row engine is one or the other (row_mults=0 with "
                             f"row_serial)")
        if self.row_narrow and (self.row_narrow < 18 or self.row_serial or self.setup_serial):
            raise ValueError(f"row_narrow={self.row_narrow}: mantissas of 18 to 24 bits, with "
                             f"the channels together (row_serial=0, setup_serial=0); here "
                             f"row_serial={self.row_serial}, setup_serial={self.setup_serial}")
        products = row_products(self.modes)
        if self.row_mults > products:      # fewer: shared, a longer row interval; more than
            raise ValueError(f"row_mults must be at most the row engine's {products} "
                             f"products a row (one each: a row a clock), not {self.row_mults}")
        if self.setup_ii:
            self._check_interval()

    def _check_interval(self):
        n, fits = self.setup_products
        ii, top = self.setup_ii, KNOBS["setup_mults"][1][1]
        if self.setup_narrow:                  # the narrow ones take every product that fits
            if ii * self.setup_narrow < fits:
                raise ValueError(f"setup_ii={ii} is too short: the {fits} of the setup's "
                                 f"products that fit 18 x 18 on setup_narrow="
                                 f"{self.setup_narrow} take at least "
                                 f"{-(-fits // self.setup_narrow)} clocks")
            n -= fits
        if ii * self.setup_mults < n:
            need = -(-n // ii)
            raise ValueError(f"setup_ii={ii} is too short: the setup's {n} products on "
                             f"setup_mults={self.setup_mults} wide multiplier(s) take at least "
                             f"{-(-n // self.setup_mults)} clocks; at this interval they need "
                             f"setup_mults={need}"
                             + (f", more than the {top} allowed" if need > top else ""))

    @property
    def setup_products(self):
        """The setup's products per triangle, and how many of them fit a narrow multiplier
        (its program on a schedule of its own)."""
        p = self.params()
        return _products(self.screen_bits, self.sub_bits, len(self.channels), p["modes"],
                         self.recip, self.recip_iters, p["groups"], self.row_narrow)


@functools.lru_cache(maxsize=None)
def _products(*params):
    from amaranth.hdl import Const, Fragment, Module, Signal

    from ..sched import Schedule
    from ..setup_unit.formats import triangle_fields
    from ..setup_unit.setup import Setup
    setup = Setup(*params)
    m, w = Module(), setup.w
    sc = Schedule(m, "count", Const(1))
    fields = triangle_fields(w.screen_bits, w.sub_bits, setup.channels, max(setup.groups) + 1)
    v = {f.name: Signal(f.fmt.shape, name=f.name) for f in fields}
    setup.program(sc, {**v, "tri": Signal(32)})
    Fragment.get(m, None)                        # (its ROMs are used, for Amaranth's checks)
    return sum(len(u) for u in sc.mults), sc.fits


@functools.lru_cache(maxsize=None)
def _timing(plan):
    from amaranth.hdl import Fragment, Module

    from ..fixed import layout
    from ..setup_unit.formats import flat_fields, triangle_fields
    from .row_engine import RowEngine, const_fields, row_fields
    from .setup_engine import SetupEngine
    from .walker import Walker
    flats = flat_fields(plan.flat)
    flat = [f.name for f in flats]
    fields = triangle_fields(plan.screen_bits, plan.sub_bits, len(plan.channels),
                             plan.groups) + flats
    m = Module()
    m.submodules.setup = su = SetupEngine(plan, layout(fields), flat)
    m.submodules.walker = wk = Walker(plan.setup.w, len(plan.channels), su.fields,
                                      su.current_fields, flat, bool(su.const_fields),
                                      bool(plan.row_narrow))
    if plan.row_narrow:
        from .row_pair import RowPair
        m.submodules.row_engine = re = RowPair(plan, row_fields(wk), flat)
    else:
        m.submodules.row_engine = re = RowEngine(plan, row_fields(wk), flat, const_fields(su))
    Fragment.get(m, None)                        # (every part used, for Amaranth's checks)
    return Timing(su.clocks, re.ii, re.length, su.end)
