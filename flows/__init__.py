"""The flows built on the simulators: place and route (``fpga``), proofs (``formal``), what
accuracy costs (``tradeoffs``, ``losses``, ``recip_cost``), generated inputs (``fuzz``),
speed and endurance (``bench``, ``soak``), the texel cache's figures (``texcache``) and the
units' hardware counts (``report``). Each is a ``make`` target; each runs as
``python -m flows.<name>``."""
