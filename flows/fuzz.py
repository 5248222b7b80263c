"""``make fuzz``: generated scene files and npz inputs, malformed and valid-but-hard (hypothesis).

Scenes, by class:

- malformed: ``syntax`` (a valid file's text cut or with a character inserted), ``type`` (a
  key given a value of another type), ``range`` (out of its range), ``nonfinite`` (nan, inf),
  ``unknown`` (a key or table no scene has), ``degenerate`` (zero vectors, the eye at the
  target, up along the view), ``file`` (a bump map or OBJ that is missing, a directory, not an
  image, a 1 x 1 image, a corrupt npz), ``huge`` (TOML extreme in nesting or size: arrays and
  inline tables nested up to 50,000 deep, megabytes of string or keys);
- ``hard``, valid: cameras inside the mesh and far away, dense meshes, sub-pixel and
  screen-sized triangles, lights behind the surface, every method and bump method.

Each one is loaded and prepared as ``make render`` does, and its float model run: it must
either give a clear error (one of the errors ``sim`` turns into one line and exit 2; for a
malformed scene, naming the key) or a picture. Anything else is a traceback: a bug. Valid
scenes of a few pipeline configurations (``rtl_configs()``, so the simulator models stay
cached) also go through the RTL on the batch path: the same pixels as the model, each within
one level (tests/test_scenes.py's bound; phong with Fenney's power and fenney_polar: each
fragment within its candidates, ``scene.models.candidates``),
and no hang (the batch harness's watchdog).

npz inputs: ``python -m sim run``, ``python -m golden run`` and ``python -m sim check`` (in
process, through their ``main``) on malformed files: wrong types, shapes, lengths, missing and
extra fields, out-of-range values, nan, random bytes, truncated and empty files, a bare .npy.
Each must exit 2 with one line.

``python -m flows.fuzz [--scenes N] [--npz N] [--rtl N] [--seed S]``: writes
build/fuzz/fuzz.{json,md} and each failure's input under build/fuzz/failures/.
"""
import argparse
import contextlib
import io
import json
import math
import shutil
import sys
import time
import traceback
from collections import Counter

import numpy as np
import tomli_w
from hypothesis import HealthCheck, given, seed as hseed, settings, strategies as st

from scene import driver as S
from scene import registry
from scene.pipeline import ScenePipeline

from sim.verilog import BUILD

OUT = BUILD / "fuzz"
CLEAR = None        # the exception types ``sim.cli_common.user_errors`` reports in one line

RTL_SIZE = 64


def rtl_configs():
    """The pipeline configurations whose scenes also run through the RTL (their data varies
    freely: it is loaded at run time, so each is one model), read from the registered stages
    when asked (a method of one's own too): each shading method and each bump method once, so that every stage and every raster mode is
    in one. The k-th shading method takes the power kinds in turn, one light and two in turn
    (one where its stages shade only one), and every third is diffuse only; a bump method
    takes the defaults and a map of 64 (as tests/ use: their models are shared)."""
    out, powers = {}, registry.powers()
    for k, m in enumerate(registry.methods()):
        c = {"shading": {"method": m, "specular": k % 3 != 2, "power": powers[k % len(powers)]},
             "lights": 1 + k % 2}
        out[m] = c if _valid(c) else {**c, "lights": 1}
    for b in registry.bumps()[1:]:
        out[b] = {"shading": dict(S.tables()[0]["shading"]), "bump": {"method": b, "size": 64}}
    return out


def _config_scene(c):
    return {"image": {"width": RTL_SIZE, "height": RTL_SIZE}, "shading": c["shading"],
            "lights": [S.DEFAULTS["lights"][0]] * c.get("lights", 1),
            **({"bump": c["bump"]} if "bump" in c else {})}


def _valid(c):
    try:
        S.parse(_config_scene(c), "config")
    except S.SceneError:
        return False
    return True



def _clear_errors():
    global CLEAR
    if CLEAR is None:
        from hdl.fixed import FieldError
        from hdl.units import ParamError
        from sim.cli_common import UsageError
        CLEAR = (S.SceneError, UsageError, FieldError, ParamError)
    return CLEAR


# ---- scenes ----------------------------------------------------------------------------------

finite = lambda lo, hi: st.floats(lo, hi, allow_nan=False, allow_infinity=False)
vec3 = lambda lo, hi: st.lists(finite(lo, hi), min_size=3, max_size=3)


@st.composite
def valid_scene(draw, config=None):
    """A scene the contract allows, often a hard one."""
    size = draw(st.sampled_from([16, 24, 32, 48, 64]))
    d = {"image": {"width": size, "height": draw(st.sampled_from([16, 32, 64]))}}
    direction = np.array(draw(vec3(-1, 1)))
    if np.linalg.norm(direction) < 1e-3:
        direction = np.array([0.0, -1.0, 0.5])
    dist = draw(st.sampled_from([0.05, 0.3, 0.8, 2.0, 4.0, 10.0, 60.0]))   # inside .. far
    eye = (direction / np.linalg.norm(direction) * dist).tolist()
    up = [0.0, 0.0, 1.0] if abs(direction[2]) < 0.9 * np.linalg.norm(direction) \
        else [0.0, 1.0, 0.0]
    d["camera"] = {"eye": eye, "target": draw(vec3(-0.5, 0.5)), "up": up,
                   "fov_y": draw(finite(5, 120))}
    shape = draw(st.sampled_from(["torus", "sphere", "plane"]))
    segs = draw(st.sampled_from([3, 4, 8, 12, 24, 48, 96]))
    d["mesh"] = {"shape": shape, "segments": [segs, draw(st.sampled_from([3, 6, 12, 64]))],
                 "scale": draw(st.sampled_from([0.001, 0.05, 0.5, 1.0, 3.0, 40.0])),
                 "rotate": draw(vec3(-180, 180))}
    d["material"] = {"color": draw(vec3(0, 1)), "ambient": draw(finite(0, 1)),
                     "diffuse": draw(finite(0, 1)), "specular": draw(finite(0, 1)),
                     "shininess": draw(st.sampled_from([1.0, 2.0, 8.0, 32.0, 128.0, 1000.0]))}
    n = draw(st.integers(1, 4))
    d["lights"] = [{"to_light": draw(vec3(-1, 1).filter(lambda v: any(v))),
                    "color": draw(vec3(0, 2))} for _ in range(n)]
    d["shading"] = {"method": draw(st.sampled_from(tuple(registry.methods()))),
                    "specular": draw(st.booleans()),
                    "power": draw(st.sampled_from(registry.powers()))}
    bump = draw(st.sampled_from(registry.bumps() + ("none", "none", "none")))
    if bump != "none":
        d["bump"] = {"method": bump, "map": draw(st.sampled_from(["flat", "bricks", "dimples"])),
                     "size": draw(st.sampled_from([16, 32, 64, 128])),
                     "depth": draw(st.sampled_from([0.0, 0.5, 1.0, 8.0]))}
        for key, options in _bump_choices(bump).items():     # its stages' own (the filter,
            d["bump"][key] = draw(st.sampled_from(options))  # the rotation; a filter that
            #                                                  its texels refuse: an error)
    if config:                                  # an RTL configuration: its effects, our data
        c = rtl_configs()[config]
        d["shading"] = dict(c["shading"])
        want = c.get("lights", 1)          # each light its own direction and colour
        d["lights"] = (d["lights"] + [{"to_light": draw(vec3(-1, 1).filter(lambda v: any(v))),
                                       "color": draw(vec3(0, 2))} for _ in range(want)])[:want]
        d["image"] = {"width": RTL_SIZE, "height": RTL_SIZE}
        d.pop("bump", None)
        if "bump" in c:                          # its method and size; our map and depth
            d["bump"] = {**c["bump"], "map": draw(st.sampled_from(["flat", "bricks",
                                                                    "dimples"])),
                         "depth": draw(st.sampled_from([0.0, 0.5, 1.0, 8.0]))}
    return d


def _bump_choices(bump):
    """[bump]'s keys that the stages wanted for the bump method ``bump`` give a choice or a
    switch: ``{key: options}``."""
    out, q = {}, {**ScenePipeline.PARAMS, "bump": bump}
    for cls in (cls for cls in registry.stages() if cls.wanted(q)):
        for key, (_, rule) in cls.scene_keys.get("bump", {}).items():
            if rule[0] in ("choice", "bool"):
                out[key] = rule[1] if rule[0] == "choice" else (False, True)
    return out


# every key by table: a value of another type, and values out of range
_WRONG = ["text", True, [1, 2], {"a": 1}, 7, 0.5, [], [[1.0, 2.0, 3.0]], ""]


def _rules():
    """Every scene key's rule: the base tables' and each stage's own (``scene.parse.tables``)."""
    return S.tables()[1]


def _keys():
    return [(t, k) for t, rules in _rules().items() for k in rules]


# the classes of malformed scene (module docstring, docs/formal.md's make fuzz)
MALFORMED = ("syntax", "type", "range", "nonfinite", "unknown", "degenerate", "file",
             "extreme", "huge")


@st.composite
def malformed_scene(draw, tmp, kinds=MALFORMED):
    """``(class, text, key)``: the key the error must name (None: any)."""
    base = draw(valid_scene())
    base["lights"] = base["lights"][:1]       # so that the defect is the file's only one
    kind = draw(st.sampled_from(kinds))
    table, key = draw(st.sampled_from(_keys()))
    path = f"lights[0].{key}" if table == "lights" else f"{table}.{key}"

    def put(value):
        if table == "lights":
            base["lights"][0][key] = value
        else:
            base.setdefault(table, {})[key] = value
    if kind == "huge":          # TOML extreme in nesting or size: the parser's own limits
        text = tomli_w.dumps(base)
        depth = draw(st.sampled_from([100, 1000, 5000, 50000]))
        shape = draw(st.sampled_from(["array", "table", "string", "keys"]))
        if shape == "array":
            text += f"\n[extra]\nv = {'[' * depth}1{']' * depth}\n"
        elif shape == "table":
            text += f"\n[extra]\nv = {'{ a = ' * depth}1{' }' * depth}\n"
        elif shape == "string":
            text += f'\n[extra]\nv = "{"x" * depth * 40}"\n'
        else:
            text += "\n[extra]\n" + "".join(f"k{j} = {j}\n" for j in range(depth * 4))
        return kind, text, None
    if kind == "syntax":
        text = tomli_w.dumps(base)
        at = draw(st.integers(0, len(text)))
        cut = draw(st.sampled_from(["cut", "insert"]))
        text = text[:at] if cut == "cut" else text[:at] + draw(
            st.sampled_from(["[", "]", "=", '"', "{", ",", "\x00", "é", "[[", "= ="])) + text[at:]
        return kind, text, None
    if kind == "type":
        rule = _rules()[table][key]
        wrong = [v for v in _WRONG if not _fits(rule, v)]
        put(draw(st.sampled_from(wrong)))
    elif kind in ("range", "nonfinite"):
        rule = _rules()[table][key]
        if rule[0] not in ("num", "int", "vec", "ints"):     # a key of its class instead,
            #                                                  so that every class is drawn
            table, key = ("image", "width") if kind == "range" else ("camera", "fov_y")
            path, rule = f"{table}.{key}", _rules()[table][key]
        if kind == "nonfinite":
            bad = draw(st.sampled_from([math.nan, math.inf, -math.inf]))
        else:
            lo, hi = rule[-2], rule[-1]
            opts = [v for v in (lo - 1, hi + 1, -1e308, 1e308, lo - 1e-9) if not lo <= v <= hi]
            bad = draw(st.sampled_from(opts)) if opts else math.nan
            if rule[0] in ("int", "ints") and not (isinstance(bad, float) and math.isnan(bad)):
                bad = int(bad) if abs(bad) < 1e18 else 10 ** 19
                if lo <= bad <= hi:             # lo - 1e-9 rounds back into the range
                    bad = int(lo) - 1
        if rule[0] in ("vec", "ints"):
            value = [rule[2] if rule[2] > -math.inf else 0] * rule[1]
            at = draw(st.integers(0, rule[1] - 1))
            value[at] = bad
            path += f"[{at}]"
            put(value)
        else:
            put(bad)
    elif kind == "extreme":          # allowed by the contract, at its far ends
        num = [(t, k) for t, k in _keys() if _rules()[t][k][0] in ("num", "vec")]
        table, key = draw(st.sampled_from(num))
        path = f"lights[0].{key}" if table == "lights" else f"{table}.{key}"
        rule = _rules()[table][key]
        lo, hi = rule[-2], rule[-1]
        value = draw(st.sampled_from([v for v in (lo, hi, 1e300, -1e300, 1e-300, 5e-324)
                                      if lo <= v <= hi and math.isfinite(v)] or [lo]))
        put([value] * rule[1] if rule[0] == "vec" else value)
    elif kind == "unknown":
        if draw(st.booleans()):
            base.setdefault(table if table != "lights" else "image", {})["colour_depth"] = 8
            path = None
        else:
            base["textures"] = {"x": 1}
            path = "textures"
    elif kind == "degenerate":
        which = draw(st.sampled_from(["to_light", "axis", "eye", "up"]))
        if which == "to_light":
            base["lights"][0]["to_light"], path = [0.0, 0.0, 0.0], "lights[0].to_light"
        elif which == "axis":
            base["turntable"], path = {"axis": [0.0, 0.0, 0.0]}, "turntable.axis"
        elif which == "eye":
            base["camera"]["target"], path = list(base["camera"]["eye"]), "camera.target"
        else:
            cam = base["camera"]
            base["camera"]["up"] = (np.subtract(cam["target"], cam["eye"]) * 2).tolist()
            path = "camera.up"
    elif kind == "file":
        what = draw(st.sampled_from(["missing", "directory", "text", "one_pixel", "corrupt_npz",
                                     "npz_floats", "npz_strings", "npz_shapes", "empty",
                                     "obj_missing", "obj_text", "obj_bad_index"]))
        f = _bad_file(tmp, what)
        if what.startswith("obj"):
            base["mesh"] = {"shape": "obj", "file": str(f)}
            base.pop("bump", None)
            path = "mesh.file"
        else:
            base["bump"] = {"method": draw(st.sampled_from(registry.bumps()[1:])), "map": str(f)}
            path = "bump.map"
    return kind, tomli_w.dumps(base), path


def _fits(rule, v):
    kind = rule[0]
    if kind == "num":
        return isinstance(v, (int, float)) and not isinstance(v, bool)
    if kind == "int":
        return isinstance(v, int) and not isinstance(v, bool)
    if kind == "bool":
        return isinstance(v, bool)
    if kind in ("str", "choice"):
        return isinstance(v, str)
    return isinstance(v, list) and len(v) == rule[1] and all(
        isinstance(x, (int, float)) and not isinstance(x, bool) for x in v)


def _bad_file(tmp, what):
    from PIL import Image
    tmp.mkdir(parents=True, exist_ok=True)
    f = tmp / f"bad_{what}"
    if what == "missing" or what == "obj_missing":
        return tmp / "no_such_file.png"
    if what == "directory":
        f.mkdir(exist_ok=True)
        return f
    if what in ("text", "obj_text"):
        f = f.with_suffix(".obj" if what == "obj_text" else ".png")
        f.write_bytes(b"\x89PNG not really\n\x00\x01garbage")
        return f
    if what == "one_pixel":
        f = f.with_suffix(".png")
        Image.new("L", (1, 1)).save(f)
        return f
    if what == "corrupt_npz":
        f = f.with_suffix(".npz")
        f.write_bytes(b"PK\x03\x04" + bytes(range(200)))
        return f
    if what.startswith("npz_"):                # texel files (fenney_xz) of the wrong kind
        f = f.with_suffix(".npz")
        a = {"npz_floats": np.full((16, 16), np.nan), "npz_strings": np.full((16, 16), "x"),
             "npz_shapes": np.zeros(16, np.int64)}[what]
        np.savez(f, texel_x=a, texel_z=a)
        return f
    if what == "obj_bad_index":
        f = f.with_suffix(".obj")
        f.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")
        return f
    f = f.with_suffix(".png")
    f.write_bytes(b"")
    return f


def try_scene(text, tmp, name="fuzz"):
    """``(outcome, message, prep)``: ``error`` (a clear one), ``ok`` or ``traceback``."""
    path = tmp / f"{name}.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        scene = S.load(path)
        prep = S.prepare(scene)
        S.model(prep)
        return "ok", "", prep
    except _clear_errors() as e:
        return "error", str(e), None
    except Exception:
        return "traceback", traceback.format_exc(), None


def rtl_check(prep):
    """A valid scene through the RTL on the batch path: ``None`` or what was wrong."""
    from sim.batch import BatchError
    from sim.run import simulate
    from sim.stream import StreamError
    from sim.stream import Memory
    memory = None if prep["memory"] is None else Memory(prep["memory"], latency=12)
    try:
        out, _ = simulate("scene", prep["params"], S.rtl_inputs(prep), "verilator",
                          memory=memory)
    except (BatchError, StreamError) as e:
        return f"RTL: {e}"
    frag, ch = S.model_fragments(prep)          # the same fragments, in the same order, each
    if not all(np.array_equal(out[k], frag[k]) for k in ("tri", "x", "y")):   # a colour its
        return f"fragments differ: {len(out['x'])} from the RTL, {len(frag['x'])} model"
    hit = S.within(prep, frag, ch, np.stack([out[c] for c in "rgb"], -1))   # stages' bounds
    return None if hit.all() else f"{int((~hit).sum())} fragments outside the bound"


def fuzz_scenes(n, seed, tmp, rtl=0, log=None, detail=None, configs=None, kinds=None):
    """``n`` generated scenes (a third valid, the rest malformed; ``kinds``: of these classes
    only, "hard" the valid ones) and ``rtl`` valid ones of ``rtl_configs()`` (or of
    ``configs``, some of them) through the RTL. Returns ``(counts, failures)``: counts by
    (class, outcome); failures: ``[(class, what, text)]``."""
    counts, failures = Counter(), []
    tmp.mkdir(parents=True, exist_ok=True)

    def record(kind, text, outcome, message, key):
        counts[kind, outcome] += 1
        if outcome == "traceback":
            failures.append((kind, message.strip().splitlines()[-1], text))
            if detail is not None:
                detail.append(message)
        elif outcome == "error" and key and kind != "extreme" and not _names(message, key):
            counts[kind, "error not naming the key"] += 1
            failures.append((kind, f"the error does not name {key}: {message}", text))
        elif outcome == "ok" and kind not in ("hard", "extreme"):
            counts[kind, "accepted"] += 1
            if kind not in ("syntax", "unknown") or key:
                failures.append((kind, f"accepted, expected an error naming {key}", text))
        if log:
            log()

    bad = tuple(k for k in kinds or MALFORMED if k != "hard")
    scenes = st.one_of(*[st.tuples(st.just("hard"), valid_scene().map(tomli_w.dumps),
                                   st.none())] * (kinds is None or "hard" in kinds),
                       *[malformed_scene(tmp, bad)] * (2 if bad else 0))

    @settings(max_examples=max(n, 1), database=None, deadline=None, derandomize=False,
              suppress_health_check=list(HealthCheck))
    @hseed(seed)
    @given(scenes)
    def one(case):
        kind, text, key = case
        outcome, message, _ = try_scene(text, tmp)
        if kind == "syntax" and outcome == "ok":      # a cut at a line's end is still valid
            counts[kind, "ok (cut left a valid file)"] += 1
            if log:
                log()
            return
        record(kind, text, outcome, message, key)
    if n:
        one()

    if rtl:
        @settings(max_examples=rtl, database=None, deadline=None,
                  suppress_health_check=list(HealthCheck))
        @hseed(seed + 1)
        @given(st.sampled_from(list(configs or rtl_configs())).flatmap(
            lambda c: st.tuples(st.just(c), valid_scene(c))))
        def through_rtl(case):
            config, data = case
            text = tomli_w.dumps(data)
            outcome, message, prep = try_scene(text, tmp, "rtl")
            if outcome != "ok":
                record("rtl", text, outcome, message, None)
                return
            wrong = rtl_check(prep)
            counts["rtl", "within bound" if wrong is None else "out of bound"] += 1
            counts[f"rtl {config}", "rendered"] += 1
            if wrong:
                failures.append(("rtl", wrong, text))
            if log:
                log()
        through_rtl()
    return counts, failures


def _names(message, key):
    """The error names the key (``lights[0].x``: ``lights[0].x`` or its table's place)."""
    return key in message or key.split("[")[0].split(".")[0] in message


# ---- npz inputs ------------------------------------------------------------------------------

def npz_cases(rng, fields, tmp, k):
    """One malformed file of ``fields``: ``(kind, path, a good file's arrays)``. (Booleans
    are not among the defects: ``check_arrays`` takes them as 0 and 1, by design.)"""
    fields = {f.name: f.fmt for f in fields}
    n = int(rng.integers(1, 5))
    good = {name: np.full(n, max(fmt.min, 0), np.int64) for name, fmt in fields.items()}
    kind = rng.choice(["missing_field", "float", "complex", "string", "2d", "0d",
                       "lengths", "over_max", "under_min", "nan", "huge", "random_bytes",
                       "truncated", "empty_file", "npy", "empty_zip", "object"])
    path = tmp / f"in{k}.npz"
    arrays = dict(good)
    name = rng.choice(list(fields))
    fmt = fields[name]
    if kind == "lengths" and len(fields) == 1:     # one field: any length is a valid file
        kind = "missing_field"
    if kind == "missing_field":
        arrays.pop(name)
    elif kind == "float":
        arrays[name] = arrays[name].astype(float) + 0.5
    elif kind == "complex":
        arrays[name] = arrays[name].astype(complex) + 1j
    elif kind == "string":
        arrays[name] = np.array(["a"] * n)
    elif kind == "2d":
        arrays[name] = np.zeros((n, 2), np.int64)
    elif kind == "0d":
        arrays[name] = np.array(3)
    elif kind == "lengths":
        arrays[name] = np.zeros(n + 1, np.int64)
    elif kind == "over_max":
        arrays[name] = np.full(n, fmt.max + 1, np.int64)
    elif kind == "under_min":
        arrays[name] = np.full(n, fmt.min - 1, np.int64)
    elif kind == "nan":
        arrays[name] = np.full(n, np.nan)
    elif kind == "huge":
        arrays[name] = np.full(n, 2 ** 63 - 1, np.int64) if fmt.max < 2 ** 62 else \
            np.full(n, 1e300)
    if kind == "random_bytes":
        path.write_bytes(rng.bytes(int(rng.integers(0, 300))))
    elif kind == "truncated":
        np.savez(path, **good)
        data = path.read_bytes()
        path.write_bytes(data[:int(rng.integers(4, max(5, len(data) - 1)))])
    elif kind == "empty_file":
        path.write_bytes(b"")
    elif kind == "npy":
        np.save(path.with_suffix(".npy"), good[name])
        path.write_bytes(path.with_suffix(".npy").read_bytes())
    elif kind == "empty_zip":
        np.savez(path)
    elif kind == "object":
        import zipfile
        with zipfile.ZipFile(path, "w") as z:
            buf = io.BytesIO()
            np.save(buf, np.array([{"a": 1}] * n, dtype=object), allow_pickle=True)
            z.writestr(f"{name}.npy", buf.getvalue())
    else:
        np.savez(path, **arrays)
    return str(kind), path, good


def try_cli(main, argv):
    """``(outcome, text)``: ``error`` (exit 2, one line), ``ok`` (exit 0 or 1), ``traceback``."""
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            main(argv)
        return "ok", err.getvalue()
    except SystemExit as e:
        text = err.getvalue()
        lines = [ln for ln in text.splitlines() if not ln.startswith("warning:")]
        if e.code == 2 and len(lines) == 1 and lines[0].startswith("error: "):
            return "error", text
        if e.code == 2:
            return "usage", text        # argparse's own (not generated here)
        return ("ok" if e.code in (0, 1, None) else "traceback"), text
    except Exception:
        return "traceback", traceback.format_exc()


def fuzz_npz(n, seed, tmp, log=None):
    """``n`` malformed inputs, each through ``sim run``, ``golden run`` or ``sim check``."""
    from golden.__main__ import main as golden_main
    from hdl.units import UNITS, make_unit
    from sim.__main__ import main as sim_main
    rng = np.random.default_rng(seed)
    tmp.mkdir(parents=True, exist_ok=True)
    counts, failures = Counter(), []
    names = [u for u in UNITS]
    for k in range(n):
        name = names[k % len(names)]
        unit = make_unit(name, spec=True)
        cli = ("sim run", "golden run", "sim check in", "sim check out")[k % 4]
        kind, path, good = npz_cases(rng, unit.outputs if cli == "sim check out" else
                                     unit.inputs, tmp, k % 64)
        out = tmp / "out.npz"
        if cli == "sim run":
            outcome, text = try_cli(sim_main, ["run", name, "--in", str(path), "--out", str(out),
                                               "--simulator", "amaranth"])
        elif cli == "golden run":
            outcome, text = try_cli(golden_main, ["run", name, "--in", str(path), "--out",
                                                  str(out)])
        else:
            goodf = tmp / "good.npz"
            if cli == "sim check in":
                outcome, text = try_cli(sim_main, ["check", name, "--in", str(path), "--out",
                                                   str(path)])
            else:
                inputs = {f.name: np.full(len(next(iter(good.values()))), max(f.fmt.min, 0),
                                          np.int64) for f in unit.inputs}
                np.savez(goodf, **inputs)
                outcome, text = try_cli(sim_main, ["check", name, "--in", str(goodf), "--out",
                                                   str(path)])
        counts[f"{cli}: {kind}", outcome] += 1
        if outcome != "error":
            failures.append((f"{cli}: {kind}", text.strip().splitlines()[-1] if text.strip()
                             else outcome, f"{name} {path}"))
            keep = OUT / "failures" / f"npz_{k}_{name}.npz"
            keep.parent.mkdir(parents=True, exist_ok=True)
            if path.is_file():
                shutil.copy(path, keep)
        if log:
            log()
    return counts, failures


# ---- report ----------------------------------------------------------------------------------

def report(scene_counts, npz_counts, failures, seconds):
    rows = ["| scenes: class | outcome | count |", "| --- | --- | --- |"]
    rows += [f"| {k} | {o} | {c:,} |" for (k, o), c in sorted(scene_counts.items())]
    rows += ["", "| npz: command and defect | outcome | count |", "| --- | --- | --- |"]
    rows += [f"| {k} | {o} | {c:,} |" for (k, o), c in sorted(npz_counts.items())]
    tracebacks = sum(c for (_, o), c in {**scene_counts, **npz_counts}.items()
                     if o == "traceback")
    rows += ["", f"{sum(scene_counts.values()):,} scene outcomes, "
                 f"{sum(npz_counts.values()):,} npz runs, {tracebacks} tracebacks, "
                 f"{len(failures)} failures, {seconds:.0f} s"]
    for kind, what, where in failures[:40]:
        rows.append(f"- {kind}: {what}")
    return "\n".join(rows) + "\n"


def main(argv=None):
    from tqdm import tqdm
    ap = argparse.ArgumentParser(prog="python -m flows.fuzz", description=__doc__.split("\n")[0])
    ap.add_argument("--scenes", type=int, default=10000)
    ap.add_argument("--npz", type=int, default=10000)
    ap.add_argument("--rtl", type=int, default=300, help="valid scenes through the RTL")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)
    t0 = time.monotonic()
    tmp = OUT / "work"
    shutil.rmtree(OUT / "failures", ignore_errors=True)
    bar = tqdm(total=args.scenes + args.rtl + args.npz, desc="fuzz", unit="case",
               file=sys.stderr)
    if args.rtl:
        from sim.batch import build
        for config in rtl_configs():        # the models first, each once
            build("scene", _config_params(config))
    sc, sf = fuzz_scenes(args.scenes, args.seed, tmp, args.rtl, log=lambda: bar.update(1))
    nc, nf = fuzz_npz(args.npz, args.seed, tmp / "npz", log=lambda: bar.update(1))
    bar.close()
    failures = sf + nf
    for k, (kind, what, text) in enumerate(sf):
        f = OUT / "failures" / f"scene_{k}_{kind}.toml"
        f.parent.mkdir(parents=True, exist_ok=True)
        f.write_text("".join(f"# {ln}\n" for ln in what.splitlines()) + text)
    text = report(sc, nc, failures, time.monotonic() - t0)
    (OUT / "fuzz.md").write_text(text)
    (OUT / "fuzz.json").write_text(json.dumps(
        {"scenes": {f"{k} / {o}": c for (k, o), c in sc.items()},
         "npz": {f"{k} / {o}": c for (k, o), c in nc.items()},
         "failures": [{"class": k, "what": w} for k, w, _ in failures]}, indent=2) + "\n")
    print(text)
    if failures:
        sys.exit(f"make fuzz: {len(failures)} failure(s); inputs in {OUT / 'failures'}")


def _config_params(config):
    """The pipeline parameters of an RTL configuration (its model's key)."""
    return S.pipeline_params(S.parse(_config_scene(rtl_configs()[config]), "config"))


if __name__ == "__main__":
    main()
