"""Assignable expressions (GLSL 4.10 §5.8): variables, swizzles and subscripts of them; ``=``, the
compound assignments and ``++``/``--``.

An :class:`LValue` is a variable and a :class:`ComponentPath` into its flat components; a subscript whose
index differs between lanes gives a per-lane choice of components, and stores under the active lanes'
mask blend the new components into the old ones.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ..runtime import Frame, is_uniform, mask_and
from ..types import Type
from .base import CompilerBase
from .components import wrap
from .values import Expr, Node, Var, zeros

#: Assignable node type -> method; anything else is not assignable.
LVALUE_RULES = {
    "parenthesized_expression": "lvalue_parenthesized",
    "identifier": "lvalue_identifier",
    "field_expression": "lvalue_field",
    "subscript_expression": "lvalue_subscript",
}


class ComponentPath:
    """Where an lvalue sits in its variable's flat components: static indices, or a per-lane choice."""

    def __init__(self, static: tuple[int, ...] | None = None, resolve=None) -> None:
        self.static = static
        self.resolve = resolve  # frame -> list of (lane condition or None, indices)

    def options(self, f: Frame) -> list[tuple[object, tuple[int, ...]]]:
        """(lane condition or None for all lanes, component indices) pairs for the current frame."""
        return [(None, self.static)] if self.static is not None else self.resolve(f)

    def map(self, pick: Callable[[tuple[int, ...]], tuple[int, ...]]) -> ComponentPath:
        """The path to a part (``pick`` selects among this path's indices)."""
        if self.static is not None:
            return ComponentPath(pick(self.static))
        inner = self.resolve
        return ComponentPath(resolve=lambda f: [(c, pick(idx)) for c, idx in inner(f)])


class LValue:
    """An assignable location: a variable and a path into its components."""

    def __init__(self, var: Var, type_: Type, path: ComponentPath) -> None:
        self.var = var
        self.type = type_
        self.path = path
        slot = var.slot
        if var.is_global:
            self.load = lambda f: f.globals[slot]

            def store(f, value):
                f.globals[slot] = value
        else:
            self.load = lambda f: f.slots[slot]

            def store(f, value):
                f.slots[slot] = value

        self.store = store

    def get(self, f: Frame) -> tuple:
        """The current components (0 where a per-lane index is out of range, as when reading ``a[i]``)."""
        root = self.load(f)
        if self.path.static is not None:
            return tuple(root[i] for i in self.path.static)
        out = zeros(self.type)
        for cond, idx in self.path.resolve(f):
            value = tuple(root[i] for i in idx)
            out = value if cond is None else tuple(map(np.where, [cond] * len(value), value, out))
        return out

    def set(self, f: Frame, value: tuple) -> None:
        """Store ``value`` in the active lanes."""
        root = self.load(f)
        static = self.path.static
        if static is not None and len(static) == len(root) and f.mask is None:
            self.store(f, value)
            return
        new = list(root)
        for cond, idx in self.path.options(f):
            mask = f.mask if cond is None else mask_and(f.mask, cond)
            if mask is False:
                continue
            for k, i in enumerate(idx):
                new[i] = value[k] if mask is None else np.where(mask, value[k], new[i])
        self.store(f, tuple(new))


class LValuesMixin(CompilerBase):
    """Compiles assignments and the expressions they assign to."""

    def lvalue(self, node: Node) -> LValue:
        """The location an assignable expression names."""
        return self.dispatch(LVALUE_RULES, node, lambda n: self.error("expression is not assignable", n))

    def lvalue_parenthesized(self, node: Node) -> LValue:
        """``(x) = ...``."""
        return self.lvalue(node.named_children[0])

    def lvalue_identifier(self, node: Node) -> LValue:
        """A variable, unless read-only (const, uniform, const parameter) or a macro."""
        name = self.text(node)
        var = self.lookup(name)
        if var is None:
            if name in self.macros:
                raise self.error(f"cannot assign to macro '{name}'", node)
            raise self.error(f"unknown identifier '{name}'", node)
        if var.readonly:
            raise self.error(f"cannot assign to {var.readonly} '{name}'", node)
        if var.param_index is not None and self.function is not None:
            self.function.used_params.add(var.param_index)
        return LValue(var, var.type, ComponentPath(tuple(range(var.type.size))))

    def lvalue_field(self, node: Node) -> LValue:
        """A swizzle without repeated components (``v.xz = ...``)."""
        base = self.lvalue(node.child_by_field_name("argument"))
        picks = self.swizzle(base.type, node.child_by_field_name("field"))
        if len(set(picks)) != len(picks):
            raise self.error("cannot assign to a swizzle that repeats a component", node)
        return LValue(
            base.var,
            Type(base.type.base, len(picks)) if len(picks) > 1 else Type(base.type.base),
            base.path.map(lambda idx: tuple(idx[p] for p in picks)),
        )

    def lvalue_subscript(self, node: Node) -> LValue:
        """``a[i] = ...``: a static path for a constant index, a per-lane choice otherwise."""
        base = self.lvalue(node.child_by_field_name("argument"))
        element, groups, index = self.subscript(base.type, node)
        if isinstance(index, int):
            group = groups[index]
            return LValue(base.var, element, base.path.map(lambda idx: tuple(idx[p] for p in group)))
        ev = index.ev
        inner = base.path

        def resolve(f):
            i = ev(f)[0]
            out = []
            for cond, idx in inner.options(f):
                if is_uniform(i):
                    if np.isfinite(i) and 0 <= i < len(groups):  # out of range: the store is dropped
                        out.append((cond, tuple(idx[p] for p in groups[int(i)])))
                    continue
                for k, group in enumerate(groups):
                    hit = i == k
                    out.append((hit if cond is None else np.logical_and(cond, hit), tuple(idx[p] for p in group)))
            return out

        return LValue(base.var, element, ComponentPath(resolve=resolve))

    def expr_assignment(self, node: Node) -> Expr:
        """``x = e`` and the compound assignments ``x op= e``."""
        op = self.text(node.child_by_field_name("operator"))
        target = self.lvalue(node.child_by_field_name("left"))
        right_node = node.child_by_field_name("right")
        value = self.expr(right_node)
        if op != "=":
            current = Expr(target.type, target.get)
            value = self.arithmetic(op[:-1], current, value, node)
        value = self.convert(value, target.type, right_node)
        ev = value.ev

        def run(f):
            v = ev(f)
            target.set(f, v)
            return v

        return Expr(target.type, run, effects=True)

    def expr_update(self, node: Node) -> Expr:
        """``++x``, ``x++``, ``--x``, ``x--``."""
        op_node = node.child_by_field_name("operator")
        op = self.text(op_node)
        arg = node.child_by_field_name("argument")
        prefix = op_node.start_byte < arg.start_byte
        if not prefix and arg.type == "unary_expression":
            # tree-sitter-glsl parses -x++ as (-x)++; GLSL's postfix operators bind tighter: -(x++).
            inner = self.update(arg.child_by_field_name("argument"), op, False, node)
            return self.apply_unary(self.text(arg.child_by_field_name("operator")), inner, arg)
        return self.update(arg, op, prefix, node)

    def update(self, arg: Node, op: str, prefix: bool, node: Node) -> Expr:
        """Increment or decrement ``arg`` by one (integers wrap to 32 bits); the new or the old value."""
        target = self.lvalue(arg)
        t = target.type
        if not (t.is_numeric or t.is_matrix) or t.is_array:
            raise self.error(f"'{op}' needs a number, not {t}", node)
        delta = 1.0 if op == "++" else -1.0
        base = t.base

        def step(x):
            return wrap(x + delta, base) if base != "float" else x + delta

        def run(f):
            old = target.get(f)
            new = tuple(step(x) for x in old)
            target.set(f, new)
            return new if prefix else old

        return Expr(t, run, effects=True)
