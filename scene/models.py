"""A scene's pipeline in its models: each stage's model with the RTL's formats
(``model``, ``model.png``), or its ideal on reals (``ideal``, ``ideal.png``); and the sets of
colours the RTL may give where a stage's bound is wider than a level (the tests' and
``make fuzz``'s checks)."""
import numpy as np

from hdl.shade_unit.formats import RGB

from .framebuffer import framebuffer

__all__ = ["model", "model_fragments", "run_models", "ideal", "bump_model", "candidates",
           "interval", "within", "shade_fragments"]


def model(prep, **bound):
    """The float model of the scene's pipeline with the RTL's formats: each stage's model in
    turn (the raster's float model from the same raw inputs, then the stages' models of the
    same steps), the quantised uniforms, the same depth test. Returns (image, covered,
    fragments)."""
    frag, ch = model_fragments(prep)
    ch = run_models(prep, frag, ch, prep["pipeline"].stages[1:], **bound)
    rgb = np.stack([ch[c] for c in RGB], -1).astype(np.uint8)
    img, cov = framebuffer(prep["size"], frag["x"], frag["y"], ch["depth"], rgb,
                           prep["scene"]["image"]["background"])
    return img, cov, len(frag["x"])


def model_fragments(prep):
    """The raster's float model on the scene: its fragments, and the values by name."""
    return prep["pipeline"].raster.model(prep)


def run_models(prep, frag, ch, stages, **bound):
    """``stages``' models in turn on the values ``ch`` (by name) of fragments ``frag``;
    ``bound``: the tests' offsets, each stage takes those it knows (``scene/stages/``)."""
    ch = dict(ch)
    for stage in stages:
        ch = stage.model(prep, frag, ch, bound)
    return ch


def ideal(prep, formats=()):
    """The float ideal of the scene's pipeline: each stage's algorithm on reals with no
    format (the stages' ``ideal``: unrounded inputs, exact functions for tables, no rounding
    but the final colour's 8 bits), the same pixels and the depth test on its depth.
    Returns (image, covered). Against the reference it is the method's own error; the RTL
    against it, the formats'.

    ``formats``: groups of stages run as their models instead, with the RTL's formats (raster,
    texels, shading, power, colour: each stage's ``format_group``), so each group's own loss
    can be measured (``flows.losses``); all of them give the model's image."""
    stages = prep["pipeline"].stages
    modes = ["model" if s.format_group in formats else "ideal" for s in stages]
    frag, ch = stages[0].model(prep) if modes[0] == "model" else stages[0].ideal(prep)
    for stage, mode, was in zip(stages[1:], modes[1:], modes):
        for each in stages if mode != was else ():     # the values, as the stage takes them
            ch = each.convert(ch, mode == "ideal")
        ch = stage.model(prep, frag, ch, {}) if mode == "model" else stage.ideal(prep, frag, ch)
    rgb = np.stack([ch[c] for c in RGB], -1).astype(np.uint8)
    return framebuffer(prep["size"], frag["x"], frag["y"], ch["depth"], rgb,
                       prep["scene"]["image"]["background"])


def bump_model(prep, frag, ch, **bound):
    """The bump stages' models (texture fetch to N.L and N.H, or d and p for angular)."""
    return run_models(prep, frag, ch, [s for s in prep["pipeline"].stages if s.bump],
                      **bound)


def candidates(prep, frag, ch):
    """``(colours, slack)``: where a stage's bound is wider than a level, every colour the
    RTL may give, ``(choices, n, 3)``, each fragment's within ``slack`` levels of one of
    them (the last stage that gives them: ``Stage.candidates``); or None, the model's
    colour within a level."""
    for stage in reversed(prep["pipeline"].stages):
        colours = stage.candidates(prep, frag, ch)
        if colours is not None:
            return colours, stage.slack
    return None


def interval(prep, frag, ch):
    """``(lo, hi)``: where a stage's bound is an interval of the values it gives (the last
    that has one: ``Stage.interval``), their least and largest per fragment; or None."""
    stages = [s for s in prep["pipeline"].stages[1:] if s.bump]
    for k in reversed(range(len(stages))):
        before = lambda **bound: run_models(prep, frag, ch, stages[:k], **bound)
        span = stages[k].interval(prep, frag, ch, before)
        if span is not None:
            return span
    return None


def within(prep, frag, ch, rgb):
    """Per fragment, whether the RTL's colour ``rgb`` (n, 3) is one its stages' bounds allow
    (the fragments being the model's ``frag``, its values ``ch``): one of the ``candidates``
    within their slack; or between the colours at the ends of the ``interval``; or else
    within one level of the model's colour (the raster's values are within one LSB of
    2^-14 of its float model, which moves the 8-bit colour by far less than a level, and the
    shading units after it are bit-exact or within one: tests/test_scenes.py)."""
    rgb = np.asarray(rgb).astype(np.int64)
    bound = candidates(prep, frag, ch)
    if bound is not None:
        colours, slack = bound
        return np.abs(colours - rgb[None]).max(-1).min(0) <= slack
    span = interval(prep, frag, ch)
    if span is not None:
        c_lo, c_hi = (shade_fragments(prep, {**ch, **end}).astype(np.int64) for end in span)
        return ((rgb >= c_lo) & (rgb <= c_hi)).all(-1)
    want = shade_fragments(prep, bump_model(prep, frag, ch), frag).astype(np.int64)
    return np.abs(rgb - want).max(-1) <= 1


def shade_fragments(prep, ch, frag=None):
    """The stages after the raster and the bump stages (phong, the power, colour) on the
    values ``ch``: rgb (n, 3)."""
    stages = [s for s in prep["pipeline"].stages[1:] if not s.bump]
    ch = run_models(prep, frag, ch, stages)
    return np.stack([ch[c] for c in RGB], -1).astype(np.uint8)
