"""Bump maps for the bump pipelines (scenes.md ``[bump]``; seeds 003 and 004): height maps, the
normals they give in the tangent frame, per-vertex tangent frames, and each method's texels.

Conventions (stated here once, used by the models and the hardware's tables):

- A height map ``h[t, s]`` (row t along the bitangent, column s along the tangent) holds
  heights in [0, 1] over one tile, and tiles without a seam.
- **The normal** of texel (s, t) in the tangent frame (tangent along s, bitangent along t,
  normal out) is ``normalise(-g_s, -g_t, 1)`` with the slopes in tile units,
  ``g_s = depth / 16 * (h[t, s+1] - h[t, s-1]) / 2 * size`` (central differences, wrapping)
  and ``g_t`` likewise down the columns: at ``depth = 1`` a feature of height 1 stands 1/16 of
  the tile above the surface, whatever the map's size.
- **Tangent frames** per vertex: analytic on the torus and the sphere (the derivatives of the
  parametrisation along i and j, which is how their texture coordinates run), and from the
  texture coordinates otherwise (each triangle's dP/ds and dP/dt, summed at its vertices,
  Gram-Schmidt against the normal). T x B = N on every built-in shape.
- **Texels:** X/Z (seed 004, second embodiment) through :func:`golden.fenney.texel_encode` with
  the patent's y axis as the surface normal: (x, y, z) = (n_s, n_out, n_t). S/R (first
  embodiment): S the elevation above the surface plane in 90 deg / 256, R the azimuth from the
  tangent in turns / 256. (phi, theta) (seed 003): :func:`golden.angular.to_polar` of the
  tangent-frame normal.
"""
import math
import zipfile
from pathlib import Path

import numpy as np

from hdl.texture_unit import weight_bits

from .angular import to_polar
from .fenney import texel_decode, texel_encode

MAPS = ("flat", "bricks", "dimples")
DEPTH_SCALE = 1 / 16          # height 1 at depth 1, in tile widths


class BumpError(ValueError):
    pass


def height_map(name, size=256):
    """A built-in map (``MAPS``) of ``size`` x ``size`` texels, or a greyscale image file."""
    if name not in MAPS:
        return _image(name)
    if size < 16:
        raise BumpError(f"bump.size: {size} texels is too small for a map (at least 16)")
    c = (np.arange(size) + 0.5) / size                  # texel centres in tile units
    t, s = np.meshgrid(c, c, indexing="ij")
    if name == "flat":
        return np.zeros((size, size))
    if name == "bricks":          # 4 courses of 2 bricks, alternate courses offset by half
        rows, cols, mortar, bevel = 4, 2, 1 / 64, 1 / 32
        course = np.floor(t * rows)
        ss = np.mod(s * cols + 0.5 * (course % 2), 1.0) / cols      # within a brick, tiles
        tt = np.mod(t * rows, 1.0) / rows
        edge = np.minimum.reduce([ss, 1 / cols - ss, tt, 1 / rows - tt])   # to the brick's edge
        return np.clip((edge - mortar) / bevel, 0.0, 1.0)
    # dimples: a 4 x 4 grid of spherical bowls of radius 0.35 cells
    cells, radius = 4, 0.35
    ds, dt = (np.mod(x * cells, 1.0) - 0.5 for x in (s, t))
    r2 = (ds * ds + dt * dt) / radius ** 2
    return 1.0 - np.sqrt(np.clip(1.0 - r2, 0.0, 1.0))


def _image(path):
    from PIL import Image, UnidentifiedImageError
    p = Path(path)
    if not p.is_file():
        raise BumpError(f"bump.map: {path!r} is neither a built-in map ({', '.join(MAPS)}) "
                        f"nor an image file")
    try:
        with Image.open(p) as im:
            h = np.asarray(im.convert("L"), float) / 255.0
    except (UnidentifiedImageError, OSError) as e:
        raise BumpError(f"bump.map: {path!r} is not a readable image ({e})") from None
    if min(h.shape) < 2:
        raise BumpError(f"bump.map: {path!r} is {h.shape[1]} x {h.shape[0]}: too small")
    return h


def tangent_normals(h, depth=1.0):
    """Unit normals (rows, cols, 3) in the tangent frame (see the module's docstring)."""
    if not (math.isfinite(depth) and depth >= 0):
        raise BumpError(f"bump.depth: must be a finite number >= 0, not {depth}")
    rows, cols = h.shape
    gs = depth * DEPTH_SCALE * (np.roll(h, -1, 1) - np.roll(h, 1, 1)) / 2 * cols
    gt = depth * DEPTH_SCALE * (np.roll(h, -1, 0) - np.roll(h, 1, 0)) / 2 * rows
    n = np.stack([-gs, -gt, np.ones_like(h)], -1)
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def grid_frames(shape, m, n):
    """Analytic (T, B, N) per vertex of the built-in shapes' (i, j) grids, before the mesh's
    rotation: T along i, B along j, N outward (the sphere's grid runs pole to pole, n + 1
    rows; the plane's is (m + 1) x (n + 1))."""
    if shape == "plane":
        k = (m + 1) * (n + 1)
        return tuple(np.broadcast_to(v, (k, 3)).copy() for v in np.eye(3))
    phi = 2 * np.pi * np.arange(m) / m
    other = 2 * np.pi * np.arange(n) / n if shape == "torus" else np.pi * np.arange(n + 1) / n
    phi, a = np.meshgrid(phi, other, indexing="ij")
    T = np.stack([-np.sin(phi), np.cos(phi), np.zeros_like(phi)], -1)
    if shape == "torus":          # a = psi around the tube
        B = np.stack([-np.sin(a) * np.cos(phi), -np.sin(a) * np.sin(phi), np.cos(a)], -1)
        N = np.stack([np.cos(a) * np.cos(phi), np.cos(a) * np.sin(phi), np.sin(a)], -1)
    else:                         # sphere: a = theta from the -z pole
        B = np.stack([np.cos(a) * np.cos(phi), np.cos(a) * np.sin(phi), np.sin(a)], -1)
        N = np.stack([np.sin(a) * np.cos(phi), np.sin(a) * np.sin(phi), -np.cos(a)], -1)
    return tuple(x.reshape(-1, 3) for x in (T, B, N))


def frames_from_uv(pos, nrm, uv, tris, period=(np.inf, np.inf)):
    """(T, B, N) per vertex from texture coordinates: each triangle's dP/ds and dP/dt (from
    its edges and their (s, t) steps), weighted by its area and summed at its vertices, then
    T made orthogonal to N and B = N x T (B's sign from dP/dt, so a mirrored mapping keeps its
    handedness). ``period``: (s, t) steps are taken within half of it (a periodic mapping's
    seam)."""
    p, w = pos[tris], uv[tris]
    e1, e2 = p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]
    finite = np.isfinite(np.asarray(period, float))
    period = np.where(finite, period, 1.0)
    wrap = lambda d: np.where(finite, np.mod(d + period / 2, period) - period / 2, d)
    d1, d2 = wrap(w[:, 1] - w[:, 0]), wrap(w[:, 2] - w[:, 0])
    det = d1[:, 0] * d2[:, 1] - d2[:, 0] * d1[:, 1]
    ok = np.abs(det) > 1e-12
    inv = np.where(ok, 1.0 / np.where(ok, det, 1.0), 0.0)[:, None]
    dps = (e1 * d2[:, 1:2] - e2 * d1[:, 1:2]) * inv
    dpt = (e2 * d1[:, 0:1] - e1 * d2[:, 0:1]) * inv
    area = np.linalg.norm(np.cross(e1, e2), axis=-1)[:, None]
    ts, tt = np.zeros_like(pos), np.zeros_like(pos)
    for c in range(3):
        np.add.at(ts, tris[:, c], dps * area)
        np.add.at(tt, tris[:, c], dpt * area)
    N = _unit(nrm)
    T = ts - np.einsum("ij,ij->i", ts, N)[:, None] * N
    used = np.zeros(len(pos), bool)
    used[tris.ravel()] = True
    bad = used & (np.linalg.norm(T, axis=-1) < 1e-12)
    if bad.any():
        raise BumpError(f"mesh: {int(bad.sum())} vertices have no tangent (their texture "
                        f"coordinates do not vary along the surface)")
    T[~used] = np.nan                             # in no triangle: no frame
    T = _unit(T)
    B = np.cross(N, T)
    B *= np.where(np.einsum("ij,ij->i", B, tt) < 0, -1.0, 1.0)[:, None]
    return T, B, N


def texcoords(scene):
    """Per-vertex texture coordinates (s, t) of the built-in shapes, in tiles (scenes.md: the
    grid's (i / M, j / N) times ``repeat``; the plane's (x + 1) / 2, (y + 1) / 2 likewise)."""
    msh, rep = scene["mesh"], np.array(scene["bump"]["repeat"], float)
    m, n = msh["segments"]
    rows, cols = {"torus": (m, n), "sphere": (m, n + 1), "plane": (m + 1, n + 1)}[msh["shape"]]
    i, j = np.meshgrid(np.arange(rows), np.arange(cols), indexing="ij")
    return (np.stack([i / m, j / n], -1).reshape(-1, 2) * rep)


def rotation(degrees):
    """A mesh's rotation matrix (scenes.md ``mesh.rotate``): about x, then y, then z."""
    rot = np.eye(3)
    for axis, deg in enumerate(degrees):
        c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
        a, b = [k for k in range(3) if k != axis]
        r = np.eye(3)
        r[a, a], r[a, b], r[b, a], r[b, b] = c, -s, s, c
        rot = r @ rot
    return rot


def to_tangent(v, T, B, N):
    """World vectors (..., 3) in the tangent frame (components along T, B, N)."""
    return np.stack([np.einsum("...i,...i->...", v, f) for f in (T, B, N)], -1)


# ---- each method's texels ---------------------------------------------------------------------


def xz_texels(n):
    """Seed 004's X/Z texels (u8 each) of tangent-frame normals."""
    return texel_encode(np.stack([n[..., 0], n[..., 2], n[..., 1]], -1))


def sr_texels(n):
    """Seed 004's S/R texels: S = asin(n_out) in 90 deg / 256 (0..255), R = atan2(n_t, n_s) in
    turns / 256 (0..255, wrapping)."""
    s = np.arcsin(np.clip(n[..., 2], 0.0, 1.0)) / (np.pi / 2) * 256
    r = np.mod(np.arctan2(n[..., 1], n[..., 0]) / (2 * np.pi) * 256, 256)
    return np.minimum(np.rint(s), 255).astype(np.int64), np.rint(r).astype(np.int64) % 256


def polar_texels(n, bits=12):
    """Seed 003's (phi, theta) of tangent-frame normals, each in turns * 2**bits."""
    phi, theta = to_polar(n)
    q = lambda a: np.rint(a / (2 * np.pi) * (1 << bits)).astype(np.int64) % (1 << bits)
    return q(phi), q(theta)


# ---- texel fetch (hdl/texture_unit: the same definitions) -------------------------------------


def fetch(codes, raw_s, raw_t, filter="nearest"):
    """An 8-bit code map (size x size, row t, column s) at texture coordinates given as the
    raster's raw values (tiles, 14 fraction bits), wrapping: the nearest texel, or the
    bilinear filter of hdl/texture_unit/texture.py, bit for bit (integers, round half up)."""
    size = codes.shape[0]
    b = size.bit_length() - 1
    raw_s, raw_t = (np.asarray(r, np.int64) for r in (raw_s, raw_t))
    if filter == "nearest":
        return codes[(raw_t >> (14 - b)) & (size - 1), (raw_s >> (14 - b)) & (size - 1)]
    F = weight_bits(b)
    u = [(r - (1 << (13 - b))) & ((1 << 14) - 1) for r in (raw_s, raw_t)]
    i0 = [x >> (14 - b) for x in u]
    f = [(x >> (14 - b - F)) & ((1 << F) - 1) for x in u]
    i1 = [(i + 1) & (size - 1) for i in i0]
    c = codes.astype(np.int64)
    rows = [c[j, i0[0]] * (1 << F) + (c[j, i1[0]] - c[j, i0[0]]) * f[0] for j in (i0[1], i1[1])]
    r = rows[0] * (1 << F) + (rows[1] - rows[0]) * f[1]
    return (r + (1 << (2 * F - 1))) >> (2 * F)


def sample(normals, st, filter="nearest"):
    """The reference's normal at exact texture coordinates (tiles, (n, 2)): the texel's, or
    the bilinear blend of the four around it (texel centres at half-integers), normalised."""
    size = normals.shape[0]
    u = np.mod(st, 1.0) * size
    if filter == "nearest":
        i = np.floor(u).astype(np.int64) % size
        return normals[i[:, 1], i[:, 0]]
    u = u - 0.5
    i0 = np.floor(u).astype(np.int64)
    f = u - i0
    i0, i1 = i0 % size, (i0 + 1) % size
    ws, wt = (1 - f[:, 0], f[:, 0]), (1 - f[:, 1], f[:, 1])
    cs, ct = (i0[:, 0], i1[:, 0]), (i0[:, 1], i1[:, 1])
    n = sum(normals[ct[b], cs[a]] * (ws[a] * wt[b])[:, None] for a in (0, 1) for b in (0, 1))
    return n / np.linalg.norm(n, axis=-1, keepdims=True)


# ---- what a texture ROM holds ------------------------------------------------------------------

KINDS = {"fenney_polar": "sr", "fenney_xz": "xz", "angular": "polar"}


def texel_file(path):
    """Pre-encoded X/Z texels (fenney_xz; the patent's tools write texels, not heights): an
    .npz with arrays ``texel_x`` and ``texel_z`` of codes 0..255, square. Codes that the
    encoder never writes (255, or past the diamond |X - 127| + |Z - 127| <= 127) are allowed:
    texel_decode's guard meets them."""
    try:
        with np.load(path) as f:
            tx, tz = (np.asarray(f[k]) for k in ("texel_x", "texel_z"))
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as e:
        raise BumpError(f"bump.map: {path!r} is not an .npz of texel_x and texel_z ({e})") \
            from None
    if tx.shape != tz.shape or tx.ndim != 2 or tx.dtype.kind not in "iu" \
            or tz.dtype.kind not in "iu" or not ((0 <= tx) & (tx <= 255)).all() \
            or not ((0 <= tz) & (tz <= 255)).all():
        raise BumpError(f"bump.map: {path!r}: texel_x and texel_z must be equal 2-D arrays of "
                        f"integer codes 0..255")
    return tx.astype(np.int64), tz.astype(np.int64)


def bump_texels(kind, bump_map, size, depth, bits=8):
    """``(hi, lo, normals)``: a map's texels as its texture ROM stores them (``kind`` "sr": S,
    R; "xz": TexelX, TexelZ; "polar": theta, phi of ``bits`` each) and the exact
    tangent-frame normals the reference shades with. A texel file's normals are its decoded
    vectors, normalised."""
    if str(bump_map).endswith(".npz"):
        if kind != "xz":
            raise BumpError(f"bump.map: a texel file ({bump_map!r}) holds X/Z texels, for "
                            f"bump.method = fenney_xz only")
        tx, tz = texel_file(bump_map)
        d = texel_decode(tx, tz)
        n = np.stack([d["x"], d["z"], d["y"]], -1).astype(float)
        return tx, tz, n / np.linalg.norm(n, axis=-1, keepdims=True)
    n = tangent_normals(height_map(bump_map, size), depth)
    if kind == "polar":
        lo, hi = polar_texels(n, bits)
    else:
        hi, lo = sr_texels(n) if kind == "sr" else xz_texels(n)
    return hi, lo, n
