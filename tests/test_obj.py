"""OBJ meshes (``mesh.shape = "obj"``, scene/obj.py): the reader against the built-in shapes
it must reproduce, the normals and texture coordinates it makes where a file has none, bad
files named by file and line, and the shipped model through the RTL."""
import subprocess
import sys

import numpy as np
import pytest

from scene import driver as S
from scene import obj

from sim.simulators import available

SCENES = "scenes"


def write_obj(path, pos, tris, nrm=None, uv=None):
    """An OBJ of a vertex-indexed mesh: each corner names its vertex's own normal and
    texture coordinate, if given."""
    lines = [f"v {p[0]:.17g} {p[1]:.17g} {p[2]:.17g}" for p in pos]
    lines += [f"vn {n[0]:.17g} {n[1]:.17g} {n[2]:.17g}" for n in (nrm if nrm is not None else [])]
    lines += [f"vt {t[0]:.17g} {t[1]:.17g}" for t in (uv if uv is not None else [])]
    corner = "{0}" + ("/{0}" if uv is not None else "/" if nrm is not None else "") + \
        ("/{0}" if nrm is not None else "")
    lines += ["f " + " ".join(corner.format(k + 1) for k in t) for t in tris]
    path.write_text("\n".join(lines) + "\n")
    return path


def builtin(shape="torus", **mesh):
    sc = S.parse({"mesh": {"shape": shape, **mesh}})
    return sc, S.mesh(sc)


def test_torus_obj_is_the_builtin_torus(tmp_path):
    """The default torus written as an OBJ (positions, normals, the same triangles) gives the
    hardware exactly the built-in torus's inputs, and the same counts."""
    sc, (pos, nrm, tris) = builtin()
    path = write_obj(tmp_path / "torus.obj", pos, tris, nrm)
    a = S.prepare(sc)
    b = S.prepare(S.parse({"mesh": {"shape": "obj", "file": str(path)}}))
    assert a["triangles"] == b["triangles"] == {"in": 288, "culled": 152, "drawn": 136}
    assert a["inputs"].keys() == b["inputs"].keys()
    for k in a["inputs"]:
        np.testing.assert_array_equal(a["inputs"][k], b["inputs"][k], err_msg=k)


def test_smooth_normals_where_the_file_has_none(tmp_path):
    """Without ``vn`` a vertex takes the area-weighted sum of its triangles' normals. A small
    triangle's geometric normal is the surface's normal at a point inside it (to first order),
    so it lies within the cone of its vertices' true normals: each computed normal is within
    the widest angle between the true normals of a triangle at that vertex (and far closer
    where the mesh is symmetric about the vertex, as the torus is everywhere)."""
    sc, (pos, nrm, tris) = builtin(segments=[24, 16])
    m = obj.read(write_obj(tmp_path / "t.obj", pos, tris))
    assert m.counts["normals_from"] == "computed" and len(m.pos) == len(pos)
    got = np.array([m.nrm[np.flatnonzero((m.pos == p).all(1))[0]] for p in pos])
    ang = np.degrees(np.arccos(np.clip((got * nrm).sum(1), -1, 1)))
    spread = np.zeros(len(pos))
    for t in tris:
        a = max(np.degrees(np.arccos(np.clip(nrm[i] @ nrm[j], -1, 1)))
                for i in t for j in t)
        spread[t] = np.maximum(spread[t], a)
    assert (ang <= spread).all() and ang.max() < 0.1 * spread.max()


def test_faces_corners_and_vertices(tmp_path):
    """Polygons split as fans from their first corner; 1-based and negative indices; a corner
    triple seen twice is one vertex, a position with two texture coordinates two."""
    path = tmp_path / "q.obj"
    path.write_text("# a quad and a pentagon\no thing\ng a\ns 1\nusemtl m\n"
                    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\n"
                    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 1.5 0\nvn 0 0 2\n"
                    "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
                    "f -5/1/-1 -4/2/-1 -3/3/-1 -1/5/-1 -2/4/-1\n"
                    "f 1/3/1 2/2/1 3/3/1\nl 1 2\n")
    m = obj.read(path)
    assert m.counts["faces"] == 3 and len(m.tris) == 2 + 3 + 1
    first = [tuple(map(tuple, m.pos[t].tolist())) for t in m.tris[:2]]
    assert first == [((0, 0, 0), (1, 0, 0), (1, 1, 0)), ((0, 0, 0), (1, 1, 0), (0, 1, 0))]
    assert len(m.pos) == 5 + 1            # corner (1, vt 3) is new; the rest repeat
    assert np.allclose(m.nrm, [0, 0, 1]) and m.counts["texcoords_from"] == "file"
    assert m.periodic == (False, False)


def test_cylindrical_projection_and_bump_frames(tmp_path):
    """Without texture coordinates, s runs around the model's y axis (periodic) and t up it.
    On a cylinder (a torus's outer band stood up) the frames derived from them have T along
    the circumference, B up the axis, and a bump method renders across the projection's
    seam."""
    k = 32
    phi = 2 * np.pi * np.arange(k) / k
    ring = np.stack([np.sin(phi), np.zeros(k), np.cos(phi)], -1)
    pos = np.concatenate([ring, ring + [0, 3, 0]])                    # y the longest axis
    tris = [(a, (a + 1) % k, k + (a + 1) % k) for a in range(k)] + \
        [(a, k + (a + 1) % k, k + a) for a in range(k)]
    path = write_obj(tmp_path / "cyl.obj", pos, tris)
    m = obj.read(path)
    assert m.periodic == (True, False) and m.counts["texcoords_from"] == "cylindrical projection"
    np.testing.assert_allclose(m.uv[:, 1], (m.pos[:, 1] > 1.5).astype(float))
    sc = S.parse({"mesh": {"shape": "obj", "file": str(path)},
                  "bump": {"method": "fenney_polar", "repeat": [4.0, 0.5], "size": 64},
                  "image": {"width": 64, "height": 64}})
    T, B, N = S.tangent_frames(sc)
    radial = m.pos * [1, 0, 1]
    assert np.allclose(N, radial, atol=0.05) and np.allclose(B, [0, 1, 0], atol=0.05)
    assert np.allclose(np.cross(T, B), N)
    prep = S.prepare(sc)
    img, cov, n = S.model(prep)
    assert n > 100 and prep["triangles"]["drawn"] > 0


BAD = [
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ":4: 'f': v index 4 is out of range (3 read"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n", ":4: 'f': a face needs 3 or more corners, not 2"),
    ("v 0 0\n", ":1: 'v' takes 3 to 7 numbers, not 2"),
    ("v 0 0 x\n", ":1: 'v': not a number in '0 0 x'"),
    ("\n\nv 0 nan 0\n", ":3: 'v': 0 nan 0 is not finite"),
    ("vn 0 0 0\n", ":1: 'vn': the zero vector is no normal"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n", ":4: 'f': 'a' is not an index"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n", ":4: 'f': '1/1/1/1' is not a corner"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", ":4: 'f': vt index 1 is out of range"),
    ("cstype bspline\n", ":1: 'cstype' is not supported"),
    ("v 0 0 0\n# nothing else\n", ": no faces"),
]


@pytest.mark.parametrize("text,message", BAD, ids=[m.split(":")[-1].strip()[:24] for _, m in BAD])
def test_bad_obj_files_name_the_file_and_line(tmp_path, text, message):
    path = tmp_path / "bad.obj"
    path.write_text(text)
    with pytest.raises(S.SceneError) as e:
        S.parse({"mesh": {"shape": "obj", "file": str(path)}})
    assert str(e.value).startswith(f"mesh.file: {path}") and message in str(e.value), e.value


def test_obj_keys_and_unreadable_files(tmp_path):
    (tmp_path / "bin.obj").write_bytes(b"\x89PNG\r\n\x1a\n\xff\xfe")
    cases = [({"shape": "obj"}, 'mesh.file: mesh.shape = "obj" needs the OBJ file'),
             ({"file": "x.obj"}, 'mesh.file: only with mesh.shape = "obj", not with \'torus\''),
             ({"shape": "obj", "file": str(tmp_path / "none.obj")}, "cannot read the OBJ file"),
             ({"shape": "obj", "file": str(tmp_path)}, "is a directory, not an OBJ file"),
             ({"shape": "obj", "file": str(tmp_path / "bin.obj")}, "not a text OBJ file"),
             ({"shape": "obj", "file": 3}, "mesh.file: must be a string")]
    for mesh, message in cases:
        with pytest.raises(S.SceneError, match=message):
            S.parse({"mesh": mesh})


def test_file_is_relative_to_the_scene_and_errors_exit_2(tmp_path):
    """``mesh.file`` is read from the scene file's folder, wherever the command runs; a bad
    OBJ is one line naming the file and line, exit 2, no traceback."""
    sc = S.load(f"{SCENES}/wuson.toml")
    assert sc["mesh"]["file"].endswith("scenes/models/wuson.obj")
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / "bad.obj").write_text("v 1 2 3\nf 1 1 9\n")
    (tmp_path / "s.toml").write_text('[mesh]\nshape = "obj"\nfile = "m/bad.obj"\n')
    r = subprocess.run([sys.executable, "-m", "sim", "render", str(tmp_path / "s.toml"),
                        "--simulator", "amaranth", "--out", str(tmp_path / "o")],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr, r.stderr
    assert f"mesh.file: {tmp_path / 'm' / 'bad.obj'}:2: 'f': v index 9 is out of range" \
        in r.stderr


@pytest.mark.xdist_group("verilator-scene")
@pytest.mark.skipif(bool(available("verilator")), reason=f"verilator: {available('verilator')}")
def test_shipped_model_through_the_rtl(tmp_path):
    """scenes/wuson.toml at 64 x 64 on the batch path (the default scene's model at that
    size): the model's fragments in its order, each within one level of the model's colour.
    The framebuffers may differ only where the depth test is a tie in the RTL's depth format
    (1 LSB of 2^-14) that the float model's depth breaks: the real mesh has surfaces that meet
    (z-fighting), which the torus never has."""
    from sim.render import render
    m = render(f"{SCENES}/wuson.toml", tmp_path, "verilator", (64, 64), quiet=True)
    assert m["triangles"]["in"] == 3732 and m["mesh"]["normals_from"] == "file"
    assert m["rtl_vs_model"]["coverage_mismatch"] == 0 and m["fragments"] == m["fragments_model"]
    from sim.run import simulate
    sc = S.load(f"{SCENES}/wuson.toml")
    sc["image"].update(width=64, height=64)
    prep = S.prepare(S.parse({k: v for k, v in sc.items() if k != "name"}))
    out, _ = simulate("scene", prep["params"], S.rtl_inputs(prep), "verilator")
    frag, ch = S.model_fragments(prep)
    for key in ("tri", "x", "y"):
        np.testing.assert_array_equal(out[key], frag[key])
    model = S.run_models(prep, frag, ch, prep["pipeline"].stages[1:])
    for c in "rgb":
        assert np.abs(out[c].astype(int) - model[c].astype(int)).max() <= 1
    rgb = np.stack([out[c] for c in "rgb"], -1).astype(np.uint8)
    rtl, _ = S.framebuffer(prep["size"], out["x"], out["y"], out["depth"], rgb, [0, 0, 0])
    img, _, _ = S.model(prep)
    for y, x in zip(*np.nonzero(np.abs(rtl.astype(int) - img.astype(int)).max(-1) > 1)):
        at = (out["x"] == x) & (out["y"] == y)
        assert (out["depth"][at] == out["depth"][at].max()).sum() > 1, (x, y)


def test_bump_on_a_model_without_texture_coordinates_is_refused():
    """Wuson's file names one texture coordinate for every corner (none, in effect): the
    projection's s wraps whole turns around the triangles at the ends of its axis, beyond the
    raster's range, so a bump method is a scene error saying what to give instead."""
    sc = S.load(f"{SCENES}/wuson.toml")
    sc["bump"].update(method="fenney_polar", size=128)
    sc = S.parse({k: v for k, v in sc.items() if k != "name"})
    assert obj.read(sc["mesh"]["file"]).counts["texcoords_from"] == \
        "cylindrical projection (the file's span no area)"
    with pytest.raises(S.SceneError, match="bump.repeat: .*give the OBJ finer texture "
                                           "coordinates"):
        S.prepare(sc)
