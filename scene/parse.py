"""A scene file read and validated (``design/scenes.md``): every key's rule, range and
default, and the pipeline's parameters a scene calls for. Every failure is one
``SceneError`` whose message names the key (or the file)."""
import math
import tomllib
from pathlib import Path

import numpy as np

from . import obj, registry
from .pipeline import ScenePipeline, choose
from .stage import SceneError

__all__ = ["SceneError", "DEFAULTS", "RULES", "tables", "parse", "load", "pipeline_params"]


DEFAULTS = {
    "image": {"width": 256, "height": 256, "background": [0.0, 0.0, 0.0]},
    "camera": {"eye": [0.0, -3.5, 2.5], "target": [0.0, 0.0, 0.0], "up": [0.0, 0.0, 1.0],
               "fov_y": 40.0},
    "mesh": {"shape": "torus", "major_radius": 1.0, "minor_radius": 0.5, "segments": [12, 12],
             "rotate": [0.0, 0.0, 0.0], "translate": [0.0, 0.0, 0.0], "scale": 1.0, "file": ""},
    "material": {"color": [0.9, 0.5, 0.2], "ambient": 0.1, "diffuse": 0.7, "specular": 0.4,
                 "shininess": 32.0},
    "lights": [{"type": "directional", "to_light": [-1.0, -1.0, 2.0],
                "color": [1.0, 1.0, 1.0]}],
    # [shading] and [bump]'s method: the stages' choices, filled in by ``tables()``; the rest
    # of [bump]: the bump stages' scene_keys
    "shading": {}, "bump": {},
    "turntable": {"spin": "light", "axis": [0.0, 0.0, 1.0], "degrees": 360.0, "frames": 24,
                  "frame": 0},
}
LIGHT = DEFAULTS["lights"][0]
# Each key's kind and range: ("num", lo, hi) finite reals, ("int", lo, hi), ("vec", n, lo, hi)
# n finite reals, ("ints", n, lo, hi), ("choice", options), ("bool",), ("str",).
INF = math.inf
RULES = {
    "image": {"width": ("int", 16, 1024), "height": ("int", 16, 1024),
              "background": ("vec", 3, 0.0, 1.0)},
    "camera": {"eye": ("vec", 3, -INF, INF), "target": ("vec", 3, -INF, INF),
               "up": ("vec", 3, -INF, INF), "fov_y": ("num", 1.0, 170.0)},
    "mesh": {"shape": ("choice", ("torus", "sphere", "plane", "obj")), "file": ("str",),
             "major_radius": ("num", 1e-6, INF), "minor_radius": ("num", 1e-6, INF),
             "segments": ("ints", 2, 3, 256), "rotate": ("vec", 3, -INF, INF),
             "translate": ("vec", 3, -INF, INF), "scale": ("num", 1e-6, INF)},
    "material": {"color": ("vec", 3, 0.0, 1.0), "ambient": ("num", 0.0, 1.0),
                 "diffuse": ("num", 0.0, 1.0), "specular": ("num", 0.0, 1.0),
                 "shininess": ("num", 1.0, INF)},
    "lights": {"type": ("choice", ("directional",)), "to_light": ("vec", 3, -INF, INF),
               "color": ("vec", 3, 0.0, 2.0)},
    "shading": {}, "bump": {},
    "turntable": {"spin": ("choice", ("light", "mesh")), "axis": ("vec", 3, -INF, INF),
                  "degrees": ("num", -INF, INF), "frames": ("int", 1, 100000),
                  "frame": ("int", 0, 100000)},
}


def tables():
    """``(defaults, rules)`` of every scene table: the ones above, the choices of
    ``shading.method``, ``shading.power`` and ``bump.method`` (the registered stages', the
    first the default), and each stage's own keys (its ``scene_keys``: ``{table: {key:
    (default, rule)}}``), read from the stages as they are now, so a new stage's keys and
    choices are parsed, checked and fuzzed with no edit here."""
    defaults = {t: dict(v) if isinstance(v, dict) else v for t, v in DEFAULTS.items()}
    rules = {t: dict(v) for t, v in RULES.items()}
    ch = registry.choices()
    defaults["shading"] = {"method": ch["method"][0], "specular": True, "power": ch["power"][0]}
    rules["shading"] = {"method": ("choice", ch["method"]), "specular": ("bool",),
                        "power": ("choice", ch["power"])}
    defaults["bump"], rules["bump"] = {"method": "none"}, {"method": ("choice", ch["bump"])}
    for cls in registry.stages():
        for table, keys in cls.scene_keys.items():
            for key, (default, rule) in keys.items():
                defaults.setdefault(table, {})[key] = default
                rules.setdefault(table, {})[key] = rule
    return defaults, rules


def _number(key, v, lo, hi, what="a finite number"):
    rng = f">= {lo:g}" if hi == INF else f"in {lo:g}..{hi:g}"
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v) \
            or not lo <= v <= hi:
        raise SceneError(f"{key}: must be {what} {rng}, not {v!r}")
    return v


def _value(key, rule, v):
    kind = rule[0]
    if kind == "num":
        return float(_number(key, v, *rule[1:]))
    if kind == "int":
        if isinstance(v, bool) or not isinstance(v, int):
            raise SceneError(f"{key}: must be an integer, not {v!r}")
        return _number(key, v, *rule[1:], what="an integer")
    if kind in ("vec", "ints"):
        n, lo, hi = rule[1:]
        if not isinstance(v, list) or len(v) != n:
            raise SceneError(f"{key}: must be a list of {n} numbers, not {v!r}")
        if kind == "ints":
            return [_value(f"{key}[{k}]", ("int", lo, hi), x) for k, x in enumerate(v)]
        return [float(_number(f"{key}[{k}]", x, lo, hi)) for k, x in enumerate(v)]
    if kind == "bool":
        if not isinstance(v, bool):
            raise SceneError(f"{key}: must be true or false, not {v!r}")
        return v
    if not isinstance(v, str):
        raise SceneError(f"{key}: must be a string, not {v!r}")
    if kind == "choice" and v not in rule[1]:
        raise SceneError(f"{key}: must be one of {', '.join(rule[1])}, not {v!r}")
    return v


def _table(key, given, defaults, rules):
    if not isinstance(given, dict):
        raise SceneError(f"{key}: must be a table, not {given!r}")
    unknown = sorted(set(given) - set(rules))
    if unknown:
        raise SceneError(f"{key}.{unknown[0]}: unknown key (known: {', '.join(rules)})")
    return {k: _value(f"{key}.{k}", rules[k], given.get(k, defaults[k])) for k in rules}


def parse(data, name="scene", base=None):
    """A validated scene (every key filled in) from a parsed TOML document; ``base``: the
    directory a relative ``mesh.file`` is read from (the scene file's; default: the current
    one). ``mesh.file`` comes out absolute, so a parsed scene parses again to itself."""
    defaults, rules = tables()
    unknown = sorted(set(data) - set(defaults))
    if unknown:
        raise SceneError(f"{unknown[0]}: unknown table (known: {', '.join(defaults)})")
    scene = {"name": name}
    for key in defaults:
        if key == "lights":
            lights = data.get("lights", defaults["lights"])
            if not isinstance(lights, list) or not lights:
                raise SceneError("lights: must be one or more [[lights]] tables")
            scene["lights"] = [_table(f"lights[{k}]", l, LIGHT, rules["lights"])
                               for k, l in enumerate(lights)]
            for k, l in enumerate(scene["lights"]):
                if not any(l["to_light"]):
                    raise SceneError(f"lights[{k}].to_light: must not be the zero vector")
        else:
            scene[key] = _table(key, data.get(key, {}), defaults[key], rules[key])
    _mesh_file(scene["mesh"], base)
    for cls in registry.stages():     # a stage's keys set where it is not called for
        cls.check_scene(scene)
    turn = scene["turntable"]
    if not any(turn["axis"]):
        raise SceneError("turntable.axis: must not be the zero vector")
    if turn["frame"] >= turn["frames"]:
        raise SceneError(f"turntable.frame: must be below turntable.frames ({turn['frames']}), "
                         f"not {turn['frame']}")
    cam = scene["camera"]
    with np.errstate(over="ignore"):
        f = np.subtract(cam["target"], cam["eye"])
    if not np.isfinite(f).all():
        raise SceneError("camera.eye: its distance to camera.target overflows (keep the "
                         "coordinates below 1e300)")
    if not np.linalg.norm(f) > 0:
        raise SceneError("camera.target: must differ from camera.eye")
    if not np.linalg.norm(np.cross(f, cam["up"])) > 1e-9 * np.linalg.norm(f):
        raise SceneError("camera.up: must not be parallel to the view direction")
    most = ScenePipeline.RANGES["lights"][1]
    if len(scene["lights"]) > most:
        raise SceneError(f"lights: {len(scene['lights'])} lights; the pipeline shades at most "
                         f"{most}")
    try:                              # each stage's own checks, naming the scene key
        choose(pipeline_params(scene))
    except ValueError as e:
        raise SceneError(str(e)) from None
    return scene


MAX_SCENE_BYTES = 1 << 20      # a scene is a few hundred bytes; its mesh is a file of its own


def load(path):
    """Read and validate a scene file. Whatever the file holds, a failure is one
    ``SceneError`` naming the file (and the key, where one is wrong): tomllib's own limits
    (nesting past Python's recursion limit, an integer past Python's 4,300 digits) and sizes
    no scene needs are caught here, where the file is read."""
    path = Path(path)
    try:
        with open(path, "rb") as f:
            text = f.read(MAX_SCENE_BYTES + 1)
    except OSError as e:
        raise SceneError(f"{path}: cannot read the scene file ({e.strerror})") from None
    if len(text) > MAX_SCENE_BYTES:
        raise SceneError(f"{path}: larger than {MAX_SCENE_BYTES} bytes; a scene file is "
                         f"a few hundred (a mesh goes in its own file: mesh.file)")
    try:
        data = tomllib.loads(text.decode("utf-8"))
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as e:
        raise SceneError(f"{path}: not a valid TOML file: {e}") from None
    except RecursionError:
        raise SceneError(f"{path}: not a valid scene file: arrays or tables nested too "
                         f"deeply to read") from None
    except Exception as e:         # any other limit of the reader's (an integer of 4,301
        #                            digits or more: Python's int conversion limit)
        raise SceneError(f"{path}: not a readable scene file: {_first_line(e)}") from None
    try:
        return parse(data, path.stem, path.parent)
    except SceneError as e:        # the key's message, behind the file's name
        raise SceneError(f"{path}: {e}") from None


def _first_line(e):
    """An exception's message, one line, at most 160 characters."""
    text = (str(e).splitlines() or [type(e).__name__])[0]
    return text if len(text) <= 160 else text[:157] + "..."


def _mesh_file(msh, base):
    """``mesh.file``: given exactly when ``mesh.shape = "obj"``, made absolute and read (so
    that a bad OBJ is a scene error naming its file and line)."""
    if msh["shape"] != "obj":
        if msh["file"]:
            raise SceneError(f'mesh.file: only with mesh.shape = "obj", not with '
                             f'{msh["shape"]!r}')
        return
    if not msh["file"]:
        raise SceneError('mesh.file: mesh.shape = "obj" needs the OBJ file\'s path')
    msh["file"] = str((Path(base or ".") / msh["file"]).resolve())
    try:
        obj.read(msh["file"])
    except obj.ObjError as e:
        raise SceneError(f"mesh.file: {e}") from None


def pipeline_params(scene, bump_size=None, hardware=None):
    """The pipeline's parameters for a scene: its effects and sizes (``bump_size``: the
    map's, where it has its own size), never its data. ``hardware``: parameters chosen for
    the build rather than by the scene (``texture``, the cache's sizes), or set over the
    scene's (``make tradeoffs``: a method of one's own on the default scene)."""
    img, sh, b = scene["image"], scene["shading"], scene["bump"]
    pipe = dict(screen_bits=max(4, (max(img["width"], img["height"]) - 1).bit_length()),
                sub_bits=ScenePipeline.PARAMS["sub_bits"], method=sh["method"],
                lights=len(scene["lights"]), specular=sh["specular"], power=sh["power"])
    if b["method"] != "none":
        pipe.update(bump=b["method"], bump_size=bump_size or b["size"], filter=b["filter"])
    pipe.update(hardware or {})
    q = {**ScenePipeline.PARAMS, **pipe}
    for cls in registry.stages():   # the scene keys a stage reads for its build
        if cls.wanted(q):
            q.update(cls.scene_params(scene))
    return q
