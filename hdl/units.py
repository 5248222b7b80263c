# amaranth: UnusedElaboratable=no
"""The registry of units: name -> component class. The CLI, the tests and the Verilog export
all go through it, so a unit registered here is exported, linted, simulated and described."""
from .illum_unit import (BumpPolar, FenneyDot, FenneyPolar, FenneyPower, FenneyXZ, Illum,
                         Peercy, TexelDecode)
from .rotation_unit import Rotation
from .shade_unit import Colour, Phong, PowerTable
from .span_unit import Raster
from .unit import Unit

UNITS = {cls.NAME: cls for cls in (TexelDecode, FenneyPower, FenneyDot, FenneyXZ, FenneyPolar,
                                   Illum, Rotation, BumpPolar, Peercy, Raster, Phong,
                                   PowerTable, Colour)}


# Composed designs: built by make_unit and every simulator like a unit, not listed as units.
# They register here from the package above (``scene.pipeline``: a scene's stages), which
# ``sim`` imports, so hdl imports nothing of the layers above it.
PIPELINES = {}


def _pipelines():
    return PIPELINES


class ParamError(ValueError):
    pass


def parse_params(name, pairs):
    """``["NAME=VALUE", ...]`` -> dict, typed like the unit's defaults."""
    cls = UNITS.get(name) or _pipelines()[name]
    out = {}
    for pair in pairs or ():
        key, sep, text = pair.partition("=")
        if not sep:
            raise ParamError(f"--param {pair!r}: expected NAME=VALUE")
        if key not in cls.PARAMS:
            raise ParamError(f"{name}: unknown parameter {key!r}; "
                             f"known: {', '.join(cls.PARAMS) or 'none'}")
        default = cls.PARAMS[key]
        if isinstance(default, bool):
            if text.lower() not in ("true", "false", "1", "0"):
                raise ParamError(f"{name}: parameter {key} must be true or false, not {text!r}")
            out[key] = text.lower() in ("true", "1")
        elif isinstance(default, float):
            try:
                out[key] = float(text)
            except ValueError:
                raise ParamError(f"{name}: parameter {key} must be a number, not {text!r}") from None
        elif isinstance(default, int):
            try:
                out[key] = int(text, 0)
            except ValueError:
                raise ParamError(f"{name}: parameter {key} must be an integer, not {text!r}") from None
        else:
            out[key] = text
    return out


def make_unit(name, *, spec=False, **params) -> Unit:
    """A unit to elaborate, or with ``spec=True`` one used only for its formats and params."""
    cls = UNITS.get(name) or _pipelines().get(name)
    if cls is None:
        raise ParamError(f"unknown unit {name!r}; known: {', '.join(UNITS)}")
    try:
        return cls.spec(**params) if spec else cls(**params)
    except (TypeError, ValueError) as e:
        raise ParamError(str(e)) from None


def describe(name):
    unit = (UNITS.get(name) or _pipelines()[name]).spec()
    return {"name": name, "doc": unit.DOC, "params": dict(unit.PARAMS),
            "param_ranges": unit.param_ranges(),
            "latency": unit.latency,
            "inputs": [f.describe() for f in unit.inputs],
            "outputs": [f.describe() for f in unit.outputs]}
