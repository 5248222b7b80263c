"""The float model of the ``raster`` unit (setup -> span), and an independent coverage rule.

Coverage (``coverage``) uses edge functions on pixel centres (x + 0.5, y + 0.5), in exact
integer arithmetic (half sub-pixel units), with the top-left fill rule: a centre on an edge
belongs to the triangle only if the edge is a left edge (the interior lies towards +x) or a
top edge (horizontal, the interior below). The RTL walks edges with a DDA instead; the tests
compare the two.

Values (``run``): each covered pixel's channel values from the float model of the channel's
mode at the exact pixel centre, ``Phi(u, v)`` (seed 001 eq 17-21), from the same quantised
inputs the RTL gets, saturated to the value format like the RTL.
"""
import numpy as np

from hdl.setup_unit.formats import (EDGE, VALUE, edge_names, parse_groups, parse_modes,
                                   parse_precision)

from . import quadratic as q

__all__ = ["coverage", "culled", "run", "channel_uv", "sorted_triangles"]


def _vertices(inputs):
    x = np.stack([np.asarray(inputs[f"x{k}"], np.int64) for k in range(3)], -1)
    y = np.stack([np.asarray(inputs[f"y{k}"], np.int64) for k in range(3)], -1)
    return x, y


def _area2(x, y):
    """Twice the signed area of each triangle (Omega, seed 002 eq 47), sub-pixel units."""
    return (x[:, 1] - x[:, 0]) * (y[:, 2] - y[:, 0]) - (x[:, 2] - x[:, 0]) * (y[:, 1] - y[:, 0])


def culled(inputs):
    """How many triangles the setup drops as degenerate (Omega = 0)."""
    return int(np.sum(_area2(*_vertices(inputs)) == 0))


def coverage(x, y, sub_bits, screen_bits):
    """Pixels whose centres each triangle covers: (tri, px, py) arrays, sorted by tri, y, x.
    ``x``, ``y``: (n, 3) raw vertex coordinates with ``sub_bits`` fraction bits."""
    size = 1 << screen_bits
    half = 1 << sub_bits                                  # one pixel in half sub-pixel units
    tris, pxs, pys = [], [], []
    for t in range(len(x)):
        vx, vy = 2 * x[t].astype(np.int64), 2 * y[t].astype(np.int64)
        area = (vx[1] - vx[0]) * (vy[2] - vy[0]) - (vx[2] - vx[0]) * (vy[1] - vy[0])
        if area == 0:
            continue
        if area < 0:
            vx, vy = vx[[0, 2, 1]], vy[[0, 2, 1]]
        # pixel index range of the bounding box, clipped to the screen
        lo_x = max(0, int(vx.min() // (2 * half)) - 1)
        hi_x = min(size, int(vx.max() // (2 * half)) + 2)
        lo_y = max(0, int(vy.min() // (2 * half)) - 1)
        hi_y = min(size, int(vy.max() // (2 * half)) + 2)
        if lo_x >= hi_x or lo_y >= hi_y:
            continue
        cy, cx = np.mgrid[lo_y:hi_y, lo_x:hi_x]
        px, py = (2 * cx + 1) * half, (2 * cy + 1) * half   # centres, half sub-pixel units
        inside = np.ones(cx.shape, bool)
        for a, b in ((0, 1), (1, 2), (2, 0)):
            ex, ey = vx[b] - vx[a], vy[b] - vy[a]
            e = ex * (py - vy[a]) - ey * (px - vx[a])          # > 0 inside (y down)
            gx, gy = -ey, ex                                   # the inward normal
            tie = gx > 0 or (gx == 0 and gy > 0)               # left or top edge
            inside &= (e > 0) | ((e == 0) if tie else False)
        k = np.flatnonzero(inside.ravel())
        tris.append(np.full(len(k), t))
        pxs.append(cx.ravel()[k])
        pys.append(cy.ravel()[k])
    cat = lambda a: np.concatenate(a).astype(np.int64) if a else np.zeros(0, np.int64)
    return cat(tris), cat(pxs), cat(pys)


def channel_uv(mode, I, e):
    """a..f of one channel from its sorted vertex values I = (I1, I2, I3) and edge constants
    e = (e12, e13, e23) (all real): X-shading (eq 32), exact mid-edges (eq 4-6, 16) or linear
    (seed 000 eq 24-28)."""
    if mode == "xshading":
        return q.xshading_uv(*I, *e)
    if mode == "exact":
        return q.ortho_uv(q.exact_samples(*I, *e, lo=VALUE.min * VALUE.lsb,
                                          hi=VALUE.max * VALUE.lsb))
    return q.linear_uv(*I)


_EDGE_OF = {(0, 1): "e01", (1, 0): "e01", (0, 2): "e02", (2, 0): "e02", (1, 2): "e12",
            (2, 1): "e12"}


def sorted_triangles(inputs, channels, sub_bits, groups=1, real=None):
    """Sort each triangle's vertices (by y, then x), as the setup unit does; returns the order,
    the top vertex, x1 y1 x2 y2 (pixels), the sorted values per channel and, per group, the
    edge constants (e12, e13, e23) in sorted labels. ``real``: the same keys as ``inputs``
    before rounding (in their raw units, as floats): the positions, values and edge
    constants are taken from it, the order from ``inputs``."""
    x, y = _vertices(inputs)
    order = np.lexsort((x, y), axis=-1)
    if real is not None:
        inputs, x, y = real, *(np.stack([np.asarray(real[f"{a}{k}"], float) for k in range(3)],
                                        -1) for a in "xy")
    xs, ys = np.take_along_axis(x, order, -1), np.take_along_axis(y, order, -1)
    scale = 2.0 ** -sub_bits
    rel = [(xs[:, k] - xs[:, 0]) * scale for k in (1, 2)], [(ys[:, k] - ys[:, 0]) * scale
                                                            for k in (1, 2)]
    es = []
    for g in range(groups):
        names = edge_names(g)
        edges = {n: np.asarray(inputs[m], float) * EDGE.lsb
                 for n, m in zip(("e01", "e02", "e12"), names)}
        e = []
        for a, b in ((0, 1), (0, 2), (1, 2)):
            pair = np.array([_EDGE_OF[(int(i), int(j))]
                             for i, j in zip(order[:, a], order[:, b])])
            e.append(np.select([pair == "e01", pair == "e02"], [edges["e01"], edges["e02"]],
                               edges["e12"]))
        es.append(e)
    vals = []
    for ch in range(channels):
        v = np.stack([np.asarray(inputs[f"v{ch}_{k}"], float) for k in range(3)], -1)
        vals.append(np.take_along_axis(v, order, -1) * VALUE.lsb)
    return dict(x0=xs[:, 0] * scale, y0=ys[:, 0] * scale, x1=rel[0][0], y1=rel[1][0],
                x2=rel[0][1], y2=rel[1][1], values=vals, e=es[0], groups=es)


def run(inputs, screen_bits=10, sub_bits=4, channels=2, modes="xshading", groups="0", flat=0,
        real=None, precision="14", **_):
    """Fragments of every triangle: ``tri x y`` and ``v{k}`` (reals, saturated to the value
    range, its top at the channel's ``precision``), in the order the RTL emits them (by
    triangle, row, column); each channel with its group's edge constants; the ``flat`` words ``f{k}`` of each fragment's triangle.
    ``real``: the inputs before rounding (``sorted_triangles``): the same fragments, their
    values from the unrounded positions, vertex values and edge constants, unsaturated (the
    ideal model's)."""
    modes = parse_modes(modes, channels)
    groups = parse_groups(groups, channels)
    x, y = _vertices(inputs)
    tri, px, py = coverage(x, y, sub_bits, screen_bits)
    out = {"tri": tri, "x": px, "y": py,
           **{f"f{k}": np.asarray(inputs[f"f{k}"])[tri] for k in range(flat)}}
    st = sorted_triangles(inputs, channels, sub_bits, max(groups) + 1, real)
    X = px + 0.5 - st["x0"][tri]
    Y = py + 0.5 - st["y0"][tri]
    g = {k: st[k][tri] for k in ("x1", "y1", "x2", "y2")}
    with np.errstate(divide="ignore", invalid="ignore"):
        u, v = q.uv_of(g["x1"], g["y1"], g["x2"], g["y2"], X, Y)
    for ch, (mode, p) in enumerate(zip(modes, parse_precision(precision, channels))):
        lo, hi = ((VALUE.min * VALUE.lsb, 2 - 2.0 ** -p) if real is None else
                  (-np.inf, np.inf))
        I = [st["values"][ch][:, k] for k in range(3)]
        uv = channel_uv(mode, I, st["groups"][groups[ch]])
        out[f"v{ch}"] = np.clip(q.eval_uv(uv[tri], u, v), lo, hi)
    return out

