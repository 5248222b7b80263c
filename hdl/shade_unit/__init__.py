"""Per-fragment shading after the raster: per-pixel Phong (the quality reference), the specular
power from a table, and the colour sum. The scene pipeline (``scene.pipeline``) composes them."""
from .phong import Phong
from .power import PowerTable
from .colour import Colour

__all__ = ["Phong", "PowerTable", "Colour"]
