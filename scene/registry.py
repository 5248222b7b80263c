"""The stages a scene's pipeline is chosen from, and every list derived from them.

The project's own stages (``scene/stages/``) come first; a stage of one's own joins them
without an edit to the project, in any of three ways:

- ``scene.registry.register(MyStage)`` from Python (``registered(MyStage)``: for a while);
- the entry-point group ``shading_hw.stages`` of an installed package, each entry a stage
  class (``[project.entry-points."shading_hw.stages"] mine = "my_pkg.mine:Mine"``);
- ``SHADING_STAGES``: Python files or module names, separated by ``os.pathsep``; each
  :class:`~scene.stage.Stage` subclass a file defines (and names) is registered, in order.

The last two are read the first time the stages are asked for, so every tool (``python -m
sim``, the gallery, ``make tradeoffs``, ``make formal``, ``make fuzz``) sees them. Each stage
is checked as it is registered (:func:`check`): a missing required hook, a name that is
taken, a channel mode the raster does not have is one :class:`~scene.stage.StageError`
naming the stage and the hook. The choices of the scene's keys (``method``, ``power``,
``bump``), the build parameters and their ranges are computed from the stages as they are
when asked, never at import.
"""
import importlib
import importlib.util
import os
from contextlib import contextmanager
from importlib.metadata import entry_points
from pathlib import Path

from hdl.setup_unit.formats import MODES

from .stage import Stage, StageError
from .stages.bump_polar import BumpPolar
from .stages.colour import Colour
from .stages.fenney_dot import FenneyDot
from .stages.fenney_polar import FenneyPolar
from .stages.fenney_power import FenneyPower
from .stages.phong import Phong
from .stages.power_table import PowerTable
from .stages.raster import Raster
from .stages.texel_decode import TexelDecode
from .stages.texture import Texture

__all__ = ["register", "unregister", "registered", "stages", "check", "methods", "powers",
           "bumps", "choices", "build_params", "ENTRY_POINTS", "ENV"]

ENTRY_POINTS = "shading_hw.stages"
ENV = "SHADING_STAGES"
# the pipeline's order: the raster, the bump stages, phong, the power, the colour
BUILTIN = (Raster, Texture, TexelDecode, FenneyDot, FenneyPolar, BumpPolar, Phong, PowerTable,
           FenneyPower, Colour)
# the keys whose values choose stages (the first value of each is the default), and the
# pipeline's own parameters, which no stage may take
CHOICE_KEYS = ("method", "power", "bump")
OWN = ("screen_bits", "sub_bits", "lights", "specular", *CHOICE_KEYS)

_stages = list(BUILTIN)
_loaded = False


def _plugins():
    """The stages named outside the tree: the entry points', then ``SHADING_STAGES``'."""
    global _loaded
    if _loaded:
        return
    _loaded = True
    for ep in entry_points(group=ENTRY_POINTS):
        try:
            cls = ep.load()
        except Exception as e:
            raise StageError(f"entry point {ep.name} = {ep.value} ({ENTRY_POINTS}): cannot "
                             f"load it: {type(e).__name__}: {e}") from None
        register(cls)
    for item in filter(None, os.environ.get(ENV, "").split(os.pathsep)):
        for cls in _module_stages(item):
            register(cls)


def _module_stages(item):
    """The stage classes a file or module (``SHADING_STAGES``'s item) defines, in order."""
    try:
        if item.endswith(".py"):
            path = Path(item)
            if not path.is_file():
                raise StageError(f"{ENV}: {item}: no such file")
            spec = importlib.util.spec_from_file_location(f"shading_stage_{path.stem}", path)
            mod = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(mod)
        else:
            mod = importlib.import_module(item)
    except StageError:
        raise
    except Exception as e:
        raise StageError(f"{ENV}: {item}: cannot import it: {type(e).__name__}: {e}") \
            from None
    found = [v for v in vars(mod).values() if isinstance(v, type) and issubclass(v, Stage)
             and v.__module__ == mod.__name__ and v.name]
    if not found:
        raise StageError(f"{ENV}: {item}: defines no Stage subclass with a name")
    return found


def stages():
    """The registered stages, in the pipeline's order (the raster first)."""
    _plugins()
    return tuple(_stages)


def _overrides(cls, hook):
    return getattr(cls, hook, None) is not getattr(Stage, hook)


def check(cls, taken=None):
    """A stage class checked before it joins: ``StageError`` naming the stage and the hook."""
    if not (isinstance(cls, type) and issubclass(cls, Stage)):
        raise StageError(f"{cls!r}: not a scene.stage.Stage subclass")
    who = f"{cls.__module__}.{cls.__qualname__}"
    if not isinstance(cls.name, str) or not cls.name.isidentifier():
        raise StageError(f"stage {who}: name: must be a Python identifier (the submodule's "
                         f"name in the top), not {cls.name!r}")
    who = f"stage {cls.name!r}"
    for other in taken if taken is not None else _stages:
        if other.name == cls.name and other is not cls:
            raise StageError(f"{who}: name: taken by {other.__module__}."
                             f"{other.__qualname__}")
    for hooks in Stage.REQUIRED:
        if not any(_overrides(cls, h) for h in hooks):
            raise StageError(f"{who}: {' or '.join(hooks)}: missing (required: "
                             f"{', '.join('/'.join(h) for h in Stage.REQUIRED)}; "
                             f"scene/stage.py)")
    if isinstance(cls.channels, (tuple, list)):
        for c in cls.channels:
            if not (isinstance(c, tuple) and len(c) == 3):
                raise StageError(f"{who}: channels: each is (name, mode, group), not {c!r}")
            if c[1] not in MODES:
                raise StageError(f"{who}: channels: {c[0]!r} has mode {c[1]!r}; the raster's "
                                 f"modes are {', '.join(MODES)}")
    if cls.interpolates is not None and cls.interpolates not in MODES:
        raise StageError(f"{who}: interpolates: {cls.interpolates!r} is not one of the "
                         f"raster's modes ({', '.join(MODES)})")
    if not isinstance(cls.when, dict):
        raise StageError(f"{who}: when: must be a dict of parameters' values, not "
                         f"{cls.when!r}")
    if "method" in cls.when:
        if cls.when["method"] in MODES:
            raise StageError(f"{who}: when: method {cls.when['method']!r} is the raster's "
                             f"own mode; a method of its own needs a name of its own")
        if "lighting" not in cls.gives and cls.interpolates is None:
            raise StageError(f"{who}: interpolates: a shading method's stage says in which "
                             f"of the raster's modes ({', '.join(MODES)}) N.L and N.H are "
                             f"interpolated, or gives them (gives = ('lighting',))")
    clash = sorted(set(cls.build_params) & set(OWN))
    if clash:
        raise StageError(f"{who}: build_params: {clash[0]!r} is the pipeline's own parameter")
    if cls.before is not None:
        names = [s.name for s in (taken if taken is not None else _stages)]
        if cls.before not in names or cls.before == BUILTIN[0].name:
            raise StageError(f"{who}: before: {cls.before!r} names no stage it can go "
                             f"before (known: {', '.join(names[1:])})")
    return cls


def register(cls):
    """Add a stage class to the pipeline's choices, checked (:func:`check`): before the
    stage its ``before`` names, or after the last. Registering it again changes nothing."""
    _plugins()
    if cls in _stages:
        return cls
    check(cls)
    at = len(_stages) if cls.before is None else \
        [s.name for s in _stages].index(cls.before)
    _stages.insert(at, cls)
    return cls


def unregister(cls):
    """Take a stage of one's own out again (the project's own stay)."""
    if cls in BUILTIN:
        raise StageError(f"stage {cls.name!r}: one of the project's own; it stays")
    if cls in _stages:
        _stages.remove(cls)


@contextmanager
def registered(*classes):
    """The stages registered for a while (a test, a script), then taken out again."""
    added = [cls for cls in classes if cls not in stages()]
    try:
        for cls in added:
            register(cls)
        yield
    finally:
        for cls in added:
            unregister(cls)


def _choices(key):
    return tuple(dict.fromkeys(s.when[key] for s in stages() if key in s.when))


def methods():
    """The shading methods, the default first: ``{name: the raster's mode for N.L and N.H,
    or None where a stage gives them}``: the raster's own modes, then each method a stage
    is wanted for (``when = {"method": ...}``)."""
    out = {m: m for m in Raster.methods}
    for s in stages():
        if "method" in s.when:
            out.setdefault(s.when["method"], s.interpolates)
    return out


def powers():
    """The power kinds, the default first."""
    return _choices("power")


def bumps():
    """The bump methods: none (the default), then each a stage is wanted for."""
    return ("none",) + _choices("bump")


def choices():
    """``{key: values}``: the scene keys that choose stages, the first value the default."""
    return {"method": tuple(methods()), "power": powers(), "bump": bumps()}


def build_params():
    """The pipeline's parameters the stages own: ``{name: (default, range)}``."""
    return {k: v for s in stages() for k, v in s.build_params.items()}
