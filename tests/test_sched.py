"""The schedule's record of operands (``hdl/term.py``): a term is the Amaranth value it
stands for, and it knows the registers it reads, whether it is wiring only, and how to be
rebuilt with registers replaced; the schedule places each operation after the registers it
reads are ready. (The raster's RTL tests hold the schedules' results bit for bit.)"""
from amaranth.hdl import Cat as ACat, Const, Fragment, Module, Mux as AMux, Signal, Value

from hdl.sched import Schedule
from hdl.term import Cat, Mux, Term, term


def test_a_term_is_the_value_it_stands_for():
    a, b, c = Signal(8, name="a"), Signal(8, name="b"), Signal(4, name="c")
    for t, v in (((term(a) + b) >> 2, (a + b) >> 2), (3 - term(a), 3 - a),
                 (Mux(term(c)[0], a, b), AMux(c[0], a, b)), (Cat(term(a), c), ACat(a, c)),
                 ((~term(a)).as_signed()[1:], (~a).as_signed()[1:]),
                 (term(Const(1, 4)) - a, Const(1, 4) - a), (abs(term(a).as_signed()),
                                                             abs(a.as_signed()))):
        assert repr(Value.cast(t)) == repr(v)


def test_leaves_wiring_and_map():
    a, b, c = Signal(8, name="a"), Signal(8, name="b"), Signal(8, name="c")
    s = term(a) + b
    assert [id(x) for x in s.leaves()] == [id(a), id(b)] and not s.wiring
    assert term(a)[2:6].wiring and Cat(term(a), Const(0, 2)).wiring
    assert (term(a) << 3).wiring and not (term(a) << term(b)[:2]).wiring
    assert not Mux(term(a)[0], b, 0).wiring and not term(a).any().wiring
    m = s.map(lambda r: term(c) if r is a else Term.leaf(r))
    assert [id(x) for x in m.leaves()] == [id(c), id(b)]
    assert repr(Value.cast(m)) == repr(c + b)
    assert isinstance(Mux(a[0], b, 0), Value) and isinstance(Cat(a, b), Value)   # no terms


def test_the_schedule_waits_for_its_operands():
    m = Module()
    sc = Schedule(m, "t", Const(1))
    x = sc.input("x", Signal(8))                   # written at the start: ready at 1
    y = sc.let("y", x + 1)                         # at 1, ready at 2
    z = sc.let("z", Mux(y[0], x, y))               # reads y: at 2
    w = sc.let("w", Term.call(lambda v: v + 1, z)) # through a function: at 3
    assert [sc.ready[r] for r in (x, y, z, w)] == [1, 2, 3, 4]
    assert sc.reads[y] == 2 and sc.reads[z] == 3
    Fragment.get(m, None)                         # built: Amaranth sees the module used
