"""The fenney_polar stage (seed 004, first embodiment, FIG. 3): the S/R texel shaded against
each lane's per-triangle constants k1, k2, k3 and Q (the light held per triangle), which the
raster carries as one flat word per lane; the power of the H lanes is the power stage's."""
import numpy as np
from amaranth.hdl import Cat, Const

from golden import fenney
from hdl.illum_unit.fenney_polar import FenneyPolar as Unit, polar_lanes
from hdl.setup_unit.formats import VALUE

from ..stage import Stage, lane_key

CONSTANTS = ("k1", "k2", "k3", "q")     # a flat word, k1 at the top, 8 bits each


def pack(consts):
    """A lane's flat word from its constants (arrays), as the raster carries it."""
    return sum(np.asarray(consts[c], np.int64) << 8 * (3 - j) for j, c in enumerate(CONSTANTS))


class FenneyPolar(Stage):
    bump = True
    name = "fenney_polar"
    when = {"bump": "fenney_polar"}

    @property
    def flat(self):
        return [f"_k{t}{k}" for t, k in self.lanes]

    @property
    def params(self):
        return dict(trig_bits=self.q["trig_bits"])

    @property
    def why(self):
        vectors = f"L{' and H' if self.q['specular'] else ''} per light"
        return f"bump.method = fenney_polar: {len(self.lanes)} lanes ({vectors})"

    @property
    def latency(self):
        unit = Unit.spec(**self.params)
        return unit.latency - unit.power.latency          # its lanes; the power is a stage

    def rtl(self, p, v, uni):
        for t, k in self.lanes:
            word = v.pop(f"_k{t}{k}")
            v.update({f"{t}{k}_{c}": word[8 * (3 - j):8 * (4 - j)]
                      for j, c in enumerate(CONSTANTS)})
        lanes = [tuple(f"{t}{k}_{c}" for c in CONSTANTS) + (f"_i{t}{k}", None)
                 for t, k in self.lanes]
        v = polar_lanes(p, v, "_hi", "_lo", lanes, self.q["trig_bits"])     # S, R
        for t, k in self.lanes:
            # N.L (d) and N.H (s) as values: i / 255 by bit replication, (i << 6) | (i >> 2),
            # within 2**-14 (s >> 4 is then the power unit's X)
            i = v.pop(f"_i{t}{k}")
            v[lane_key(t, k)] = Cat(i[2:8], i, Const(0, 2)).as_signed()
        return v

    def ideal(self, prep, frag, ch):
        """The texel's S and R exact (from the normal), each lane's light held per triangle
        unrounded (elevation, clamped at the horizon, and rotation): k2 sin S + k3 cos S
        cos(R - Q) with k2 = sin, k3 = cos of the elevation (eq 1-4, h = 1)."""
        ch = dict(ch)
        n = ch.pop("_n")
        s_ang = np.arcsin(np.clip(n[:, 2], 0.0, 1.0))
        r_ang = np.arctan2(n[:, 1], n[:, 0])
        for t, k in self.lanes:
            ch.pop(f"_k{t}{k}")
            elev, rot = (x[frag["tri"]] for x in prep["bump"]["held"][f"{t}{k}"])
            ch[lane_key(t, k)] = np.clip(np.sin(elev) * np.sin(s_ang) + np.cos(elev)
                                         * np.cos(s_ang) * np.cos(r_ang - rot), 0, 1)
        return ch

    def model(self, prep, frag, ch, bound):
        """``golden.fenney.polar_float`` rounded, per lane; d and s as the RTL widens the
        intensity. ``bound``: ``offset`` ``{key: n}`` added to a lane's intensity before it
        is clamped (the tests' bound on the RTL's rounding)."""
        ch = dict(ch)
        texel = {"s": ch.pop("_hi"), "r": ch.pop("_lo")}
        for t, k in self.lanes:
            word = ch.pop(f"_k{t}{k}")
            c = {n: (word >> 8 * (3 - j)) & 255 for j, n in enumerate(CONSTANTS)}
            key = lane_key(t, k)
            i = np.clip(np.rint(fenney.polar_float({**texel, **c}))
                        + bound.get("offset", {}).get(key, 0), 0, 255).astype(np.int64)
            ch[key] = ((i << 6) | (i >> 2)) * VALUE.lsb
        return ch
