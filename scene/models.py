"""A scene's pipeline in its models: each stage's model with the RTL's formats
(``model``, ``model.png``), or its ideal on reals (``ideal``, ``ideal.png``); and the sets of
colours the RTL may give where a stage's bound is wider than a level (the tests' and
``make fuzz``'s checks)."""
import numpy as np

from hdl.shade_unit.formats import RGB

from .framebuffer import framebuffer

__all__ = ["model", "model_fragments", "run_models", "ideal", "bump_model", "polar_candidates",
           "fenney_candidates", "shade_fragments"]


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


def polar_candidates(prep, frag, ch):
    """fenney_polar's bound, per fragment: every colour the RTL may give, (choices, n, 3).
    The texel one either way along s and t (the raster's coordinates are within one LSB of
    the model's), and each lane's intensity one either way (fenney_polar is within
    ``golden.fenney.polar_bound``, 0.874, of the float eq 3, which the model rounds); the
    rest is exact (tests/test_bump_scenes.py)."""
    lanes = [("d" if t == "l" else "s") + str(k) for t, k in prep["bump"]["lanes"]]
    out = []
    for ds in (-1, 0, 1):
        for dt in (-1, 0, 1):
            for offs in np.ndindex(*(3,) * len(lanes)):
                off = {key: o - 1 for key, o in zip(lanes, offs)}
                c = {**ch, **bump_model(prep, frag, ch, ds=ds, dt=dt, offset=off)}
                out.append(shade_fragments(prep, c))
    return np.stack(out)


def fenney_candidates(prep, frag, ch):
    """phong with Fenney's power: every colour the RTL may give, (choices, n, 3). The power
    takes X = floor(s / 16); phong's RTL is within its derived bound b of the float s the
    model rounds, so where s lies within b of a multiple of 16 the RTL's X may be the next one
    either way, and at high concentrations one step of X is up to 63/1024 of the power (C =
    255, X 1021: 10 levels at ks 0.5 and a light of 1.3). Each light's s is tried at -b, 0
    and +b (the ends of the interval reach every X in it); the colour is then within 1 level
    of one of them."""
    stages = prep["pipeline"].stages[1:]
    phong = next(s for s in stages if s.name == "phong")
    lights = prep["params"]["lights"]
    b = phong.bounds(prep, ch)
    out = []
    for signs in np.ndindex(*(3,) * lights):
        off = {k: (signs[k] - 1) * b[f"s{k}"] for k in range(lights)}
        c = run_models(prep, frag, ch, stages, s_offset=off)
        out.append(np.stack([c[x] for x in RGB], -1))
    return np.stack(out).astype(np.int64)


def shade_fragments(prep, ch, frag=None):
    """The stages after the raster and the bump stages (phong, the power, colour) on the
    values ``ch``: rgb (n, 3)."""
    stages = [s for s in prep["pipeline"].stages[1:] if not s.bump]
    ch = run_models(prep, frag, ch, stages)
    return np.stack([ch[c] for c in RGB], -1).astype(np.uint8)
