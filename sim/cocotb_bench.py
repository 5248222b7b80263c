"""The cocotb test bench every unit runs under (Icarus or Verilator).

It drives the exported Verilog's named ports (``i_<field>``, ``o_<field>``, ``i_valid`` ...,
see ``build/verilog/<unit>.json``), reads the vectors and the field list from the files that
``sim.cocotb_run`` names in the environment, streams them with the same
:class:`sim.stream.Traffic` as the Amaranth bench, and writes what came out. Inputs change on
the falling edge; handshakes are sampled in the read-only phase before the rising edge, which
is race-free on both simulators.
"""
import json
import os

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from sim.progress import report_to
from sim.stream import COUNTERS, Memory, Traffic, timed_rows


@cocotb.test()
async def stream_vectors(dut):
    with open(os.environ["SHADE_SPEC"]) as f:
        spec = json.load(f)
    fin, fout = spec["inputs"], spec["outputs"]
    with np.load(os.environ["SHADE_IN"]) as z:     # raw two's complement -> port bits
        cols = [(z[f["name"]] & ((1 << f["width"]) - 1)).tolist() for f in fin]
    rows = list(zip(*cols))
    traffic = Traffic(list(range(len(rows))), p_valid=spec["p_valid"], p_ready=spec["p_ready"],
                      seed=spec["seed"], many=spec["many"],
                      progress=report_to(os.environ["SHADE_PROGRESS"]),
                      timed=timed_rows({f["name"]: c for f, c in zip(fin, cols)}))
    busy = dut.busy if spec["many"] else None
    mems = []
    if "memory" in spec:                             # the texture memory behind the ports
        with np.load(os.environ["SHADE_MEM"]) as z:
            mems = Memory(z["words"], **spec["memory"]).ports(len(spec["memory_ports"]))
        for q, r in spec["memory_ports"]:
            getattr(dut, f"{q}_ready").value = 0
            getattr(dut, f"{r}_valid").value = 0
    in_ports = [getattr(dut, f"i_{f['name']}") for f in fin]
    out_ports = [getattr(dut, f"o_{f['name']}") for f in fout]
    Clock(dut.clk, 10, unit="ns").start()
    dut.rst.value = 1
    dut.i_valid.value = 0
    dut.o_ready.value = 0
    for port in in_ports:
        port.value = 0
    for u in spec["uniforms"]:                       # held for the whole run
        getattr(dut, f"u_{u['name']}").value = u["value"] & ((1 << u["width"]) - 1)
    for _ in range(2):
        await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.rst.value = 0
    i_valid, o_ready, i_ready, o_valid = dut.i_valid, dut.o_ready, dut.i_ready, dut.o_valid
    offered = None
    while not traffic.done:
        await FallingEdge(dut.clk)
        valid, row, ready = traffic.drive()
        i_valid.value = valid
        if valid and row != offered:                 # a new row: set its fields
            offered = row
            for port, value in zip(in_ports, rows[row]):
                port.value = value
        o_ready.value = ready
        for mem, (q, r) in zip(mems, spec.get("memory_ports", ())):
            take, rv, rd = mem.drive()
            getattr(dut, f"{q}_ready").value = int(take)
            getattr(dut, f"{r}_valid").value = int(rv)
            getattr(dut, f"{r}_data").value = rd
        await ReadOnly()
        ov = int(o_valid.value)
        got = tuple(int(p.value) for p in out_ports) if ov and ready else 0
        b = int(busy.value) if busy is not None else None
        for mem, (q, r) in zip(mems, spec.get("memory_ports", ())):
            mem.edge(traffic.cycles, int(getattr(dut, f"{q}_valid").value),
                     int(getattr(dut, f"{q}_addr").value), int(getattr(dut, f"{r}_ready").value))
            b = b or mem.busy
        traffic.edge(int(i_ready.value), ov, got, b)
    out = {}
    for k, f in enumerate(fout):
        col = np.array([row[k] for row in traffic.out], dtype=np.int64)
        if f["signed"]:
            col = np.where(col >> (f["width"] - 1) & 1, col - (1 << f["width"]), col)
        out[f["name"]] = col
    status = {k: int(getattr(dut, k).value) for k in COUNTERS if k in spec.get("status", ())}
    if mems:
        status["memory_reads"] = sum(mem.reads for mem in mems)
    np.savez(os.environ["SHADE_OUT"], latency=traffic.latency if traffic.latency is not None
             else -1, cycles=traffic.cycles, **status, **out)
