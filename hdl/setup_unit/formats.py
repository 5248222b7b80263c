"""The formats of the quadratic-shading pipeline (setup -> span), stated once.

- Vertex coordinates: pixels, signed, ``sub_bits`` fraction bits, two integer bits beyond the
  screen (a vertex may lie up to one screen width outside it on either side).
- Channel values (vertex values in, fragment values out): ``VALUE``, s16 with 14 fraction bits,
  range [-2, 2); a fragment value outside it saturates.
- Per-edge constants of X-shading (Ni.Nj - 1)/2: ``EDGE``, s16 with 15 fraction bits, [-1, 0]
  for unit normals. One set per group of channels (``groups``: the normal's for scalars, a
  vector's own, (L'i.L'j - 1)/2, for its components, seed 000 section 2): ``e01 e02 e12`` for
  group 0, ``e01_g e02_g e12_g`` for group g.
- Fragment coordinates: unsigned pixel indices below the screen size.
- Flat words: ``FLAT``, u32, a triangle's constants packed by whoever sends them (the scene's
  fenney_polar: k1, k2, k3 and Q of one lane, 8 bits each, Q at the bottom).
"""
from ..fixed import Field, s, u

VALUE = s(16, 14)
EDGE = s(16, 15)
TRI = u(32)                       # the input row a fragment came from
FLAT = u(32)                      # a flat word: a triangle's constants, packed


def coord(screen_bits, sub_bits):
    return s(screen_bits + 2 + sub_bits, sub_bits, "px")


def edge_names(group):
    """The per-edge constants of one group, by vertex pair."""
    return tuple(f"e{p}{f'_{group}' if group else ''}" for p in ("01", "02", "12"))


def triangle_fields(screen_bits, sub_bits, channels, groups=1):
    c = coord(screen_bits, sub_bits)
    return ([Field(f"{a}{k}", c) for k in range(3) for a in "xy"]
            + [Field(n, EDGE) for g in range(groups) for n in edge_names(g)]
            + [Field(f"v{ch}_{k}", VALUE) for ch in range(channels) for k in range(3)])


def fragment_fields(screen_bits, channels):
    return ([Field("tri", TRI), Field("x", u(screen_bits, 0, "px")),
             Field("y", u(screen_bits, 0, "px"))]
            + [Field(f"v{ch}", VALUE) for ch in range(channels)])


def flat_fields(words):
    """A triangle's constants that the raster carries to its fragments unchanged: ``f{k}``."""
    return [Field(f"f{k}", FLAT) for k in range(words)]


MODES = ("xshading", "exact", "linear")
EXACT_G_MAX = 64.0   # exact mid-edges: 1/||Ni + Nj|| clamps here (normals within 0.9 deg of opposite)


def _per_channel(name, value, channels):
    """``"a,b,c"`` -> a tuple of its stripped parts, one per channel (one part applies to
    all); a ``TypeError``/``ValueError`` names ``name``."""
    if not isinstance(value, str):
        raise TypeError(f"{name} must be a comma-separated string, not {value!r}")
    out = tuple(p.strip() for p in value.split(","))
    if len(out) == 1:
        out = out * channels
    if len(out) != channels:
        raise ValueError(f"{name} names {len(out)} channel(s) but channels={channels}")
    return out


def parse_groups(groups, channels):
    """``"0,0,1,1,1"`` -> a tuple, each channel's edge-constant group (one number applies to
    all), numbered from 0 without gaps."""
    parts = _per_channel("groups", groups, channels)
    try:
        out = tuple(int(g) for g in parts)
    except ValueError:
        raise ValueError(f"groups must be numbers, one per channel, not {groups!r}") from None
    if sorted(set(out)) != list(range(max(out) + 1)):
        raise ValueError(f"groups must be numbered 0, 1, ... without gaps, not {groups!r}")
    return out


def parse_modes(modes, channels):
    """``"xshading,linear"`` -> a tuple, one mode per channel (one name applies to all)."""
    out = _per_channel("modes", modes, channels)
    bad = [m for m in out if m not in MODES]
    if bad:
        raise ValueError(f"unknown mode {bad[0]!r}; modes are {', '.join(MODES)}")
    return out


# A channel's output precision: the fraction bits it is rounded to (its value stays in
# ``VALUE``, the bits below it zero), 1 to VALUE's 14; the raster's internal widths follow
# (``Widths.fi``; docs/quadratic.md "A channel's precision").
PRECISIONS = tuple(str(p) for p in range(1, VALUE.frac_bits + 1))


def parse_precision(precision, channels):
    """``"14,8,8"`` -> a tuple of ints, each channel's fraction bits (one applies to all)."""
    out = _per_channel("precision", precision, channels)
    bad = [p for p in out if p not in PRECISIONS]
    if bad:
        raise ValueError(f"precision must be fraction bits from 1 to {VALUE.frac_bits}, one "
                         f"per channel, not {bad[0]!r}")
    return tuple(int(p) for p in out)
