"""The texture join (issue 51 §5): the texel cache between fragments and a memory of any
latency, in simulation against the memory's own words, and the short version of its proof
(``flows/texjoin.py``; the whole table is ``make formal``'s)."""
import random
import shutil

import pytest
from amaranth.sim import Simulator

from flows.sby import tools_env
from flows.texjoin import JOINS, LN_BITS, MUTANTS, SEQ, TEXEL_BITS, Join, run

SBY = shutil.which("yowasp-sby", path=tools_env()["PATH"])
needs_sby = pytest.mark.skipif(SBY is None, reason="yowasp-sby is not installed")


def word(k, ln, shared):
    """The memory's word at bank k's line ``ln`` (the address as the cache sends it): a
    pattern of the address, so each texel names the line it came from."""
    addr = (k << LN_BITS | ln) if shared or k else ln
    return (addr ^ 0x5a5a5a) & ((1 << TEXEL_BITS) - 1)


def _simulate(join, n, hold, seed):
    """``n`` fragments of random lines through ``Join``, each memory port taking a request
    and giving a response at random and holding at most ``hold`` requests, the output
    stalled at random. Returns the fragments in and out: ``[(seq, lines, texels)]``."""
    rng = random.Random(seed)
    dut = Join(**join)
    sent = [[rng.randrange(1 << LN_BITS) for _ in range(join["banks"])] for _ in range(n)]
    got = []

    async def bench(ctx):
        queues = [[] for _ in dut.req]
        k = 0
        for _ in range(60 * n):
            offer = k < n and rng.random() < 0.7
            ctx.set(dut.i_valid, offer)
            if k < n:
                ctx.set(dut.i_seq, k % (1 << SEQ))
                for x, ln in zip(dut.i_ln, sent[k]):
                    ctx.set(x, ln)
            ctx.set(dut.o_ready, rng.random() < 0.6)
            for q, (_, ready, _), (valid, _, data) in zip(queues, dut.req, dut.resp):
                ctx.set(ready, len(q) < hold and rng.random() < 0.5)
                ctx.set(valid, bool(q) and rng.random() < 0.5)
                ctx.set(data, q[0] if q else 0)
            if offer and ctx.get(dut.i_ready):
                k += 1
            if ctx.get(dut.o_valid) and ctx.get(dut.o_ready):
                got.append((ctx.get(dut.o_seq), [ctx.get(x) for x in dut.o_ln],
                            [ctx.get(x) for x in dut.o_tex]))
            for q, (valid, ready, addr), (rvalid, rready, _) in zip(queues, dut.req, dut.resp):
                if ctx.get(rvalid) and ctx.get(rready):
                    q.pop(0)
                if ctx.get(valid) and ctx.get(ready):
                    a = ctx.get(addr)
                    q.append((a ^ 0x5a5a5a) & ((1 << TEXEL_BITS) - 1))
            await ctx.tick()
            if len(got) == n:
                return
    sim = Simulator(dut)
    sim.add_clock(1e-6)
    sim.add_testbench(bench)
    sim.run()
    return sent, got


@pytest.mark.parametrize("name", list(JOINS))
@pytest.mark.parametrize("hold", [1, 2, 16])
def test_every_fragment_leaves_in_order_with_its_own_texels(name, hold):
    """Every fragment out, once, in order, with each bank's texel the memory's word for its
    line (the cache hits, misses and evicts: 16 lines a bank, 2 cached), whatever the
    memory holds before it answers: one request, two (the proof's), or many."""
    join = JOINS[name]
    sent, got = _simulate(join, 150, hold, seed=hold)
    assert len(got) == len(sent), f"{len(got)} of {len(sent)} fragments out: the join hung"
    for j, ((seq, lns, texels), lines) in enumerate(zip(got, sent)):
        assert seq == j % (1 << SEQ) and lns == lines
        assert texels == [word(k, ln, join["shared"]) for k, ln in enumerate(lines)], j


@needs_sby
def test_the_join_proven_and_its_mutants_caught():
    """The short version of make formal's join rows: the one-port join's safety properties
    proven by k-induction (memory latency unbounded), its drain bound checked, and each
    mutant caught by the property it breaks."""
    for check in ("prove", "drain"):
        r = run("texjoin_nearest", check)
        assert r["status"] == "pass" and not r["failed"], r
    for mutant, (_, prop) in MUTANTS.items():
        r = run("texjoin_nearest", prop, mutant=mutant)
        assert r["status"] == "fail" and any(f.startswith(prop) for f in r["failed"]), r
