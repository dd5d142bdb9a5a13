"""Symbolic components: the numpy backend's closures run once on them, and every operation becomes one line
of scalar Python source.

A :class:`Tracer` stands for one float64 or bool component of one direction pair. It is an (empty) numpy array
subclass, so the numpy backend's run-time code (:mod:`..runtime`, :mod:`..builtins`,
:mod:`..compiler.components`) treats it as a per-lane value: a condition on it runs both branches under masks
and blends them with ``np.where`` — for a single lane that is exactly the branch taken, evaluated as a select.
Each ufunc applied to it is recorded by the :class:`Recorder` as ``tN = <expression>`` over generated names
(``tN``, ``pN``, the arguments ``lx``…``vz`` and ``u[k]``) and literals printed from their values with
``repr(float)``: no text of the shader ever reaches the source (the design of the "tracing JIT" of
Gal et al., PLDI 2009, without guards: a trace is only accepted when nothing in it depends on a value).

Operations the scalar source cannot express exactly (integer bit patterns taken through ``np.asarray(...,
int64)``, a decision in Python on a symbolic value, a ufunc outside :data:`UFUNCS`) raise :class:`Unsupported`
and the shader stays with the numpy backend.
"""

from __future__ import annotations

import contextlib
import math
import threading

import numpy as np

#: Longest generated function body, in lines (the examples need 15–410): Numba compiles about 300 lines a second
#: on one core of the development machine, so a bigger trace is left to numpy, which compiles in milliseconds.
MAX_LINES = 3_000
#: Values one loop carries from one iteration to the next, its counters included (the examples: 7–15). Numba's
#: compile time grows about quadratically with them (measured under load: 16 carried 1 s, 32 5 s, 64 17 s, 256 a
#: RecursionError inside Numba after a minute): an array written at a computed index in a loop costs one each.
MAX_LOOP_CARRIED = 40


class Unsupported(Exception):  # noqa: N818 - not an error: the shader stays with the numpy backend
    """The shader uses something the native backend does not express; the numpy backend evaluates it."""


_state = threading.local()


def current() -> Recorder:
    """The recorder of the trace running in this thread."""
    recorder = getattr(_state, "recorder", None)
    if recorder is None:
        raise Unsupported("a symbolic value outside a trace")
    return recorder


@contextlib.contextmanager
def recording(recorder: Recorder):
    """Run a trace into ``recorder`` (per thread)."""
    previous = getattr(_state, "recorder", None)
    _state.recorder = recorder
    try:
        yield recorder
    finally:
        _state.recorder = previous


class Recorder:
    """Lines of the generated function body, with the indentation of the loops they are in."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.depth = 1
        self.count = 0

    def name(self, prefix: str = "t") -> str:
        """A new generated identifier (``t`` for values, ``p`` for loop-carried variables)."""
        self.count += 1
        return f"{prefix}{self.count}"

    def carry(self, count: int) -> None:
        """Refuse a loop carrying more than :data:`MAX_LOOP_CARRIED` values."""
        if count > MAX_LOOP_CARRIED:
            raise Unsupported(f"a loop carries more than {MAX_LOOP_CARRIED} values")

    def emit(self, line: str) -> None:
        """Append one line at the current depth."""
        if len(self.lines) >= MAX_LINES:
            raise Unsupported(f"more than {MAX_LINES} generated lines")
        self.lines.append("    " * self.depth + line)

    def value(self, expression: str, kind: str) -> Tracer:
        """``tN = expression`` and the tracer standing for tN (kind ``"f"`` float64 or ``"b"`` bool)."""
        sym = self.name()
        self.emit(f"{sym} = {expression}")
        return Tracer.of(sym, kind)


class Tracer(np.ndarray):
    """One symbolic component: ``sym`` is its generated name, the dtype (float64 or bool) its kind."""

    sym: str | None = None

    @staticmethod
    def of(sym: str, kind: str) -> Tracer:
        """A tracer for the generated name ``sym``."""
        t = np.empty(0, dtype=bool if kind == "b" else np.float64).view(Tracer)
        t.sym = sym
        return t

    def __array_finalize__(self, obj) -> None:
        self.sym = None  # a view numpy made of a tracer is no value of ours: using it is refused

    @property
    def kind(self) -> str:
        """``"b"`` for a bool component, ``"f"`` for a float64 one."""
        return "b" if self.dtype == bool else "f"

    def __array_ufunc__(self, ufunc, method, *inputs, out=None, **kwargs):
        if method != "__call__" or kwargs or ufunc.__name__ not in UFUNCS:
            raise Unsupported(f"numpy {ufunc.__name__}.{method}")
        result = apply(ufunc.__name__, inputs)
        if out is not None:  # numpy writes into a temporary of the caller's: rebind that tracer to the result
            (target,) = out
            if not isinstance(target, Tracer) or target.kind != result.kind:
                raise Unsupported("an output buffer that is no tracer of the same kind")
            target.sym = result.sym
            return target
        return result

    def __array_function__(self, func, types, args, kwargs):
        if func is np.where and not kwargs and len(args) == 3:
            return where(*args)
        if func in (np.any, np.all) and len(args) == 1 and not kwargs:
            return func is np.any  # "some lane may, not every lane must": both branches are traced
        if func in (np.ndim, np.shape):
            return func._implementation(*args, **kwargs)
        raise Unsupported(f"numpy {getattr(func, '__name__', func)}")

    def any(self, *args, **kwargs):  # noqa: D102 - the mask helpers' question, answered as np.any above
        if args or kwargs:
            raise Unsupported("any() with arguments")
        return True

    def all(self, *args, **kwargs):  # noqa: D102
        if args or kwargs:
            raise Unsupported("all() with arguments")
        return False

    def _refuse(self, *args, **kwargs):
        raise Unsupported("a Python decision on a symbolic value")

    __bool__ = __float__ = __int__ = __index__ = __iter__ = __getitem__ = __setitem__ = __len__ = _refuse
    __reduce__ = __copy__ = __deepcopy__ = astype = tolist = item = _refuse


def literal(value) -> str:
    """A constant component as source: ``True``/``False`` or a float printed from its value."""
    if isinstance(value, bool | np.bool_):
        return "True" if value else "False"
    x = float(value)
    if math.isnan(x):
        return "NAN"
    if math.isinf(x):
        return "INF" if x > 0 else "(-INF)"
    text = repr(x)
    return f"({text})" if x < 0 or text.startswith("-") else text


def operand(value, kind: str) -> str:
    """``value`` (a tracer or a constant) as source of ``kind``, converting bool ↔ float as numpy would."""
    if isinstance(value, Tracer):
        if value.sym is None:
            raise Unsupported("a numpy view of a symbolic value")
        if value.kind == kind:
            return value.sym
        return f"float({value.sym})" if kind == "f" else f"({value.sym} != 0.0)"
    if isinstance(value, np.ndarray):
        if value.ndim:
            raise Unsupported("a numpy array computed from a symbolic value")
        value = value[()]
    if not isinstance(value, bool | int | float | np.bool_ | np.integer | np.floating):
        raise Unsupported(f"a constant of type {type(value).__name__}")
    if kind == "b":
        return literal(bool(value))
    return literal(float(value))


def _kind(value) -> str:
    if isinstance(value, Tracer):
        return value.kind
    return "b" if isinstance(value, bool | np.bool_) or (isinstance(value, np.ndarray) and value.dtype == bool) else "f"


_FLOAT_CALLS = (
    "sqrt exp exp2 log log2 sin cos tan arcsin arccos arctan sinh cosh tanh arcsinh arccosh arctanh "
    "floor ceil trunc rint sign"
).split()
#: numpy ufunc name -> (result kind, operand kind or None when the operands' kinds decide, source template).
UFUNCS: dict[str, tuple[str, str | None, str]] = {
    "add": ("f", "f", "({0} + {1})"),
    "subtract": ("f", "f", "({0} - {1})"),
    "multiply": ("f", "f", "({0} * {1})"),
    "true_divide": ("f", "f", "({0} / {1})"),
    "divide": ("f", "f", "({0} / {1})"),
    "negative": ("f", "f", "(-{0})"),
    "positive": ("f", "f", "(+{0})"),
    "absolute": ("f", "f", "abs({0})"),
    **{name: ("f", "f", f"np.{name}({{0}})") for name in _FLOAT_CALLS},
    **{name: ("f", "f", f"np.{name}({{0}}, {{1}})") for name in ("fmin", "fmax", "remainder", "arctan2", "power")},
    "isnan": ("b", "f", "np.isnan({0})"),
    "isinf": ("b", "f", "np.isinf({0})"),
    "isfinite": ("b", "f", "np.isfinite({0})"),
    "less": ("b", "f", "({0} < {1})"),
    "less_equal": ("b", "f", "({0} <= {1})"),
    "greater": ("b", "f", "({0} > {1})"),
    "greater_equal": ("b", "f", "({0} >= {1})"),
    "equal": ("b", None, "({0} == {1})"),
    "not_equal": ("b", None, "({0} != {1})"),
    "logical_and": ("b", "b", "({0} and {1})"),
    "logical_or": ("b", "b", "({0} or {1})"),
    "logical_xor": ("b", "b", "({0} != {1})"),
    "logical_not": ("b", "b", "(not {0})"),
    "bitwise_and": ("b", "b", "({0} and {1})"),
    "bitwise_or": ("b", "b", "({0} or {1})"),
    "bitwise_xor": ("b", "b", "({0} != {1})"),
    "invert": ("b", "b", "(not {0})"),
}
_BITWISE = ("bitwise_and", "bitwise_or", "bitwise_xor", "invert")


#: Constant integer exponents computed by multiplications (square and multiply: at most 7 roundings, a relative
#: difference under 1e-15 from the C library's pow, which numpy's vectorized pow itself differs from by an ulp).
#: A scalar pow costs 15–35 ns, the products of x^5 (Schlick's Fresnel) 2 ns.
POWER_BY_PRODUCTS = range(3, 17)


def _power_by_products(base: Tracer, exponent: int) -> Tracer:
    rec, result, square = current(), None, base
    while exponent:
        if exponent & 1:
            result = square if result is None else rec.value(f"({result.sym} * {square.sym})", "f")
        exponent >>= 1
        if exponent:
            square = rec.value(f"({square.sym} * {square.sym})", "f")
    return result


def apply(name: str, inputs: tuple) -> Tracer:
    """Record the ufunc ``name`` on ``inputs`` (tracers and constants) and return its result."""
    if name == "power" and isinstance(inputs[0], Tracer) and inputs[0].kind == "f" and inputs[0].sym is not None:
        exponent = inputs[1]
        if not isinstance(exponent, np.ndarray | bool | np.bool_) and isinstance(exponent, int | float | np.number):
            if float(exponent) in POWER_BY_PRODUCTS:
                return _power_by_products(inputs[0], int(exponent))
    kind, operand_kind, template = UFUNCS[name]
    kinds = [_kind(x) for x in inputs]
    if name in _BITWISE and "f" in kinds:
        raise Unsupported("a bitwise operation on numbers")  # integer bit patterns: numpy's int64 route
    if operand_kind == "f" and kind == "f" and all(k == "b" for k in kinds):
        raise Unsupported(f"{name} on bools")  # numpy would give a bool (logical) result
    if operand_kind is None:
        operand_kind = "b" if all(k == "b" for k in kinds) else "f"
    return current().value(template.format(*(operand(x, operand_kind) for x in inputs)), kind)


def where(cond, yes, no):
    """``np.where`` on one lane: a conditional expression (a new value, as numpy returns a new array)."""
    kind = "b" if _kind(yes) == "b" and _kind(no) == "b" else "f"
    if not isinstance(cond, Tracer):
        chosen = yes if operand(cond, "b") == "True" else no
        if isinstance(chosen, Tracer):
            return current().value(operand(chosen, kind), kind)
        return np.bool_(chosen) if kind == "b" else np.float64(chosen)
    text = f"({operand(yes, kind)} if {operand(cond, 'b')} else {operand(no, kind)})"
    return current().value(text, kind)
