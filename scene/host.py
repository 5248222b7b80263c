"""The host port: a scene's data written at run time, through the triangles' own stream.

The scene pipeline's input stream ``i`` carries two kinds of row, in order (the field map
lists both):

- a triangle (``cmd = 0``): the raster's fields;
- a write (``cmd = 1``): ``data`` (u32, the value's raw bits at the bottom) to ``addr``
  (u24); the triangle's fields are ignored.

**Order.** A write waits at the head of the stream until every triangle before it has left the
pipeline (``busy`` low: nothing in any stage, queue or output register; seen a clock later,
through a register), then takes one clock,
and applies to every triangle after it. A write behind triangles in flight therefore holds the
stream (``i.ready`` low) until they drain, so no triangle is ever shaded with half of one
material and half of another; writes in a row take a clock each. The write is registered once
before it reaches a register or a RAM; a triangle that follows it reaches its first table or
register at least the raster's latency (over 100 clocks) later.

**Address map** (``addr``):

- ``0x000000 + k``: register k, the pipeline's ``registers`` in order (lights, material colours,
  the Fenney concentration: each stage's ``uniforms``);
- ``0x010000 + 0x1000 j + e``: entry e of loaded table j (the power table, bump_polar's
  specular table: each stage's ``tables``, in the pipeline's order);
- ``0x100000 + a``: word a of the on-chip texture RAM (``texture = "onchip"``), in
  ``hdl.texture_unit.memory_image``'s layout.

A board bridge (UART, SPI) only has to frame these rows: the order rule holds for any source.
"""
import numpy as np
from amaranth.hdl import Signal, unsigned

from hdl.fixed import Field, u
from hdl.lut import WriteBus

__all__ = ["FIELDS", "REGISTERS", "TABLES", "TEXTURE", "TABLE_STRIDE", "writes", "stream",
           "address_map", "table_buses", "texture_bus", "equals"]

ADDR_BITS, DATA_BITS = 24, 32
FIELDS = (Field("cmd", u(1)), Field("addr", u(ADDR_BITS)), Field("data", u(DATA_BITS)))
REGISTERS, TABLES, TEXTURE = 0x000000, 0x010000, 0x100000
TABLE_STRIDE = 0x1000                 # a table's entries: up to 4096
MAX_TABLES = (TEXTURE - TABLES) // TABLE_STRIDE


def tables(stages):
    """The loaded tables in address order: ``[(base, stage, key, lut)]``."""
    out = [(s, key, lut) for s in stages for key, lut in s.tables.items() if key != "texture"]
    if len(out) > MAX_TABLES:
        raise ValueError(f"{len(out)} loaded tables; the host port addresses {MAX_TABLES}")
    for s, key, lut in out:
        if lut.depth > TABLE_STRIDE:
            raise ValueError(f"{s.name}.{key}: {lut.depth} entries; a table holds at most "
                             f"{TABLE_STRIDE}")
    return [(TABLES + j * TABLE_STRIDE, s, key, lut) for j, (s, key, lut) in enumerate(out)]


def address_map(pipeline):
    """What the host writes, for the field map and the docs: ``[{addr, what, ...}]``."""
    rows = [{"addr": f"{REGISTERS + k:#08x}", "register": f.name, **f.fmt.describe()}
            for k, f in enumerate(pipeline.registers)]
    rows += [{"addr": f"{base:#08x}", "table": f"{s.name}.{key}", "entries": lut.depth,
              **lut.fmt.describe()} for base, s, key, lut in tables(pipeline.stages)]
    for s in pipeline.stages:
        if "texture" in s.tables:
            lut = s.tables["texture"]
            rows.append({"addr": f"{TEXTURE:#08x}", "texture": s.name, "words": lut.depth,
                         **lut.fmt.describe()})
    return rows


def writes(pipeline, registers, table_values, texture=None):
    """The writes that load a scene's data, in the order a host sends them: ``(addr, data)``,
    int64 arrays. ``registers``: raw values by name; ``table_values``: ``{(stage, key):
    contents}``; ``texture``: the on-chip texture's words, or None."""
    addr, data = [], []
    for k, f in enumerate(pipeline.registers):
        addr.append([REGISTERS + k])
        data.append([int(registers[f.name]) & ((1 << f.fmt.width) - 1)])
    for base, s, key, lut in tables(pipeline.stages):
        values = np.asarray(table_values[s.name, key], np.int64)
        if len(values) != lut.depth:
            raise AssertionError(f"{s.name}.{key}: {len(values)} entries, its RAM {lut.depth}")
        addr.append(base + np.arange(lut.depth))
        data.append(values & ((1 << lut.fmt.width) - 1))
    if texture is not None:
        addr.append(TEXTURE + np.arange(len(texture)))
        data.append(np.asarray(texture, np.int64))
    if not addr:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    return (np.concatenate(addr).astype(np.int64),
            np.concatenate(data).astype(np.int64) & ((1 << DATA_BITS) - 1))


def stream(triangles, load, at=None):
    """The input rows: the writes ``load`` (``(addr, data)``) and the triangles (a dict of
    field arrays), one stream. ``at``: ``[(position, (addr, data))]`` further writes, each before
    the triangle of that index (a material changed between triangles); by default every write
    comes first."""
    n = len(next(iter(triangles.values())))
    groups = [(0, load)] + sorted(at or [], key=lambda g: g[0])
    parts, start = [], 0
    for pos, (a, d) in groups:
        if pos > start:
            parts.append(_rows(triangles, start, pos))
            start = pos
        parts.append(_write_rows(triangles, a, d))
    parts.append(_rows(triangles, start, n))
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[-1]}


def _rows(triangles, lo, hi):
    out = {k: np.asarray(v[lo:hi], np.int64) for k, v in triangles.items()}
    zero = np.zeros(hi - lo, np.int64)
    return {**out, "cmd": zero, "addr": zero, "data": zero}


def _write_rows(triangles, addr, data):
    zero = np.zeros(len(addr), np.int64)
    return {**{k: zero for k in triangles}, "cmd": zero + 1,
            "addr": np.asarray(addr, np.int64), "data": np.asarray(data, np.int64)}


def equals(value, k):
    """``value == k`` as a reduction (Amaranth writes ``x == 0`` as a logical not, which
    Verilator's lint takes for a width mistake)."""
    return ~(value ^ k).any()


def table_buses(w_en, w_addr, w_data, bases):
    """Each loaded table's :class:`WriteBus` from the registered write (``bases``: ``{key:
    base}``): selected by the address's top bits, the entry its low 12."""
    sel = lambda base: w_en & equals(w_addr[12:], base >> 12)
    return {key: WriteBus(sel(base), w_addr[:12], w_data) for key, base in bases.items()}


def texture_bus(w_en, w_addr, w_data):
    """The on-chip texture RAM's :class:`WriteBus`: addresses from ``TEXTURE`` up."""
    return WriteBus(w_en & equals(w_addr[20:], TEXTURE >> 20), w_addr[:20], w_data)


def write_signals():
    """The registered write inside the top: ``(en, addr, data)``."""
    return (Signal(name="w_en"), Signal(unsigned(ADDR_BITS), name="w_addr"),
            Signal(unsigned(DATA_BITS), name="w_data"))
