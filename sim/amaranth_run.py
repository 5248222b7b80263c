"""Streaming vectors through a unit in Amaranth's simulator."""
import threading

from amaranth.sim import Simulator

from .stream import COUNTERS, Traffic, memory_ports, pack, timed_rows, unpack


def fields_of(unit):
    return ([f.describe() for f in unit.inputs], [f.describe() for f in unit.outputs])


def run_amaranth(unit, inputs, *, p_valid=1.0, p_ready=1.0, seed=0, vcd=None, progress=None,
                 uniforms=None, memory=None):
    """Run every row of ``inputs`` through ``unit`` (its uniform ports held at ``uniforms``;
    ``memory`` behind its memory port); returns ``(outputs, traffic)``."""
    fin, fout = fields_of(unit)
    many = hasattr(unit, "busy")
    traffic = Traffic(pack(fin, inputs), p_valid=p_valid, p_ready=p_ready, seed=seed,
                      progress=progress, many=many, timed=timed_rows(inputs))
    i_raw, o_raw = unit.i.payload.as_value(), unit.o.payload.as_value()
    busy = unit.busy if many else unit.o.valid

    async def bench(ctx):
        for f in unit.uniforms:
            ctx.set(getattr(unit, f"u_{f.name}"), int(uniforms[f.name]))
        names = memory_ports(unit)
        mems = memory.ports(len(names)) if names else []
        ports = [(getattr(unit, q), getattr(unit, r)) for q, r in names]
        sampled = [s for q, r in ports for s in (q.valid, q.payload.addr, r.ready)]
        while not traffic.done:
            valid, payload, ready = traffic.drive()
            ctx.set(unit.i.valid, valid)
            ctx.set(i_raw, payload)
            ctx.set(unit.o.ready, ready)
            for mem, (q, r) in zip(mems, ports):
                take, rv, rd = mem.drive()
                ctx.set(q.ready, take)
                ctx.set(r.valid, rv)
                ctx.set(r.payload.data, rd)
            _, _, i_ready, o_valid, o_payload, b, *got = \
                await ctx.tick().sample(unit.i.ready, unit.o.valid, o_raw, busy, *sampled)
            for k, mem in enumerate(mems):
                mem.edge(traffic.cycles, *got[3 * k:3 * k + 3])
                b = b or mem.busy
            traffic.edge(i_ready, o_valid, o_payload, b)
        if many:
            traffic.status = {k: ctx.get(getattr(unit, k)) for k in COUNTERS
                              if k in unit.status_ports}
            if mems:
                traffic.status["memory_reads"] = sum(mem.reads for mem in mems)

    sim = Simulator(unit)
    sim.add_clock(1e-8)
    sim.add_testbench(bench)

    def run():
        if vcd:
            with sim.write_vcd(str(vcd)):
                sim.run()
        else:
            sim.run()
    in_thread(run)
    return unpack(fout, traffic.out), traffic


def in_thread(fn):
    """``fn()`` in a thread of its own, its exception raised here. CPython 3.11 keeps a
    thread's frames in 16 KB chunks and frees a chunk when its first frame returns; the
    simulator's compiled process for the raster has a 14 KB frame, so when the caller's
    stack leaves less room than that in its chunk, every call of it maps and unmaps one:
    measured on ``sim run raster`` (16 triangles at 32 x 32), 2.4 million mmap and munmap
    pairs and 57 s, where the same run takes 9 s. A thread of its own starts the simulation
    at the same depth whoever calls it."""
    err = []

    def body():
        try:
            fn()
        except BaseException as e:                  # raised again in the caller's thread
            err.append(e)
    t = threading.Thread(target=body, daemon=True)  # daemon: Ctrl-C ends the process
    t.start()
    t.join()
    if err:
        raise err[0]
