"""A schedule's record of its operands (``hdl.sched``): a :class:`Term` is an Amaranth value
built from the schedule's registers, with the tree it was built from kept beside it.

A schedule places each operation at the first offset where every register it reads is
ready, and reads a register late from a copy (``Schedule.late``); so it must see which
registers a value reads, and rebuild the value with some of them replaced. Amaranth's public
API gives neither (a value's signals and its transformers are private), so the schedule's
registers are terms and every operation on a term gives a term: ``leaves`` are the registers
read, ``map(sub)`` rebuilds the term with each register replaced by ``sub(register)``, and
``wiring`` says that the value is registers and constants sliced, concatenated, cast or
shifted by constants, with no logic (an operand multiplexer's inputs must be).

A term is ``ValueCastable``, so it goes wherever a value does; an Amaranth function given a
term gives a plain value, whose registers the schedule cannot see: inside a schedule's
program use :func:`Mux`, :func:`Cat` and :meth:`Term.call` instead (they give terms).
"""
import operator

from amaranth.hdl import Cat as _Cat, Const, Mux as _Mux, Signal, Value, ValueCastable

__all__ = ["Term", "Mux", "Cat", "term"]


class Term(ValueCastable):
    """``fn(*args)`` lowered, its arguments terms or Python values; or a register (``reg``)."""

    def __init__(self, fn=None, args=(), wiring=False, reg=None):
        self._fn, self._reg = fn, reg
        self._args = tuple(Term.leaf(a) if isinstance(a, Signal) else a for a in args)
        self.wiring = wiring
        self._value = None

    @classmethod
    def leaf(cls, reg):
        return cls(reg=reg, wiring=True)

    @classmethod
    def call(cls, fn, *args, wiring=False):
        """``fn(*args)`` as a term (``fn`` on values, such as ``arith.leading_one``)."""
        return cls(fn, args, wiring and all(_wiring(a) for a in args))

    @property
    def reg(self):
        """The register a leaf is, else None."""
        return self._reg

    def map(self, sub):
        """The same term, each register ``r`` replaced by the term ``sub(r)``."""
        if self._reg is not None:
            return sub(self._reg)
        return Term(self._fn, (a.map(sub) if isinstance(a, Term) else a for a in self._args),
                    self.wiring)

    def leaves(self):
        """The registers it reads, each once, in the order met."""
        seen, out, stack = set(), [], [self]
        while stack:
            t = stack.pop()
            if t._reg is not None:
                if id(t._reg) not in seen:
                    seen.add(id(t._reg))
                    out.append(t._reg)
                continue
            stack.extend(reversed([a for a in t._args if isinstance(a, Term)]))
        return out

    def as_value(self):
        if self._value is None:
            self._value = (self._reg if self._reg is not None else
                           Value.cast(self._fn(*(a.as_value() if isinstance(a, Term) else a
                                                  for a in self._args))))
        return self._value

    def shape(self):
        return self.as_value().shape()

    def __len__(self):
        return len(self.as_value())

    def __bool__(self):
        raise TypeError("a term has no truth value; use .bool() or .any()")

    def __repr__(self):
        return f"(term {self.as_value()!r})"

    def eq(self, value):
        return self.as_value().eq(value)

    # slices, casts and shifts by constants are wiring; everything else is logic
    def __getitem__(self, key):
        return Term(operator.getitem, (self, key), self.wiring)

    def as_signed(self):
        return Term(Value.as_signed, (self,), self.wiring)

    def as_unsigned(self):
        return Term(Value.as_unsigned, (self,), self.wiring)

    def __lshift__(self, other):
        return Term(operator.lshift, (self, other), self.wiring and isinstance(other, int))

    def __rshift__(self, other):
        return Term(operator.rshift, (self, other), self.wiring and isinstance(other, int))


def _binary(fn):
    return (lambda self, other: Term(fn, (self, other)),
            lambda self, other: Term(lambda a, b: fn(b, a), (self, other)))


for _name, _fn in (("add", operator.add), ("sub", operator.sub), ("mul", operator.mul),
                   ("and", operator.and_), ("or", operator.or_), ("xor", operator.xor)):
    _l, _r = _binary(_fn)
    setattr(Term, f"__{_name}__", _l)
    setattr(Term, f"__r{_name}__", _r)
for _name, _fn in (("eq", operator.eq), ("ne", operator.ne), ("lt", operator.lt),
                   ("le", operator.le), ("gt", operator.gt), ("ge", operator.ge)):
    setattr(Term, f"__{_name}__", _binary(_fn)[0])
for _name, _fn in (("neg", operator.neg), ("invert", operator.invert), ("abs", abs)):
    setattr(Term, f"__{_name}__", lambda self, fn=_fn: Term(fn, (self,)))
for _name in ("any", "all", "bool"):
    setattr(Term, _name, lambda self, name=_name: Term(getattr(Value, name), (self,)))
Term.__hash__ = None          # == builds a term, as it builds a value


def _wiring(x):
    if isinstance(x, Term):
        return x.wiring
    return isinstance(x, (int, Const, Signal))


def term(x):
    """``x`` as a term: itself, a signal as a leaf (a register of no schedule is ready at
    offset 0), any other value or constant opaque (it reads no register the schedule sees)."""
    if isinstance(x, Term):
        return x
    if isinstance(x, Signal):
        return Term.leaf(x)
    return Term(lambda: x, (), isinstance(x, (int, Const)))


def Mux(sel, val1, val0):
    """Amaranth's ``Mux``; a term if any operand is one."""
    if any(isinstance(x, Term) for x in (sel, val1, val0)):
        return Term(_Mux, (sel, val1, val0))
    return _Mux(sel, val1, val0)


def Cat(*parts):
    """Amaranth's ``Cat``; a term if any part is one (wiring if every part is)."""
    if len(parts) == 1 and not isinstance(parts[0], (Term, Value, int)):
        parts = tuple(parts[0])
    if any(isinstance(x, Term) for x in parts):
        return Term(_Cat, parts, all(_wiring(x) for x in parts))
    return _Cat(*parts)
