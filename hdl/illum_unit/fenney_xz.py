"""The second embodiment end to end: texel_decode -> fenney_dot -> fenney_power."""
from ..unit import Unit
from .fenney_dot import FenneyDot
from .fenney_power import FenneyPower
from .texel_decode import TexelDecode


class FenneyXZ(Unit):
    """X/Z texel and interpolated light to shade, one per clock; latency = sum of the parts."""
    NAME = "fenney_xz"
    DOC = "Fenney X/Z bump shading: decode, dot, power (US 6,819,319, second embodiment)"
    PARAMS = FenneyDot.PARAMS
    RANGES = FenneyDot.RANGES
    inputs = (TexelDecode.inputs
              + tuple(f for f in FenneyDot.inputs if f.name in ("lx", "ly", "lz", "h"))
              + tuple(f for f in FenneyPower.inputs if f.name == "c"))
    outputs = FenneyPower.outputs + (TexelDecode.outputs[-1],)   # p, invalid

    def validate(self, **params):
        self.parts = (TexelDecode.spec(), FenneyDot.spec(**params), FenneyPower.spec())

    @property
    def latency(self):
        return sum(part.latency for part in self.parts)

    def datapath(self, p, v):
        for part in self.parts:
            v = part.datapath(p, v)
        return v
