"""``simulate``: inputs through a unit's RTL on any simulator, the one entry point the CLI,
the renderer, the benches and the tests share."""
from hdl.units import make_unit

from .simulators import available

__all__ = ["simulate"]


def simulate(name, params, inputs, simulator, *, p_valid=1.0, p_ready=1.0, seed=0,
             waves=None, window=None, progress=False, uniforms=None, memory=None):
    """Run inputs through the RTL on any simulator (``sim.simulators``); returns
    ``(outputs, info)``.

    ``waves``: a path without suffix for the trace (FST from Icarus, VCD from the others); ``window``: (first, last) cycles to trace, on the
    batch path. With ``progress``, a progress bar on stderr (``progress`` a string: its label).
    ``uniforms``: the values of the unit's uniform ports (a scene pipeline's lights and
    colours), held for the run. ``memory``: the texture memory behind its memory port
    (:class:`sim.stream.Memory`; its line is set from the unit's cache)."""
    from .cli_common import UsageError, rows
    reason = available(simulator)
    if reason:
        raise UsageError(f"{simulator}: {reason}")
    unit = make_unit(name, spec=True, **params)
    many = bool(unit.status_ports)
    if simulator == "verilator":
        from .batch import build as build_batch
        build_batch(name, params, trace=bool(waves))              # before the progress bar
    elif simulator != "amaranth":
        from .cocotb_run import build
        build(name, params, simulator, waves=bool(waves))
    bar = None
    if progress:
        from .progress import Progress
        label = progress if isinstance(progress, str) else name
        bar = Progress(f"{label} on {simulator}", rows(inputs), many,
                       "tri" if many else "row")
    if memory is not None and unit.stream_ports:
        memory = memory.with_line(unit.params["cache_line"])
    traffic = dict(p_valid=p_valid, p_ready=p_ready, seed=seed, uniforms=uniforms,
                   memory=memory)
    try:
        if simulator == "amaranth":
            from .amaranth_run import run_amaranth
            vcd = waves and waves.with_suffix(".vcd")
            out, tr = run_amaranth(make_unit(name, **params), inputs, vcd=vcd, progress=bar,
                                   **traffic)
            return out, {"latency": tr.latency, "cycles": tr.cycles, "waves": vcd,
                         **getattr(tr, "status", {})}
        if simulator == "verilator":
            from .batch import run_batch
            return run_batch(name, params, inputs, waves=waves, window=window, progress=bar,
                             **traffic)
        from .cocotb_run import run_cocotb
        return run_cocotb(name, params, inputs, simulator, waves=waves, progress=bar, **traffic)
    finally:
        if bar:
            bar.close()
