"""The formats of per-fragment shading, stated once.

- ``VALUE`` (the raster's channel format, s16 with 14 fraction bits): N.L and N.H as the
  raster interpolates them, the interpolated normal's components, the light vectors L and H.
- ``POWER``: (N.H)^n, u11 with 10 fraction bits (1.0 is 1024 exactly).
- ``COEF``: a colour coefficient (ambient x colour, kd x light x colour, ks x light), u16 with
  14 fraction bits, range [0, 4): 10 fraction bits cost the exact method 1.1 dB and two
  lights 2.0 dB against their float ideals (``make accuracy``); 14 leave 0.2 at most, and a
  product by it still fits an 18 x 18 multiplier.
- ``LEVEL``: an 8-bit colour channel, round(255 x value), clamped.
"""
from ..fixed import Field, u
from ..setup_unit.formats import VALUE

POWER = u(11, 10)
COEF = u(16, 14)
LEVEL = u(8, 0, "1/255")
RGB = "rgb"
ONE = 1 << VALUE.frac_bits            # 1.0 in VALUE


def light_fields(lights, specular, *names):
    """``<name><k>`` for each light k and each name (``d`` and, with specular, ``s``...)."""
    return [Field(f"{n}{k}", VALUE) for k in range(lights) for n in names
            if specular or not n.startswith(("s", "h"))]


def colour_fields(lights, specular):
    return ([Field(f"amb_{c}", COEF) for c in RGB]
            + [Field(f"{t}{k}_{c}", COEF) for k in range(lights)
               for t in ("kd", "ks") if specular or t == "kd" for c in RGB])
