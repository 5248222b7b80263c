"""Running the RTL: Amaranth's simulator, cocotb on the exported Verilog (Icarus, Verilator),
the Verilog export, and the command line (``python -m sim``)."""
