"""make turntable: a frame is the scene with its turntable key set, and the frames come out the
same from a local process pool and from a Dask LocalCluster."""
import numpy as np
import pytest
from PIL import Image

from scene import driver as S
from sim.simulators import available
from sim.turntable import turntable, variant


def _inputs_equal(a, b):
    pa, pb = S.prepare(a), S.prepare(b)
    assert pa["inputs"].keys() == pb["inputs"].keys()
    for k in pa["inputs"]:
        np.testing.assert_array_equal(pa["inputs"][k], pb["inputs"][k], err_msg=k)
    return pa


def test_a_frame_is_the_scene_turned():
    """Frame k of n is the scene turned by degrees * k / n about the axis: for the mesh,
    exactly the scene with that ``mesh.rotate`` (about z, after the mesh's own rotation); for
    the light, the scene with ``to_light`` turned by hand (the rotation matrix written out)."""
    base = {"image": {"width": 64, "height": 64}}
    spun = S.parse({**base, "turntable": {"spin": "mesh", "degrees": 90.0, "frames": 6,
                                          "frame": 2}})
    _inputs_equal(spun, S.parse({**base, "mesh": {"rotate": [0.0, 0.0, 30.0]}}))
    a = np.radians(120.0)
    rz = np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])
    orbit = variant(S.parse(base), "xshading", 1, 3)
    prep = _inputs_equal(orbit, S.parse({**base, "lights": [
        {"to_light": list(rz @ np.array(S.DEFAULTS["lights"][0]["to_light"]))}]}))
    assert prep["triangles"]["drawn"] > 0
    with pytest.raises(S.SceneError, match="turntable.frame: must be below turntable.frames"):
        S.parse({"turntable": {"frame": 3, "frames": 3}})
    with pytest.raises(S.SceneError, match="turntable.axis: must not be the zero vector"):
        S.parse({"turntable": {"axis": [0, 0, 0]}})


@pytest.mark.xdist_group("verilator-scene")
@pytest.mark.skipif(bool(available("verilator")), reason=f"verilator: {available('verilator')}")
def test_local_pool_and_dask_cluster_give_the_same_frames(tmp_path):
    """Three frames of the default torus at 64 x 64 (the default scene's model at that size,
    built once and shared by every worker), its light orbiting: identical images and figures
    from two local processes and from a two-worker LocalCluster; frame 0 is the scene itself,
    and the light's turn moves the image."""
    distributed = pytest.importorskip("distributed")
    from sim.render import run_rtl
    scene = S.parse({"image": {"width": 64, "height": 64}}, "default")
    local = turntable(scene, 3, jobs=2, out_dir=tmp_path, quiet=True)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, \
            distributed.Client(cluster) as client:
        remote = turntable(scene, 3, dask=client, quiet=True)
        workers = {w["id"] for w in client.scheduler_info()["workers"].values()}
    assert len(workers) == 2
    for a, b in zip(local, remote):
        assert a["frame"] == b["frame"]
        np.testing.assert_array_equal(a["rtl"]["xshading"], b["rtl"]["xshading"])
        np.testing.assert_array_equal(a["reference"], b["reference"])
        strip = lambda f: {k: v for k, v in f.items() if k != "rtl_wall_s"}
        assert strip(a["figures"]["xshading"]) == strip(b["figures"]["xshading"])
    still = run_rtl(S.prepare(scene))[0]
    np.testing.assert_array_equal(local[0]["rtl"]["xshading"], still)
    assert (local[1]["rtl"]["xshading"] != still).any()
    gif = Image.open(tmp_path / "turntable.gif")
    assert gif.n_frames == 3 and gif.size == (2 * 64, 64 + 14)
    for f in ("psnr.png", "strip.png", "turntable.json"):
        assert (tmp_path / f).stat().st_size > 0


def test_bad_arguments_exit_2_without_a_traceback():
    import subprocess
    import sys
    for args, message in ((["--frames", "0"], "--frames: must be 1 or more"),
                          (["--size", "abc"], "--size: must be WxH"),
                          (["--methods", "gouraud"], "shading.method: must be one of"),
                          (["--size", "8x8"], "image.width: must be an integer in 16..1024")):
        r = subprocess.run([sys.executable, "-m", "sim.turntable", *args], capture_output=True,
                           text=True)
        assert r.returncode == 2 and message in r.stderr and "Traceback" not in r.stderr, r.stderr
