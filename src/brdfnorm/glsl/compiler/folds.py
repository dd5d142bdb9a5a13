"""Mesa's constant folds: results its optimizer fixes from compile-time constants, imitated here.

Measured on llvmpipe (Mesa 22.3), these change results the specification leaves undefined: ``x * 0.0``,
``0.0 * x`` and ``0.0 / x`` are 0 for every x (inf and NaN included) when that side is a constant 0 (NIR's
inexact algebraic rules; ``x / y`` becomes ``x * rcp(y)``); ``mod(x, 0.0) = x`` and ``mix(x, y, 0.0) = x``;
a constant exponent or base steers ``pow`` (:func:`..builtins.pow_impl`). Constant propagation treats a
variable initialized with a constant and never written anywhere as a constant, as Mesa's SSA form does
(:func:`written_names`). Not imitated: folds that need value numbering (``x - x`` → 0 for a non-constant x).
"""

from __future__ import annotations

from collections.abc import Callable

from .. import builtins
from ..types import Type
from .values import Expr, Node


def constant_zeros(op: str, left: Expr, right: Expr, t: Type) -> list[bool]:
    """Components Mesa's optimizer folds to 0 whatever the other operand (inf and NaN included).

    Measured on llvmpipe: ``x * 0.0``, ``0.0 * x`` and ``0.0 / x`` are 0 for every x (NIR's inexact
    algebraic rules; ``x / y`` becomes ``x * rcp(y)``). ``x / 0.0`` is left to IEEE arithmetic: llvmpipe
    writes no result at all for it. Both operands constant: folded as usual.
    """
    zero = [False] * t.size
    if left.const is not None and right.const is not None:
        return zero
    for e in (left, right) if op == "*" else (left,):
        if e.const is not None:
            for i in range(t.size):
                if e.const[0 if len(e.const) == 1 else i] == 0:
                    zero[i] = True
    return zero


def constant_overrides(name: str, args: list[Expr]) -> dict[int, int]:
    """Result components that Mesa's optimizer fixes from constant arguments (measured on llvmpipe).

    Returns component index -> argument index whose component is the result: ``mod(x, 0.0) = x`` and
    ``mix(x, y, 0.0) = x`` (products with a constant 0 are folded to 0, whatever the other factor).
    """
    if name not in ("mod", "mix") or not all(a.type.is_numeric for a in args):
        return {}
    if all(a.const is not None for a in args):
        return {}  # a call with constant arguments only is folded with IEEE arithmetic (measured)

    def const(k: int, i: int):
        c = args[k].const
        return None if c is None else c[0 if len(c) == 1 else i]

    size = max(a.type.size for a in args)
    out: dict[int, int] = {}
    for i in range(size):
        if name == "mod" and const(1, i) == 0:
            out[i] = 0
        elif name == "mix" and const(2, i) == 0:
            out[i] = 0
    return out


def with_overrides(impl: Callable, overrides: dict[int, int]) -> Callable:
    """``impl`` with the components of :func:`constant_overrides` taken from the named arguments."""

    def fn(*values):
        out = list(impl(*values))
        for i, k in overrides.items():
            out[i] = values[k][i if len(values[k]) > 1 else 0]
        return tuple(out)

    return fn


def pow_with_constants(x: Expr, y: Expr, size: int) -> Callable | None:
    """``pow`` per component with Mesa's rewrites for constant bases/exponents, or None when none applies."""
    fns = [
        builtins.pow_impl(
            None if x.const is None else x.const[i if len(x.const) > 1 else 0],
            None if y.const is None else y.const[i if len(y.const) > 1 else 0],
        )
        for i in range(size)
    ]
    if all(fn is builtins.pow_runtime for fn in fns):
        return None

    def impl(a, b):
        return tuple(fn(a[i], b[i]) for i, fn in enumerate(fns))

    return impl


def written_names(root: Node, text: Callable[[Node], str]) -> set[str]:
    """Names of every variable the translation unit may write (assignments, ++/--, call arguments).

    Used to treat variables initialized with a constant and never written as constants, as Mesa's
    SSA-based constant propagation does (which matters for pow's constant-exponent rewrites).
    """
    names: set[str] = set()
    # Only calls of user functions (out/inout parameters) and of modf can write their arguments.
    writers = {"modf"}
    stack = [root]
    while stack:
        node = stack.pop()
        if node.type == "function_declarator":
            writers.add(text(node.child_by_field_name("declarator")))
        stack.extend(node.children)

    def root_name(node: Node) -> None:
        while node.type in ("field_expression", "subscript_expression", "parenthesized_expression"):
            node = node.named_children[0]
        if node.type == "identifier":
            names.add(text(node))

    stack = [root]
    while stack:
        node = stack.pop()
        if node.type == "assignment_expression":
            root_name(node.child_by_field_name("left"))
        elif node.type == "update_expression":
            root_name(node.child_by_field_name("argument"))
        elif node.type == "call_expression" and text(node.child_by_field_name("function")) in writers:
            args = node.child_by_field_name("arguments")
            for arg in args.named_children if args is not None else ():
                root_name(arg)
        stack.extend(node.children)
    return names
