"""The host port (scene/host.py): a scene's data written at run time, so that the hardware
depends only on the effects and the sizes.

Bounds: as tests/test_scenes.py, every pixel within 1 level of the model with exactly its
coverage (the raster's values are within one LSB of 2^-14 of its float model). A loaded table
holds exactly the ROM's contents (the same ``build_lut``), so a render through loaded tables
is the render through ROMs, bit for bit: the gallery's images are unchanged.
"""
import subprocess
import sys

import numpy as np
import pytest
from amaranth.back import verilog

from hdl.unit import NamedPorts
from hdl.units import make_unit
from scene import driver as S, host
from sim.run import simulate
from sim.simulators import available

from .conftest import long_where, per_simulator

SCENES = "scenes"


def scene(base, **tables):
    """``scenes/<base>.toml`` with ``tables`` (``{table: {key: value}}``) merged in."""
    import tomllib
    data = tomllib.loads(open(f"{SCENES}/{base}.toml").read()) if base != "default" else {}
    for key, table in tables.items():
        if key == "lights":
            data["lights"] = table
        else:
            data.setdefault(key, {}).update(table)
    return S.parse(data, base)


# material, light and bump map all changed; the effects and sizes kept
OTHER = {"material": {"color": [0.2, 0.9, 0.4], "shininess": 8.0, "specular": 0.3},
         "lights": [{"to_light": [1.0, -0.5, 1.0], "color": [1.0, 0.8, 0.6]}]}


@pytest.mark.parametrize("base,tables,hardware", [
    ("bump_polar", {"bump": {"size": 64}, "image": {"width": 32, "height": 32}},
     {"texture": "onchip"}),
    ("fenney_power", {"image": {"width": 32, "height": 32}}, None)], ids=["polar", "fenney"])
def test_data_is_not_in_the_verilog(base, tables, hardware):
    """Two scenes that differ only in material, light and bump map: the same parameters and
    byte-identical Verilog (the first with the power table and the on-chip texture loaded,
    the second with Fenney's concentration in a register)."""
    a = S.prepare(scene(base, **tables), hardware)
    other = {**tables, **OTHER, "bump": {**tables.get("bump", {}), "map": "dimples"}}
    b = S.prepare(scene(base, **other), hardware)
    assert a["params"] == b["params"]
    assert not np.array_equal(a["load"][1], b["load"][1])          # the data does differ
    text = [verilog.convert(NamedPorts(make_unit("scene", **p["params"])), name="scene",
                            emit_src=False) for p in (a, b)]
    assert text[0] == text[1]


def _fragments(prep):
    """The model's fragments in the raster's order, and their RGB."""
    frag, ch = S.model_fragments(prep)
    ch = S.run_models(prep, frag, ch, prep["pipeline"].stages[1:])
    return frag, np.stack([ch[c] for c in "rgb"], -1).astype(int)


@pytest.mark.parametrize("simulator,name", long_where(
    per_simulator(["scene"], only=("amaranth", "verilator")), "amaranth-scene"))
def test_writes_between_triangles_under_backpressure(simulator, name):
    """The default scene (64 x 64 on the batch path, 32 x 32 on Amaranth's), its material changed
    halfway: the second material's writes (registers and the whole power table) follow
    triangle k - 1 while it is in flight, with random gaps and stalls. Every fragment of a
    triangle before k is shaded with the first material, every one after with the second:
    within 1 level of its own model, and beyond 1 level of the other on most."""
    side = 64 if simulator == "verilator" else 32      # 64: the batch model test_scenes builds
    size = {"image": {"width": side, "height": side}}
    a, b = S.prepare(scene("default", **size)), S.prepare(scene("default", **size, **OTHER))
    k = len(a["inputs"]["x0"]) // 2
    # the light is in the triangles too (each vertex's N.L and N.H): the second half is b's
    tris = {key: np.concatenate([a["inputs"][key][:k], b["inputs"][key][k:]])
            for key in a["inputs"]}
    rows = host.stream(tris, a["load"], at=[(k, b["load"])])
    out, info = simulate("scene", a["params"], rows, simulator, p_valid=0.6, p_ready=0.5,
                         seed=3)
    frag, rgb_a = _fragments(a)
    _, rgb_b = _fragments(b)
    for key in ("tri", "x", "y"):
        np.testing.assert_array_equal(out[key], frag[key])
    rtl = np.stack([out[c] for c in "rgb"], -1).astype(int)
    want = np.where((frag["tri"] < k)[:, None], rgb_a, rgb_b)
    assert np.abs(rtl - want).max() <= 1
    late = frag["tri"] >= k
    assert late.sum() > 100 and (~late).sum() > 100
    assert (np.abs(rtl - rgb_a)[late].max(1) > 1).mean() > 0.5     # the writes did land
    assert info["loading"] >= len(a["load"][0]) + len(b["load"][0])


@pytest.mark.parametrize("base,bump", [
    ("bump_polar", {"size": 64}),
    pytest.param("bump_xz", {"size": 32, "filter": "bilinear"}, marks=pytest.mark.long)],
    ids=["nearest", "bilinear"])
def test_onchip_texture_is_the_external_one(base, bump):
    """The on-chip texture RAM, loaded through the host port, gives the fragments that the
    external memory behind the texel cache gives, bit for bit (Amaranth's simulator, 24 x 24):
    nearest (one bank) and bilinear (four banks, written by the memory image's layout). The
    external map sits at base 4096, above other words: the base register moves it."""
    tables = {"bump": bump, "image": {"width": 24, "height": 24},
              "mesh": {"segments": [10, 6]}}                # fewer triangles: fewer clocks
    sc = scene(base, **tables)
    ext, on = S.prepare(sc), S.prepare(sc, {"texture": "onchip"})
    assert on["memory"] is None and len(on["load"][0]) > len(ext["load"][0])
    # the external map at a base of 4096 (a register): the memory holds something else below
    addr, data = ext["load"]
    at = host.REGISTERS + [f.name for f in ext["pipeline"].registers].index("tex_base")
    ext["load"] = (addr, np.where(addr == at, 4096, data))
    from sim.stream import Memory
    memory = Memory(np.concatenate([np.arange(4096) * 40503 % 65536, ext["memory"]]))
    got = [simulate("scene", p["params"], S.rtl_inputs(p), "amaranth", p_ready=0.7, seed=1,
                    memory=mem)[0] for p, mem in ((ext, memory), (on, None))]
    assert len(got[0]["x"]) > 100
    for key in got[0]:
        np.testing.assert_array_equal(got[0][key], got[1][key], err_msg=key)


def test_a_texture_beyond_the_onchip_ram_is_refused():
    r = subprocess.run([sys.executable, "-m", "sim", "render", f"{SCENES}/bump_polar.toml",
                        "--texture", "onchip", "--simulator", "amaranth"],
                       capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr
    assert "bump.size: 256 x 256 texels exceed the on-chip texture RAM (at most 128 x 128" \
        in r.stderr


def test_writes_follow_the_address_map():
    """Every register, table entry and texture word is written once, at its address, with
    its raw value (two's complement bits for a signed one)."""
    prep = S.prepare(scene("bump_polar", bump={"size": 64}, image={"width": 32, "height": 32}),
                     {"texture": "onchip"})
    pipe, (addr, data) = prep["pipeline"], prep["load"]
    assert len(np.unique(addr)) == len(addr)
    regs = {f.name: k for k, f in enumerate(pipe.registers)}
    for name, value in prep["uniforms"].items():
        assert data[addr == host.REGISTERS + regs[name]] == [value % (1 << 32)]
    table = data[(addr >= host.TABLES) & (addr < host.TABLES + host.TABLE_STRIDE)]
    from hdl.shade_unit.power import power_lut
    np.testing.assert_array_equal(table, power_lut(32.0, 6).contents)
    np.testing.assert_array_equal(data[addr >= host.TEXTURE], prep["pipeline"].stages[1]
                                  .memory_image(prep["data"]))
    assert [r["addr"] for r in host.address_map(pipe)][-2:] == ["0x010000", "0x100000"]


@pytest.mark.skipif(bool(available("verilator")), reason=f"verilator: {available('verilator')}")
@pytest.mark.xdist_group("verilator-scene")
def test_one_model_renders_both(tmp_path):
    """A material and a light changed: the same parameters, so the same batch model (built
    once, keyed by them), and each render within 1 level of its own model."""
    from sim.render import render
    a = tmp_path / "a.toml"
    a.write_text("")
    b = tmp_path / "b.toml"
    b.write_text('[material]\ncolor = [0.2, 0.9, 0.4]\nshininess = 8.0\n'
                 '[[lights]]\nto_light = [1.0, -0.5, 1.0]\ncolor = [1.0, 0.8, 0.6]\n')
    m = [render(p, tmp_path / p.stem, "verilator", (64, 64), quiet=True) for p in (a, b)]
    assert m[0]["pipeline"]["params"] == m[1]["pipeline"]["params"]
    for x in m:
        assert x["rtl_vs_model"]["coverage_mismatch"] == 0 and x["rtl_vs_model"]["max_abs"] <= 1
        assert x["load"]["words"] == 649 and x["load"]["cycles"] == 649
    assert m[0]["rtl_vs_reference"]["psnr_db"] != m[1]["rtl_vs_reference"]["psnr_db"]
