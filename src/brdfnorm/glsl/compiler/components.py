"""Component arithmetic at run time: conversions, integer operators and the operator tables.

Integers are held as float64 holding integral values (see :mod:`..types`); conversions follow GLSL 4.10
§5.4.1 with x86's results for out-of-range floats, ``/`` and ``%`` follow Mesa llvmpipe (measured), and the
bitwise operators work on the 32-bit two's complement pattern.
"""

from __future__ import annotations

import operator
from collections.abc import Callable

import numpy as np

from .. import builtins

INT_MIN = -(2.0**31)


def to_int(x):
    """float → int conversion: truncation; NaN, ±inf and out-of-range give INT_MIN as on x86."""
    t = np.trunc(x)
    return np.where(np.abs(t) < 2.0**31, t, INT_MIN) if np.ndim(t) else (t if abs(t) < 2.0**31 else INT_MIN)


def convert_component(x, src: str, dst: str):
    """Constructor conversion of one component between scalar base types (§5.4.1)."""
    if src == dst:
        return x
    if dst == "bool":
        return x != 0
    if src == "bool":
        return np.where(x, 1.0, 0.0)
    if dst == "float":
        return x
    if dst == "int":
        value = to_int(x) if src == "float" else x
        return np.where(value >= 2.0**31, value - 2.0**32, value) if src == "uint" else value
    value = to_int(x) if src == "float" else x  # to uint: two's complement wrap of negative values
    return np.where(value < 0, value + 2.0**32, value)


def int_div(a, b):
    """Integer ``/``: truncation toward zero; ``x / 0`` is 0 (Mesa llvmpipe, measured)."""
    with np.errstate(all="ignore"):
        q = np.trunc(np.true_divide(a, b))
    return np.where(b == 0, 0.0, q)


def int_mod(a, b):
    """Integer ``%`` as Mesa evaluates it: an unsigned 32-bit remainder, ``x % 0`` all bits set."""
    ua = np.mod(np.asarray(a, dtype=np.int64), 2**32)
    ub = np.mod(np.asarray(b, dtype=np.int64), 2**32)
    r = np.where(ub == 0, 2**32 - 1, ua % np.maximum(ub, 1))
    return (np.where(r >= 2**31, r - 2**32, r)).astype(np.float64)


def bitwise(op):
    """A bitwise operator on the 32-bit two's complement patterns of two integers."""
    def fn(a, b):
        r = op(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)) & 0xFFFFFFFF
        return np.where(r >= 2**31, r - 2**32, r).astype(np.float64)

    return fn


def shift(left: bool):
    """``<<`` or ``>>`` (arithmetic for negative ints) by the low 5 bits of the count."""
    def fn(a, b):
        x = np.asarray(a, dtype=np.int64) & 0xFFFFFFFF
        s = np.asarray(b, dtype=np.int64) & 31
        r = (x << s if left else np.where(x >= 2**31, x - 2**32, x) >> s) & 0xFFFFFFFF
        return np.where(r >= 2**31, r - 2**32, r).astype(np.float64)

    return fn


UFUNCS = {"+": np.add, "-": np.subtract, "*": np.multiply, "/": np.true_divide}


def in_place(ufunc: np.ufunc, side: int) -> Callable:
    """Componentwise ``ufunc`` writing into operand ``side``'s arrays (temporaries) where shapes allow."""

    def fn(x, y):
        out = []
        for p, q in zip(x if len(x) > 1 else x * len(y), y if len(y) > 1 else y * len(x), strict=True):
            buffer, other = (p, q) if side == 0 else (q, p)
            if builtins.in_place_ok(buffer, other):
                out.append(ufunc(p, q, out=buffer))
            else:
                out.append(ufunc(p, q))
        return tuple(out)

    return fn


# numpy's divide, not Python's: IEEE results (inf, NaN) for constant operands too, never ZeroDivisionError.
ARITH = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": np.true_divide}


def _int_mul(a, b):
    """The low 32 bits of a·b, exactly: 16-bit halves keep every partial product below 2**53."""
    ua, ub = np.mod(a, 2.0**32), np.mod(b, 2.0**32)
    a_high, a_low = np.floor(ua / 65536.0), np.mod(ua, 65536.0)
    b_high, b_low = np.floor(ub / 65536.0), np.mod(ub, 65536.0)
    return a_low * b_low + np.mod(a_high * b_low + a_low * b_high, 65536.0) * 65536.0


INT_ARITH = {"+": operator.add, "-": operator.sub, "*": _int_mul, "/": int_div, "%": int_mod}
BITWISE = {
    "&": bitwise(operator.and_),
    "|": bitwise(operator.or_),
    "^": bitwise(operator.xor),
    "<<": shift(True),
    ">>": shift(False),
}
COMPARE = {"<": operator.lt, ">": operator.gt, "<=": operator.le, ">=": operator.ge}


def sum_terms(terms):
    """The sum of ``terms`` in order (a dot product of components for the matrix products)."""
    it = iter(terms)
    total = next(it)
    for x in it:
        total = total + x
    return total


def wrap(x, base: str):
    """An int (two's complement) or uint value reduced to 32 bits, as GLSL's integer arithmetic wraps
    (GLSL 4.10 §4.1.3: ``-1u`` is 4294967295, ``2147483647 + 1`` is -2147483648)."""
    if base == "uint":
        return np.mod(x, 2.0**32)
    return np.mod(x + 2.0**31, 2.0**32) - 2.0**31


def integer_op(fn: Callable, base: str) -> Callable:
    """An integer operator on 32-bit values of ``base``: uint operands (an int converted implicitly included)
    are taken modulo 2**32, and the result wraps to 32 bits."""
    if base == "uint":
        return lambda a, b: wrap(fn(wrap(a, base), wrap(b, base)), base)
    return lambda a, b: wrap(fn(a, b), base)
