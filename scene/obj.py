"""Wavefront OBJ meshes (scenes.md: ``mesh.shape = "obj"``, ``file = "..."``).

Read here, not through a mesh library: the format is a line format, and a user's mistake must
name the file and the line, which no loader on PyPI reports (trimesh and meshio raise their own
parse errors without one). What is read:

- ``v x y z [w | r g b]``: positions (the first three numbers; a weight or a vertex colour is
  ignored);
- ``vn x y z``: normals, normalised;
- ``vt u [v [w]]``: texture coordinates (u, v; v = 0 where it is missing);
- ``f a b c ...``: faces of three or more corners, each ``v``, ``v/vt``, ``v//vn`` or
  ``v/vt/vn``, 1-based, or negative (relative to the elements read so far). A polygon is split
  as a fan from its first corner, which is right for the convex polygons modelling tools write.
- Grouping and materials (``o``, ``g``, ``s``, ``usemtl``, ``mtllib``), points and lines
  (``p``, ``l``) do not change the surface and are skipped; any other statement (free-form
  curves and surfaces) is an error.

A corner is a (position, texture coordinate, normal) triple; each distinct triple is one vertex
of the mesh, so a seam in the file's normals or texture coordinates stays a seam.

- **Normals where the file has none** (at a corner without ``vn``): the smooth normal of its
  position, the sum of the geometric normals (p1 - p0) x (p2 - p0) of every triangle that uses
  the position, so each weighted by its area, normalised.
- **Texture coordinates where the file has none** (unless every corner has one, and they
  span some area: a file whose corners all name one ``vt`` has none in effect): a cylindrical
  projection about the longest axis of the model's bounding box (say y), through its centre:
  s = atan2(x - cx, z - cz) / 2 pi + 1/2, t = (y - y_min) / (y_max - y_min) (the axes
  cycled for the others: about x, atan2(z, y); about z, atan2(y, x)). The frames derived
  from it are right-handed (T x B = N).
  s is then periodic (a triangle across the seam takes its vertices' s within half a turn of
  each other), t is not.
"""
import math
from functools import lru_cache
from pathlib import Path

import numpy as np

__all__ = ["ObjError", "ObjMesh", "read"]

SKIPPED = {"o", "g", "s", "usemtl", "mtllib", "p", "l"}


class ObjError(ValueError):
    """An OBJ file that cannot be read: the message names the file and, where there is one,
    the line."""


class ObjMesh:
    """A read OBJ: per vertex ``pos`` (n, 3), ``nrm`` (n, 3), ``uv`` (n, 2); ``tris`` (m, 3);
    ``periodic``: which of (s, t) wrap (the projection's s); ``counts``: what the file held."""

    def __init__(self, pos, nrm, uv, tris, periodic, counts):
        self.pos, self.nrm, self.uv, self.tris = pos, nrm, uv, tris
        self.periodic, self.counts = periodic, counts


def read(path):
    """The mesh of an OBJ file (cached by path, size and modification time)."""
    path = Path(path)
    try:
        st = path.stat()
    except OSError as e:
        raise ObjError(f"{path}: cannot read the OBJ file ({e.strerror})") from None
    return _read(str(path), st.st_size, st.st_mtime_ns)


@lru_cache(maxsize=8)
def _read(path, size, mtime):
    try:
        text = Path(path).read_bytes().decode("utf-8")
    except IsADirectoryError:
        raise ObjError(f"{path}: is a directory, not an OBJ file") from None
    except OSError as e:
        raise ObjError(f"{path}: cannot read the OBJ file ({e.strerror})") from None
    except UnicodeDecodeError as e:
        raise ObjError(f"{path}: not a text OBJ file (byte {e.start} is not UTF-8)") from None
    lists = {"v": [], "vt": [], "vn": []}
    corners, faces = [], 0                  # corners: (v, vt, vn) per triangle corner, -1: none

    def numbers(line, words, lo, hi, key):
        if not lo <= len(words) <= hi:
            raise ObjError(f"{path}:{line}: '{key}' takes {lo} to {hi} numbers, not "
                           f"{len(words)}")
        try:
            vals = [float(w) for w in words]
        except ValueError:
            raise ObjError(f"{path}:{line}: '{key}': not a number in {' '.join(words)!r}") \
                from None
        if not all(math.isfinite(x) for x in vals):
            raise ObjError(f"{path}:{line}: '{key}': {' '.join(words)} is not finite")
        return vals

    def index(line, word, kind):
        n = len(lists[kind])
        try:
            k = int(word)
        except ValueError:
            raise ObjError(f"{path}:{line}: 'f': {word!r} is not an index") from None
        k = k - 1 if k > 0 else n + k if k < 0 else -1
        if not 0 <= k < n:
            raise ObjError(f"{path}:{line}: 'f': {kind} index {word} is out of range ({n} "
                           f"read so far)")
        return k

    for line, raw in enumerate(text.splitlines(), 1):
        words = raw.split("#", 1)[0].split()
        if not words:
            continue
        key, args = words[0], words[1:]
        if key == "v":
            lists["v"].append(numbers(line, args, 3, 7, key)[:3])
        elif key == "vn":
            n = np.array(numbers(line, args, 3, 3, key))
            if not np.linalg.norm(n) > 0:
                raise ObjError(f"{path}:{line}: 'vn': the zero vector is no normal")
            lists["vn"].append(n / np.linalg.norm(n))
        elif key == "vt":
            uv = numbers(line, args, 1, 3, key)
            lists["vt"].append((uv + [0.0])[:2])
        elif key == "f":
            if len(args) < 3:
                raise ObjError(f"{path}:{line}: 'f': a face needs 3 or more corners, not "
                               f"{len(args)}")
            face = []
            for a in args:
                parts = a.split("/")
                if len(parts) > 3 or not parts[0]:
                    raise ObjError(f"{path}:{line}: 'f': {a!r} is not a corner (v, v/vt, "
                                   f"v//vn or v/vt/vn)")
                parts += [""] * (3 - len(parts))
                face.append(tuple(index(line, p, k) if p else -1
                                  for p, k in zip(parts, ("v", "vt", "vn"))))
            faces += 1
            corners += [(face[0], face[k], face[k + 1]) for k in range(1, len(face) - 1)]
        elif key not in SKIPPED:
            raise ObjError(f"{path}:{line}: '{key}' is not supported (positions, normals, "
                           f"texture coordinates and faces are read)")
    if not corners:
        raise ObjError(f"{path}: no faces")
    return _mesh(np.array(corners, np.int64), *(np.array(lists[k], float).reshape(-1, w)
                                                 for k, w in (("v", 3), ("vt", 2), ("vn", 3))),
                 faces)


def _mesh(corners, P, T, Nf, faces):
    """One vertex per distinct corner triple; the normals and texture coordinates the file
    lacks (the module's docstring)."""
    flat = corners.reshape(-1, 3)
    triples, inverse = np.unique(flat, axis=0, return_inverse=True)
    tris = inverse.reshape(-1, 3)
    vi, ti, ni = triples.T
    p = P[corners[..., 0]]                                       # (m, 3, 3)
    geo = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])         # area-weighted
    smooth = np.zeros_like(P)
    for c in range(3):
        np.add.at(smooth, corners[:, c, 0], geo)
    length = np.linalg.norm(smooth, axis=-1, keepdims=True)
    smooth = np.where(length > 0, smooth / np.where(length > 0, length, 1), [0.0, 0.0, 1.0])
    nrm = np.where((ni >= 0)[:, None], Nf[np.maximum(ni, 0)] if len(Nf) else 0.0, smooth[vi])
    given = (ti >= 0).all()
    if given:
        w = T[corners[..., 1]]
        e1, e2 = w[:, 1] - w[:, 0], w[:, 2] - w[:, 0]
        given = bool((np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0]) > 0).any())
    if given:
        uv, periodic = T[ti], (False, False)
    else:
        lo, hi = P.min(0), P.max(0)
        a = int(np.argmax(hi - lo))                              # the axis
        b, c = (a + 1) % 3, (a + 2) % 3                          # z, x about y (right-handed)
        q = P[vi] - (lo + hi) / 2
        t = (P[vi, a] - lo[a]) / (hi[a] - lo[a]) if hi[a] > lo[a] else 0 * q[:, a]
        uv = np.stack([np.arctan2(q[:, c], q[:, b]) / (2 * np.pi) + 0.5, t], -1)
        periodic = (True, False)
    counts = {"positions": len(P), "normals": len(Nf), "texcoords": len(T), "faces": faces,
              "triangles": len(tris), "vertices": len(triples),
              "normals_from": "file" if (ni >= 0).all() else
                              "computed" if (ni < 0).all() else "file and computed",
              "texcoords_from": "file" if not periodic[0] else "cylindrical projection" + (
                  "" if (ti < 0).any() else " (the file's span no area)")}
    return ObjMesh(P[vi], nrm, uv, tris, periodic, counts)
