"""Expressions (GLSL 4.10 §5): the dispatch table, literals, identifiers and macros, ``?:``, the comma
operator, swizzles (§5.5) and subscripts (§5.7).

Every expression node becomes an :class:`.values.Expr`; operators live in :mod:`.operators`, assignments
in :mod:`.lvalues`, calls and constructors in :mod:`.calls`.
"""

from __future__ import annotations

import re

import numpy as np

from .. import builtins
from ..parser import parse_expression
from ..runtime import is_uniform, mask_and, mask_and_not, select
from ..types import BOOL, FLOAT, INT, UINT, Type, converts, parse_type_name
from .base import CompilerBase
from .values import Expr, Node, zeros

#: Expression node type -> method.
EXPRESSION_RULES = {
    "parenthesized_expression": "expr_parenthesized",
    "number_literal": "expr_number",
    "true": "expr_boolean",
    "false": "expr_boolean",
    "identifier": "expr_identifier",
    "comma_expression": "expr_comma",
    "unary_expression": "expr_unary",
    "binary_expression": "expr_binary",
    "conditional_expression": "expr_conditional",
    "assignment_expression": "expr_assignment",
    "update_expression": "expr_update",
    "field_expression": "expr_field",
    "subscript_expression": "expr_subscript",
    "call_expression": "expr_call",
}
_SWIZZLE_SETS = ("xyzw", "rgba", "stpq")
#: Integer literals longer than this cannot be 32-bit (and Python refuses to convert 4300+ digits).
_MAX_INTEGER_DIGITS = 12


class ExpressionsMixin(CompilerBase):
    """Compiles expressions other than operators, assignments and calls."""

    def expr(self, node: Node) -> Expr:
        """Compile one expression."""
        return self.dispatch(EXPRESSION_RULES, node, self.unsupported_expression)

    def unsupported_expression(self, node: Node):
        """The error for an expression kind GLSL does not have."""
        if node.type == "cast_expression":
            return self.error("C-style casts are not GLSL; use a constructor such as float(x)", node)
        return self.error(f"unsupported expression ({node.type.replace('_', ' ')})", node)

    def expr_parenthesized(self, node: Node) -> Expr:
        """``(e)``."""
        inner = [c for c in node.named_children if c.type != "comment"]
        return self.expr(inner[0])

    def expr_number(self, node: Node) -> Expr:
        """A number literal, with the sign tree-sitter-glsl folds into some literals (``x * -1.0``)."""
        text = self.text(node)
        if text[:1] in "+-":
            return self.apply_unary(text[0], self.number(text[1:].strip(), node), node)
        return self.number(text, node)

    def number(self, text: str, node: Node) -> Expr:
        """The value and type of an unsigned literal (§4.1.3, §4.1.4): decimal, octal and hex integers wrap
        to 32 bits when they fit in 32 bits unsigned; floats must be finite."""
        if re.fullmatch(r"0[xX][0-9a-fA-F]+[uU]?", text):
            digits = text[2:].rstrip("uU").lstrip("0")
            value = int(digits, 16) if 0 < len(digits) <= _MAX_INTEGER_DIGITS else 2**32 if digits else 0
            t = UINT if text[-1] in "uU" else INT
        elif re.fullmatch(r"[0-9]+[uU]?", text):
            digits = text.rstrip("uU")
            octal = len(digits) > 1 and digits[0] == "0"
            if octal and not re.fullmatch(r"[0-7]+", digits):
                raise self.error(f"malformed number '{text}': octal literals (leading 0) take digits 0-7", node)
            significant = digits.lstrip("0")
            if len(significant) > _MAX_INTEGER_DIGITS:
                value = 2**32
            else:
                value = int(significant or "0", 8 if octal else 10)
            t = UINT if text[-1] in "uU" else INT
        elif re.fullmatch(r"(?:[0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)(?:[eE][+-]?[0-9]+)?[fF]?", text):
            if not re.search(r"[.eEfF]", text):
                raise self.error(f"malformed number '{text}'", node)
            value, t = float(text.rstrip("fF")), FLOAT
            if not np.isfinite(value):
                raise self.error(f"number '{text[:40]}' is out of range", node)
        elif re.fullmatch(r".*(lf|LF)", text):
            raise self.error(f"unsupported feature: double-precision literal '{text[:40]}'", node)
        else:
            raise self.error(f"malformed number '{text[:40]}'", node)
        if t != FLOAT:
            if value >= 2**32:
                raise self.error(f"integer '{text[:40]}' is out of range", node)
            if t == INT and value >= 2**31:
                value -= 2**32  # GLSL: decimal/hex int literals wrap to 32 bits
        const = (np.float64(value),)  # numpy scalars: IEEE arithmetic, no Python ZeroDivisionError
        return Expr(t, lambda f: const, const)

    def expr_boolean(self, node: Node) -> Expr:
        """``true`` and ``false``."""
        const = (node.type == "true",)
        return Expr(BOOL, lambda f: const, const)

    def expr_identifier(self, node: Node) -> Expr:
        """A variable (its constant value when it has one) or a macro."""
        name = self.text(node)
        if name in self.macros:
            return self.macro(name, node)
        var = self.lookup(name)
        if var is None:
            if name in self.functions or builtins.is_builtin(name) or parse_type_name(name):
                raise self.error(f"'{name}' is a function or type, not a variable", node)
            if name == "discard":
                raise self.error("unsupported feature: discard (fragment shaders only)", node)
            if name.startswith("gl_"):
                raise self.error(f"unsupported feature: built-in shader variable '{name}'", node)
            raise self.error(f"unknown identifier '{name}'", node)
        if var.readonly == "uniform":
            self.uses.add(name)
        if var.param_index is not None and self.function is not None:
            self.function.used_params.add(var.param_index)
        if var.const is not None:
            const = var.const
            return Expr(var.type, lambda f: const, const)
        slot = var.slot
        if var.is_global:
            return Expr(var.type, lambda f: f.globals[slot])
        return Expr(var.type, lambda f: f.slots[slot])

    def macro(self, name: str, node: Node) -> Expr:
        """Expand an object-like macro: its body (parsed once per definition) is compiled where the name is used."""
        definition = self.macros[name]
        if definition is None:
            raise self.error(f"macro '{name}' has no value", node)
        if name in self.expanding:
            raise self.error(f"macro '{name}' expands to itself", node)
        text, value_node, src = definition
        key = (id(src), value_node.start_byte)  # one definition: the shader's sources live as long as the compiler
        if key not in self.macro_bodies:
            self.macro_bodies[key] = parse_expression(text, src, value_node)
        expression, msrc = self.macro_bodies[key]
        self.sources.append(msrc)
        self.expanding.append(name)
        try:
            return self.expr(expression)
        finally:
            self.sources.pop()
            self.expanding.pop()

    def expr_comma(self, node: Node) -> Expr:
        """``a, b``: both evaluated, the value of ``b``."""
        left = self.expr(node.child_by_field_name("left"))
        right = self.expr(node.child_by_field_name("right"))
        if not left.effects:
            return right
        a, b = left.ev, right.ev
        return Expr(right.type, lambda f: (a(f), b(f))[1], effects=True)

    def expr_conditional(self, node: Node) -> Expr:
        """``c ? a : b``: only the branch taken runs in each lane."""
        cond = self.expr(node.child_by_field_name("condition"))
        if cond.type != BOOL:
            raise self.error(f"condition must be a bool, not {cond.type}", node.child_by_field_name("condition"))
        yes = self.expr(node.child_by_field_name("consequence"))
        no = self.expr(node.child_by_field_name("alternative"))
        if yes.type != no.type:
            if converts(yes.type, no.type):
                yes = self.convert(yes, no.type, node)
            elif converts(no.type, yes.type):
                no = self.convert(no, yes.type, node)
            else:
                raise self.error(f"the two branches of '?:' have different types ({yes.type}, {no.type})", node)
        if cond.const is not None:
            return yes if cond.const[0] else no
        c, a, b = cond.ev, yes.ev, no.ev
        masked = yes.effects or no.effects

        def run(f):
            x = c(f)[0]
            if is_uniform(x):
                return a(f) if x else b(f)
            if not masked:
                return tuple(map(np.where, [x] * yes.type.size, a(f), b(f)))
            saved = f.mask
            f.mask = mask_and(saved, x)
            p = a(f) if f.mask is not False else zeros(yes.type)
            f.mask = mask_and_not(saved, x)
            q = b(f) if f.mask is not False else zeros(yes.type)
            f.mask = saved
            return tuple(map(np.where, [x] * yes.type.size, p, q))

        return Expr(yes.type, run, effects=cond.effects or masked)

    def swizzle(self, t: Type, field_node: Node) -> list[int]:
        """Component indices of a swizzle (``.xyz``, ``.rgba``, ``.stpq``)."""
        name = self.text(field_node)
        if t.is_array or t.is_matrix or t.base == "void":
            raise self.error(f"'{t}' has no field '{name}'", field_node)
        for letters in _SWIZZLE_SETS:
            if all(ch in letters for ch in name):
                picks = [letters.index(ch) for ch in name]
                if len(picks) > 4:
                    raise self.error(f"swizzle '{name}' is longer than 4 components", field_node)
                if max(picks) >= t.rows:
                    raise self.error(f"swizzle '{name}' is out of range for {t}", field_node)
                return picks
        raise self.error(f"invalid swizzle or field '{name}' for {t}", field_node)

    def expr_field(self, node: Node) -> Expr:
        """A swizzle ``v.xy``."""
        base = self.expr(node.child_by_field_name("argument"))
        picks = self.swizzle(base.type, node.child_by_field_name("field"))
        t = Type(base.type.base, len(picks)) if len(picks) > 1 else Type(base.type.base)
        return self.make(t, lambda a: tuple(a[p] for p in picks), [base])

    def subscript(self, t: Type, node: Node) -> tuple[Type, list[tuple[int, ...]], int | Expr]:
        """Element type, the component groups an index selects from, and the index (int if constant)."""
        index_node = node.child_by_field_name("index")
        if t.is_array:
            element, count = t.element, t.length
        elif t.is_matrix:
            element, count = t.column(), t.cols
        elif t.is_vector:
            element, count = Type(t.base), t.rows
        else:
            raise self.error(f"cannot index a {t}", node)
        size = element.size
        groups = [tuple(range(k * size, (k + 1) * size)) for k in range(count)]
        index = self.expr(index_node)
        if not (index.type.is_integer and index.type.is_scalar):
            raise self.error(f"index must be an integer, not {index.type}", index_node)
        if index.const is not None:
            value = float(index.const[0])
            if not (np.isfinite(value) and 0 <= value < count):
                raise self.error(f"index {value:.0f} is out of range for {t}", index_node)
            return element, groups, int(value)
        return element, groups, index

    def expr_subscript(self, node: Node) -> Expr:
        """``a[i]`` of an array, a matrix (a column) or a vector (a component)."""
        base = self.expr(node.child_by_field_name("argument"))
        element, groups, index = self.subscript(base.type, node)
        if isinstance(index, int):
            group = groups[index]
            return self.make(element, lambda a: tuple(a[p] for p in group), [base])
        default = zeros(element)
        return self.make(
            element, lambda a, i: select(i[0], [tuple(a[p] for p in g) for g in groups], default), [base, index]
        )
