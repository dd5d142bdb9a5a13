"""Calls and constructors: user functions (GLSL 4.10 §6.1, overloads and in/out/inout copy semantics),
built-in functions (:mod:`..builtins`, with Mesa's folds for constant arguments), ``modf``, ``length()``,
and the scalar, vector, matrix (§5.4) and array constructors.

A user function's body is compiled once; each call runs it in a new :class:`..runtime.Frame` sharing
the globals, under the caller's lane mask. Built-ins hidden by a user function of the same name are not
called.
"""

from __future__ import annotations

import numpy as np

from .. import builtins
from ..runtime import Frame
from ..types import INT, VOID, Type, converts, parse_type_name, unsupported_type_feature
from .base import CompilerBase
from .components import convert_component
from .folds import constant_overrides, pow_with_constants, with_overrides
from .values import ONE, ZERO, Expr, Function, Node, zeros


class CallsMixin(CompilerBase):
    """Compiles calls: user functions, built-ins and constructors."""

    def expr_call(self, node: Node) -> Expr:
        """A call: constructor, array constructor, ``.length()``, user function or built-in."""
        function = node.child_by_field_name("function")
        args_node = node.child_by_field_name("arguments")
        arg_nodes = [a for a in args_node.named_children if a.type != "comment"]
        if function.type == "subscript_expression":  # array constructor float[3](...)
            element = self.type_of(function.child_by_field_name("argument"))
            length = self.array_length(function) if function.child_by_field_name("index") else len(arg_nodes)
            return self.array_constructor(Type(element.base, element.rows, element.cols, length), arg_nodes, node)
        if function.type == "field_expression":
            if self.text(function.child_by_field_name("field")) == "length" and not arg_nodes:
                base = self.expr(function.child_by_field_name("argument"))
                if base.type.is_array or base.type.is_vector or base.type.is_matrix:
                    n = (
                        base.type.length or base.type.cols
                        if (base.type.is_array or base.type.is_matrix)
                        else base.type.rows
                    )
                    const = (float(n),)
                    return Expr(INT, lambda f: const, const)
            raise self.error("unsupported method call", function)
        if function.type != "identifier":
            raise self.error("unsupported call", function)
        name = self.text(function)
        t = parse_type_name(name)
        if t is not None:
            if t == VOID:
                raise self.error("cannot construct void", function)
            return self.constructor(t, arg_nodes, node)
        if name in self.functions:
            args = [self.expr(a) for a in arg_nodes]
            return self.user_call(name, args, arg_nodes, node, function)
        if name in builtins.UNSUPPORTED:
            raise self.error(f"unsupported feature: {builtins.UNSUPPORTED[name]} ({name})", function)
        if unsupported_type_feature(name):
            raise self.error(f"unsupported feature: {unsupported_type_feature(name)}", function)
        if not builtins.is_builtin(name):
            if self.lookup(name) is not None:
                raise self.error(f"'{name}' is a variable, not a function", function)
            raise self.error(f"unknown function '{name}'", function)
        args = [self.expr(a) for a in arg_nodes]
        return self.builtin_call(name, args, arg_nodes, node, function)

    def builtin_call(self, name: str, args: list[Expr], arg_nodes: list[Node], node: Node, fnode: Node) -> Expr:
        """A built-in function: arity, overload resolution, Mesa's constant folds."""
        arity = builtins.ARITY[name]
        if len(args) not in arity:
            expected = " or ".join(str(n) for n in arity)
            raise self.error(f"wrong number of arguments to '{name}': expected {expected}, got {len(args)}", fnode)
        self.uses.add(name)
        types = [a.type for a in args]
        if name == "modf":
            return self.modf(args, arg_nodes, fnode)
        overrides = constant_overrides(name, args)
        resolved = builtins.resolve(name, types, [] if overrides else [a.fresh for a in args])
        if resolved is None:
            raise self.error(f"no matching overload for '{name}({', '.join(map(str, types))})'", fnode)
        t, impl = resolved
        if overrides:
            impl = with_overrides(impl, overrides)
        if name == "pow":
            impl = pow_with_constants(*args, t.size) or impl
        # an override may pass an argument through: the result is then no temporary of ours
        fresh = name in builtins.FRESH and t.base == "float" and not overrides
        return self.make(t, impl, args, fresh=fresh)

    def modf(self, args: list[Expr], arg_nodes: list[Node], fnode: Node) -> Expr:
        """``modf(x, out i)``: the fraction, the whole part stored into ``i``."""
        x = args[0]
        if not (x.type.is_numeric and (x.type.is_scalar or x.type.is_vector)):
            raise self.error(f"no matching overload for 'modf({x.type}, {args[1].type})'", fnode)
        t = x.type.with_base("float")
        target = self.lvalue(arg_nodes[1])
        if target.type != t:
            raise self.error(f"modf's second argument must be an {t} variable, not {target.type}", arg_nodes[1])
        ev = x.ev

        def run(f):
            value = ev(f)
            whole = tuple(np.trunc(v) for v in value)
            target.set(f, whole)
            return tuple(v - w for v, w in zip(value, whole, strict=False))

        return Expr(t, run, effects=True)

    def user_call(self, name: str, args: list[Expr], arg_nodes: list[Node], node: Node, fnode: Node) -> Expr:
        """A call of a user function: overload resolution (§6.1) and in/out/inout copies."""
        types = [a.type for a in args]
        overloads = self.functions[name]
        candidates = [fn for fn in overloads if len(fn.params) == len(args)]
        if not candidates:
            counts = sorted({len(fn.params) for fn in overloads})
            expected = " or ".join(map(str, counts))
            raise self.error(f"wrong number of arguments to '{name}': expected {expected}, got {len(args)}", fnode)

        def fits(fn: Function) -> bool:
            return all(
                converts(t, p.type) if p.qualifier == "in" else t == p.type
                for t, p in zip(types, fn.params, strict=False)
            )

        exact = [fn for fn in candidates if [p.type for p in fn.params] == types]
        matches = exact or [fn for fn in candidates if fits(fn)]
        if len(matches) > 1:
            cost = [sum(t != p.type for t, p in zip(types, fn.params, strict=False)) for fn in matches]
            best = min(cost)
            matches = [fn for fn, c in zip(matches, cost, strict=False) if c == best]
        if not matches:
            raise self.error(f"no matching overload for '{name}({', '.join(map(str, types))})'", fnode)
        if len(matches) > 1:
            raise self.error(f"ambiguous call to '{name}({', '.join(map(str, types))})'", fnode)
        fn = matches[0]
        if self.function is not None:
            self.function.calls.append((fn, fnode, self.source))
        else:
            self.global_calls.append((fn, fnode, self.source))
        evs, outs = [], []
        for k, (p, a, an) in enumerate(zip(fn.params, args, arg_nodes, strict=False)):
            if p.qualifier == "in":
                evs.append(a.ev)
            else:
                target = self.lvalue(an)
                default = zeros(p.type)
                evs.append(target.get if p.qualifier == "inout" else (lambda f, z=default: z))
                outs.append((target, k))
        ret_zeros = zeros(fn.ret)

        def call(f):
            values = [ev(f) for ev in evs]
            g = Frame(fn.nslots, f.globals, f.mask, f.budget)
            for slot, v in zip(fn.param_slots, values, strict=False):
                g.slots[slot] = v
            fn.body(g)
            for target, k in outs:
                target.set(f, g.slots[fn.param_slots[k]])
            return g.ret if g.ret is not None else ret_zeros

        return Expr(fn.ret, call, effects=True)

    def constructor(self, t: Type, arg_nodes: list[Node], node: Node) -> Expr:
        """A scalar, vector or matrix constructor (§5.4.1–5.4.2)."""
        args = [self.expr(a) for a in arg_nodes]
        if not args:
            raise self.error(f"constructor {t} needs arguments", node)
        for a, an in zip(args, arg_nodes, strict=False):
            if a.type.is_array or a.type == VOID:
                raise self.error(f"cannot construct {t} from {a.type}", an)
        bases = [a.type.base for a in args]
        convert = convert_component
        if t.is_scalar:
            src = bases[0]
            if len(args) > 1:
                raise self.error(f"too many arguments to constructor {t}", arg_nodes[1])
            return self.make(t, lambda a: (convert(a[0], src, t.base),), args)
        if t.is_matrix and len(args) == 1 and args[0].type.is_matrix:
            src_t = args[0].type
            rows, cols = t.rows, t.cols

            def from_matrix(a):
                return tuple(
                    a[j * src_t.rows + i] if i < src_t.rows and j < src_t.cols else (ONE if i == j else ZERO)
                    for j in range(cols)
                    for i in range(rows)
                )

            return self.make(t, from_matrix, args)
        if len(args) == 1 and args[0].type.is_scalar:
            src = bases[0]
            if t.is_matrix:
                rows, cols = t.rows, t.cols
                return self.make(
                    t,
                    lambda a: tuple(
                        convert(a[0], src, "float") if i == j else ZERO for j in range(cols) for i in range(rows)
                    ),
                    args,
                )
            n = t.size
            return self.make(t, lambda a: (convert(a[0], src, t.base),) * n, args)
        if t.is_matrix and any(a.type.is_matrix for a in args):
            raise self.error(f"cannot construct {t} from a matrix and other arguments", node)
        # Components of the arguments, in order (§5.4.2); every argument must contribute.
        need = t.size
        taken, plan = 0, []
        for a, an in zip(args, arg_nodes, strict=False):
            if taken >= need:
                raise self.error(f"too many arguments to constructor {t}", an)
            k = min(a.type.size, need - taken)
            plan.append((k, a.type.base))
            taken += k
        if taken < need:
            raise self.error(f"not enough components for constructor {t} ({taken} of {need})", node)

        def build(*values):
            out = []
            for (k, src), v in zip(plan, values, strict=False):
                out.extend(convert(x, src, t.base) for x in v[:k])
            return tuple(out)

        return self.make(t, build, args)

    def array_constructor(self, t: Type, arg_nodes: list[Node], node: Node) -> Expr:
        """An array constructor ``float[3](a, b, c)``."""
        if len(arg_nodes) != t.length:
            raise self.error(f"array constructor {t} needs {t.length} arguments, got {len(arg_nodes)}", node)
        args = [self.convert(self.expr(a), t.element, a) for a in arg_nodes]
        return self.make(t, lambda *values: tuple(x for v in values for x in v), args)
