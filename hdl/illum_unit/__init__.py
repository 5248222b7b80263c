"""Illumination units: Fenney's bump texels (US 6,819,319) now; the law-of-cosines unit of
seed 003 comes with its own issue."""
from .texel_decode import TexelDecode
from .fenney_power import FenneyPower
from .fenney_dot import FenneyDot
from .fenney_xz import FenneyXZ
from .fenney_polar import FenneyPolar

__all__ = ["TexelDecode", "FenneyPower", "FenneyDot", "FenneyXZ", "FenneyPolar"]
