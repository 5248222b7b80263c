"""The bump map in hardware: a texture ROM addressed by the raster's texture coordinates."""
from .texture import FILTERS, MAX_TEXTURE, fetch, fetch_latency, texture_lut, weight_bits

__all__ = ["FILTERS", "MAX_TEXTURE", "fetch", "fetch_latency", "texture_lut", "weight_bits"]
