"""golden/bump.py: height maps, tangent-frame normals, tangent frames and each bump method's
texels, checked against their definitions and derived bounds (no hardware here)."""
import numpy as np
import pytest
from PIL import Image

from golden.bump import (MAPS, BumpError, frames_from_uv, grid_frames, height_map,
                         polar_texels, sr_texels, tangent_normals, xz_texels)
from golden.fenney import texel_decode
from scene.mesh import grid_triangles


def _angle(a, b):
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    return np.degrees(np.arccos(np.clip(np.einsum("...i,...i", a, b), -1, 1)))


@pytest.mark.parametrize("name", MAPS)
def test_maps_tile_without_a_seam_and_normals_point_out(name):
    """Across the tile's edge a map steps no more than anywhere inside it, so its wrapped
    differences make no seam; its normals are unit vectors pointing out of the surface."""
    h = height_map(name, 128)
    assert h.shape == (128, 128) and h.min() >= 0 and h.max() <= 1
    for ax in (0, 1):
        inside = np.abs(np.diff(h, axis=ax)).max()
        across = np.abs(np.take(h, 0, ax) - np.take(h, -1, ax)).max()
        assert across <= inside + 1e-12
    n = tangent_normals(h, 1.0)
    assert np.allclose(np.linalg.norm(n, axis=-1), 1) and (n[..., 2] > 0).all()
    if name == "flat":
        assert (n == [0, 0, 1]).all()
    else:
        assert n[..., 2].min() < 0.95          # the map has relief


def test_the_difference_rule_on_a_ramp():
    """h = s / size along each row (a ramp of one per tile): g_s = depth / 16 exactly, so the
    normal is normalise(-depth / 16, 0, 1) away from the wrap; depth 0 is flat."""
    size, depth = 64, 3.0
    h = np.tile(np.arange(size) / size, (size, 1))
    n = tangent_normals(h, depth)[:, 1:-1]
    want = np.array([-depth / 16, 0, 1]) / np.hypot(depth / 16, 1)
    assert np.allclose(n, want, atol=1e-12)
    assert (tangent_normals(h, 0.0) == [0, 0, 1]).all()


@pytest.mark.parametrize("shape,m,n", [("torus", 48, 32), ("sphere", 48, 24), ("plane", 6, 5)])
def test_analytic_frames_against_frames_from_texture_coordinates(shape, m, n):
    """The analytic frames are orthonormal with T x B = N; the ones found from texture
    coordinates on the faceted mesh agree within half a segment's angle (each triangle's
    dP/ds is a chord, within half its arc's angle of the tangent, and so is their average;
    making it orthogonal to the exact N only brings it closer). Seam triangles left out."""
    T, B, N = grid_frames(shape, m, n)
    assert np.allclose(np.einsum("ij,ij->i", T, B), 0) and np.allclose(np.cross(T, B), N)
    rows = n if shape == "torus" else n + 1
    if shape == "plane":
        mm, nn = m + 1, n + 1
        i, j = np.meshgrid(np.arange(mm), np.arange(nn), indexing="ij")
        pos = np.stack([2 * i / m - 1, 2 * j / n - 1, 0 * i], -1).reshape(-1, 3)
        uv = np.stack([i / m, j / n], -1).reshape(-1, 2)
        tris, inner = grid_triangles(mm, nn, False, False), np.ones(mm * nn, bool)
        half = 0.0
    else:
        R, r = (1.0, 0.5) if shape == "torus" else (1.0, 0.0)
        i, j = np.meshgrid(np.arange(m), np.arange(rows), indexing="ij")
        radial = np.stack([T[:, 1], -T[:, 0], 0 * T[:, 0]], -1)     # (cos phi, sin phi, 0)
        pos = r * N + R * (N if shape == "sphere" else radial)
        uv = np.stack([i / m, j / n], -1).reshape(-1, 2)
        tris = grid_triangles(m, rows, False, False)      # no wrap: no seam in (s, t)
        p = pos[tris]
        tris = tris[np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=-1)
                    > 1e-12]
        inner = ((i > 0) & (i < m - 1) & (j > 0) & (j < rows - 1)).ravel()
        half = 0.5 * 360 / min(m, 2 * n if shape == "torus" else 2 * n)   # the longer arc
    t2, b2, n2 = frames_from_uv(pos, N, uv, tris)
    bound = max(half, 1e-9)
    assert _angle(t2[inner], T[inner]).max() <= bound
    assert _angle(b2[inner], B[inner]).max() <= bound
    framed = np.isfinite(t2).all(1)                       # vertices in some triangle
    assert framed[inner].all() and np.allclose(np.cross(t2, b2)[framed], n2[framed])


def test_xz_texels_decode_to_the_normal():
    """Encode then decode (the patent's decode, y up): the direction comes back within the
    truncation's reach. In L1 units each of x and z is cut by less than 1/127, and y =
    255 - |bx| - |bz| (over 254) by less than 2/127 + 1/254; an L1-unit vector is at least
    1/sqrt(3) long, so the angle is at most asin(sqrt(2 (1/127)^2 + (2/127 + 1/254)^2) sqrt(3))."""
    rng = np.random.default_rng(3)
    v = rng.normal(size=(20000, 3))
    v[:, 2] = np.abs(v[:, 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    tx, tz = xz_texels(v)
    d = texel_decode(tx, tz)
    assert not d["invalid"].any()
    back = np.stack([d["x"], d["z"], d["y"]], -1).astype(float)
    err = np.sqrt(2 * (1 / 127) ** 2 + (2 / 127 + 1 / 254) ** 2) * np.sqrt(3)
    assert _angle(back, v).max() <= np.degrees(np.arcsin(err))
    assert list(xz_texels(np.array([0.0, 0.0, 1.0]))) == [127, 127]


def test_sr_and_polar_texels_come_back_within_their_quanta():
    """S/R: S rounds to 90/256 deg (one quantum at the clamp to 255), R to 360/256 deg, which
    moves the vector by that times cos S; (phi, theta) round to 360/4096 deg each."""
    rng = np.random.default_rng(4)
    v = rng.normal(size=(20000, 3))
    v[:, 2] = np.abs(v[:, 2])
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    s, r = sr_texels(v)
    S, Rr = s * (np.pi / 2) / 256, r * 2 * np.pi / 256
    back = np.stack([np.cos(S) * np.cos(Rr), np.cos(S) * np.sin(Rr), np.sin(S)], -1)
    bound = 90 / 256 + 0.5 * 360 / 256 * np.sqrt(1 - v[:, 2] ** 2)
    assert (_angle(back, v) <= bound + 1e-9).all()
    phi, theta = polar_texels(v, 12)
    p, t = phi * 2 * np.pi / 4096, theta * 2 * np.pi / 4096
    back = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1)
    assert _angle(back, v).max() <= 360 / 4096


def test_an_image_map_and_bad_maps(tmp_path):
    """A greyscale PNG is read as heights / 255; a missing or unreadable file, or a bad
    depth, is an error that names the key."""
    img = (np.arange(32 * 16).reshape(16, 32) % 256).astype(np.uint8)
    Image.fromarray(img).save(tmp_path / "h.png")
    assert np.array_equal(height_map(str(tmp_path / "h.png")), img / 255.0)
    (tmp_path / "bad.png").write_text("not an image")
    for path in (tmp_path / "none.png", tmp_path / "bad.png"):
        with pytest.raises(BumpError, match="bump.map"):
            height_map(str(path))
    with pytest.raises(BumpError, match="bump.depth"):
        tangent_normals(np.zeros((4, 4)), float("nan"))


@pytest.mark.parametrize("shape", ["torus", "sphere", "plane"])
def test_scene_frames_follow_the_mesh(shape):
    """A scene's frames carry the mesh's rotation: their N is the mesh's own normal, and there
    is one frame and one (s, t) per vertex, the torus's running to ``repeat`` tiles."""
    from scene.driver import mesh, parse, tangent_frames, texcoords
    sc = parse({"mesh": {"shape": shape, "segments": [8, 6], "rotate": [30.0, -20.0, 75.0]}})
    pos, nrm, _ = mesh(sc)
    T, B, N = tangent_frames(sc)
    assert np.allclose(N, nrm) and np.allclose(np.cross(T, B), N)
    uv, periodic = texcoords(sc)
    assert periodic == (True, True)
    assert uv.shape == (len(pos), 2)
    if shape == "torus":
        assert np.allclose(uv.max(0), np.array(sc["bump"]["repeat"]) * [7 / 8, 5 / 6])
