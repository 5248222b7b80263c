"""Seed 003's bump mapping end to end: L and H rotated into the frame of the surface normal N,
then the law-of-cosines illumination against the bump normal B from the bump map.

In ``phi_n theta_n phi_l theta_l phi_h theta_h phi_b theta_b``; out as ``illum``. The two
rotations run one after the other on one pipeline (the H angles ride along through the first),
so the latency is twice the rotation's (21 for the paper's, 44 for the exact one) + 11, and the
throughput one vector pair per clock.
"""
from ..rotation_unit import Rotation
from ..unit import Unit
from .illum import Illum

# angles shared by both parts; each part keeps its own table parameters
ROTATION_PARAMS = ("method", "angle_bits", "trig_bits", "asin_bits", "atan_bits", "prop_bits",
                   "iterations")


class BumpPolar(Unit):
    """rotation(N, L) -> rotation(N, H) -> illum(L', H', B)."""
    NAME = "bump_polar"
    DOC = "Angular bump mapping: two rotations and the law-of-cosines illumination (seed 003)"
    PARAMS = {**Rotation.PARAMS, "table_bits": 10, "shininess": 16}
    RANGES = {**{k: Illum.RANGES[k] for k in ("table_bits", "shininess")}, **Rotation.RANGES}

    def validate(self, **params):
        self.rotation = Rotation.spec(**{k: params[k] for k in ROTATION_PARAMS})
        self.illum = Illum.spec(angle_bits=params["angle_bits"],
                                trig_bits=params["trig_bits"],
                                table_bits=params["table_bits"],
                                shininess=params["shininess"])

    @property
    def inputs(self):
        a = self.rotation.angle
        return tuple(a(n) for n in ("phi_n", "theta_n", "phi_l", "theta_l", "phi_h",
                                    "theta_h", "phi_b", "theta_b"))

    @property
    def outputs(self):
        return self.illum.outputs

    @property
    def latency(self):
        return 2 * self.rotation.latency + self.illum.latency

    def datapath(self, p, v):
        v = dict(v)
        normal = {"n_phi": v["phi_n"], "n_theta": v.pop("theta_n")}
        v = {**v, **normal, "theta_n": normal["n_theta"],
             "phi_a": v.pop("phi_l"), "theta_a": v.pop("theta_l")}
        v = self.rotation.datapath(p, v)                                   # L'
        v["phi_l"], v["theta_l"] = v.pop("phi"), v.pop("theta")
        v.update(phi_n=v.pop("n_phi"), theta_n=v.pop("n_theta"),
                 phi_a=v.pop("phi_h"), theta_a=v.pop("theta_h"))
        v = self.rotation.datapath(p, v)                                   # H'
        v["phi_h"], v["theta_h"] = v.pop("phi"), v.pop("theta")
        v["phi_n"], v["theta_n"] = v.pop("phi_b"), v.pop("theta_b")       # the bump normal
        return self.illum.datapath(p, v)
