"""Synthesisable Amaranth RTL of the shading units, one folder per unit."""
