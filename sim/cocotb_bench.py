"""The cocotb test bench every unit runs under (Icarus or Verilator).

It reads the vectors and the port layout from the files that ``sim.cocotb_run`` names in the
environment, streams them with the same :class:`sim.stream.Traffic` as the Amaranth bench, and
writes what came out. Inputs change on the falling edge; handshakes are sampled in the
read-only phase before the rising edge, which is race-free on both simulators.
"""
import json
import os

import cocotb
import numpy as np
from cocotb.clock import Clock
from cocotb.triggers import FallingEdge, ReadOnly, RisingEdge

from sim.stream import Traffic, pack, unpack


@cocotb.test()
async def stream_vectors(dut):
    spec = json.loads(open(os.environ["SHADE_SPEC"]).read())
    inputs = dict(np.load(os.environ["SHADE_IN"]))
    traffic = Traffic(pack(spec["inputs"], inputs), p_valid=spec["p_valid"],
                      p_ready=spec["p_ready"], seed=spec["seed"], many=spec["many"])
    busy = dut.busy if spec["many"] else None
    Clock(dut.clk, 10, unit="ns").start()
    dut.rst.value = 1
    dut.i__valid.value = 0
    dut.i__payload.value = 0
    dut.o__ready.value = 0
    for _ in range(2):
        await RisingEdge(dut.clk)
    await FallingEdge(dut.clk)
    dut.rst.value = 0
    i_valid, i_payload, o_ready = dut.i__valid, dut.i__payload, dut.o__ready
    i_ready, o_valid, o_payload = dut.i__ready, dut.o__valid, dut.o__payload
    while not traffic.done:
        await FallingEdge(dut.clk)
        valid, payload, ready = traffic.drive()
        i_valid.value = valid
        i_payload.value = payload
        o_ready.value = ready
        await ReadOnly()
        ov = int(o_valid.value)
        traffic.edge(int(i_ready.value), ov, o_payload.value.to_unsigned() if ov else 0,
                     int(busy.value) if busy is not None else None)
    status = {"culled": int(dut.culled.value)} if spec["many"] else {}
    np.savez(os.environ["SHADE_OUT"], latency=traffic.latency if traffic.latency is not None
             else -1, cycles=traffic.cycles, **status, **unpack(spec["outputs"], traffic.out))
