"""Scenes: the driver (a scene file to the hardware's inputs, the float images and the
framebuffer), the stages a scene's pipeline is made of (``stages/``, one file each, with its
channels, uniforms, parameters, checks, latency, RTL and model) and the composed top
(``pipeline.py``). Above ``hdl`` (the units) and ``golden`` (their models); ``sim`` uses it."""
from . import pipeline  # noqa: F401  (registers the scene pipeline with hdl.units)
