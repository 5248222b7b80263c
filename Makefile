# Two commands on a fresh clone: `make render` and `make test`. Each installs what it needs first.
PYTHON  ?= python3
VENV    := .venv
PY      := $(VENV)/bin/python
STAMP   := $(VENV)/.installed
UNIT    ?=
PARAM   ?=
SIM     ?= icarus
VECTORS ?=
WAVES   ?=
# Two pytest workers: CI has two cores.
JOBS    ?= 2

.PHONY: setup render gallery test verilog sim report accuracy recip-cost bench soak fpga formal fuzz tradeoffs texcache turntable board-sim bitstream clean

setup: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e .
	touch $@

# The main job: a scene through the RTL of the pipeline it calls for, beside the float model
# and the reference: make render [SCENE=scenes/default.toml] [SIM=verilator|amaranth|icarus]
# [RASTER=setup_ii=16,setup_mults=2,setup_narrow=2] (the raster's build knobs).
# Writes build/render/<scene>/{rtl,model,reference,diff}.png and metrics.json.
SCENE   ?= scenes/default.toml
render: setup
	$(PY) -m sim render $(SCENE) --simulator $(if $(filter command line,$(origin SIM)),$(SIM),verilator)$(if $(TEXTURE), --texture $(TEXTURE))$(if $(RASTER), --raster $(RASTER))

# Every scene in scenes/, and one contact sheet: build/render/gallery.png.
gallery: setup
	$(PY) -m sim.render $(if $(filter command line,$(origin SIM)),$(SIM),verilator)

# The ULX3S (docs/board.md). A scene through the board's core on Verilator, its link bytes in
# and one whole video frame's TMDS symbols out, decoded and held to the model:
# make board-sim [SCENE=board/scenes/default.toml] -> build/board_sim/<scene>/{tmds.npy,frame.png,board.json}
# The bitstream of a scene's effects: make bitstream [SCENE=...] [BOARD=ulx3s-25f|ulx3s-85f]
# -> build/bitstream/<scene>/{<name>.bit,report.json,logs}. Run it alone: tens of minutes.
BOARD   ?= ulx3s-25f
BSCENE  := $(if $(filter command line,$(origin SCENE)),$(SCENE),board/scenes/default.toml)
board-sim: setup
	$(PY) -m board sim $(BSCENE) --board $(BOARD) --out build/board_sim/$(basename $(notdir $(BSCENE)))

bitstream: setup
	timeout 2400 $(PY) -m board build $(BSCENE) --board $(BOARD) --out build/bitstream/$(basename $(notdir $(BSCENE)))

# Every test: models, RTL on Amaranth's simulator, cocotb on Icarus and Verilator.
test: setup
	$(PY) -m pytest -n $(JOBS) --dist loadgroup --durations=25

# Verilog of every unit into build/verilog/, each linted by Verilator (-Wall); SCENE=...: that
# scene's pipeline. TARGET=ecp5: the form make fpga places (MULT18X18D with their registers;
# a bump scene's texture on chip), for a user's own ECP5 flow.
verilog: setup
	$(PY) -m sim verilog$(if $(TARGET), --target $(TARGET))$(if $(filter command line,$(origin SCENE)), --scene $(SCENE))

# Golden vectors through a simulator: make sim [UNIT=name] [SIM=icarus|cocotb-verilator|verilator|amaranth]
# [VECTORS=n|all] [PARAM="name=value ..."] [WAVES=1]. A verdict per unit; with WAVES=1 a waveform
# per unit in build/sim/<sim>/.
sim: setup
	$(PY) -m sim check --simulator $(SIM) $(if $(VECTORS),--vectors $(VECTORS)) \
		$(if $(UNIT),--unit $(UNIT)) $(if $(WAVES),--waves) $(foreach p,$(PARAM),--param $(p))

# Hardware counts of every unit from Yosys (multipliers, adders, tables), beside the seeds'.
report: setup
	$(PY) -m flows.report

# Place and route of every unit and the default scene's pipeline in a serial wrapper, on
# ECP5-25F -6 and iCE40 UP5K, 5 seeds: Fmax (median, min-max), utilisation, critical path.
# Writes build/fpga/fpga.{json,md}; unchanged designs come from build/fpga/cache/.
# make fpga [UNIT=a,b] [SEEDS=n] [RASTER=row_serial=2,setup_serial=1] (a scene pipeline's raster knobs)
SEEDS   ?= 5
fpga: setup
	$(PY) -m flows.fpga --seeds $(SEEDS) $(if $(UNIT),--units $(UNIT))$(if $(RASTER), --raster $(RASTER))

# The stream contract proven by SymbiYosys (yowasp-sby, yices): every unit and a pipeline per
# method and bump method: the one-row units by k-induction, the raster and the pipelines by
# bounded model checks; covers, and the mutants each property must
# catch: build/formal/formal.{md,json}. make formal [ONLY=raster,scene_linear,stepper] [TIMEOUT=s]
# (ONLY=raster: its held proof, covers and mutants and its parts' proofs; ONLY=raster_bmc: the
# whole raster's BMC, over an hour)
ONLY    ?=
TIMEOUT ?=
formal: setup
	$(PY) -m flows.formal $(if $(ONLY),--only $(ONLY)) $(if $(TIMEOUT),--timeout $(TIMEOUT))

# Generated inputs (hypothesis): 10,000 scene files, malformed and valid-but-hard, each a clear
# error naming its key or a picture; 300 valid ones through the RTL against the model; 10,000
# malformed npz files through sim run, golden run and sim check: build/fuzz/fuzz.{md,json}.
# make fuzz [N=scenes and npz files] [RTL=renders]
N       ?= 10000
RTL     ?= 300
fuzz: setup
	$(PY) -W ignore::RuntimeWarning -m flows.fuzz --scenes $(N) --npz $(N) --rtl $(RTL)

# What accuracy costs: every knob's settings measured side by side (image error with FLIP,
# unit error, latency, Fmax, ns per pixel, area, simulation time), the seeds' claims, Pareto
# plots: build/tradeoffs/{tradeoffs.json,report.md,pareto_*.png}. Cached by Verilog hash.
# make tradeoffs [QUICK=1] [DASK=tcp://scheduler:8786] [SEEDS=n]
QUICK   ?=
DASK    ?=
tradeoffs: setup
	$(PY) -m flows.tradeoffs $(if $(QUICK),--quick) $(if $(DASK),--dask $(DASK)) \
		$(if $(filter command line,$(origin SEEDS)),--seeds $(SEEDS))

# A scene in motion, every frame through the RTL on the batch path (the scene's [turntable]
# table: the mesh spinning or the lights orbiting): build/turntable/<scene>/{turntable.gif,
# psnr.png,strip.png,turntable.json}. No SCENE: the default torus through linear, X-shading
# and Phong side by side. make turntable [SCENE=...] [FRAMES=n] [DASK=tcp://scheduler:8786]
FRAMES  ?=
turntable: setup
	$(PY) -m sim.turntable $(if $(filter command line,$(origin SCENE)),$(SCENE)) \
		$(if $(FRAMES),--frames $(FRAMES)) $(if $(DASK),--dask $(DASK))

# The texel cache on the bump scenes: hit rate, fragments per clock, memory words per fragment
# at 256 and 1024 px, memory latency 12 and 40, three caches: build/texcache/texcache.md.
texcache: setup
	$(PY) -m flows.texcache $(if $(QUICK),--quick)

# Method errors (Fenney units, seed 003's rotation) with plots in build/accuracy/.
accuracy: setup
	$(PY) -m golden.accuracy
	$(PY) -m flows.losses

# The setup's reciprocal: Newton-Raphson steps or the divider, clocks against accuracy.
recip-cost: setup
	$(PY) -m flows.recip_cost

# Simulation speed side by side: every unit on every simulator (build/bench/).
bench: setup
	$(PY) -m flows.bench

# Long streams with random stalls on the batch path against golden: 10 million rows per unit,
# 100,000 triangles through raster.
soak: setup
	$(PY) -m flows.soak
	$(PY) -m pytest -m long -n $(JOBS) --dist loadgroup

clean:
	rm -rf build .pytest_cache .hypothesis results.xml sim_build
	find . -name __pycache__ -not -path './$(VENV)/*' -prune -exec rm -rf {} +
