"""A clock model of the raster's pipeline: fragments a clock from the setup's clocks a
triangle and the row engine's clocks a row, on a mesh's own triangles, rows and spans.

Issue 66 asks for the expected fragments a clock of a narrow raster before its RTL. This is
the model that answers it, held first to the RTL it would predict: the knob table of
docs/quadratic.md, every setting's fragments a clock on the three meshes through the
default pipeline's RTL (``python -m flows.rates``), against this model's for the same
setup clocks and row interval.

The model follows the parts (docs/quadratic.md, "The span engine"), one triangle at a time
through each:

- **setup**: a triangle takes ``setup`` clocks; one at a time (``setup_ii = 0``), the next
  starts once the walker has taken the last one's results; overlapped, one starts every
  ``setup_ii`` clocks while the setup queue (``ROW_QUEUE`` deep) has room, its results
  ``latency`` clocks after its start;
- **walker**: takes a triangle once its results are ready and the last triangle's rows are
  out, and visits its rows one a clock, ``EMPTY`` clocks a row with no pixel centre;
- **row engine**: a row with pixels starts no sooner than ``row_ii`` clocks after the last
  start, and only on a credit of the row queue (at most ``ROW_QUEUE`` rows started and not
  yet taken by the stepper); its values reach the queue ``row_clocks`` later;
- **stepper**: a row's fragments one a clock, ``GAP`` clocks between two rows.

The cycles add what ``make render`` counts around the raster: the host port's load (a word a
clock) and the shading stages' latency after the last fragment.

    python -m flows.pace          (the check against the RTL's rates, then the predictions)
"""
from collections import deque

import numpy as np

from golden import raster as R
from hdl.span_unit.plan import RasterPlan
from hdl.span_unit.queue import ROW_QUEUE

from .bfp import MESHES, _scene_inputs

BLOCKS = 12      # the raster's MULT18X18D (issue 66's budget)
WIDE = 4         # a wide product (35 x 35 bits) in passes on one MULT18X18D
MANTISSA = 21    # the narrow engine's mantissa bits (docs/quadratic.md)
TARGETS = (0.95, 0.75, 0.75, 0.75)    # issue 66's fragments a clock, MESHES then random
EMPTY = 2        # the walker's clocks on a row with no pixel centre (docs/quadratic.md)
GAP = 0          # the stepper's clocks between two rows' fragments (its skid: none)

# docs/quadratic.md's knob table, measured through the RTL (python -m flows.rates): the
# setting, then fragments a clock on MESHES (default torus, Wuson, dense torus)
MEASURED = {
    "": (0.849, 0.117, 0.107),
    "row_serial=3": (0.844, 0.116, 0.107),
    "row_serial=3,setup_serial=1": (0.836, 0.090, 0.081),
    "row_serial=2,setup_serial=1": (0.661, 0.085, 0.081),
    "setup_ii=54": (0.854, 0.195, 0.184),
    "setup_ii=24,setup_narrow=2": (0.854, 0.280, 0.296),
    "setup_ii=16,setup_mults=2,setup_narrow=2": (0.855, 0.295, 0.306),
    "setup_ii=16,setup_mults=2,setup_narrow=2,row_mults=6": (0.954, 0.544, 0.542),
}


def rows(inputs, screen_bits, sub_bits):
    """Per triangle in, in order: its rows the walker visits, each its pixel count (0: no
    pixel centre), from the coverage model (``golden.raster.coverage``)."""
    x, y = R._vertices(inputs)
    tri, _, py = R.coverage(x, y, sub_bits, screen_bits)
    size, s = 1 << screen_bits, 1 << sub_bits
    counts = {}
    for t, j in zip(tri.tolist(), py.tolist()):
        counts[t, j] = counts.get((t, j), 0) + 1
    # the rows of pixel centres between the top and the bottom vertex, on the screen
    j0 = np.clip(np.ceil(y.min(1) / s - 0.5), 0, size).astype(int)
    j1 = np.clip(np.ceil(y.max(1) / s - 0.5), 0, size).astype(int)
    area = R._area2(x, y)
    return [[counts.get((t, j), 0) for j in range(j0[t], j1[t])] if area[t] else []
            for t in range(len(x))]


def clocks(tris, setup, row_ii, row_clocks, setup_ii=0, latency=None):
    """The clock at which the last fragment leaves the stepper, drawing ``tris`` (:func:`rows`)
    with a setup of ``setup`` clocks a triangle (``setup_ii``: overlapped, one every
    ``setup_ii`` clocks, its results ``latency`` clocks after its start) and a row every
    ``row_ii`` clocks. ``setup``, ``setup_ii`` and ``row_ii`` may be one per triangle (a
    triangle on the slow path takes longer)."""
    n = len(tris)
    setup, setup_ii, row_ii = (np.broadcast_to(np.asarray(v), n).tolist()
                               for v in (setup, setup_ii, row_ii))
    latency = setup if latency is None else np.broadcast_to(np.asarray(latency), n).tolist()
    started = deque()          # the row engine's starts whose rows the stepper has not taken
    taken = []                 # the walker's takes, for the setup queue's room
    setup_start, walker_free, last_row, stepper_free, ii, last_ii = 0, 0, 0, 0, 0, 0
    walker_took = 0
    for k, tri in enumerate(tris):
        if setup_ii[k]:
            room = taken[k - ROW_QUEUE] if k >= ROW_QUEUE else 0
            setup_start = max(setup_start + ii, room) if k else 0
            ii = setup_ii[k]               # the next starts this triangle's interval later
            ready = setup_start + latency[k]
        else:
            setup_start = max(setup_start, walker_took) if k else 0
            ready = setup_start + setup[k]
        t = walker_took = max(ready, walker_free)
        taken.append(walker_took)
        for pixels in tri:
            if not pixels:
                t += EMPTY
                continue
            credit = started.popleft() if len(started) >= ROW_QUEUE else 0
            start = max(t, last_row + last_ii, credit)
            last_row, last_ii, t = start, row_ii[k], start + 1
            begin = max(start + row_clocks, stepper_free)
            stepper_free = begin + pixels + GAP
            started.append(begin)      # the stepper takes the row: its place is free
        walker_free = t
        if not setup_ii:               # the next setup starts when this one is taken
            setup_start = walker_took
    return stepper_free


def rate(tris, frags, plan, load, tail):
    """Fragments a clock of ``plan`` on a mesh, in ``make render``'s cycles."""
    t = plan.timing
    n = clocks(tris, t.setup_clocks, t.row_ii, t.row_clocks, plan.setup_ii, t.setup_end)
    return frags / (n + load + tail)


def narrow(tris, frags, fast, products, blocks, row_clocks, latency, load=0, tail=0):
    """Fragments a clock of a narrow raster (issue 66): every product of a triangle on the
    fast path one block-clock, on the slow path ``WIDE`` (the same jobs at full width, in
    passes on the same blocks). ``products``: the setup's a triangle and the row engine's a
    row; ``blocks``: the MULT18X18D each has; ``fast``: per triangle in. The setup overlaps
    triangles, one every ceil(products / blocks) clocks, its results ``latency`` after."""
    passes = np.where(fast, 1, WIDE)
    setup_ii = -(-products[0] // blocks[0]) * passes
    row_ii = -(-products[1] // blocks[1]) * passes
    n = clocks(tris, setup_ii, row_ii, row_clocks, setup_ii, np.maximum(latency, setup_ii))
    return frags / (n + load + tail)


def _random(bits=8, n=3000):
    """Random triangles as the raster's tests draw them, two X-shading channels."""
    from golden import TYPICAL_SIZE, random_triangles
    inputs = random_triangles(np.random.default_rng(49), n, screen_bits=bits, sub_bits=4,
                              channels=2, size=TYPICAL_SIZE)
    plan = RasterPlan.from_params(screen_bits=bits, sub_bits=4, channels=2)
    tris = rows(inputs, bits, 4)
    return inputs, tris, sum(map(sum, tris)), 0, 0, plan


def _mesh(name, segments):
    from scene import driver as S
    from sim.verilog import SCENES
    scene = S.load(SCENES / f"{name}.toml")
    if segments:
        scene["mesh"]["segments"] = segments
    prep = S.prepare(scene)
    inputs, sb, sub, modes = _scene_inputs(name, segments)
    tris = rows(inputs, sb, sub)
    frags = sum(map(sum, tris))
    return inputs, tris, frags, len(prep["load"][0]), prep["pipeline"].shading_latency, \
        prep["pipeline"].raster.plan


def _with(plan, setting):
    from dataclasses import replace
    from sim.cli_common import raster_knobs
    return replace(plan, **raster_knobs(setting)) if setting else plan


def main():
    meshes = [(label, *_mesh(name, seg)) for label, name, seg in MESHES]
    print("| setting | " + " | ".join(f"{label}: RTL, model" for label, *_ in meshes)
          + " |")
    print("| --- | " + " | ".join("---" for _ in meshes) + " |")
    worst = 0.0
    for setting, measured in MEASURED.items():
        cells = []
        for (label, _, tris, frags, load, tail, plan), got in zip(meshes, measured):
            r = rate(tris, frags, _with(plan, setting), load, tail)
            worst = max(worst, abs(r / got - 1))
            cells.append(f"{got:.3f}, {r:.3f}")
        print(f"| {setting or 'default'} | " + " | ".join(cells) + " |", flush=True)
    print(f"\nworst relative difference: {worst * 100:.1f} %")
    predict(meshes + [("random, 256 x 256 (golden.random_triangles)", *_random())])


def predict(meshes, m=MANTISSA):
    """The narrow raster's fragments a clock on each mesh, for each split of ``BLOCKS``
    MULT18X18D between the setup and the row engine; the fast path is the triangles the
    narrow row engine's derived bound holds at ``m`` bits (``flows.bfp.narrow_triangles``)."""
    from hdl.span_unit.span import row_products
    from .bfp import narrow_triangles
    cases = []
    for label, inputs, tris, frags, load, tail, plan in meshes:
        fast = narrow_triangles(inputs, m, plan.screen_bits, plan.sub_bits, plan.modes)
        drawn = np.array([bool(t) and sum(t) > 0 for t in tris])
        products = (plan.setup_products[0], row_products(plan.modes))
        cases.append((label, tris, frags, load, tail, plan, fast, drawn, products))
    print(f"\nThe narrow raster ({BLOCKS} MULT18X18D, {m}-bit mantissas), by this model:\n")
    print("| MULT18X18D: setup + rows | " + " | ".join(c[0] for c in cases) + " |")
    print("| --- | " + " | ".join("---" for _ in cases) + " |")
    print("| products: setup a triangle, rows a row | " + " | ".join(
        f"{c[8][0]}, {c[8][1]}" for c in cases) + " |")
    print("| fast path: triangles drawn | " + " | ".join(
        f"{c[6][c[7]].mean() * 100:.1f} %" for c in cases) + " |")
    def best(case, blocks):
        """The best split of ``blocks``: (fragments a clock, setup's blocks)."""
        label, tris, frags, load, tail, plan, fast, _, products = case
        t = plan.timing
        return max((narrow(tris, frags, fast, products, (sb, blocks - sb), t.row_clocks,
                           t.setup_end, load, tail), sb) for sb in range(1, blocks))

    for sb in range(2, BLOCKS - 1):
        cells = []
        for label, tris, frags, load, tail, plan, fast, _, products in cases:
            t = plan.timing
            r = narrow(tris, frags, fast, products, (sb, BLOCKS - sb), t.row_clocks,
                       t.setup_end, load, tail)
            cells.append(f"{r:.3f}")
        print(f"| {sb} + {BLOCKS - sb} | " + " | ".join(cells) + " |", flush=True)
    cells = []
    for case, target in zip(cases, TARGETS):
        for blocks in range(BLOCKS, 4 * BLOCKS):
            r, sb = best(case, blocks)
            if r >= target:
                cells.append(f"{blocks} ({sb} + {blocks - sb}): {r:.3f}")
                break
        else:
            cells.append(f"not within {4 * BLOCKS}")
    print("| the least MULT18X18D for the target (0.95, 0.75, 0.75, 0.75), best split | "
          + " | ".join(cells) + " |")


if __name__ == "__main__":
    main()
