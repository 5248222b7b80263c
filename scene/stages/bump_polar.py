"""The bump_polar stage (seed 003): L and H rotated into the frame of the interpolated normal
(its angles phi_N, theta_N and the texture frame's twist psi, linear channels in turns), then
the law-of-cosines illumination against the texel's (phi_B + psi, theta_B)."""
import itertools

import numpy as np
from amaranth.hdl import Cat, Const

from golden import angular
from hdl.fixed import Field, binary_angle
from hdl.illum_unit.bump_polar import BumpPolar as Unit
from hdl.setup_unit.formats import VALUE

from ..stage import Stage, Sweep, convert_powers, raw
from .texture import ANGLE_BITS

LIGHT = ("phi_l", "theta_l", "phi_h", "theta_h")      # L and H in polar form, world frame


class BumpPolar(Stage):
    bump = True
    name = "bump_polar"
    channels = (("phin", "linear", 0), ("thetan", "linear", 0), ("psi", "linear", 0))
    when = {"bump": "angular"}
    gives = ("lighting", "powers")    # N.L; its own specular table: no power stage
    ROTATIONS = ("paper", "exact")
    scene_keys = {"bump": {"rotation": (ROTATIONS[0], ("choice", ROTATIONS))}}
    build_params = {"rotation": (ROTATIONS[0], ROTATIONS)}

    @classmethod
    def sweeps(cls):
        """The rotation (seed 003): its method (the exact one's CORDIC iterations), angle bits
        and table address bits; and seed 003's comparison, the Cartesian baseline (Peercy)
        beside the angular unit."""
        rows = [Sweep("rotation", label, "rotation", p, scene, rows=20000, default=not p)
                for label, p, scene in (
                    ("paper", {}, "bump_angular"),
                    ("exact", {"method": "exact"}, "bump_angular_exact"),
                    ("exact, 12 iterations", {"method": "exact", "iterations": 12}, None),
                    ("10-bit angles", {"angle_bits": 10, "trig_bits": 12, "asin_bits": 10},
                     None),
                    ("tables -2 bits", {"asin_bits": 10, "atan_bits": 6, "prop_bits": 10},
                     None))]
        return rows + [Sweep("bump architecture", "Cartesian (Peercy)", "peercy", rows=20000),
                       Sweep("bump architecture", "angular (seed 003)", cls.name,
                             default=True)]

    @property
    def uniforms(self):
        return [Field(n, binary_angle(ANGLE_BITS)) for n in LIGHT]

    @property
    def params(self):
        return dict(method=self.q["rotation"], angle_bits=ANGLE_BITS)

    @property
    def tables(self):
        """The illumination's specular table d^n: loaded (the shininess is data)."""
        return {"specular": self.unit.illum.tables[1]}

    def table_values(self, scene):
        return {"specular": Unit.spec(**self.params, shininess=self.shininess(scene))
                .illum.tables[1].contents}

    @staticmethod
    def shininess(scene):
        return max(1, min(1024, round(scene["material"]["shininess"])))

    @property
    def label(self):
        return f"{self.q['rotation']} rotation"

    @property
    def why(self):
        return f"bump.method = angular, bump.rotation = {self.q['rotation']}: rotation x 2, illum"

    def uniform_values(self, scene, L, H):
        """The light's L and H in polar form (seed 003: phi from x, theta from z), turns."""
        angle = lambda a: int(np.rint(a / (2 * np.pi) * (1 << ANGLE_BITS))) % (1 << ANGLE_BITS)
        out = {}
        for n, vec in (("l", L[0]), ("h", H[0])):
            phi, theta = angular.to_polar(vec)
            out[f"phi_{n}"], out[f"theta_{n}"] = angle(phi), angle(theta)
        return out

    @classmethod
    def scene_params(cls, scene):
        return {"rotation": scene["bump"]["rotation"]}

    def prepare(self, scene, view, data):
        """The normal's angles (seed 003: phi from x, theta from z) and the twist psi of the
        texture's frame about N from the rotations' frame (e_theta, e_phi, N), in turns; each
        unwrapped within half a turn of the first vertex's, as the texture coordinates.
        theta_N = 0 (the hard case): phi_N means nothing there, so each triangle takes, at
        such a vertex, the mean direction of its other vertices' phi_N (the normal crosses
        the pole along it); the twist follows from that phi."""
        T, N = data["frames"][0], data["frames"][2]
        phi, theta = angular.to_polar(N)
        pole = np.sin(theta) < 1e-9
        other = np.where(pole, 0.0, 1.0)
        mean = np.arctan2((other * np.sin(phi)).sum(1), (other * np.cos(phi)).sum(1))
        phi = np.where(pole, mean[:, None], phi)
        e_t = np.stack([np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi),
                        -np.sin(theta)], -1)
        e_p = np.stack([-np.sin(phi), np.cos(phi), np.zeros_like(phi)], -1)
        psi = np.arctan2(np.einsum("...i,...i", T, e_p), np.einsum("...i,...i", T, e_t))
        turns = lambda a: a / (2 * np.pi)
        wrap = lambda a: a[:, :1] + np.mod(a - a[:, :1] + 0.5, 1.0) - 0.5
        angles = {"phin": wrap(turns(phi)), "thetan": turns(theta), "psi": wrap(turns(psi))}
        for k in ("phin", "psi"):
            angles[k] -= np.floor(angles[k].min(axis=1, keepdims=True))
        return {"angles": angles}

    def vertex_values(self, data):
        return data["angles"]

    format_group = "shading"

    def convert(self, ch, ideal):
        """The texel's codes, polar angles in turns * 2**ANGLE_BITS (theta, phi), or the
        normal they hold; its power p0."""
        ch = convert_powers(ch, ideal)
        if ideal and "_hi" in ch:
            hi, lo = np.asarray(ch.pop("_hi"), float), np.asarray(ch.pop("_lo"), float)
            turn = 2 * np.pi / (1 << ANGLE_BITS)
            ch["_n"] = angular.to_vector(lo * turn, hi * turn)
        elif not ideal and "_n" in ch:
            phi, theta = angular.to_polar(ch.pop("_n"))
            scale = (1 << ANGLE_BITS) / (2 * np.pi)
            ch["_hi"], ch["_lo"] = (np.rint(a * scale).astype(np.int64) % (1 << ANGLE_BITS)
                                    for a in (theta, phi))
        return ch

    def validate(self, q):
        if q["lights"] != 1:
            raise ValueError(f"lights: bump.method = angular shades one light (its pipeline "
                             f"rotates one L and one H), not {q['lights']}")

    @property
    def unit(self):
        return Unit.spec(**self.params)

    @property
    def latency(self):
        return 1 + self.unit.latency                     # the angles from the channels

    def describe(self):
        u = self.unit
        return {**super().describe(), "parts": [
            {"name": "rotation", "why": "L into N's frame", "latency": u.rotation.latency},
            {"name": "rotation", "why": "H into N's frame", "latency": u.rotation.latency},
            {"name": "illum", "why": "law of cosines, diffuse and specular tables",
             "latency": u.illum.latency}]}

    def rtl(self, p, v, uni):
        top, ab = VALUE.frac_bits, ANGLE_BITS            # turns: the top fraction bits
        ang = lambda key: v.pop(key)[top - ab:top]
        theta_b, phi_b = v.pop("_hi"), v.pop("_lo")
        v = p.stage(v, phi_n=ang("phin"), theta_n=ang("thetan"),
                    phi_b=(phi_b + ang("psi"))[:ab], theta_b=theta_b,
                    **{k: uni[k] for k in LIGHT})
        v = self.unit.datapath(p, v)
        v.pop("dot_l"), v.pop("dot_h")
        # diffuse (u16, 15 fraction bits) >> 1 is a value; specular >> 5 a power
        v["d0"] = Cat(v.pop("diffuse")[1:], Const(0, 1)).as_signed()
        v["p0"] = v.pop("specular")[5:]
        return v

    def inputs(self, prep, ch, bound):
        """The unit's inputs per fragment, as the RTL forms them: the channels' top
        ANGLE_BITS fraction bits, phi_B + psi; ``bound``: ``da`` (three offsets) added to the
        raw phi_N, theta_N and psi."""
        full = 1 << ANGLE_BITS
        da = bound.get("da", (0, 0, 0))
        code = lambda key, d: ((raw(ch[key]) + d) >> (VALUE.frac_bits - ANGLE_BITS)) & (full - 1)
        inp = {"phi_n": code("phin", da[0]), "theta_n": code("thetan", da[1]),
               "phi_b": (ch["_lo"] + code("psi", da[2])) & (full - 1), "theta_b": ch["_hi"]}
        inp.update({k: np.full(len(inp["phi_n"]), prep["uniforms"][k]) for k in LIGHT})
        return inp

    def ideal(self, prep, frag, ch):
        """Seed 003 on reals: the interpolated phi_N, theta_N, the texel's exact polar angles
        turned by psi, L and H rotated into N's frame by the scene's rotation (the paper's
        or the exact one), the law of cosines, the exact power."""
        turn = 2 * np.pi
        pn, tn, psi = (ch[k] * turn for k in ("phin", "thetan", "psi"))
        pb, tb = angular.to_polar(ch["_n"])
        rotate = angular.rotate_paper if self.q["rotation"] == "paper" else angular.rotate_exact
        dots = []
        for vec in (prep["float"]["L"][0], prep["float"]["H"][0]):
            pv, tv = angular.to_polar(vec)
            pr, tr = rotate(pn, tn, np.full_like(pn, pv), np.full_like(pn, tv))
            dots.append(np.clip(angular.inner_product(pr, tr, pb + psi, tb), 0, 1))
        ch = {k: x for k, x in ch.items() if k not in ("phin", "thetan", "psi", "_n")}
        return {**ch, "d0": dots[0], "p0": dots[1] ** self.shininess(prep["scene"])}

    def interval(self, prep, frag, ch, before):
        """The colour is monotone in d and p, so the RTL's lies between the model's at the
        least and largest of each over: the raw phi_N, theta_N and psi -1, 0, +1 (each can move
        its angle code by one), the texture coordinates -1, 0, +1, and the unit's own bound on
        diffuse and specular (``golden.angular.bump_polar_bounds``: the rotations' interval
        bounds through the illumination's tables), then >> 1 and >> 5 as the pipeline takes
        them."""
        lo, hi = {}, {}
        params = {**self.unit.params, "shininess": self.shininess(prep["scene"])}   # loaded
        for ds, dt in itertools.product((-1, 0, 1), repeat=2):
            for da in itertools.product((-1, 0, 1), repeat=3):
                bound = {"da": da, "ds": ds, "dt": dt}
                inp = self.inputs(prep, before(**bound), bound)
                out = angular.bump_polar_float(inp, **params)
                err = angular.bump_polar_bounds(inp, **params)
                for key, src, shift, scale in (("d0", "diffuse", 1, VALUE.lsb),
                                               ("p0", "specular", 5, 1)):
                    a = (np.floor(np.maximum(out[src] - err[src], 0)).astype(np.int64)
                         >> shift) * scale
                    b = (np.ceil(out[src] + err[src]).astype(np.int64) >> shift) * scale
                    lo[key] = np.minimum(lo.get(key, a), a)
                    hi[key] = np.maximum(hi.get(key, b), b)
        return lo, hi

    def model(self, prep, frag, ch, bound):
        """``golden.angular.bump_polar_float`` (rotations paper or exact, the illumination's
        tables), rounded to its u16 outputs; d = diffuse >> 1 (a value), p = specular >> 5."""
        out = angular.bump_polar_float(self.inputs(prep, ch, bound), **{
            **self.unit.params, "shininess": self.shininess(prep["scene"])})
        diffuse, specular = (np.rint(out[k]).astype(np.int64) for k in ("diffuse", "specular"))
        ch = {k: x for k, x in ch.items() if k not in ("phin", "thetan", "psi", "_hi", "_lo")}
        return {**ch, "d0": (diffuse >> 1) * VALUE.lsb, "p0": specular >> 5}
