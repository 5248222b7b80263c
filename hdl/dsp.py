"""One 18 x 18 multiplier with a registered operand pair and a registered product.

Yosys (0.70) infers ECP5's MULT18X18D but leaves the registers around it in the fabric
(YosysHQ/yosys#5814), so a product pays a route into the block and a route out of it inside one
clock: 10.5 ns in the raster, the critical path once its handshakes were registered. On ECP5
the block is instantiated with its own input and output registers (REG_INPUTA/B, REG_OUTPUT on
CLK0, enabled by CE0), which leaves only register-to-block routes in the fabric. Everywhere
else (simulation, iCE40, where Yosys packs SB_MAC16's registers itself) the same two clocks
are written behaviourally, so both forms are cycle-for-cycle the same.

The FPGA flow hands :class:`Target` to ``elaborate(platform)``; a design asks :func:`ecp5`.
"""
from contextlib import contextmanager
from contextvars import ContextVar

from amaranth.hdl import ClockSignal, Const, Instance, Mux, Signal, Value, signed

__all__ = ["Target", "ecp5", "mult18", "mult_narrow", "soft_mult", "soft_halves", "soft_as_mul",
           "Product"]


class Target:
    """The platform of the FPGA flow (``flows.fpga``): only the family is known."""

    def __init__(self, family):
        self.family = family


def ecp5(platform):
    return getattr(platform, "family", None) == "ecp5"


def mult18(m, name, a, b, en, platform):
    """``a * b`` (each at most 18 bits, signed or unsigned by its shape) two clocks later:
    operands registered, then the product; everything holds while ``en`` is low. Returns the
    36-bit signed product register."""
    a, b = Value.cast(a), Value.cast(b)
    unsigned_pair = not (a.shape().signed or b.shape().signed) and len(a) + len(b) <= 35
    for x in (a, b):
        # 18 bits unsigned: the block's unsigned mode, where the product fits 36 signed
        if len(x) > 18 or (len(x) == 18 and not x.shape().signed and not unsigned_pair):
            raise ValueError(f"{name}: an operand of {len(x)} bits does not fit 18 signed")
    p = Signal(signed(36), name=f"{name}_p", reset_less=True)
    if ecp5(platform):
        ext = lambda x: x.as_signed() if x.shape().signed else x     # to 18 bits, by sign
        pa, pb = (Signal(18, name=f"{name}_{s}") for s in "ab")
        m.d.comb += [pa.eq(ext(a)), pb.eq(ext(b))]
        ports = {f"i_A{k}": pa[k] for k in range(18)}
        ports.update({f"i_B{k}": pb[k] for k in range(18)})
        ports.update({f"i_C{k}": Const(0) for k in range(18)})
        ports.update({f"o_P{k}": p[k] for k in range(36)})
        reg = {f"p_REG_{r}_{x}": v for r in ("INPUTA", "INPUTB", "OUTPUT")
               for x, v in (("CLK", "CLK0"), ("CE", "CE0"), ("RST", "RST0"))}
        m.submodules[name] = Instance(
            "MULT18X18D", **reg, p_GSR="DISABLED", p_RESETMODE="SYNC",
            i_SIGNEDA=Const(int(a.shape().signed)), i_SIGNEDB=Const(int(b.shape().signed)),
            i_SOURCEA=Const(0), i_SOURCEB=Const(0), i_CLK0=ClockSignal(), i_CE0=en,
            i_RST0=Const(0), **{f"i_{s}{k}": Const(0) for s in ("CLK", "CE", "RST")
                                 for k in (1, 2, 3)}, **ports)
    else:
        ra, rb = (Signal(x.shape(), name=f"{name}_r{s}", reset_less=True)
                  for x, s in ((a, "a"), (b, "b")))
        with m.If(en):
            m.d.sync += [ra.eq(a), rb.eq(b), p.eq(ra * rb)]
    return p


def mult_narrow(m, name, a, b, en, platform, bits=20):
    """``a * b`` of two signed operands of at most ``bits`` (19-24) bits on one MULT18X18D,
    four clocks later (issue 49's narrow products, docs/quadratic.md): with k = bits - 18,
    a = 2**k aH + aL and b = 2**k bH + bL (aH, bH the top 18 bits, signed; aL, bL the low k,
    unsigned), a b = 2**2k aH bH + 2**k (aH bL + aL bH) + aL bL. aH bH is the block's
    (:func:`mult18`: operands, then the product, registered); the rest is summed in logic
    beside it, no more than two adders a clock: aH bL, aL bH and aL bL (a k-bit operand's
    conditional additions, :func:`soft_mult`), then their sum, then the sum with the block's
    product. Everything holds while ``en`` is low. Returns the 2 ``bits``-bit signed product
    register. ``flows.products`` measures it."""
    a, b = Value.cast(a), Value.cast(b)
    k = bits - 18
    if not 1 <= k <= 6:
        raise ValueError(f"{name}: a narrow product of {bits} bits: 19 to 24")
    if len(a) > bits or len(b) > bits or not (a.shape().signed and b.shape().signed):
        raise ValueError(f"{name}: operands of at most {bits} bits, signed; here {a.shape()} "
                         f"and {b.shape()}")
    wa, wb = (Signal(signed(bits), name=f"{name}_w{s}") for s in "ab")    # sign-extended
    m.d.comb += [wa.eq(a), wb.eq(b)]
    hi = mult18(m, f"{name}_hi", wa[k:].as_signed(), wb[k:].as_signed(), en, platform)
    reg = lambda shape, n: Signal(shape, name=f"{name}_{n}", reset_less=True)
    ra, rb = reg(signed(bits), "sa"), reg(signed(bits), "sb")
    x, y, z = reg(signed(18 + k), "x"), reg(signed(18 + k), "y"), reg(2 * k, "z")
    side = reg(signed(20 + 2 * k), "side")
    hi2, p = reg(signed(36), "hi2"), reg(signed(2 * bits), "p")
    with m.If(en):
        m.d.sync += [ra.eq(wa), rb.eq(wb),
                     x.eq(soft_mult(rb[:k], ra[k:].as_signed())),
                     y.eq(soft_mult(ra[:k], rb[k:].as_signed())),
                     z.eq(soft_mult(ra[:k], rb[:k])),
                     side.eq(((x + y) << k) + z), hi2.eq(hi),
                     p.eq((hi2 << 2 * k) + side)]
    return p


_SOFT_AS_MUL = ContextVar("soft_as_mul", default=False)


@contextmanager
def soft_as_mul():
    """Within it, :func:`soft_mult` is written as ``a * b`` (the same function: tests/test_fpga.py
    checks the adders against it exhaustively), so that the formal flow's product stand-in
    (``flows.formal.MUL_STANDIN``) replaces it too, instead of the solver reasoning through the
    adder tree (fenney_polar's ``order`` proof: docs/formal.md)."""
    token = _SOFT_AS_MUL.set(True)
    try:
        yield
    finally:
        _SOFT_AS_MUL.reset(token)


def soft_mult(a, b):
    """``a * b`` in logic, not a DSP: the partial products of the narrower operand's bits
    (each the other operand shifted, or 0), summed as a balanced tree of adders. For the small
    products of a pipeline that has run out of MULT18X18D (an 8 x 11 product: about 200
    LUT4). The narrower operand is unsigned; the wider may be signed (its partial products
    are then sign-extended, and so is the product)."""
    a, b = Value.cast(a), Value.cast(b)
    if len(a) > len(b) or (len(a) == len(b) and a.shape().signed):
        a, b = b, a
    if a.shape().signed:
        raise ValueError("soft_mult: the narrower operand must be unsigned")
    if _SOFT_AS_MUL.get():
        product = (a * b)[:len(a) + len(b)]
    else:
        terms = [Mux(a[i], b << i, 0) for i in range(len(a))]
        while len(terms) > 1:
            terms = [terms[k] + terms[k + 1] if k + 1 < len(terms) else terms[k]
                     for k in range(0, len(terms), 2)]
        product = terms[0][:len(a) + len(b)]
    return product.as_signed() if b.shape().signed else product


def soft_halves(a, b):
    """``a * b`` (``a`` the narrow unsigned operand) as two soft products of ``a``'s halves,
    ``(lo, hi, k)`` with ``a * b = lo + (hi << k)``: each half's tree is half as deep, so the
    halves take one clock and their sum the next (8 partial products in one clock were
    fenney_polar's critical path, 117 MHz; halves, 132.5)."""
    a = Value.cast(a)
    k = len(a) // 2
    return soft_mult(a[:k], b), soft_mult(a[k:], b), k


class Product:
    """``a * b`` on a MULT18X18D with its own registers, for a :meth:`hdl.unit.Pipeline.stage`:
    the block's input registers are this stage's, its output register the next stage's (which
    passes the value on untouched), so the product costs no clock more than a product
    between two stage registers, but Yosys need not pack those registers into the block (it
    does not: ``mult18``)."""

    def __init__(self, a, b):
        self.a, self.b = Value.cast(a), Value.cast(b)
