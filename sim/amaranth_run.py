"""Streaming vectors through a unit in Amaranth's simulator."""
from amaranth.sim import Simulator

from .stream import Traffic, pack, unpack


def fields_of(unit):
    return ([f.describe() for f in unit.inputs], [f.describe() for f in unit.outputs])


def run_amaranth(unit, inputs, *, p_valid=1.0, p_ready=1.0, seed=0, vcd=None, progress=None,
                 uniforms=None, memory=None):
    """Run every row of ``inputs`` through ``unit`` (its uniform ports held at ``uniforms``;
    ``memory`` behind its memory port); returns ``(outputs, traffic)``."""
    fin, fout = fields_of(unit)
    many = hasattr(unit, "busy")
    traffic = Traffic(pack(fin, inputs), p_valid=p_valid, p_ready=p_ready, seed=seed,
                      progress=progress, many=many)
    i_raw, o_raw = unit.i.payload.as_value(), unit.o.payload.as_value()
    busy = unit.busy if many else unit.o.valid

    async def bench(ctx):
        for f in unit.uniforms:
            ctx.set(getattr(unit, f"u_{f.name}"), int(uniforms[f.name]))
        port = [unit.tex_req.valid, unit.tex_req.payload.addr, unit.tex_resp.ready] \
            if memory else []
        while not traffic.done:
            valid, payload, ready = traffic.drive()
            ctx.set(unit.i.valid, valid)
            ctx.set(i_raw, payload)
            ctx.set(unit.o.ready, ready)
            if memory:
                take, rv, rd = memory.drive()
                ctx.set(unit.tex_req.ready, take)
                ctx.set(unit.tex_resp.valid, rv)
                ctx.set(unit.tex_resp.payload.data, rd)
            _, _, i_ready, o_valid, o_payload, b, *mem = \
                await ctx.tick().sample(unit.i.ready, unit.o.valid, o_raw, busy, *port)
            if memory:
                memory.edge(traffic.cycles, *mem)
                b = b or memory.busy
            traffic.edge(i_ready, o_valid, o_payload, b)
        if many:
            traffic.status = {"culled": ctx.get(unit.culled)}
            if memory:
                traffic.status["memory_reads"] = memory.reads

    sim = Simulator(unit)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)
    if vcd:
        with sim.write_vcd(str(vcd)):
            sim.run()
    else:
        sim.run()
    return unpack(fout, traffic.out), traffic
