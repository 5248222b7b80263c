"""The forward-difference span engine (seeds 000, 001) and ``raster``, setup -> span."""
from .raster import Raster

__all__ = ["Raster"]
