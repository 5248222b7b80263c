"""The fenney_dot stage (seed 004 eq 1): the bump vector dotted with each lane's interpolated
vector, L' and H' in the tangent frame, quadratic with each vector's own per-edge constants
(seed 000 section 2) or linear: N.L and N.H per light."""
import itertools

import numpy as np

from golden import bump as bumps, fenney
from hdl.illum_unit.fenney_dot import FenneyDot as Unit, dot_lanes
from hdl.setup_unit.formats import EDGE, VALUE
from amaranth.hdl import Cat, Const, Mux

from ..stage import SceneError, Stage, Sweep, lane_key, raw


class FenneyDot(Stage):
    bump = True
    name = "fenney_dot"
    when = {"bump": "fenney_xz"}
    gives = ("lighting",)           # N.L and N.H: the raster interpolates none
    build_params = {"vector_bits": (VALUE.frac_bits, (4, VALUE.frac_bits)),
                    "normalize": (False, None),
                    "rsqrt_bits": (Unit.PARAMS["rsqrt_bits"], Unit.RANGES["rsqrt_bits"])}

    @classmethod
    def sweeps(cls):
        """Its vector channels (six of its nine) rounded to fewer fraction bits, their Phi, d
        and 2A kept that much shorter in the raster (the patent's s8 takes 7); and its dot
        product plain or renormalised by a table of ``rsqrt_bits``."""
        rows = [Sweep("vector bits", str(b), scene="bump_xz", hardware={"vector_bits": b},
                      build="raster", default=b == VALUE.frac_bits) for b in (14, 10, 8)]
        return rows + [Sweep(cls.name, label, cls.name, p, "bump_xz", p, rows=20000,
                             default=not p, quick=label in ("plain", "renorm 12"))
                       for label, p in (("plain", {}),
                                        ("renorm 8", {"normalize": True, "rsqrt_bits": 8}),
                                        ("renorm 12", {"normalize": True, "rsqrt_bits": 12}))]

    @property
    def channels(self):
        """Each lane's vector, its components a group of edge constants of their own."""
        return [(f"{t}{k}{a}", self.lighting_mode, 1 + n) for n, (t, k) in enumerate(self.lanes)
                for a in "xyz"]

    @property
    def channel_bits(self):
        """The vectors' components, rounded to s8 here: ``vector_bits`` of them are enough
        (the pipeline's knob; 14, all of VALUE, by default)."""
        return {name: self.q["vector_bits"] for name, _, _ in self.channels}

    @property
    def params(self):
        """The patent's plain dot product, or the bump vector renormalised (the scene's
        ``bump.renormalize``; ``make tradeoffs`` also sweeps it as a hardware choice)."""
        return dict(normalize=self.q["normalize"], rsqrt_bits=self.q["rsqrt_bits"])

    @property
    def why(self):
        vectors = f"L{' and H' if self.q['specular'] else ''} per light"
        return f"bump.method = fenney_xz: {len(self.lanes)} lanes ({vectors})"

    format_group = "shading"
    scene_keys = {"bump": {"renormalize": (False, ("bool",))}}

    @classmethod
    def check_scene(cls, scene):
        if scene["bump"]["renormalize"] and scene["bump"]["method"] != cls.when["bump"]:
            raise SceneError(f"bump.renormalize: only with bump.method = "
                             f"\"{cls.when['bump']}\", not {scene['bump']['method']!r}")

    @classmethod
    def scene_params(cls, scene):
        return {"normalize": True} if scene["bump"]["renormalize"] else {}

    def prepare(self, scene, view, data):
        """Each vertex's L' and H' in its own tangent frame (they vary over the surface), in
        the patent's axes (T, N, B: y out), and each vector's per-edge constants
        (L'i.L'j - 1)/2 (seed 000 section 2), raw and unrounded."""
        frames, lanes = data["frames"], self.lanes
        vectors, consts, real = {}, {}, {}
        for n, (t, k) in enumerate(lanes):
            light = (view.L if t == "l" else view.H)[k]
            vec = np.stack([bumps.to_tangent(light, *(f[:, c] for f in frames))
                            for c in range(3)], 1)[..., [0, 2, 1]]             # (n, 3, 3)
            vectors[f"{t}{k}"] = vec
            for (a, c), name in zip(((0, 1), (0, 2), (1, 2)), ("01", "02", "12")):
                dots = np.einsum("ij,ij->i", vec[:, a], vec[:, c])
                consts[f"e{name}_{1 + n}"] = np.minimum(raw((dots - 1) / 2, EDGE), 0)
                real[f"e{name}_{1 + n}"] = np.minimum((dots - 1) / 2, 0) / EDGE.lsb
        hi, lo = data["texels"]
        return {"vectors": vectors, "constants": consts, "real_edges": real, "X": hi, "Z": lo}

    def vertex_values(self, data):
        return {f"{lane}{a}": vec[..., j] for lane, vec in data["vectors"].items()
                for j, a in enumerate("xyz")}

    def triangle_values(self, data):
        return data["constants"], data["real_edges"]

    @property
    def latency(self):
        return 1 + Unit.spec(**self.params).latency        # the vectors' conversion to s8

    def rtl(self, p, v, uni):
        conv = {}             # the interpolated vector as the patent's s8: round(127 v), clamped
        for t, k in self.lanes:
            for a in "xyz":
                c = v.pop(f"{t}{k}{a}")
                r = ((c << 7) - c + (1 << (VALUE.frac_bits - 1))) >> VALUE.frac_bits
                conv[f"_{t}{k}{a}"] = Mux(r > 127, 127, Mux(r < -127, -127, r))[:8].as_signed()
        v = p.stage(v, **conv)
        lanes = [tuple(f"_{t}{k}{a}" for a in "xyz") + (f"_h{t}{k}", f"_x{t}{k}")
                 for t, k in self.lanes]
        v.update({f"_h{t}{k}": Const(255, 8) for t, k in self.lanes})   # h = 1
        v = dot_lanes(p, v, "x", "y", "z", lanes, **self.params)
        for t, k in self.lanes:             # X / 1024 as a value: X << 4
            v[lane_key(t, k)] = Cat(Const(0, 4), v.pop(f"_x{t}{k}"), Const(0, 2)).as_signed()
        return v

    def ideal(self, prep, frag, ch):
        """Each lane's interpolated vector (not renormalised, as the patent's) dotted with the
        bump vector (L1 length 1, or unit where renormalised), h = 1."""
        ch = dict(ch)
        b = np.stack([ch.pop(a) for a in "xyz"], -1)
        if self.q["normalize"]:
            b = b / np.linalg.norm(b, axis=-1, keepdims=True)
        for t, k in self.lanes:
            lv = np.stack([ch.pop(f"{t}{k}{a}") for a in "xyz"], -1)
            ch[lane_key(t, k)] = (b * lv).sum(-1)
        return ch

    def interval(self, prep, frag, ch, before):
        """The colour is monotone in d and in s (coefficients >= 0, the powers increase), so
        the RTL's lies between the model's at the least and largest d and s per lane over:
        the texture coordinates' raw values -1, 0, +1 (bilinear weights move with them); each
        component of the interpolated vector -1, 0, +1 raw LSB (at ``vector_bits`` p,
        2**(14 - p)), which can move its rounding to the patent's s8; and X -1, 0, +1 (the
        unit is within ``golden.fenney.dot_bound``, below one LSB, of the float; the model
        rounds)."""
        lo, hi = {}, {}
        lanes = [f"{t}{k}" for t, k in self.lanes]
        keys = [lane_key(t, k) for t, k in self.lanes]
        lsb = 1 << (VALUE.frac_bits - self.q["vector_bits"])   # the vector channels' raw LSB
        for ds, dt in itertools.product((-1, 0, 1), repeat=2):
            for dl in itertools.product((-lsb, 0, lsb), repeat=3):
                bound = {"ds": ds, "dt": dt, "dl": {lane: dl for lane in lanes}}
                out = self.model(prep, frag, before(**bound), bound)
                for key in keys:
                    lo[key] = np.minimum(lo.get(key, out[key]), out[key])
                    hi[key] = np.maximum(hi.get(key, out[key]), out[key])
        step = 16 * VALUE.lsb                               # one LSB of X, as a value
        return ({k: np.maximum(v - step, 0) for k, v in lo.items()},
                {k: np.minimum(v + step, 1023 * step) for k, v in hi.items()})

    def model(self, prep, frag, ch, bound):
        """Each lane's vector as the patent's s8 (round(127 v), clamped to +-127, from its raw
        value), dotted (``golden.fenney.dot_float``, h = 1, plain or renormalised), rounded to
        the 10-bit X; X << 4 as a value. ``bound``: ``dl`` ``{lane: (dx, dy, dz)}`` added to a
        vector's raw components, ``offset`` ``{key: n}`` to X."""
        ch = dict(ch)
        inp = {a: ch.pop(a) for a in "xyz"}
        for t, k in self.lanes:
            d = bound.get("dl", {}).get(f"{t}{k}", (0, 0, 0))
            for a, da in zip("xyz", d):
                r = raw(ch.pop(f"{t}{k}{a}")) + da
                inp[f"l{a}"] = np.clip((r * 127 + (1 << 13)) >> 14, -127, 127)
            inp["h"] = np.full(len(r), 255)
            key = lane_key(t, k)
            x = np.clip(np.rint(fenney.dot_float(inp, **self.params))
                        + bound.get("offset", {}).get(key, 0), 0, 1023)
            ch[key] = (x.astype(np.int64) << 4) * VALUE.lsb
        return ch
