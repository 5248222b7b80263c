"""A scene's mesh in world space: the built-in shapes (torus, sphere, plane) or an OBJ file,
oriented, scaled and moved; the turntable's turn; per-vertex texture coordinates and tangent
frames (what the bump stages take)."""
import math

import numpy as np

from golden import bump as bumps
from golden.bump import rotation

from . import obj
from .stage import SceneError

__all__ = ["mesh", "turn", "orientation", "texcoords", "tangent_frames", "unit", "grid_triangles"]


def grid_triangles(m, n, wrap_i, wrap_j):
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
        tris = grid_triangles(m, n, True, True)
    elif msh["shape"] == "sphere":               # radius major_radius; j runs pole to pole
        phi, th = np.meshgrid(2 * np.pi * np.arange(m) / m, np.pi * np.arange(n + 1) / n,
                              indexing="ij")
        nrm = np.stack([np.sin(th) * np.cos(phi), np.sin(th) * np.sin(phi), -np.cos(th)], -1)
        pos = msh["major_radius"] * nrm
        tris = grid_triangles(m, n + 1, True, False)
    else:                                        # plane: [-1, 1]^2 at z = 0, facing +z
        x, y = np.meshgrid(np.linspace(-1, 1, m + 1), np.linspace(-1, 1, n + 1), indexing="ij")
        pos = np.stack([x, y, np.zeros_like(x)], -1)
        nrm = np.broadcast_to([0.0, 0.0, 1.0], pos.shape)
        tris = grid_triangles(m + 1, n + 1, False, False)
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
    return Rotation.from_rotvec(angle * unit(t["axis"])).as_matrix()


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


def unit(v):
    """``v`` over its length, scaled first by its largest component, so that neither a tiny
    (1e-300) nor a huge (1e300) vector underflows or overflows in the squares."""
    v = np.asarray(v, float)
    m = np.abs(v).max(axis=-1, keepdims=True)
    v = v / np.where(m > 0, m, 1.0)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)
