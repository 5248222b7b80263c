"""The bump map in hardware: texel fetch through a texel cache and the texture memory port."""
from .cache import ADDR, CACHE_LATENCY, request_fields, response_fields, texel_cache
from .texture import (FILTERS, MAX_TEXTURE, address_stages, banks, filter_stages, filtered,
                      lines, memory_image, weight_bits)

__all__ = ["ADDR", "CACHE_LATENCY", "FILTERS", "MAX_TEXTURE", "address_stages", "banks",
           "filter_stages", "filtered", "lines", "memory_image", "request_fields",
           "response_fields", "texel_cache", "weight_bits"]
