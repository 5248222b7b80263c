"""Illumination units: Fenney's bump texels (US 6,819,319) and the law-of-cosines unit of
seed 003."""
from .texel_decode import TexelDecode
from .fenney_power import FenneyPower
from .fenney_dot import FenneyDot
from .fenney_xz import FenneyXZ
from .fenney_polar import FenneyPolar
from .illum import Illum
from .bump_polar import BumpPolar
from .peercy import Peercy

__all__ = ["TexelDecode", "FenneyPower", "FenneyDot", "FenneyXZ", "FenneyPolar", "Illum", "BumpPolar",
           "Peercy"]
