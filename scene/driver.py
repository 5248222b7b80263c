"""The scene driver (``design/scenes.md``): a scene file in, what the hardware takes out, and
the two float images the RTL is compared with: the mesh, the camera, culling, the encodings of
the lights and the bump map, the framebuffer.

- ``load(path)``: reads and validates a scene (``tomllib``); every error names the key.
- ``prepare(scene)``: the mesh, transformed, projected and culled; per drawn triangle the
  raster's inputs (raw screen coordinates, per-edge constants (Ni.Nj - 1)/2, the channels'
  vertex values: depth, then N.L and N.H per light, or the normal for ``phong``); the pipeline's
  parameters and uniforms.
- ``model(prep)``: the same pipeline through its stages' models, with the RTL's formats
  (``model.png``).
- ``reference(prep)``: per-pixel Phong in float64 with the exact power (``reference.png``).

Decisions where scenes.md is silent (docs/scenes.md lists them):
- depth: the channel carries zmin / zc, zmin the nearest drawn vertex's zc, so it lies in
  (0, 1] whatever the scene's scale; a larger value is nearer;
- a triangle with a vertex beyond the raster's coordinate range (one screen outside the
  screen on either side) is dropped, like one behind the near plane, and counted as culled;
- d and s are clamped to [0, 1] per pixel before the colour sum and the power;
- the screen is the smallest power of two holding the image; fragments outside the image are
  discarded by the framebuffer.
"""
import math
import tomllib
from pathlib import Path

import numpy as np

from golden import angular, bump as bumps, fenney, raster as raster_model, shade
from golden.bump import rotation
from hdl.fixed import FieldError, check_arrays
from hdl.setup_unit.formats import EDGE, VALUE, coord
from hdl.shade_unit.formats import POWER, RGB
from hdl.texture_unit import MAX_TEXTURE

from . import host, obj
from .framebuffer import framebuffer
from .pipeline import BUMPS, METHODS, ScenePipeline, choose
from .stage import lanes as lanes_of, raw
from .stages.fenney_polar import pack
from .stages.texture import ANGLE_BITS

__all__ = ["SceneError", "load", "parse", "prepare", "rtl_inputs", "model", "ideal", "reference",
           "framebuffer", "DEFAULTS"]


class SceneError(ValueError):
    """A scene file that cannot be rendered: the message names the key."""


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
    "shading": {"method": "xshading", "specular": True, "power": "table"},
    "bump": {"method": "none", "map": "bricks", "size": 256, "repeat": [8.0, 2.0],
             "depth": 1.0, "filter": "nearest", "rotation": "paper", "renormalize": False},
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
    "shading": {"method": ("choice", METHODS), "specular": ("bool",),
                "power": ("choice", ("table", "fenney"))},
    "bump": {"method": ("choice", BUMPS), "map": ("str",), "size": ("int", 16, 4096),
             "repeat": ("vec", 2, 1e-6, INF), "depth": ("num", 0.0, INF),
             "filter": ("choice", ("nearest", "bilinear")),
             "rotation": ("choice", ("paper", "exact")), "renormalize": ("bool",)},
    "turntable": {"spin": ("choice", ("light", "mesh")), "axis": ("vec", 3, -INF, INF),
                  "degrees": ("num", -INF, INF), "frames": ("int", 1, 100000),
                  "frame": ("int", 0, 100000)},
}


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
    unknown = sorted(set(data) - set(DEFAULTS))
    if unknown:
        raise SceneError(f"{unknown[0]}: unknown table (known: {', '.join(DEFAULTS)})")
    scene = {"name": name}
    for key in DEFAULTS:
        if key == "lights":
            lights = data.get("lights", DEFAULTS["lights"])
            if not isinstance(lights, list) or not lights:
                raise SceneError("lights: must be one or more [[lights]] tables")
            scene["lights"] = [_table(f"lights[{k}]", l, LIGHT, RULES["lights"])
                               for k, l in enumerate(lights)]
            for k, l in enumerate(scene["lights"]):
                if not any(l["to_light"]):
                    raise SceneError(f"lights[{k}].to_light: must not be the zero vector")
        else:
            scene[key] = _table(key, data.get(key, {}), DEFAULTS[key], RULES[key])
    _mesh_file(scene["mesh"], base)
    if scene["bump"]["renormalize"] and scene["bump"]["method"] != "fenney_xz":
        raise SceneError(f"bump.renormalize: only with bump.method = \"fenney_xz\", not "
                         f"{scene['bump']['method']!r}")
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
    ``SceneError`` naming the file: tomllib's own limits (nesting past Python's recursion
    limit) and sizes no scene needs are caught here, where the file is read."""
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
    return parse(data, path.stem, path.parent)


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


# ---- the mesh (world space) ------------------------------------------------------------------

def _grid_triangles(m, n, wrap_i, wrap_j):
    """Index triples of the quads (i, j), (i+1, j), (i+1, j+1), (i, j+1), split as scenes.md
    says, over an (m x n) vertex grid (wrapping where asked)."""
    ii = range(m if wrap_i else m - 1)
    jj = range(n if wrap_j else n - 1)
    idx = lambda i, j: (i % m) * n + (j % n)
    tris = []
    for i in ii:
        for j in jj:
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            tris += [(a, b, c), (a, c, d)]
    return np.array(tris)


def mesh(scene):
    """(positions, normals, triangles) in world space: the shape's, oriented
    (``orientation``), scaled and translated; triangles of no area dropped."""
    msh = scene["mesh"]
    m, n = msh["segments"]
    if msh["shape"] == "obj":
        o = obj.read(msh["file"])
        pos, nrm, tris = o.pos, o.nrm, o.tris
    elif msh["shape"] == "torus":
        R, r = msh["major_radius"], msh["minor_radius"]
        phi, psi = np.meshgrid(2 * np.pi * np.arange(m) / m, 2 * np.pi * np.arange(n) / n,
                               indexing="ij")
        nrm = np.stack([np.cos(psi) * np.cos(phi), np.cos(psi) * np.sin(phi), np.sin(psi)], -1)
        pos = np.stack([(R + r * np.cos(psi)) * np.cos(phi), (R + r * np.cos(psi)) * np.sin(phi),
                        r * np.sin(psi)], -1)
        tris = _grid_triangles(m, n, True, True)
    elif msh["shape"] == "sphere":               # radius major_radius; j runs pole to pole
        phi, th = np.meshgrid(2 * np.pi * np.arange(m) / m, np.pi * np.arange(n + 1) / n,
                              indexing="ij")
        nrm = np.stack([np.sin(th) * np.cos(phi), np.sin(th) * np.sin(phi), -np.cos(th)], -1)
        pos = msh["major_radius"] * nrm
        tris = _grid_triangles(m, n + 1, True, False)
    else:                                        # plane: [-1, 1]^2 at z = 0, facing +z
        x, y = np.meshgrid(np.linspace(-1, 1, m + 1), np.linspace(-1, 1, n + 1), indexing="ij")
        pos = np.stack([x, y, np.zeros_like(x)], -1)
        nrm = np.broadcast_to([0.0, 0.0, 1.0], pos.shape)
        tris = _grid_triangles(m + 1, n + 1, False, False)
    pos, nrm = pos.reshape(-1, 3), nrm.reshape(-1, 3)
    rot = orientation(scene)
    with np.errstate(over="ignore", invalid="ignore"):
        pos = pos @ rot.T * msh["scale"] + np.array(msh["translate"])
        # drop triangles with a repeated vertex (the sphere's poles)
        p = pos[tris]
        area = np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=-1)
        least = 1e-12 * max(1.0, np.abs(pos).max()) ** 2          # numpy's: inf, no raise
    if not (np.isfinite(area).all() and np.isfinite(least)):
        raise SceneError(f"mesh.scale, mesh.translate: the mesh's coordinates (up to "
                         f"{float(np.abs(pos).max()):.3g}) overflow in its areas; keep them "
                         f"below 1e150")
    nrm = nrm @ rot.T
    return pos, nrm, tris[area > least]


def turn(scene):
    """The turntable's rotation at the scene's frame (docs/scenes.md): ``turntable.degrees``
    * frame / frames about ``turntable.axis`` (right-handed), through the mesh's origin."""
    from scipy.spatial.transform import Rotation
    t = scene["turntable"]
    angle = math.radians(t["degrees"] * t["frame"] / t["frames"])
    return Rotation.from_rotvec(angle * _unit(t["axis"])).as_matrix()


def orientation(scene):
    """The rotation from the mesh's own axes to the world's: ``mesh.rotate``, then the
    turntable's turn where it spins the mesh."""
    rot = rotation(scene["mesh"]["rotate"])
    return turn(scene) @ rot if scene["turntable"]["spin"] == "mesh" else rot


def texcoords(scene):
    """Per-vertex texture coordinates in tiles (``bump.repeat`` applied), and which of s
    and t are periodic (a triangle takes its vertices' within half a period of each other)."""
    msh = scene["mesh"]
    if msh["shape"] != "obj":
        return bumps.texcoords(scene), (True, True)
    o = obj.read(msh["file"])
    return o.uv * np.array(scene["bump"]["repeat"], float), o.periodic


def tangent_frames(scene):
    """(T, B, N) per vertex of the mesh in world space: the built-in shapes' analytic frames;
    an OBJ's from its texture coordinates (``golden.bump.frames_from_uv``)."""
    msh = scene["mesh"]
    if msh["shape"] == "obj":
        o = obj.read(msh["file"])
        uv, periodic = texcoords(scene)
        period = np.where(periodic, scene["bump"]["repeat"], np.inf)
        try:
            own = bumps.frames_from_uv(o.pos, o.nrm, uv, o.tris, period)
        except bumps.BumpError as e:
            raise SceneError(f"mesh.file: {msh['file']}: {e}") from None
    else:
        own = bumps.grid_frames(msh["shape"], *msh["segments"])
    rot = orientation(scene)
    return tuple(f @ rot.T for f in own)


def _unit(v):
    """``v`` over its length, scaled first by its largest component, so that neither a tiny
    (1e-300) nor a huge (1e300) vector underflows or overflows in the squares."""
    v = np.asarray(v, float)
    m = np.abs(v).max(axis=-1, keepdims=True)
    v = v / np.where(m > 0, m, 1.0)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def pipeline_params(scene, bump_size=None, hardware=None):
    """The pipeline's parameters for a scene: its effects and sizes (``bump_size``: the
    map's, where it has its own size), never its data. ``hardware``: parameters chosen for
    the build rather than by the scene (``texture``, the cache's sizes)."""
    img, sh, b = scene["image"], scene["shading"], scene["bump"]
    pipe = dict(screen_bits=max(4, (max(img["width"], img["height"]) - 1).bit_length()),
                sub_bits=ScenePipeline.PARAMS["sub_bits"], method=sh["method"],
                lights=len(scene["lights"]), specular=sh["specular"], power=sh["power"],
                **(hardware or {}))
    if b["method"] != "none":
        pipe.update(bump=b["method"], bump_size=bump_size or b["size"], filter=b["filter"])
        if b["method"] == "angular":
            pipe["rotation"] = b["rotation"]
        if b["method"] == "fenney_xz" and b["renormalize"]:
            pipe["normalize"] = True
    return {**ScenePipeline.PARAMS, **pipe}


def prepare(scene, hardware=None):
    """Everything the hardware and the models take; see the module's docstring.
    ``hardware``: build parameters (``pipeline_params``)."""
    img, cam = scene["image"], scene["camera"]
    W, H = img["width"], img["height"]
    pipe = pipeline_params(scene, hardware=hardware)
    screen_bits, sub_bits = pipe["screen_bits"], pipe["sub_bits"]
    pos, nrm, tris = mesh(scene)
    eye = np.array(cam["eye"])
    f = _unit(np.subtract(cam["target"], eye))
    r = _unit(np.cross(f, cam["up"]))
    u = np.cross(r, f)
    rel = pos - eye
    xc, yc, zc = rel @ r, rel @ u, rel @ f
    k = (H / 2) / math.tan(math.radians(cam["fov_y"]) / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        sx, sy = W / 2 + k * xc / zc, H / 2 - k * yc / zc
    p = pos[tris]
    facing = np.einsum("ij,ij->i", p[:, 0] - eye, np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]))
    near = (zc[tris] <= 0.1).any(1)
    cfmt = coord(screen_bits, sub_bits)
    # beyond the coordinate field once rounded to sub-pixels (127.99 px rounds to 128.0, one
    # past the field's largest value: make fuzz found it wrapping to -128 in the RTL)
    with np.errstate(invalid="ignore", over="ignore"):
        fits = lambda v: (np.rint(v * (1 << sub_bits)) >= cfmt.min) & \
            (np.rint(v * (1 << sub_bits)) <= cfmt.max)
        outside = ~(fits(sx[tris]) & fits(sy[tris])).all(1)
    keep = (facing < 0) & ~near & ~outside
    drawn = tris[keep]
    # per-vertex lighting: viewer at infinity
    V = _unit(np.subtract(cam["eye"], cam["target"]))
    spin = turn(scene) if scene["turntable"]["spin"] == "light" else np.eye(3)
    Ls = [_unit(spin @ l["to_light"]) for l in scene["lights"]]
    Hs = [_unit(L + V) for L in Ls]
    N = _unit(nrm)
    zmin = float(zc[drawn].min()) if len(drawn) else 1.0
    bump = _bump(scene, drawn, Ls, Hs, pipe) if scene["bump"]["method"] != "none" else None
    try:                              # the build's choices (hardware) checked with the scene's
        spec = ScenePipeline.spec(**pipe)
    except ValueError as e:
        raise SceneError(str(e)) from None
    vert = {"depth": zmin / zc, "nx": N[:, 0], "ny": N[:, 1], "nz": N[:, 2]}
    for j, (L, Hv) in enumerate(zip(Ls, Hs)):
        vert[f"d{j}"], vert[f"s{j}"] = N @ L, N @ Hv
    inputs, real = {}, {}           # real: the same before rounding (the ideal model's)
    S = 1 << sub_bits
    for c in range(3):
        real[f"x{c}"], real[f"y{c}"] = sx[drawn[:, c]] * S, sy[drawn[:, c]] * S
        inputs[f"x{c}"] = np.rint(sx[drawn[:, c]] * S).astype(np.int64)
        inputs[f"y{c}"] = np.rint(sy[drawn[:, c]] * S).astype(np.int64)
    for name, (a, b) in (("e01", (0, 1)), ("e02", (0, 2)), ("e12", (1, 2))):
        dots = np.einsum("ij,ij->i", N[drawn[:, a]], N[drawn[:, b]])
        inputs[name] = np.minimum(raw((dots - 1) / 2, EDGE), 0)
        real[name] = np.minimum((dots - 1) / 2, 0) / EDGE.lsb
    for ch, (name, _) in enumerate(spec.channels):
        for c in range(3):
            if name in ("s", "t"):
                val = bump["st"][:, c, "st".index(name)]
            elif bump and name[:-1] in bump.get("vectors", {}):      # a vector's component
                val = bump["vectors"][name[:-1]][:, c, "xyz".index(name[-1])]
            elif bump and name in bump.get("angles", {}):
                val = bump["angles"][name][:, c]
            else:
                val = vert[name][drawn[:, c]]
            inputs[f"v{ch}_{c}"] = raw(val, VALUE)
            real[f"v{ch}_{c}"] = val / VALUE.lsb
    if bump:
        inputs.update({k: v for k, v in bump["constants"].items() if k.startswith("e")})
        real.update(bump["real_edges"])
        for n, (t, k) in enumerate(bump["lanes"] if scene["bump"]["method"] == "fenney_polar"
                                   else ()):   # a lane's constants, its flat word
            inputs[f"f{n}"] = pack({c: bump["constants"][f"{t}{k}_{c}"]
                                    for c in ("k1", "k2", "k3", "q")})
    # the data, which the host port loads (scene/host.py): each stage's registers from the
    # scene (the lights' L and H, unit vectors), its tables, the texture's words
    uni, tables = {}, {}
    for stage in spec.stages:
        uni.update(stage.uniform_values(scene, Ls, Hs))
        tables.update({(stage.name, k): v for k, v in stage.table_values(scene).items()})
    uni = {f.name: int(uni[f.name]) for f in spec.registers}
    texture = [s for s in spec.stages if hasattr(s, "image")]
    image = texture[0].image({"bump": bump}) if texture else None
    onchip = bool(texture) and texture[0].onchip
    try:                              # every value fits its field, or the RTL would wrap it
        check_arrays(spec.raster.unit.inputs, inputs, where="prepare")
    except FieldError as e:
        raise AssertionError(f"the driver made a triangle its raster cannot take: {e}") \
            from None
    return {"scene": scene, "params": pipe, "pipeline": spec, "inputs": inputs, "real": real,
            "memory": None if onchip else image,
            "load": host.writes(spec, uni, tables, image if onchip else None),
            "uniforms": uni, "size": (W, H),
            "triangles": {"in": len(tris), "culled": int((~keep).sum()), "drawn": len(drawn)},
            "float": {"sx": sx[drawn], "sy": sy[drawn], "inv_z": zmin / zc[drawn],
                      "N": N[drawn], "L": Ls, "H": Hs}, "bump": bump}


def rtl_inputs(prep, at=None):
    """The rows of the pipeline's input stream: the scene's data (``prep["load"]``), then its
    triangles; ``at``: further writes between triangles (``scene.host.stream``)."""
    return host.stream(prep["inputs"], prep["load"], at)


def _bump(scene, drawn, Ls, Hs, pipe):
    """fenney_polar's inputs (seed 004, first embodiment), and what its model and the
    reference need; sets the pipeline's bump parameters in ``pipe``.

    - Texture coordinates per triangle (tiles): a vertex's (s, t) is taken within half a
      period of the first vertex's (so a triangle across the mesh's seam does not run back
      over the whole texture), then every vertex is shifted by the same whole tiles, so that
      the least lies in [0, 1): the texture repeats every tile, so the shift changes nothing
      but keeps the values in the raster's [-2, 2). A triangle may span less than one tile.
    - The triangle's tangent frame: the mean of its vertices' frames, made orthonormal (N, T
      against N, B = N x T). L and H in it as elevation T_L (degrees above the surface
      plane) and rotation Q from the tangent; k1 = 0, k2 = sin T_L, k3 = cos T_L (h = 1,
      eq 1-4), each * 255, and Q in turns * 256. A light below the surface's horizon is
      taken at T_L = 0: the patent's 8-bit k2 is unsigned (docs/bump.md)."""
    b = scene["bump"]
    try:
        hi, lo, normals = bumps.bump_texels(bumps.KINDS[b["method"]], b["map"], b["size"],
                                            b["depth"], ANGLE_BITS)
    except bumps.BumpError as e:           # its message names bump.map
        raise SceneError(str(e)) from None
    size = hi.shape[0]
    if hi.shape[0] != hi.shape[1] or size & (size - 1) or size > MAX_TEXTURE:
        raise SceneError(f"bump.map: {b['map']!r} is {hi.shape[1]} x {hi.shape[0]} texels; a "
                         f"texture ROM needs a square power of two up to {MAX_TEXTURE}")
    pipe["bump_size"] = size
    period = np.array(b["repeat"], float)
    uv, periodic = texcoords(scene)
    st = uv[drawn]                                                        # (n, 3, 2)
    st = np.where(periodic, st[:, :1] + np.mod(st - st[:, :1] + period / 2, period)
                  - period / 2, st)
    st -= np.floor(st.min(axis=1, keepdims=True))
    span = st.max(axis=1) - st.min(axis=1)
    if len(span) and span.max() >= 1.0 - VALUE.lsb:
        k = int(np.argmax(span.max(axis=1)))
        raise SceneError(f"bump.repeat: a triangle spans {span.max():.3g} tiles of the bump "
                         f"map (along {'st'[int(np.argmax(span[k]))]}); the raster carries "
                         f"texture coordinates in [-2, 2), so a triangle may span less than "
                         f"one tile: " + ("use more mesh.segments or a smaller repeat"
                                          if scene["mesh"]["shape"] != "obj" else
                                          "give the OBJ finer texture coordinates, or a "
                                          "smaller repeat (without them, the cylindrical "
                                          "projection wraps whole turns around the triangles "
                                          "at the ends of its axis)"))
    frames = [f[drawn] for f in tangent_frames(scene)]                    # (n, 3, 3) each
    Nt = _unit(frames[2].sum(1))
    Tt = frames[0].sum(1)
    Tt = _unit(Tt - np.einsum("ij,ij->i", Tt, Nt)[:, None] * Nt)
    Bt = np.cross(Nt, Tt)
    consts, real_edges = {}, {}
    lanes = lanes_of(pipe)
    out = {"st": st, "constants": consts, "real_edges": real_edges, "lanes": lanes,
           "normals": normals,
           "frames": frames, "size": size, "filter": b["filter"], "texels": (hi, lo)}
    if b["method"] == "angular":
        # the normal's angles (seed 003: phi from x, theta from z) and the twist psi of the
        # texture's frame about N from the rotations' frame (e_theta, e_phi, N), in turns;
        # each unwrapped within half a turn of the first vertex's, as the texture coordinates
        N = frames[2]
        phi, theta = angular.to_polar(N)
        # theta_N = 0 (the hard case): phi_N means nothing there, so each triangle takes, at
        # such a vertex, the mean direction of its other vertices' phi_N (the normal crosses
        # the pole along it); the twist follows from that phi
        pole = np.sin(theta) < 1e-9
        other = np.where(pole, 0.0, 1.0)
        mean = np.arctan2((other * np.sin(phi)).sum(1), (other * np.cos(phi)).sum(1))
        phi = np.where(pole, mean[:, None], phi)
        e_t = np.stack([np.cos(theta) * np.cos(phi), np.cos(theta) * np.sin(phi),
                        -np.sin(theta)], -1)
        e_p = np.stack([-np.sin(phi), np.cos(phi), np.zeros_like(phi)], -1)
        psi = np.arctan2(np.einsum("...i,...i", frames[0], e_p),
                         np.einsum("...i,...i", frames[0], e_t))
        turns = lambda a: a / (2 * np.pi)
        wrap = lambda a: a[:, :1] + np.mod(a - a[:, :1] + 0.5, 1.0) - 0.5
        out["angles"] = {"phin": wrap(turns(phi)), "thetan": turns(theta),
                         "psi": wrap(turns(psi))}
        for k in ("phin", "psi"):
            out["angles"][k] -= np.floor(out["angles"][k].min(axis=1, keepdims=True))
        out["theta"], out["phi"] = hi, lo
        return out
    if b["method"] == "fenney_xz":
        # each vertex's L' and H' in its own tangent frame (they vary over the surface), and
        # each vector's per-edge constants (L'i.L'j - 1)/2 (seed 000 section 2)
        out["X"], out["Z"] = hi, lo
        out["vectors"] = {}
        for t, k in lanes:
            vec = np.stack([bumps.to_tangent((Ls if t == "l" else Hs)[k], *(f[:, c] for f in
                                                                            frames))
                            for c in range(3)], 1)[..., [0, 2, 1]]             # (n, 3, 3)
            out["vectors"][f"{t}{k}"] = vec     # in the patent's axes: (T, N, B), y out
            for (a, c), name in zip(((0, 1), (0, 2), (1, 2)), ("01", "02", "12")):
                dots = np.einsum("ij,ij->i", vec[:, a], vec[:, c])
                consts[f"e{name}_{1 + lanes.index((t, k))}"] = \
                    np.minimum(raw((dots - 1) / 2, EDGE), 0)
                real_edges[f"e{name}_{1 + lanes.index((t, k))}"] = \
                    np.minimum((dots - 1) / 2, 0) / EDGE.lsb
        return out
    for t, k in lanes:
        v = bumps.to_tangent((Ls if t == "l" else Hs)[k], Tt, Bt, Nt)
        elev = np.arcsin(np.clip(v[:, 2], 0.0, 1.0))
        rot = np.arctan2(v[:, 1], v[:, 0])
        consts[f"{t}{k}_k1"] = np.zeros(len(v), np.int64)
        consts[f"{t}{k}_k2"] = np.rint(255 * np.sin(elev)).astype(np.int64)
        consts[f"{t}{k}_k3"] = np.rint(255 * np.cos(elev)).astype(np.int64)
        consts[f"{t}{k}_q"] = np.rint(rot / (2 * np.pi) * 256).astype(np.int64) % 256
        out.setdefault("held", {})[f"{t}{k}"] = (elev, rot)      # the same, unrounded
    out["S"], out["R"] = hi, lo
    return out


# ---- images ----------------------------------------------------------------------------------

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


FORMAT_GROUPS = {"raster": "raster", "texture": "texels", "texel_decode": "texels",
                 "phong": "shading", "fenney_dot": "shading", "fenney_polar": "shading",
                 "bump_polar": "shading", "colour": "colour"}      # the rest: "power"


def ideal(prep, formats=()):
    """The float ideal of the scene's pipeline: each stage's algorithm on reals with no
    format (the stages' ``ideal``: unrounded inputs, exact functions for tables, no rounding
    but the final colour's 8 bits), the same pixels and the depth test on its depth.
    Returns (image, covered). Against the reference it is the method's own error; the RTL
    against it, the formats'.

    ``formats``: groups of stages run as their models instead, with the RTL's formats (raster,
    texels, shading, power, colour: ``FORMAT_GROUPS``), so each group's own loss can be
    measured (``flows.losses``); all of them give the model's image."""
    stages = prep["pipeline"].stages
    modes = ["model" if FORMAT_GROUPS.get(s.name, "power") in formats else "ideal"
             for s in stages]
    frag, ch = stages[0].model(prep) if modes[0] == "model" else stages[0].ideal(prep)
    for stage, mode, was in zip(stages[1:], modes[1:], modes):
        ch = _as(prep, ch, mode) if mode != was else ch
        ch = stage.model(prep, frag, ch, {}) if mode == "model" else stage.ideal(prep, frag, ch)
    rgb = np.stack([ch[c] for c in RGB], -1).astype(np.uint8)
    return framebuffer(prep["size"], frag["x"], frag["y"], ch["depth"], rgb,
                       prep["scene"]["image"]["background"])


def _as(prep, ch, mode):
    """Values between a stage's model and the next stage's ideal (or back): the power in
    POWER LSBs or real; the decoded X/Z vector of L1 length 255 or 1; the texel codes (S/R,
    or polar angles in turns * 2**12) or the normal they hold."""
    ch, ideal = dict(ch), mode == "ideal"
    kind = prep["scene"]["bump"]["method"]
    for k in [k for k in ch if k[0] == "p" and k[1:].isdigit()]:
        ch[k] = ch[k] * POWER.lsb if ideal else np.rint(ch[k] / POWER.lsb).astype(np.int64)
    if "x" in ch and "y" in ch and "z" in ch:
        for a in "xyz":
            ch[a] = ch[a] / 255.0 if ideal else ch[a] * 255.0
    if ideal and "_hi" in ch:
        hi, lo = np.asarray(ch.pop("_hi"), float), np.asarray(ch.pop("_lo"), float)
        if kind == "fenney_polar":
            s_ang, r_ang = hi / 256 * (np.pi / 2), lo / 256 * (2 * np.pi)
            ch["_n"] = np.stack([np.cos(s_ang) * np.cos(r_ang), np.cos(s_ang) * np.sin(r_ang),
                                 np.sin(s_ang)], -1)
        else:
            turn = 2 * np.pi / (1 << ANGLE_BITS)
            ch["_n"] = angular.to_vector(lo * turn, hi * turn)
    elif not ideal and "_n" in ch:
        n = ch.pop("_n")
        if kind == "fenney_polar":
            ch["_hi"] = np.arcsin(np.clip(n[:, 2], 0, 1)) / (np.pi / 2) * 256
            ch["_lo"] = np.mod(np.arctan2(n[:, 1], n[:, 0]) / (2 * np.pi) * 256, 256)
        else:
            phi, theta = angular.to_polar(n)
            scale = (1 << ANGLE_BITS) / (2 * np.pi)
            ch["_hi"], ch["_lo"] = (np.rint(a * scale).astype(np.int64) % (1 << ANGLE_BITS)
                                    for a in (theta, phi))
    return ch


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


def reference(prep):
    """Per-pixel Phong in float64, exact power: each covered pixel's normal interpolated
    (affine in screen space) from the exact vertex normals at the exact projected vertices,
    normalised; the same coverage and the depth test on the exact 1/z."""
    scene, q, fl = prep["scene"], prep["params"], prep["float"]
    x = np.stack([prep["inputs"][f"x{c}"] for c in range(3)], -1)
    y = np.stack([prep["inputs"][f"y{c}"] for c in range(3)], -1)
    tri, px, py = raster_model.coverage(x, y, q["sub_bits"], q["screen_bits"])
    sx, sy = fl["sx"][tri], fl["sy"][tri]
    cx, cy = px + 0.5, py + 0.5
    det = (sx[:, 1] - sx[:, 0]) * (sy[:, 2] - sy[:, 0]) - (sx[:, 2] - sx[:, 0]) * (sy[:, 1] - sy[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        b1 = ((cx - sx[:, 0]) * (sy[:, 2] - sy[:, 0]) - (sx[:, 2] - sx[:, 0]) * (cy - sy[:, 0])) / det
        b2 = ((sx[:, 1] - sx[:, 0]) * (cy - sy[:, 0]) - (cx - sx[:, 0]) * (sy[:, 1] - sy[:, 0])) / det
    w = np.stack([1 - b1 - b2, b1, b2], -1)
    n = (w[..., None] * fl["N"][tri]).sum(1)
    n = n / np.linalg.norm(n, axis=-1, keepdims=True)
    b = prep["bump"]
    if b:     # the texel's exact normal, in the pixel's interpolated tangent frame
        st = (w[..., None] * b["st"][tri]).sum(1)
        nt = bumps.sample(b["normals"], st, b["filter"])
        T, B = ((w[..., None] * f[tri]).sum(1) for f in b["frames"][:2])
        T = T - np.einsum("ij,ij->i", T, n)[:, None] * n
        T = T / np.linalg.norm(T, axis=-1, keepdims=True)
        B = np.cross(n, T)
        n = nt[:, :1] * T + nt[:, 1:2] * B + nt[:, 2:] * n
    d = [n @ L for L in fl["L"]]
    p = [np.maximum(0, n @ Hv) ** scene["material"]["shininess"] if q["specular"]
         else np.zeros(len(tri)) for Hv in fl["H"]]
    rgb = shade.colour_float(scene, d, p)
    depth = (w * fl["inv_z"][tri]).sum(1)
    return framebuffer(prep["size"], px, py, depth, rgb, scene["image"]["background"])[:2]
