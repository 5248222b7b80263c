"""The scene driver (``design/scenes.md``): a scene file in, what the hardware takes out, and
the float images the RTL is compared with. Each job is a module of its own; this one names
them together for the tools:

- ``scene/parse.py``: ``load(path)`` and ``parse(data)``, every error naming the key;
  ``pipeline_params(scene)``;
- ``scene/mesh.py``: the mesh in world space, the turntable, texture coordinates and
  tangent frames;
- ``scene/prepare.py``: ``prepare(scene)``: the view, the culling, the raster's inputs, the
  stages' data and the host port's load; ``rtl_inputs(prep)``;
- ``scene/models.py``: ``model(prep)`` (``model.png``), ``ideal(prep)`` (``ideal.png``) and
  the colours a stage's bound allows;
- ``scene/framebuffer.py``: the depth test and ``reference(prep)`` (``reference.png``).

The effects' own parts (scene keys, encodings, constants, conversions) are the stages'
(``scene/stages/``); nothing here names one.
"""
from .framebuffer import framebuffer, reference
from .mesh import mesh, orientation, tangent_frames, \
    texcoords, turn, unit
from .models import (bump_model, candidates, ideal, interval, model, model_fragments,
                     run_models, shade_fragments, within)
from .parse import DEFAULTS, RULES, SceneError, load, parse, pipeline_params, tables
from .prepare import prepare, rtl_inputs, view

__all__ = ["SceneError", "DEFAULTS", "RULES", "tables", "load", "parse", "pipeline_params", "mesh",
           "orientation", "tangent_frames", "texcoords", "turn", "unit", "prepare", "view",
           "rtl_inputs", "model", "model_fragments", "run_models", "ideal", "bump_model",
           "candidates", "interval", "within", "shade_fragments", "framebuffer",
           "reference"]
