"""A scene made ready for the hardware and the models: the mesh seen through the camera,
culled, and per drawn triangle the raster's inputs; the pipeline's parameters; the data the
host port loads. The effects' own parts come from the stages (``scene/stage.py``): each
prepares its data (``prepare``), gives its channels' vertex values, its per-triangle
constants and flat words, its registers and its tables. Nothing here names a stage.

Decisions where scenes.md is silent (docs/scenes.md lists them):
- depth: the channel carries zmin / zc, zmin the nearest drawn vertex's zc, so it lies in
  (0, 1] whatever the scene's scale; a larger value is nearer;
- a triangle with a vertex beyond the raster's coordinate range (one screen outside the
  screen on either side) is dropped, like one behind the near plane, and counted as culled;
- the screen is the smallest power of two holding the image; fragments outside the image are
  discarded by the framebuffer.
"""
import math
from types import SimpleNamespace

import numpy as np

from hdl.fixed import FieldError, check_arrays
from hdl.setup_unit.formats import EDGE, VALUE, coord

from . import host
from .mesh import mesh, turn, unit
from .parse import SceneError, pipeline_params
from .pipeline import ScenePipeline, wanted
from .stage import raw

__all__ = ["prepare", "rtl_inputs", "view"]


def view(scene, pipe):
    """The mesh through the camera: screen positions, the drawn triangles (facing the
    camera, in front of the near plane, inside the raster's coordinate field), the lights'
    L and H (viewer at infinity) and each vertex's values (depth, normal, N.L, N.H)."""
    img, cam = scene["image"], scene["camera"]
    W, H = img["width"], img["height"]
    screen_bits, sub_bits = pipe["screen_bits"], pipe["sub_bits"]
    pos, nrm, tris = mesh(scene)
    eye = np.array(cam["eye"])
    f = unit(np.subtract(cam["target"], eye))
    r = unit(np.cross(f, cam["up"]))
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
    V = unit(np.subtract(cam["eye"], cam["target"]))
    spin = turn(scene) if scene["turntable"]["spin"] == "light" else np.eye(3)
    Ls = [unit(spin @ light["to_light"]) for light in scene["lights"]]
    Hs = [unit(L + V) for L in Ls]
    N = unit(nrm)
    zmin = float(zc[drawn].min()) if len(drawn) else 1.0
    vert = {"depth": zmin / zc, "nx": N[:, 0], "ny": N[:, 1], "nz": N[:, 2]}
    for j, (L, Hv) in enumerate(zip(Ls, Hs)):
        vert[f"d{j}"], vert[f"s{j}"] = N @ L, N @ Hv
    return SimpleNamespace(size=(W, H), sx=sx, sy=sy, zc=zc, zmin=zmin, N=N, tris=tris,
                           keep=keep, drawn=drawn, L=Ls, H=Hs, vert=vert)


def prepare(scene, hardware=None):
    """Everything the hardware and the models take. ``hardware``: build parameters
    (``pipeline_params``). Returns a dict: ``inputs`` (the raster's raw per-triangle rows) and
    ``real`` (the same unrounded, the ideal's), ``params``, ``pipeline`` (the stages),
    ``load`` (the host port's writes), ``memory`` (the texture memory's words, external),
    ``uniforms``, ``size``, ``triangles`` (counts), ``float`` (the reference's exact
    values), ``data`` (the stages' prepared data) and ``bump`` (the same, or None without a
    bump method)."""
    pipe = pipeline_params(scene, hardware=hardware)
    v = view(scene, pipe)
    drawn = v.drawn
    data = {}              # the stages' own, each from the scene (the texture's first)
    for stage in wanted(pipe):
        data.update(stage.prepare(scene, v, data))     # may settle pipe (the map's size)
    try:                              # the build's choices (hardware) checked with the scene's
        spec = ScenePipeline.spec(**pipe)
    except ValueError as e:
        raise SceneError(str(e)) from None
    vert = {name: val[drawn] for name, val in v.vert.items()}
    inputs, real = {}, {}           # real: the same before rounding (the ideal model's)
    S = 1 << pipe["sub_bits"]
    for c in range(3):
        real[f"x{c}"], real[f"y{c}"] = v.sx[drawn[:, c]] * S, v.sy[drawn[:, c]] * S
        inputs[f"x{c}"] = np.rint(v.sx[drawn[:, c]] * S).astype(np.int64)
        inputs[f"y{c}"] = np.rint(v.sy[drawn[:, c]] * S).astype(np.int64)
    for name, (a, b) in (("e01", (0, 1)), ("e02", (0, 2)), ("e12", (1, 2))):
        dots = np.einsum("ij,ij->i", v.N[drawn[:, a]], v.N[drawn[:, b]])
        inputs[name] = np.minimum(raw((dots - 1) / 2, EDGE), 0)
        real[name] = np.minimum((dots - 1) / 2, 0) / EDGE.lsb
    words = {}
    for stage in spec.stages:
        vert.update(stage.vertex_values(data))
        own, own_real = stage.triangle_values(data)
        inputs.update(own)
        real.update(own_real)
        words.update(stage.flat_values(data))
    for ch, (name, _) in enumerate(spec.channels):
        for c in range(3):
            inputs[f"v{ch}_{c}"] = raw(vert[name][:, c], VALUE)
            real[f"v{ch}_{c}"] = vert[name][:, c] / VALUE.lsb
    for n, name in enumerate(spec.raster.flat_names):
        inputs[f"f{n}"] = words[name]
    # the data, which the host port loads (scene/host.py): each stage's registers from the
    # scene (the lights' L and H, unit vectors), its tables, the texture's words
    uni, tables, image = {}, {}, None
    for stage in spec.stages:
        uni.update(stage.uniform_values(scene, v.L, v.H))
        tables.update({(stage.name, k): x for k, x in stage.table_values(scene).items()})
        image = stage.memory_image(data) if image is None else image
    uni = {f.name: int(uni[f.name]) for f in spec.registers}
    onchip = pipe.get("texture") == "onchip"
    try:                              # every value fits its field, or the RTL would wrap it
        check_arrays(spec.raster.unit.inputs, inputs, where="prepare")
    except FieldError as e:
        raise AssertionError(f"the driver made a triangle its raster cannot take: {e}") \
            from None
    return {"scene": scene, "params": pipe, "pipeline": spec, "inputs": inputs, "real": real,
            "memory": None if onchip else image,
            "load": host.writes(spec, uni, tables, image if onchip else None),
            "uniforms": uni, "size": v.size,
            "triangles": {"in": len(v.tris), "culled": int((~v.keep).sum()), "drawn": len(drawn)},
            "float": {"sx": v.sx[drawn], "sy": v.sy[drawn], "inv_z": v.zmin / v.zc[drawn],
                      "N": v.N[drawn], "L": v.L, "H": v.H},
            "data": data, "bump": data if pipe["bump"] != "none" else None}


def rtl_inputs(prep, at=None):
    """The rows of the pipeline's input stream: the scene's data (``prep["load"]``), then its
    triangles; ``at``: further writes between triangles (``scene.host.stream``)."""
    return host.stream(prep["inputs"], prep["load"], at)
