"""Running the RTL: Amaranth's simulator, cocotb on the exported Verilog (Icarus, Verilator),
the Verilog export, and the command line (``python -m sim``)."""
import scene  # noqa: F401,E402  (its pipeline registers with hdl.units: make_unit("scene"))
