"""The angular vector rotation of seed 003 (§3.1, eq 5-27, Fig 7), the published method.

A = (phi_A, theta_A) into the frame where N = (phi_N, theta_N) is the z axis, with
D = phi_A - phi_N, X = theta_A + D, Y = theta_A - D::

    theta_x = asin((sin X + sin Y) / 2)            (eq 5-7)
    Z       = theta_x - theta_N
    phi'    = atan((cos Y - cos X) / (2 sin Z))    (eq 8-9)
    yk      = (cos Y - cos X) / (2 cos Z)          (eq 27)
    theta'  = Z + (90 - Z) (1 - acos(yk) / 90)     (eq 19, 21; the bracket is table Tprop)

Datapath (21 stages, one vector per clock; every table read at a registered address and its
output registered twice, every multiplier alone in its stage): four sin/cos look-ups (one quarter-wave table
generator, folded); an adder and a subtractor; an asin table; Z and its folds; two reciprocal
tables, 1/(2 sin) and 1/(2 cos), in one generator ("the reciprocal folded into them"); the two
ratio multipliers; an atan table with a floating-point address (the ratio is unbounded) and
the Tprop table; the proportion multiplier. Three multipliers in all, as Fig 7.

The decisions for the cases the paper leaves open are golden.angular.rotate_paper's: Z wrapped
into (-180, 180] deg, phi' by quadrant from the signs of Z and of the numerator (atan2),
theta' from |Z|, |yk| clamped to 1, and 1/(2 sin 0) saturated at the table's first entry,
1/(2 sin(half an angle step)).

Formats: every angle u``angle_bits`` in turns. Bounds against the float model:
golden.angular.rotation_bounds, by interval arithmetic over every table's measured error.
"""
import functools

import numpy as np
from amaranth.hdl import Cat, Const, Mux

from ..fixed import Field, Fixed, align, binary_angle, u
from ..arith import products
from ..dsp import Product
from ..lut import build_lut, float_address, float_bins, quarter_cos_lut, rom
from ..trig import cos_address, signed_cos
from ..unit import Unit

RECIP_FRAC = 16          # 1/(2 sin a) and 1/(2 cos a): 16 fraction bits
PROP_FRAC = 16           # theta_prop: 1.0 = 2**16
ATAN_EXP_LO = 8          # the atan table's address: 2**-8 .. 2**(angle_bits - 2) in octaves
CORDIC_FRAC = 20         # the exact rotation's CORDIC datapath: 20 fraction bits (x', y', z' < 1)
ANGLE_GUARD = 8          # its angle accumulators: 8 bits below the output angle's LSB
GAIN_FRAC = 11           # the CORDIC gain K in z' * K: 11 fraction bits


def cordic_gain(iters):
    """K = prod sqrt(1 + 2**-2i): a vectoring CORDIC of ``iters`` steps lengthens by it."""
    return float(np.prod(np.sqrt(1 + 4.0 ** -np.arange(iters))))


@functools.lru_cache(maxsize=None)
def cordic_angles(iters, bits):
    """atan(2**-i) in turns * 2**bits, rounded: the micro-rotations' angles."""
    return tuple(int(round(np.arctan(2.0 ** -i) / (2 * np.pi) * 2**bits)) for i in range(iters))


@functools.lru_cache(maxsize=None)
def asin_lut(addr_bits, angle_bits):
    """asin(x) in turns * 2**angle_bits for x in [0, 1]."""
    return build_lut(lambda x: np.arcsin(np.clip(x, 0, 1)) / (2 * np.pi), addr_bits,
                     Fixed(angle_bits - 1, False, angle_bits, "turn"), domain=(0.0, 1.0))


@functools.lru_cache(maxsize=None)
def recip_sin_lut(angle_bits):
    """1 / (2 sin a) for a = 0..90 deg in angle steps; a = 0 holds the value at half a step."""
    step = 2 * np.pi / 2**angle_bits
    top = 1 / (2 * np.sin(step / 2))
    width = int(np.ceil(np.log2(top))) + 1 + RECIP_FRAC
    return build_lut(lambda a: 1 / (2 * np.sin(np.maximum(a, 0.5) * step)), angle_bits - 1,
                     u(width, RECIP_FRAC), depth=2**(angle_bits - 2) + 1)


@functools.lru_cache(maxsize=None)
def atan_lut(mant_bits, angle_bits):
    """atan(r) in turns * 2**angle_bits over r in [0, 2**(angle_bits-2)), float-addressed."""
    edges = float_bins(ATAN_EXP_LO, angle_bits - 2, mant_bits)
    return build_lut(lambda r: np.arctan(r) / (2 * np.pi), int(np.ceil(np.log2(len(edges) - 1))),
                     Fixed(angle_bits - 1, False, angle_bits, "turn"), edges=edges)


@functools.lru_cache(maxsize=None)
def prop_lut(addr_bits):
    """Tprop(yk) = 1 - acos(yk) / 90 deg for yk in [0, 1] (eq 21, 26)."""
    return build_lut(lambda y: 1 - np.arccos(np.clip(y, 0, 1)) / (np.pi / 2), addr_bits,
                     u(PROP_FRAC + 1, PROP_FRAC), domain=(0.0, 1.0))


def addsub(a, b, sub):
    """a + b, or a - b where ``sub``: one adder, b's bits inverted and ``sub`` its carry in
    (a - b = a + ~b + 1)."""
    return a + Mux(sub, ~b, b) + sub


class Rotation(Unit):
    """Seed 003's vector rotation (or the exact one), one vector per clock, three multipliers."""
    NAME = "rotation"
    DOC = "Angular vector rotation: the published method (seed 003 §3.1, Fig 7) or exact"
    PARAMS = {"method": "paper", "angle_bits": 12, "trig_bits": 14, "asin_bits": 12,
              "atan_bits": 8, "prop_bits": 12, "iterations": 16}

    RANGES = {"method": ("paper", "exact"), "angle_bits": (6, 16), "trig_bits": (8, 16),
              "asin_bits": (4, 16), "atan_bits": (2, 10), "prop_bits": (4, 16),
              "iterations": (4, 20)}

    def validate(self, method, angle_bits, trig_bits, asin_bits, atan_bits, prop_bits,
                 iterations):
        if asin_bits > trig_bits + 1:
            raise ValueError(f"asin_bits must be at most trig_bits + 1 = {trig_bits + 1}, "
                             f"not {asin_bits}")

    def angle(self, name):
        return Field(name, binary_angle(self.params["angle_bits"]))

    @property
    def inputs(self):
        return tuple(self.angle(n) for n in ("phi_n", "theta_n", "phi_a", "theta_a"))

    @property
    def outputs(self):
        return (self.angle("phi"), self.angle("theta"))

    @property
    def latency(self):
        """21 stages (the paper's); the exact rotation: 12 + a stage per micro-rotation."""
        return 21 if self.params["method"] == "paper" else 12 + 2 * self.params["iterations"]

    @property
    def tables(self):
        n, p = self.params["angle_bits"], self.params
        trig = {"trig": quarter_cos_lut(p["trig_bits"], 1 << (n - 2))}
        if p["method"] == "exact":
            return trig
        return {**trig, "asin": asin_lut(p["asin_bits"], n), "recip": recip_sin_lut(n),
                "atan": atan_lut(p["atan_bits"], n), "prop": prop_lut(p["prop_bits"])}

    def asin_address(self, magnitude, frac):
        """The asin table's address for an unsigned fixed-point value (``frac`` fraction bits,
        1.0 = 2**frac), saturated at the table's last bin."""
        top = (1 << self.params["asin_bits"]) - 1
        addr = magnitude >> (frac - self.params["asin_bits"])
        return Mux(addr > top, top, addr)

    def read(self, p, v, **reads):
        """Table reads ``key=(table, address key)`` (the addresses ``v[...]`` consumed),
        registered twice: the RAM's own read register, then a register before any logic."""
        v = p.stage(v, **{k: rom(self.tables[tab], v.pop(a), k)
                          for k, (tab, a) in reads.items()})
        return p.stage(v)

    def lookups(self, p, v, angles):
        """Cosine look-ups of ``{name: binary angle}``: the folded addresses and sign bits
        registered, then the reads (three stages); ``v[name]`` signed, 1.0 = 2**trig_bits."""
        bits = self.params["angle_bits"]
        new = {}
        for key, a in angles.items():
            new[f"_a{key}"], new[f"{key}_neg"] = cos_address(self.tables["trig"], a, bits)
        v = p.stage(v, **new)
        v = self.read(p, v, **{key: ("trig", f"_a{key}") for key in angles})
        return {**v, **{key: signed_cos(v.pop(key), v.pop(f"{key}_neg")) for key in angles}}

    def datapath(self, p, v):
        """Every table read at registered addresses and registered twice, every multiplier
        alone in its stage; 21 stages."""
        if self.params["method"] == "exact":
            return self.datapath_exact(p, v)
        n, t = self.params["angle_bits"], self.params["trig_bits"]
        quarter, half = 1 << (n - 2), 1 << (n - 1)
        v = dict(v)
        p_n, t_a, p_a = v.pop("phi_n"), v.pop("theta_a"), v.pop("phi_a")
        v = p.stage(v, _tp=t_a + (p_a - p_n), _tm=t_a - (p_a - p_n))          # X, Y
        tp, tm = v.pop("_tp"), v.pop("_tm")
        v = self.lookups(p, v, {"sx": tp - quarter, "sy": tm - quarter,          # 4 look-ups
                                "cx": tp, "cy": tm})                             # sin = cos(a - 90)
        v = p.stage(v, s2=v.pop("sx") + v.pop("sy"), n2=v.pop("cy") - v.pop("cx"))  # 2 sin thx
        s2, n2 = v.pop("s2"), v.pop("n2")
        v = p.stage(v, _as2=abs(s2), s_neg=s2 < 0, n_neg=n2 < 0, n_abs=abs(n2))
        v = p.stage(v, _aa=self.asin_address(v.pop("_as2"), t + 1))
        v = self.read(p, v, thx=("asin", "_aa"))
        thx = Mux(v.pop("s_neg"), -v["thx"], v.pop("thx"))
        v = p.stage(v, z=(thx - v.pop("theta_n"))[:n].as_signed())              # Z in (-180, 180]
        z = v.pop("z")
        v = p.stage(v, az=abs(z), z_neg=z < 0)
        az = v["az"]
        v = p.stage(v, _fs=Mux(az > quarter, half - az, az),                     # |sin Z| = sin fs
                    _fc=Mux(az > quarter, az - quarter, quarter - az),           # |cos Z| = sin fc
                    _rest=quarter - az)
        v = self.read(p, v, rs=("recip", "_fs"), rc=("recip", "_fc"))
        frac = t + RECIP_FRAC
        n_abs = v["n_abs"]
        v = products(p, {**v, "_nb": n_abs}, {"ratio": ("n_abs", "rs"), "yk": ("_nb", "rc")})
        ratio, yk = v.pop("ratio"), v.pop("yk")
        ptop = (1 << self.params["prop_bits"]) - 1
        paddr = yk >> (frac - self.params["prop_bits"])
        v = p.stage(v, _am=float_address(ratio, frac, ATAN_EXP_LO, n - 2, self.params["atan_bits"]),
                    _ap=Mux(paddr > ptop, ptop, paddr))
        v = self.read(p, v, pm=("atan", "_am"), prop=("prop", "_ap"))
        v = p.stage(v, _pr=v.pop("_rest") * v.pop("prop"))
        theta = v.pop("az") + ((v.pop("_pr") + (1 << (PROP_FRAC - 1))) >> PROP_FRAC)
        return p.stage(v, **self.quadrant(v.pop("z_neg"), v.pop("n_neg"), v.pop("pm")),
                       theta=theta[:n])

    def quadrant(self, x_neg, y_neg, magnitude):
        """phi' from its first-quadrant magnitude and the signs of x' and y' (atan2)."""
        half = 1 << (self.params["angle_bits"] - 1)
        base = Mux(x_neg, half - magnitude, magnitude)
        return {"phi": Mux(y_neg, -base, base)[:self.params["angle_bits"]]}

    def datapath_exact(self, p, v):
        """Beyond the paper: the exact rotation, A' = Ry(-tN) Rz(-phiN) A, in Cartesian form
        from the same cosine table, its angles by two vectoring CORDICs (shift and add):

            z' = cos theta' = 1/2 [cos(tA - tN) + cos(tA + tN)] + 1/2 [cos(tA - tN) - cos(tA + tN)] cos D
            x' = sin tA cos D cos tN - cos tA sin tN,  y' = sin tA sin D
            |phi'| = atan2(|y'|, |x'|), and K r = K sqrt(x'^2 + y'^2)          (CORDIC 1)
            theta' from atan2(K r, K |z'|)                                    (CORDIC 2)

        phi' by quadrant from the signs of x' and y', theta' = 180 deg - that where z' < 0. An
        angle from its tangent keeps its precision everywhere: the arcsine and arccosine of
        the first version were steep where theta' -> 0 and |phi'| -> 90 deg (1.6 deg off
        there, from 14-bit cosines). Three multipliers (two products, z' * K); latency
        12 + 2 iterations (44 at the default 16)."""
        n, t = self.params["angle_bits"], self.params["trig_bits"]
        quarter, half = 1 << (n - 2), 1 << (n - 1)
        F, iters = CORDIC_FRAC, self.params["iterations"]
        v = dict(v)
        p_n, t_a, p_a = v.pop("phi_n"), v["theta_a"], v.pop("phi_a")
        v = p.stage(v, d=p_a - p_n, _tp=t_a + (p_a - p_n), _tm=t_a - (p_a - p_n))
        t_n, t_a, d, tp, tm = (v.pop(k) for k in ("theta_n", "theta_a", "d", "_tp", "_tm"))
        v = self.lookups(p, v, {                                            # 10 look-ups
            "sx": tp - quarter, "sy": tm - quarter, "cx": tp, "cy": tm,
            "cm": t_a - t_n, "cp": t_a + t_n, "cd": d, "cn": t_n,
            "sp": t_n + t_a - quarter, "sm": t_n - t_a - quarter})
        c = {k: v.pop(k) for k in ("sx", "sy", "cx", "cy", "cm", "cp", "cd", "cn", "sp", "sm")}
        v = p.stage({**v, "s2": c["sx"] + c["sy"], "n2": c["cy"] - c["cx"],   # 2 sin tA cos D, 2 y'
                     "csum": c["cm"] + c["cp"], "cdiff": c["cm"] - c["cp"],
                     "ssum": c["sp"] + c["sm"], "cd": c["cd"], "cn": c["cn"]})  # 2 cos tA sin tN
        v = p.stage(v, pc=Product(v.pop("cdiff"), v.pop("cd")),         # MULT18X18D registers
                    px=Product(v.pop("s2"), v.pop("cn")))
        v = p.stage(v)
        v = p.stage(v, c2=(v.pop("csum") << t) + v.pop("pc"),              # 2 z', 2t bits
                    x2=v.pop("px") - (v.pop("ssum") << t))                 # 2 x', 2t bits
        c2, x2, n2 = v.pop("c2"), v.pop("x2"), v.pop("n2")
        z17 = align(abs(c2), 2 * t + 1, GAIN_FRAC + 6)                     # |z'|, 17 bits
        v = p.stage(v, _x=align(abs(x2), 2 * t + 1, F), _y=align(abs(n2), t + 1, F),
                    _z=z17[:GAIN_FRAC + 7], c_neg=c2 < 0, x_neg=x2 < 0, y_neg=n2 < 0)
        k = int(round(cordic_gain(iters) * 2**GAIN_FRAC))
        v = self.cordic(p, v, "_x", "_y", "_pm",                             # z' K beside it
                        carry={"_kz": Product(v.pop("_z"), Const(k, GAIN_FRAC + 1))})
        kz = v.pop("_kz")
        v = p.stage(v, _pm=self.rounded(v.pop("_pm")), _x=align(kz, GAIN_FRAC + 17, F),
                    _y=v.pop("_x"))                                        # (K |z'|, K r)
        phi = self.quadrant(v.pop("x_neg"), v.pop("y_neg"), v.pop("_pm"))
        v = self.cordic(p, v, "_x", "_y", "_tm", carry=phi)
        v = p.stage(v, _tm=self.rounded(v.pop("_tm")))
        tm = v.pop("_tm")
        return p.stage(v, theta=Mux(v.pop("c_neg"), half - tm, tm)[:n])

    @staticmethod
    def rounded(acc):
        """An accumulated angle to the output's binary angle, rounded to nearest."""
        return (acc + (1 << (ANGLE_GUARD - 1))) >> ANGLE_GUARD

    def cordic(self, p, v, x, y, angle, carry=None):
        """A vectoring CORDIC, one micro-rotation a stage: (v[x], v[y]), x >= 0, turned onto
        the x axis; ``v[angle]`` (new) accumulates the angle turned, atan2(y, x), in turns *
        2**(angle_bits + ANGLE_GUARD); v[x] ends as K sqrt(x^2 + y^2). ``carry``: values
        computed in the first stage beside it."""
        n, F = self.params["angle_bits"], CORDIC_FRAC
        width, awidth = F + 3, n + ANGLE_GUARD + 1                     # |x|, |y| < 4
        fit = lambda e, w: e[:w].as_signed()
        acc = None
        for i, a in enumerate(cordic_angles(self.params["iterations"], n + ANGLE_GUARD)):
            xv, yv = (u if u.shape().signed else Cat(u, Const(0, 1)).as_signed()  # zero-extended
                      for u in (v.pop(x), v.pop(y)))
            up = yv < 0                                     # turn anticlockwise, or not
            new = {x: fit(addsub(xv, yv >> i, up), width),     # x - y 2^-i where y < 0
                   y: fit(addsub(yv, xv >> i, ~up), width),    # y - x 2^-i where y >= 0
                   angle: fit(Mux(up, -a, a) if acc is None else acc + Mux(up, -a, a),
                              awidth)}
            v = p.stage(v, **new, **(carry if i == 0 and carry else {}))
            acc = v.pop(angle)
            v[angle] = acc
        return v
