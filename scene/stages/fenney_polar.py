"""The fenney_polar stage (seed 004, first embodiment, FIG. 3): the S/R texel shaded against
each lane's per-triangle constants k1, k2, k3 and Q (the light held per triangle), which the
raster carries as one flat word per lane; the power of the H lanes is the power stage's."""
import numpy as np
from amaranth.hdl import Cat, Const

from golden import bump as bumps, fenney
from hdl.illum_unit.fenney_polar import FenneyPolar as Unit, polar_lanes
from hdl.setup_unit.formats import VALUE

from ..mesh import unit
from ..stage import Stage, Sweep, lane_key

CONSTANTS = ("k1", "k2", "k3", "q")     # a flat word, k1 at the top, 8 bits each


def pack(consts):
    """A lane's flat word from its constants (arrays), as the raster carries it."""
    return sum(np.asarray(consts[c], np.int64) << 8 * (3 - j) for j, c in enumerate(CONSTANTS))


class FenneyPolar(Stage):
    bump = True
    name = "fenney_polar"
    when = {"bump": "fenney_polar"}
    gives = ("lighting",)           # N.L and N.H: the raster interpolates none
    build_params = {"trig_bits": (10, (4, 16))}

    @classmethod
    def sweeps(cls):
        """Fenney's first embodiment (the other bump methods are the fenney_dot and rotation
        rows)."""
        return [Sweep("bump method", cls.name, cls.name, scene="bump_polar", default=True)]

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

    format_group = "shading"

    def prepare(self, scene, view, data):
        """The triangle's tangent frame: the mean of its vertices' frames, made orthonormal
        (N, T against N, B = N x T). L and H in it as elevation T_L (degrees above the
        surface plane) and rotation Q from the tangent; k1 = 0, k2 = sin T_L, k3 = cos T_L
        (h = 1, eq 1-4), each * 255, and Q in turns * 256. A light below the surface's
        horizon is taken at T_L = 0: the patent's 8-bit k2 is unsigned (docs/bump.md)."""
        frames = data["frames"]
        Nt = unit(frames[2].sum(1))
        Tt = frames[0].sum(1)
        Tt = unit(Tt - np.einsum("ij,ij->i", Tt, Nt)[:, None] * Nt)
        Bt = np.cross(Nt, Tt)
        consts, held = {}, {}
        for t, k in self.lanes:
            v = bumps.to_tangent((view.L if t == "l" else view.H)[k], Tt, Bt, Nt)
            elev = np.arcsin(np.clip(v[:, 2], 0.0, 1.0))
            rot = np.arctan2(v[:, 1], v[:, 0])
            consts[f"{t}{k}_k1"] = np.zeros(len(v), np.int64)
            consts[f"{t}{k}_k2"] = np.rint(255 * np.sin(elev)).astype(np.int64)
            consts[f"{t}{k}_k3"] = np.rint(255 * np.cos(elev)).astype(np.int64)
            consts[f"{t}{k}_q"] = np.rint(rot / (2 * np.pi) * 256).astype(np.int64) % 256
            held[f"{t}{k}"] = (elev, rot)                 # the same, unrounded
        return {"constants": consts, "held": held}

    def flat_values(self, data):
        c = data["constants"]
        return {f"_k{t}{k}": pack({n: c[f"{t}{k}_{n}"] for n in CONSTANTS})
                for t, k in self.lanes}

    def convert(self, ch, ideal):
        """The texel's codes S and R (the patent's: S in quarter turns * 256, R in turns *
        256), or the normal they hold."""
        ch = dict(ch)
        if ideal and "_hi" in ch:
            hi, lo = np.asarray(ch.pop("_hi"), float), np.asarray(ch.pop("_lo"), float)
            s_ang, r_ang = hi / 256 * (np.pi / 2), lo / 256 * (2 * np.pi)
            ch["_n"] = np.stack([np.cos(s_ang) * np.cos(r_ang), np.cos(s_ang) * np.sin(r_ang),
                                 np.sin(s_ang)], -1)
        elif not ideal and "_n" in ch:
            n = ch.pop("_n")
            ch["_hi"] = np.arcsin(np.clip(n[:, 2], 0, 1)) / (np.pi / 2) * 256
            ch["_lo"] = np.mod(np.arctan2(n[:, 1], n[:, 0]) / (2 * np.pi) * 256, 256)
        return ch

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
            elev, rot = (x[frag["tri"]] for x in prep["data"]["held"][f"{t}{k}"])
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

    def candidates(self, prep, frag, ch):
        """Every colour the RTL may give, ``(choices, n, 3)``, one of them exactly: the texel
        one either way along s and t (the raster's coordinates are within one LSB of the
        model's), and each lane's intensity one either way (fenney_polar is within
        ``golden.fenney.polar_bound``, 0.874, of the float eq 3, which the model rounds); the
        rest is exact (tests/test_bump_scenes.py)."""
        from ..models import bump_model, shade_fragments
        lanes = [("d" if t == "l" else "s") + str(k) for t, k in self.lanes]
        out = []
        for ds in (-1, 0, 1):
            for dt in (-1, 0, 1):
                for offs in np.ndindex(*(3,) * len(lanes)):
                    off = {key: o - 1 for key, o in zip(lanes, offs)}
                    c = {**ch, **bump_model(prep, frag, ch, ds=ds, dt=dt, offset=off)}
                    out.append(shade_fragments(prep, c))
        return np.stack(out)
