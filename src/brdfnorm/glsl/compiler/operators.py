"""Operators (GLSL 4.10 §5.9): unary, arithmetic, bitwise, relational, equality, logical and ``^^``.

Arithmetic on float operands reuses a temporary operand's arrays as the output where it can; integer
results wrap to 32 bits (:func:`.components.wrap`); Mesa's folds of products with a constant 0 are applied
(:func:`.folds.constant_zeros`).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..runtime import is_uniform, mask_and, mask_and_not
from ..types import BOOL, Type, converts
from .base import CompilerBase
from .components import ARITH, BITWISE, COMPARE, INT_ARITH, UFUNCS, in_place, integer_op, sum_terms, wrap
from .folds import constant_zeros
from .values import ZERO, Expr, Node


class OperatorsMixin(CompilerBase):
    """Compiles operator expressions."""

    def expr_unary(self, node: Node) -> Expr:
        """``-x``, ``+x``, ``!b``, ``~i``."""
        op = self.text(node.child_by_field_name("operator"))
        return self.apply_unary(op, self.expr(node.child_by_field_name("argument")), node)

    def apply_unary(self, op: str, e: Expr, node: Node) -> Expr:
        """A unary operator applied to a compiled operand (also for signs folded into literals)."""
        t = e.type
        if op == "!":
            if t != BOOL:
                raise self.error(f"'!' needs a bool, not {t}", node)
            return self.make(BOOL, lambda a: (np.logical_not(a[0]),), [e])
        if op in ("-", "+"):
            if not (t.is_numeric or (t.base == "float" and t.is_matrix)) or t.is_array:
                raise self.error(f"unary '{op}' needs a number, vector or matrix, not {t}", node)
            if op == "+":
                return e
            if t.is_integer:  # -INT_MIN is INT_MIN, -1u is 4294967295 (32-bit wrap-around)
                base = t.base
                return self.make(t, lambda a: tuple(wrap(-x, base) for x in a), [e])
            return self.make(t, lambda a: tuple(-x for x in a), [e], fresh=True)
        if op == "~":
            if not t.is_integer:
                raise self.error(f"'~' needs an integer, not {t}", node)
            base, xor = t.base, self.integer_function("^")
            return self.make(t, lambda a: tuple(wrap(xor(x, -1.0), base) for x in a), [e])
        raise self.error(f"unsupported operator '{op}'", node)

    def binary_types(self, op: str, a: Type, b: Type, node: Node) -> tuple[Type, Callable]:
        """Result type and component function of an arithmetic operator (§5.9)."""
        def bad() -> Exception:  # built only when raised: this runs for every binary operator compiled
            return self.error(f"operator '{op}' cannot be applied to {a} and {b}", node)

        if a.is_array or b.is_array or a.base in ("bool", "void") or b.base in ("bool", "void"):
            raise bad()
        integer = a.is_integer and b.is_integer
        base = ("uint" if "uint" in (a.base, b.base) else "int") if integer else "float"
        if op == "%" and not integer:
            raise self.error("operator '%' needs integers (use mod() for floats)", node)
        if op in BITWISE and not integer:
            raise self.error(f"operator '{op}' needs integers", node)
        fn = integer_op(self.integer_function(op), base) if integer else ARITH[op]
        if op == "*" and (a.is_matrix or b.is_matrix) and not (a.is_scalar or b.is_scalar):
            return self.linear_algebra(a, b, bad)
        if op in ("<<", ">>"):
            if not (b.is_scalar or b.rows == a.rows):
                raise bad()
            if b.is_scalar:
                return a.with_base(base), lambda x, y: tuple(fn(p, y[0]) for p in x)
            return a.with_base(base), lambda x, y: tuple(map(fn, x, y))
        if a.is_scalar and not b.is_scalar:
            return b.with_base(base), lambda x, y: tuple(fn(x[0], q) for q in y)
        if b.is_scalar and not a.is_scalar:
            return a.with_base(base), lambda x, y: tuple(fn(p, y[0]) for p in x)
        if a.rows != b.rows or a.cols != b.cols:
            raise bad()
        if a.is_scalar:
            return a.with_base(base), lambda x, y: (fn(x[0], y[0]),)
        return a.with_base(base), lambda x, y: tuple(map(fn, x, y))

    def integer_function(self, op: str) -> Callable:
        """The component function of an integer operator, before the 32-bit wrap (the native backend traces
        the bit operations its own way)."""
        return (BITWISE if op in BITWISE else INT_ARITH)[op]

    def linear_algebra(self, a: Type, b: Type, bad: Callable[[], Exception]) -> tuple[Type, Callable]:
        """Matrix × matrix, matrix × column vector and row vector × matrix products (§5.10)."""
        if a.is_matrix and b.is_matrix:
            if a.cols != b.rows:
                raise bad()
            n, m, k = a.rows, b.cols, a.cols

            def matmul(x, y):
                return tuple(
                    sum_terms(x[p * n + i] * y[j * k + p] for p in range(k)) for j in range(m) for i in range(n)
                )

            return Type("float", n, m), matmul
        if a.is_matrix:  # mat * column vector
            if b.rows != a.cols or b.cols != 1:
                raise bad()
            n, k = a.rows, a.cols
            return Type("float", n), lambda x, y: tuple(
                sum_terms(x[p * n + i] * y[p] for p in range(k)) for i in range(n)
            )
        if a.rows != b.rows or a.cols != 1:  # row vector * mat
            raise bad()
        n, m = b.rows, b.cols
        return Type("float", m), lambda x, y: tuple(sum_terms(x[i] * y[j * n + i] for i in range(n)) for j in range(m))

    def arithmetic(self, op: str, left: Expr, right: Expr, node: Node) -> Expr:
        """``left op right`` for an arithmetic or bitwise ``op`` (also the compound assignments)."""
        t, fn = self.binary_types(op, left.type, right.type, node)
        componentwise = not (op == "*" and (left.type.is_matrix or right.type.is_matrix))
        if t.base == "float" and componentwise and op in UFUNCS:
            # Reuse a temporary operand (not broadcast over the other's components) as the output.
            if left.fresh and left.type.size == t.size:
                fn = in_place(UFUNCS[op], 0)
            elif right.fresh and right.type.size == t.size:
                fn = in_place(UFUNCS[op], 1)
        if op in ("*", "/") and t.base == "float" and not t.is_matrix and componentwise:
            zero = constant_zeros(op, left, right, t)
            if all(zero) and not (left.effects or right.effects):
                const = (ZERO,) * t.size
                return Expr(t, lambda f: const, const)
            if any(zero):
                inner = fn
                fn = lambda x, y: tuple(ZERO if z else v for z, v in zip(zero, inner(x, y), strict=True))  # noqa: E731
        return self.make(t, fn, [left, right], fresh=t.base == "float")

    def expr_binary(self, node: Node) -> Expr:
        """A binary operator; ``||`` chains holding a rewritten ``^^`` are regrouped first."""
        op_node = node.child_by_field_name("operator")
        op = self.text(op_node)
        if op == "||" and self.has_xor(node):
            return self.or_xor_chain(node)
        if op in ("&&", "||"):
            return self.logical(op, node.child_by_field_name("left"), node.child_by_field_name("right"), node)
        left = self.expr(node.child_by_field_name("left"))
        right = self.expr(node.child_by_field_name("right"))
        if op in ARITH or op in BITWISE or op == "%":
            return self.arithmetic(op, left, right, node)
        if op in COMPARE:
            a, b = left.type, right.type
            if not (a.is_scalar and b.is_scalar and a.is_numeric and b.is_numeric):
                raise self.error(f"operator '{op}' needs scalar numbers, not {a} and {b} (use lessThan etc.)", node)
            fn = COMPARE[op]
            return self.make(BOOL, lambda x, y: (fn(x[0], y[0]),), [left, right])
        if op in ("==", "!="):
            return self.equality(op, left, right, node)
        raise self.error(f"unsupported operator '{op}'", node)

    def equality(self, op: str, left: Expr, right: Expr, node: Node) -> Expr:
        """``==`` and ``!=``: all components equal (after an implicit conversion)."""
        a, b = left.type, right.type
        if converts(a, b):
            left = self.convert(left, b, node)
        elif converts(b, a):
            right = self.convert(right, a, node)
        else:
            raise self.error(f"cannot compare {a} and {b}", node)

        def eq(x, y):
            out = x[0] == y[0]
            for p, q in zip(x[1:], y[1:], strict=False):
                out = np.logical_and(out, p == q)
            return (out if op == "==" else np.logical_not(out),)

        return self.make(BOOL, eq, [left, right])

    def logical(self, op: str, left_node: Node, right_node: Node, node: Node) -> Expr:
        """``&&`` and ``||`` on bools."""
        left, right = self.expr(left_node), self.expr(right_node)
        for e, n in ((left, left_node), (right, right_node)):
            if e.type != BOOL:
                raise self.error(f"operator '{op}' needs bools, not {e.type}", n)
        return self.short_circuit(op, left, right)

    @staticmethod
    def short_circuit(op: str, left: Expr, right: Expr) -> Expr:
        """``&&`` / ``||``: the right side runs only in the lanes where the left does not decide."""
        conj = op == "&&"
        if left.const is not None and right.const is not None:
            value = (
                bool(left.const[0]) and bool(right.const[0]) if conj else bool(left.const[0]) or bool(right.const[0]),
            )
            return Expr(BOOL, lambda f: value, value)
        a, b, masked = left.ev, right.ev, right.effects
        combine = np.logical_and if conj else np.logical_or

        def run(f):
            x = a(f)[0]
            if is_uniform(x):
                if bool(x) == conj:
                    return b(f)
                return (x,)
            if not masked:
                return (combine(x, b(f)[0]),)
            saved = f.mask
            f.mask = mask_and(saved, x) if conj else mask_and_not(saved, x)
            y = b(f)[0] if f.mask is not False else conj
            f.mask = saved
            return (combine(x, y),)

        return Expr(BOOL, run, effects=left.effects or right.effects)

    def has_xor(self, node: Node) -> bool:
        """Whether an ``||`` chain holds an ``^^`` rewritten by the parser."""
        while node.type == "binary_expression" and self.text(node.child_by_field_name("operator")) == "||":
            if node.child_by_field_name("operator").start_byte in self.source.xor_offsets:
                return True
            node = node.child_by_field_name("left")
        return False

    def or_xor_chain(self, node: Node) -> Expr:
        """An ``||`` chain regrouped so that ``^^`` binds tighter than ``||``."""
        # The text had '^^' rewritten to '||' (see parser): regroup the left-associated chain so that
        # '^^' binds tighter than '||' (GLSL 4.10 §5.1).
        operands, xor = [], []
        while node.type == "binary_expression" and self.text(node.child_by_field_name("operator")) == "||":
            operands.append(node.child_by_field_name("right"))
            xor.append(node.child_by_field_name("operator").start_byte in self.source.xor_offsets)
            node = node.child_by_field_name("left")
        operands.append(node)
        operands.reverse()
        xor.reverse()
        groups = [[operands[0]]]
        for is_xor, operand in zip(xor, operands[1:], strict=False):
            if is_xor:
                groups[-1].append(operand)
            else:
                groups.append([operand])
        exprs = []
        for group in groups:
            e = self.expr(group[0])
            for n in group[1:]:
                e2 = self.expr(n)
                for x, xn in ((e, group[0]), (e2, n)):
                    if x.type != BOOL:
                        raise self.error(f"operator '^^' needs bools, not {x.type}", xn)
                e = self.make(BOOL, lambda x, y: (np.logical_xor(x[0], y[0]),), [e, e2])
            exprs.append(e)
        result = exprs[0]
        for e in exprs[1:]:
            if result.type != BOOL or e.type != BOOL:
                raise self.error("operator '||' needs bools", node)
            result = self.short_circuit("||", result, e)
        return result
