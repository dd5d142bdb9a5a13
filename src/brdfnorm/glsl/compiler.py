"""Compilation of a tree-sitter GLSL syntax tree into closures over numpy arrays.

Every expression node becomes an :class:`Expr` (static type, optional compile-time constant, and a
closure ``ev(frame) -> tuple of components``); every statement a closure ``run(frame)``. Nothing is
ever turned into Python source: identifiers of the shader only ever index the compiler's own symbol
tables, so a shader variable named ``__import__`` or ``exec`` is just a slot in a list.

Semantics follow the OpenGL Shading Language 4.10 specification: §5.8–5.10 (operators, implicit
int → float conversion, int division truncating toward zero), §5.4 (constructors), §5.5 (swizzles),
§6.1 (functions, overloading, in/out/inout copy semantics; built-ins hidden by a user function of the
same name), §6.2–6.4 (switch, loops, jumps), with Mesa llvmpipe's choices where the specification leaves
results undefined (see :mod:`.builtins`). Per-lane control flow is executed with masks (:mod:`.runtime`);
a condition that is the same in every lane runs only the branch taken.

Mesa's optimizer changes some results the specification leaves undefined; measured on llvmpipe (Mesa
22.3) and imitated here: ``x * 0.0``, ``0.0 * x`` and ``0.0 / x`` are 0 for every x (inf and NaN
included) when that side is a compile-time constant 0; integer ``x / 0`` is 0 and ``%`` is an unsigned
32-bit remainder (``x % 0`` = -1); constant arguments steer ``pow``, ``mod`` and ``mix``
(:meth:`Compiler.constant_overrides`). A float division by a constant 0 keeps IEEE semantics (±inf,
NaN): llvmpipe writes no result at all for a shader doing it, so there is nothing to match. Constant
propagation treats a variable initialized with a constant and never written anywhere as a constant, as
Mesa's SSA form does. Not imitated: folds that need value numbering (``x - x`` → 0 for a non-constant x)
and float32 overflow/underflow.

Loops are bounded: one execution of a loop may run :data:`MAX_LOOP_ITERATIONS` iterations and all loops
of one evaluation :data:`MAX_TOTAL_ITERATIONS`; past that, :class:`~brdfnorm.errors.EvaluationError`
names the loop's ``FILE:LINE:COL``. Recursion is refused at compile time.
"""

from __future__ import annotations

import operator
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
import tree_sitter

from ..errors import BrdfFileError, EvaluationError
from . import builtins
from .parser import Source, parse, parse_expression
from .runtime import (
    Frame,
    LoopState,
    blend,
    is_uniform,
    mask_and,
    mask_and_not,
    mask_or,
    select,
)
from .types import BOOL, FLOAT, INT, UINT, VEC3, VOID, Type, converts, parse_type_name, unsupported_type_feature

Node = tree_sitter.Node

#: Iterations one execution of one loop may take before evaluation stops with an EvaluationError.
MAX_LOOP_ITERATIONS = 10_000
#: Loop iterations all loops together may take in one evaluation of the shader.
MAX_TOTAL_ITERATIONS = 100_000
#: Longest array a shader may declare (each element is held as its own component arrays).
MAX_ARRAY_LENGTH = 1024

_SWIZZLE_SETS = ("xyzw", "rgba", "stpq")
_INT_MIN = -(2.0**31)


@dataclass
class Expr:
    """A compiled expression: its type, its evaluator, its value if constant, whether it writes."""

    type: Type
    ev: Callable[[Frame], tuple]
    const: tuple | None = None
    effects: bool = False
    fresh: bool = False  # components are new arrays used by nobody else: reusable as output buffers


@dataclass
class Var:
    """A variable: local (``slot`` in the frame) or global (``slot`` in the globals list)."""

    name: str
    type: Type
    slot: int
    is_global: bool
    const: tuple | None = None
    readonly: str | None = None  # "const" or "uniform" when it cannot be assigned
    param_index: int | None = None  # position among BRDF's parameters, for the entry point


@dataclass
class Param:
    name: str | None
    type: Type
    qualifier: str  # "in", "out" or "inout"
    const: bool = False


@dataclass(eq=False)
class Function:
    name: str
    ret: Type
    params: list[Param]
    node: Node
    source: Source
    body_node: Node | None = None
    body: Callable[[Frame], None] | None = None
    nslots: int = 0
    param_slots: list[int] = field(default_factory=list)
    calls: list[tuple[Function, Node, Source]] = field(default_factory=list)
    used_params: set[int] = field(default_factory=set)

    def signature(self) -> str:
        return f"{self.ret} {self.name}({', '.join(str(p.type) for p in self.params)})"


class _Scope(dict):
    pass


def _zeros(t: Type) -> tuple:
    return (False,) * t.size if t.base == "bool" else (_ZERO,) * t.size


def _to_int(x):
    """float → int conversion: truncation; NaN, ±inf and out-of-range give INT_MIN as on x86."""
    t = np.trunc(x)
    return np.where(np.abs(t) < 2.0**31, t, _INT_MIN) if np.ndim(t) else (t if abs(t) < 2.0**31 else _INT_MIN)


def _convert_component(x, src: str, dst: str):
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
        value = _to_int(x) if src == "float" else x
        return np.where(value >= 2.0**31, value - 2.0**32, value) if src == "uint" else value
    value = _to_int(x) if src == "float" else x  # to uint: two's complement wrap of negative values
    return np.where(value < 0, value + 2.0**32, value)


def _int_div(a, b):
    with np.errstate(all="ignore"):
        q = np.trunc(np.true_divide(a, b))
    return np.where(b == 0, 0.0, q)


def _int_mod(a, b):
    # Mesa evaluates % as an unsigned 32-bit remainder (x % 0 gives all bits set), measured on llvmpipe.
    ua = np.mod(np.asarray(a, dtype=np.int64), 2**32)
    ub = np.mod(np.asarray(b, dtype=np.int64), 2**32)
    r = np.where(ub == 0, 2**32 - 1, ua % np.maximum(ub, 1))
    return (np.where(r >= 2**31, r - 2**32, r)).astype(np.float64)


def _bitwise(op):
    def fn(a, b):
        r = op(np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)) & 0xFFFFFFFF
        return np.where(r >= 2**31, r - 2**32, r).astype(np.float64)

    return fn


def _shift(left: bool):
    def fn(a, b):
        x = np.asarray(a, dtype=np.int64) & 0xFFFFFFFF
        s = np.asarray(b, dtype=np.int64) & 31
        r = (x << s if left else np.where(x >= 2**31, x - 2**32, x) >> s) & 0xFFFFFFFF
        return np.where(r >= 2**31, r - 2**32, r).astype(np.float64)

    return fn


_UFUNCS = {"+": np.add, "-": np.subtract, "*": np.multiply, "/": np.true_divide}


def _in_place(ufunc: np.ufunc, side: int) -> Callable:
    """Componentwise ``ufunc`` writing into operand ``side``'s arrays (temporaries) where shapes allow."""

    def fn(x, y):
        out = []
        for p, q in zip(x if len(x) > 1 else x * len(y), y if len(y) > 1 else y * len(x), strict=True):
            buffer, other = (p, q) if side == 0 else (q, p)
            if builtins._owned(buffer, other):
                out.append(ufunc(p, q, out=buffer))
            else:
                out.append(ufunc(p, q))
        return tuple(out)

    return fn


# numpy's divide, not Python's: IEEE results (inf, NaN) for constant operands too, never ZeroDivisionError.
_ARITH = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": np.true_divide}
_ZERO = np.float64(0.0)


def _override(impl: Callable, overrides: dict[int, int], size: int) -> Callable:
    def fn(*values):
        out = list(impl(*values))
        for i, k in overrides.items():
            out[i] = values[k][i if len(values[k]) > 1 else 0]
        return tuple(out)

    return fn


_INT_ARITH = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": _int_div, "%": _int_mod}
_BITWISE = {
    "&": _bitwise(operator.and_),
    "|": _bitwise(operator.or_),
    "^": _bitwise(operator.xor),
    "<<": _shift(True),
    ">>": _shift(False),
}
_COMPARE = {"<": operator.lt, ">": operator.gt, "<=": operator.le, ">=": operator.ge}


def _written_names(root: Node, text: Callable[[Node], str]) -> set[str]:
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


class _Path:
    """Where an lvalue sits in its variable's flat components: static indices, or a per-lane choice."""

    def __init__(self, static: tuple[int, ...] | None = None, resolve=None) -> None:
        self.static = static
        self.resolve = resolve  # frame -> list of (lane condition or None, indices)

    def options(self, f: Frame) -> list[tuple[object, tuple[int, ...]]]:
        return [(None, self.static)] if self.static is not None else self.resolve(f)

    def map(self, pick: Callable[[tuple[int, ...]], tuple[int, ...]]) -> _Path:
        if self.static is not None:
            return _Path(pick(self.static))
        inner = self.resolve
        return _Path(resolve=lambda f: [(c, pick(idx)) for c, idx in inner(f)])


class LValue:
    """An assignable location: a variable and a path into its components."""

    def __init__(self, var: Var, type_: Type, path: _Path) -> None:
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
        root = self.load(f)
        if self.path.static is not None:
            return tuple(root[i] for i in self.path.static)
        out = _zeros(self.type)  # an out-of-range index reads 0, as in x_subscript_expression
        for cond, idx in self.path.resolve(f):
            value = tuple(root[i] for i in idx)
            out = value if cond is None else tuple(map(np.where, [cond] * len(value), value, out))
        return out

    def set(self, f: Frame, value: tuple) -> None:
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


class Compiler:
    def __init__(self, source: str, path: str, first_line: int, first_column: int, uniforms: Mapping[str, str]):
        self.tree, self.src = parse(source, path, first_line, first_column)
        self.path = path
        self.sources: list[Source] = [self.src]
        self.scopes: list[_Scope] = [_Scope()]  # scopes[0]: globals
        self.globals_count = 0
        self.global_inits: list[Callable[[Frame], None]] = []
        # name -> (type, slot, declared by the caller, value when none is given)
        self.uniforms: dict[str, tuple[Type, int, bool, tuple]] = {}
        self.functions: dict[str, list[Function]] = {}
        self.macros: dict[str, tuple[str, Node, Source] | None] = {}
        self.uses: set[str] = set()
        self.function: Function | None = None
        self.nslots = 0
        self.loop_depth = 0
        self.switch_depth = 0
        self.written = _written_names(self.tree.root_node, self.text)
        self.global_calls: list[tuple[Function, Node, Source]] = []
        self.expanding: list[str] = []
        for name, kind in uniforms.items():
            t = parse_type_name(kind)
            if t is None or t.length is not None or t.base == "void":
                raise BrdfFileError(f"unsupported uniform type '{kind}' for '{name}'", path, first_line, first_column)
            self.declare_uniform(name, t, None, caller=True)

    # --- helpers ----------------------------------------------------------------------------------------

    @property
    def source(self) -> Source:
        return self.sources[-1]

    def text(self, node: Node) -> str:
        return self.source.text_of(node)

    def error(self, message: str, node: Node | None) -> BrdfFileError:
        return self.source.error(message, node)

    def where(self, node: Node) -> str:
        line, column = self.source.position(node)
        return f"{self.path}:{line}:{column}"

    def lookup(self, name: str) -> Var | None:
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return None

    def declare_uniform(
        self, name: str, t: Type, node: Node | None, caller: bool = False, default: tuple | None = None
    ) -> None:
        if name in self.uniforms:
            previous = self.uniforms[name][0]
            if previous != t:
                raise self.error(f"uniform '{name}' declared as {t}, but the parameter is {previous}", node)
            return
        slot = self.new_global()
        self.uniforms[name] = (t, slot, caller, default if default is not None else _zeros(t))
        self.scopes[0][name] = Var(name, t, slot, True, readonly="uniform")

    def new_global(self) -> int:
        self.globals_count += 1
        return self.globals_count - 1

    def make(self, t: Type, fn: Callable, args: list[Expr], effects: bool = False, fresh: bool = False) -> Expr:
        """An expression applying ``fn`` to the arguments' component tuples; folded when all are constant.

        ``fresh`` declares that ``fn`` returns new arrays only (see :attr:`Expr.fresh`).
        """
        effects = effects or any(a.effects for a in args)
        if not effects and all(a.const is not None for a in args):
            with np.errstate(all="ignore"):
                value = fn(*(a.const for a in args))
            return Expr(t, lambda f: value, value)
        evs = [a.ev for a in args]
        if len(evs) == 1:
            (a,) = evs
            return Expr(t, lambda f: fn(a(f)), effects=effects, fresh=fresh)
        if len(evs) == 2:
            a, b = evs
            return Expr(t, lambda f: fn(a(f), b(f)), effects=effects, fresh=fresh)
        if len(evs) == 3:
            a, b, c = evs
            return Expr(t, lambda f: fn(a(f), b(f), c(f)), effects=effects, fresh=fresh)
        return Expr(t, lambda f: fn(*(e(f) for e in evs)), effects=effects, fresh=fresh)

    def type_of(self, node: Node) -> Type:
        name = self.text(node).strip()
        t = parse_type_name(name)
        if t is None:
            feature = unsupported_type_feature(name)
            if feature:
                raise self.error(f"unsupported feature: {feature}", node)
            if node.type == "struct_specifier":
                raise self.error("unsupported feature: structs", node)
            raise self.error(f"unknown type '{name}'", node)
        return t

    def array_length(self, declarator: Node) -> int:
        size = declarator.child_by_field_name("size") or declarator.child_by_field_name("index")
        if size is None:
            raise self.error("arrays need an explicit constant size", declarator)
        e = self.expr(size)
        if e.const is None or not e.type.is_integer or not e.type.is_scalar:
            raise self.error("array size must be a constant integer expression", size)
        n = int(e.const[0])
        if n <= 0:
            raise self.error("array size must be positive", size)
        if n > MAX_ARRAY_LENGTH:
            raise self.error(f"array size {n} exceeds the supported maximum of {MAX_ARRAY_LENGTH}", size)
        return n

    # --- translation unit -----------------------------------------------------------------------------

    def compile(self) -> None:
        root = self.tree.root_node
        for node in root.named_children:  # pass 1: function signatures, so calls may precede definitions
            if node.type == "function_definition":
                self.declare_function(node, node.child_by_field_name("declarator"), defined=True)
            elif node.type == "declaration" and self.is_prototype(node):
                self.declare_function(node, node.child_by_field_name("declarator"), defined=False)
        for node in root.named_children:  # pass 2: globals, macros and bodies in source order
            if node.type == "function_definition":
                self.compile_function(node)
            elif node.type == "declaration":
                if not self.is_prototype(node):
                    self.global_declaration(node)
            elif node.type == "comment":
                continue
            elif node.type.startswith("preproc"):
                self.preprocessor(node)
            elif node.type == "struct_specifier":
                raise self.error("unsupported feature: structs", node)
            elif node.type == "expression_statement" and self.text(node).strip() == ";":
                continue
            else:
                raise self.error(f"unexpected {node.type.replace('_', ' ')} at global scope", node)
        self.check_calls()

    def is_prototype(self, node: Node) -> bool:
        declarator = node.child_by_field_name("declarator")
        return declarator is not None and declarator.type == "function_declarator"

    def preprocessor(self, node: Node) -> None:
        if node.type == "preproc_def":
            name = self.text(node.child_by_field_name("name"))
            value = node.child_by_field_name("value")
            self.macros[name] = (self.text(value).strip(), value, self.source) if value is not None else None
        elif node.type == "preproc_function_def":
            name = self.text(node.child_by_field_name("name"))
            raise self.error(f"unsupported feature: function-like macro '{name}'", node)
        elif node.type == "preproc_extension":
            return
        elif node.type == "preproc_call":
            directive = self.text(node.child_by_field_name("directive")).strip()
            argument = node.child_by_field_name("argument")
            if directive == "#undef" and argument is not None:
                self.macros.pop(self.text(argument).strip(), None)
            elif directive not in ("#version", "#extension", "#pragma", "#line"):
                raise self.error(f"unsupported preprocessor directive {directive}", node)
        else:
            first = self.text(node).split()[0] if self.text(node).split() else node.type
            raise self.error(f"unsupported preprocessor directive {first}", node)

    def qualifiers(self, node: Node) -> set[str]:
        found = set()
        for child in node.children:
            if child.type == "type_qualifier":
                found.update(self.text(child).split())
            elif child.type == "layout_specification":
                found.add("layout")
            elif not child.is_named and child.type in ("in", "out", "inout", "uniform", "buffer", "shared"):
                found.add(child.type)
        return found

    def parse_params(self, declarator: Node) -> list[Param]:
        params = []
        plist = declarator.child_by_field_name("parameters")
        for p in plist.named_children:
            if p.type == "comment":
                continue
            if p.type != "parameter_declaration":
                raise self.error("unsupported parameter declaration", p)
            t = self.type_of(p.child_by_field_name("type"))
            quals = self.qualifiers(p)
            qualifier = "inout" if "inout" in quals else "out" if "out" in quals else "in"
            d = p.child_by_field_name("declarator")
            name = None
            if d is not None:
                if d.type == "array_declarator":
                    t = Type(t.base, t.rows, t.cols, self.array_length(d))
                    d = d.child_by_field_name("declarator")
                name = self.text(d)
            if t == VOID:
                if len(plist.named_children) == 1 and name is None:
                    return []
                raise self.error("parameters cannot be void", p)
            params.append(Param(name, t, qualifier, "const" in quals))
        return params

    def declare_function(self, node: Node, declarator: Node, defined: bool) -> None:
        name_node = declarator.child_by_field_name("declarator")
        name = self.text(name_node)
        if parse_type_name(name) is not None:
            raise self.error(f"cannot define a function named '{name}' (a type name)", name_node)
        ret = self.type_of(node.child_by_field_name("type"))
        params = self.parse_params(declarator)
        overloads = self.functions.setdefault(name, [])
        for fn in overloads:
            if [p.type for p in fn.params] == [p.type for p in params]:
                if fn.ret != ret:
                    raise self.error(f"function '{name}' redeclared with another return type", name_node)
                if defined and fn.body_node is not None:
                    raise self.error(f"function '{fn.signature()}' is defined twice", name_node)
                if defined:
                    fn.body_node = node.child_by_field_name("body")
                    fn.node = name_node
                    fn.params = params
                return
        fn = Function(name, ret, params, name_node, self.source)
        if defined:
            fn.body_node = node.child_by_field_name("body")
        overloads.append(fn)

    def find_defined(self, node: Node) -> Function:
        declarator = node.child_by_field_name("declarator")
        name = self.text(declarator.child_by_field_name("declarator"))
        body = node.child_by_field_name("body")
        return next(fn for fn in self.functions[name] if fn.body_node is not None and fn.body_node == body)

    def compile_function(self, node: Node) -> None:
        fn = self.find_defined(node)
        self.function, self.nslots, self.loop_depth, self.switch_depth = fn, 0, 0, 0
        self.scopes.append(_Scope())
        fn.param_slots = []
        for index, p in enumerate(fn.params):
            slot = self.new_slot()
            fn.param_slots.append(slot)
            if p.name is not None:
                readonly = "const parameter" if p.const else None
                self.scopes[-1][p.name] = Var(p.name, p.type, slot, False, readonly=readonly, param_index=index)
        body = self.block(fn.body_node, new_scope=False)
        self.scopes.pop()
        fn.body = body
        fn.nslots = self.nslots
        self.function = None

    def new_slot(self) -> int:
        self.nslots += 1
        return self.nslots - 1

    def check_calls(self) -> None:
        for overloads in self.functions.values():
            for fn in overloads:
                for callee, node, src in fn.calls:
                    if callee.body_node is None:
                        raise src.error(f"function '{callee.signature()}' is declared but never defined", node)
        state: dict[int, int] = {}

        def visit(fn: Function, chain: list[str]) -> None:
            state[id(fn)] = 1
            for callee, node, src in fn.calls:
                if state.get(id(callee)) == 1:
                    cycle = " -> ".join(
                        [*chain, fn.name, callee.name][chain.index(callee.name) if callee.name in chain else 0 :]
                    )
                    raise src.error(f"recursion is not allowed in GLSL ({cycle})", node)
                if id(callee) not in state:
                    visit(callee, [*chain, fn.name])
            state[id(fn)] = 2

        for overloads in self.functions.values():
            for fn in overloads:
                if id(fn) not in state:
                    visit(fn, [])

    # --- declarations -----------------------------------------------------------------------------------

    def declarators(self, node: Node):
        """(name node, array length or None, initializer or None) for each declarator of a declaration."""
        for d in node.children_by_field_name("declarator"):
            value = None
            if d.type == "init_declarator":
                value = d.child_by_field_name("value")
                d = d.child_by_field_name("declarator")
            length = None
            if d.type == "array_declarator":
                length = self.array_length(d)
                d = d.child_by_field_name("declarator")
            if d.type != "identifier":
                raise self.error(f"unsupported declarator '{self.text(d)}'", d)
            yield d, length, value

    def global_declaration(self, node: Node) -> None:
        quals = self.qualifiers(node)
        type_node = node.child_by_field_name("type")
        if (
            type_node is None
            or "buffer" in quals
            or "shared" in quals
            or any(c.type == "field_declaration_list" for c in node.children)
        ):
            raise self.error("unsupported feature: interface blocks / shader storage buffers", node)
        if type_node.type == "struct_specifier":
            raise self.error("unsupported feature: structs", node)
        base = self.type_of(type_node)
        if "in" in quals or "out" in quals:
            raise self.error("unsupported feature: shader inputs/outputs ('in'/'out' globals)", node)
        for name_node, length, value in self.declarators(node):
            name = self.text(name_node)
            t = Type(base.base, base.rows, base.cols, length)
            if "uniform" in quals:
                if t.length is not None:
                    raise self.error("unsupported feature: uniform arrays", name_node)
                default = None
                if value is not None:  # GLSL 1.20+: the value a uniform has until one is set
                    default = self.convert(self.expr(value), t, value).const
                    if default is None:
                        raise self.error(f"uniform '{name}' needs a constant initializer", value)
                self.declare_uniform(name, t, name_node, default=default)
                continue
            if name in self.scopes[0]:
                raise self.error(f"'{name}' is already declared", name_node)
            self.variable(name_node, name, t, value, "const" in quals, is_global=True)

    def variable(self, name_node: Node, name: str, t: Type, value: Node | None, const: bool, is_global: bool):
        """Declare a variable in the current scope; return the initializing closure (or None)."""
        if t == VOID:
            raise self.error("variables cannot be void", name_node)
        init = self.convert(self.expr(value), t, value) if value is not None else None
        if const and (init is None or init.const is None):
            raise self.error(f"const variable '{name}' needs a constant initializer", value or name_node)
        effective = init.const if init is not None and (const or name not in self.written) else None
        slot = self.new_global() if is_global else self.new_slot()
        var = Var(name, t, slot, is_global, const=effective, readonly="const" if const else None)
        self.scopes[-1][name] = var
        zeros = _zeros(t)
        ev = init.ev if init is not None else (lambda f: zeros)
        if is_global:
            self.global_inits.append(lambda f: f.globals.__setitem__(slot, ev(f)))
            return None

        def run(f):
            f.slots[slot] = ev(f)

        return run

    # --- statements ---------------------------------------------------------------------------------------

    def block(self, node: Node, new_scope: bool = True) -> Callable[[Frame], None]:
        if new_scope:
            self.scopes.append(_Scope())
        stmts = [s for s in (self.statement(child) for child in node.named_children) if s is not None]
        if new_scope:
            self.scopes.pop()
        return _sequence(stmts)

    def statement(self, node: Node) -> Callable[[Frame], None] | None:
        kind = node.type
        if kind == "compound_statement":
            return self.block(node)
        if kind == "comment":
            return None
        if kind == "declaration":
            if self.is_prototype(node):
                raise self.error("functions cannot be declared inside a function", node)
            return self.local_declaration(node)
        if kind == "expression_statement":
            if not node.named_children:
                return None
            return self.expression_effect(node.named_children[0])
        if kind == "if_statement":
            return self.if_statement(node)
        if kind in ("for_statement", "while_statement", "do_statement"):
            return self.loop(node)
        if kind == "return_statement":
            return self.return_statement(node)
        if kind == "break_statement":
            if self.loop_depth == 0 and self.switch_depth == 0:
                raise self.error("'break' outside a loop or switch", node)
            return _break
        if kind == "continue_statement":
            if self.loop_depth == 0:
                raise self.error("'continue' outside a loop", node)
            return _continue
        if kind.startswith("preproc"):
            self.preprocessor(node)
            return None
        if kind == "switch_statement":
            return self.switch(node)
        if kind in ("goto_statement", "labeled_statement"):
            raise self.error(f"unsupported feature: {kind.split('_')[0]} (not GLSL)", node)
        raise self.error(f"unsupported statement ({kind.replace('_', ' ')})", node)

    def local_declaration(self, node: Node) -> Callable[[Frame], None] | None:
        quals = self.qualifiers(node)
        if quals - {"const"}:
            word = sorted(quals - {"const"})[0]
            raise self.error(f"'{word}' variables cannot be declared inside a function", node)
        type_node = node.child_by_field_name("type")
        if type_node.type == "struct_specifier":
            raise self.error("unsupported feature: structs", node)
        base = self.type_of(type_node)
        runs = []
        for name_node, length, value in self.declarators(node):
            name = self.text(name_node)
            if name in self.scopes[-1]:
                raise self.error(f"'{name}' is already declared in this scope", name_node)
            t = Type(base.base, base.rows, base.cols, length)
            runs.append(self.variable(name_node, name, t, value, "const" in quals, is_global=False))
        return _sequence(runs)

    def condition(self, node: Node) -> Callable[[Frame], object]:
        if node.type == "parenthesized_expression":
            node = node.named_children[0]
        e = self.expr(node)
        if e.type != BOOL:
            raise self.error(f"condition must be a bool, not {e.type}", node)
        if e.const is not None:
            value = bool(e.const[0])
            return lambda f: value
        ev = e.ev
        return lambda f: ev(f)[0]

    def if_statement(self, node: Node) -> Callable[[Frame], None]:
        cond = self.condition(node.child_by_field_name("condition"))
        then = self.statement(node.child_by_field_name("consequence")) or _nothing
        alternative = node.child_by_field_name("alternative")
        other = _nothing
        if alternative is not None:
            inner = [c for c in alternative.named_children if c.type != "comment"]
            other = self.statement(inner[0]) or _nothing

        def run(f):
            c = cond(f)
            if is_uniform(c):
                (then if c else other)(f)
                return
            mask = f.mask
            taken = mask_and(mask, c)
            if taken is False:
                other(f)
                return
            skipped = mask_and_not(mask, c)
            if skipped is False:
                then(f)
                return
            f.mask = taken
            then(f)
            after = f.mask
            f.mask = skipped
            other(f)
            f.mask = mask_or(after, f.mask)

        return run

    def loop(self, node: Node) -> Callable[[Frame], None]:
        self.scopes.append(_Scope())
        init = update = None
        if node.type == "for_statement":
            initializer = node.child_by_field_name("initializer")
            if initializer is not None:
                init = (
                    self.local_declaration(initializer)
                    if initializer.type == "declaration"
                    else self.expression_effect(initializer)
                )
            cond_node = node.child_by_field_name("condition")
            cond = self.condition(cond_node) if cond_node is not None else None
            upd = node.child_by_field_name("update")
            update = self.expression_effect(upd) if upd is not None else None
        else:
            cond = self.condition(node.child_by_field_name("condition"))
        self.loop_depth += 1
        body = self.statement(node.child_by_field_name("body")) or _nothing
        self.loop_depth -= 1
        self.scopes.pop()
        test_first = node.type != "do_statement"
        where = self.where(node)

        def run(f):
            if init is not None:
                init(f)
            state = LoopState()
            f.loops.append(state)
            exited = False
            count = 0
            try:
                while True:
                    if cond is not None and (test_first or count > 0):
                        c = cond(f)
                        if is_uniform(c):
                            if not c:
                                exited = mask_or(exited, f.mask)
                                break
                        else:
                            exited = mask_or(exited, mask_and_not(f.mask, c))
                            f.mask = mask_and(f.mask, c)
                            if f.mask is False:
                                break
                    count += 1
                    f.budget[0] += 1
                    if count > MAX_LOOP_ITERATIONS:
                        raise EvaluationError(f"loop exceeded {MAX_LOOP_ITERATIONS} iterations", where)
                    if f.budget[0] > MAX_TOTAL_ITERATIONS:
                        raise EvaluationError(
                            f"loops exceeded {MAX_TOTAL_ITERATIONS} iterations in total in one evaluation", where
                        )
                    body(f)
                    f.mask = mask_or(f.mask, state.continued)
                    state.continued = False
                    if f.mask is False:
                        break
                    if update is not None:
                        update(f)
            finally:
                f.loops.pop()
            f.mask = mask_or(exited, state.broken)

        return run

    def switch(self, node: Node) -> Callable[[Frame], None]:
        """``switch`` with fall-through (GLSL 4.10 §6.2): each case label adds its lanes to the running set."""
        cond_node = node.child_by_field_name("condition")
        selector = self.expr(cond_node.named_children[0] if cond_node.type == "parenthesized_expression" else cond_node)
        if not (selector.type.is_integer and selector.type.is_scalar):
            raise self.error(f"switch needs an int or uint selector, not {selector.type}", cond_node)
        self.scopes.append(_Scope())
        self.switch_depth += 1
        groups: list[tuple[float | None, Callable]] = []  # (case value, None for default; statements)
        seen: set = set()
        for case in node.child_by_field_name("body").named_children:
            if case.type == "comment":
                continue
            if case.type != "case_statement":
                raise self.error("statements in a switch must follow a case label", case)
            value_node = case.child_by_field_name("value")
            value = None
            if value_node is not None:
                e = self.expr(value_node)
                if e.const is None or not e.type.is_integer or not e.type.is_scalar:
                    raise self.error("case label must be a constant integer expression", value_node)
                value = float(e.const[0])
            if value in seen:
                raise self.error("duplicate case label" if value is not None else "duplicate default label", case)
            seen.add(value)
            body = [c for c in case.named_children if c != value_node and c.type != "comment"]
            groups.append((value, _sequence([self.statement(c) for c in body])))
        self.switch_depth -= 1
        self.scopes.pop()
        values = [v for v, _ in groups if v is not None]
        ev = selector.ev

        def run(f):
            entry = f.mask
            sel = ev(f)[0]
            matched = False
            for v in values:
                matched = mask_or(matched, mask_and(entry, sel == v))
            state = LoopState(switch=True)
            f.loops.append(state)
            activated = False
            f.mask = False
            try:
                for value, statements in groups:
                    new = mask_and(entry, sel == value) if value is not None else _mask_minus(entry, matched)
                    new = _mask_minus(new, activated)
                    activated = mask_or(activated, new)
                    f.mask = mask_or(f.mask, new)
                    if f.mask is not False:
                        statements(f)
            finally:
                f.loops.pop()
            f.mask = mask_or(f.mask, state.broken)

        return run

    def expression_effect(self, node: Node) -> Callable[[Frame], None] | None:
        e = self.expr(node)
        if not e.effects:
            return None
        ev = e.ev

        def run(f):
            ev(f)

        return run

    def return_statement(self, node: Node) -> Callable[[Frame], None]:
        fn = self.function
        values = node.named_children
        if not values:
            if fn.ret != VOID:
                raise self.error(f"'{fn.name}' must return a {fn.ret}", node)

            def run_void(f):
                f.mask = False

            return run_void
        if fn.ret == VOID:
            raise self.error(f"void function '{fn.name}' cannot return a value", values[0])
        ev = self.convert(self.expr(values[0]), fn.ret, values[0]).ev

        def run(f):
            value = ev(f)
            f.ret = value if f.ret is None else blend(f.mask, value, f.ret)
            f.mask = False

        return run

    # --- expressions --------------------------------------------------------------------------------------

    def convert(self, e: Expr, t: Type, node: Node) -> Expr:
        """Implicit conversion of ``e`` to ``t`` (a no-op at run time: ints are held as floats)."""
        if e.type == t:
            return e
        if converts(e.type, t):
            return Expr(t, e.ev, e.const, e.effects)
        raise self.error(f"cannot convert {e.type} to {t}", node)

    def expr(self, node: Node) -> Expr:
        method = getattr(self, "x_" + node.type, None)
        if method is None:
            if node.type in ("cast_expression",):
                raise self.error("C-style casts are not GLSL; use a constructor such as float(x)", node)
            raise self.error(f"unsupported expression ({node.type.replace('_', ' ')})", node)
        return method(node)

    def x_parenthesized_expression(self, node: Node) -> Expr:
        inner = [c for c in node.named_children if c.type != "comment"]
        return self.expr(inner[0])

    def x_number_literal(self, node: Node) -> Expr:
        text = self.text(node)
        if text[:1] in "+-":  # tree-sitter-glsl folds a unary sign into some literals (e.g. `x * -1.0`)
            e = self.x_number_text(text[1:].strip(), node)
            return self.apply_unary(text[0], e, node)
        return self.x_number_text(text, node)

    def x_number_text(self, text: str, node: Node) -> Expr:
        if re.fullmatch(r"0[xX][0-9a-fA-F]+[uU]?", text):
            value, t = int(text.rstrip("uU"), 16), UINT if text[-1] in "uU" else INT
        elif re.fullmatch(r"[0-9]+[uU]?", text):
            digits = text.rstrip("uU")
            value = int(digits, 8) if len(digits) > 1 and digits[0] == "0" else int(digits)
            t = UINT if text[-1] in "uU" else INT
        elif re.fullmatch(r"(?:[0-9]+\.[0-9]*|\.[0-9]+|[0-9]+)(?:[eE][+-]?[0-9]+)?[fF]?", text):
            if not re.search(r"[.eEfF]", text):
                raise self.error(f"malformed number '{text}'", node)
            value, t = float(text.rstrip("fF")), FLOAT
            if not np.isfinite(value):
                raise self.error(f"number '{text}' is out of range", node)
        elif re.fullmatch(r".*(lf|LF)", text):
            raise self.error(f"unsupported feature: double-precision literal '{text}'", node)
        else:
            raise self.error(f"malformed number '{text}'", node)
        if t != FLOAT:
            if value >= 2**32:
                raise self.error(f"integer '{text}' is out of range", node)
            if t == INT and value >= 2**31:
                value -= 2**32  # GLSL: decimal/hex int literals wrap to 32 bits
        const = (np.float64(value),)  # numpy scalars: IEEE arithmetic, no Python ZeroDivisionError
        return Expr(t, lambda f: const, const)

    def x_true(self, node: Node) -> Expr:
        return Expr(BOOL, lambda f: (True,), (True,))

    def x_false(self, node: Node) -> Expr:
        return Expr(BOOL, lambda f: (False,), (False,))

    def x_identifier(self, node: Node) -> Expr:
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
        definition = self.macros[name]
        if definition is None:
            raise self.error(f"macro '{name}' has no value", node)
        if name in self.expanding:
            raise self.error(f"macro '{name}' expands to itself", node)
        text, value_node, src = definition
        expression, msrc = parse_expression(text, src, value_node)
        self.sources.append(msrc)
        self.expanding.append(name)
        try:
            return self.expr(expression)
        finally:
            self.sources.pop()
            self.expanding.pop()

    def x_comma_expression(self, node: Node) -> Expr:
        left = self.expr(node.child_by_field_name("left"))
        right = self.expr(node.child_by_field_name("right"))
        if not left.effects:
            return right
        a, b = left.ev, right.ev
        return Expr(right.type, lambda f: (a(f), b(f))[1], effects=True)

    # operators

    def x_unary_expression(self, node: Node) -> Expr:
        op = self.text(node.child_by_field_name("operator"))
        arg_node = node.child_by_field_name("argument")
        e = self.expr(arg_node)
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
            return self.make(t, lambda a: tuple(-x for x in a), [e], fresh=t.base == "float")
        if op == "~":
            if not t.is_integer:
                raise self.error(f"'~' needs an integer, not {t}", node)
            return self.make(t, lambda a: tuple(_bitwise(operator.xor)(x, -1.0) for x in a), [e])
        raise self.error(f"unsupported operator '{op}'", node)

    def binary_types(self, op: str, a: Type, b: Type, node: Node) -> tuple[Type, Callable]:
        """Result type and component function of an arithmetic operator (§5.9)."""
        bad = self.error(f"operator '{op}' cannot be applied to {a} and {b}", node)
        if a.is_array or b.is_array or a.base in ("bool", "void") or b.base in ("bool", "void"):
            raise bad
        integer = a.is_integer and b.is_integer
        base = ("uint" if "uint" in (a.base, b.base) else "int") if integer else "float"
        if op == "%" and not integer:
            raise self.error("operator '%' needs integers (use mod() for floats)", node)
        if op in _BITWISE and not integer:
            raise self.error(f"operator '{op}' needs integers", node)
        fn = _BITWISE[op] if op in _BITWISE else (_INT_ARITH if integer else _ARITH)[op]
        if op == "*" and (a.is_matrix or b.is_matrix) and not (a.is_scalar or b.is_scalar):
            return self.linear_algebra(a, b, bad)
        if op in ("<<", ">>"):
            if not (b.is_scalar or b.rows == a.rows):
                raise bad
            if b.is_scalar:
                return a.with_base(base), lambda x, y: tuple(fn(p, y[0]) for p in x)
            return a.with_base(base), lambda x, y: tuple(map(fn, x, y))
        if a.is_scalar and not b.is_scalar:
            return b.with_base(base), lambda x, y: tuple(fn(x[0], q) for q in y)
        if b.is_scalar and not a.is_scalar:
            return a.with_base(base), lambda x, y: tuple(fn(p, y[0]) for p in x)
        if a.rows != b.rows or a.cols != b.cols:
            raise bad
        if a.is_scalar:
            return a.with_base(base), lambda x, y: (fn(x[0], y[0]),)
        return a.with_base(base), lambda x, y: tuple(map(fn, x, y))

    def linear_algebra(self, a: Type, b: Type, bad: Exception) -> tuple[Type, Callable]:
        if a.is_matrix and b.is_matrix:
            if a.cols != b.rows:
                raise bad
            n, m, k = a.rows, b.cols, a.cols

            def matmul(x, y):
                return tuple(_sum(x[p * n + i] * y[j * k + p] for p in range(k)) for j in range(m) for i in range(n))

            return Type("float", n, m), matmul
        if a.is_matrix:  # mat * column vector
            if b.rows != a.cols or b.cols != 1:
                raise bad
            n, k = a.rows, a.cols
            return Type("float", n), lambda x, y: tuple(_sum(x[p * n + i] * y[p] for p in range(k)) for i in range(n))
        if a.rows != b.rows or a.cols != 1:  # row vector * mat
            raise bad
        n, m = b.rows, b.cols
        return Type("float", m), lambda x, y: tuple(_sum(x[i] * y[j * n + i] for i in range(n)) for j in range(m))

    def arithmetic(self, op: str, left: Expr, right: Expr, node: Node) -> Expr:
        t, fn = self.binary_types(op, left.type, right.type, node)
        componentwise = not (op == "*" and (left.type.is_matrix or right.type.is_matrix))
        if t.base == "float" and componentwise and op in _UFUNCS:
            # Reuse a temporary operand (not broadcast over the other's components) as the output.
            if left.fresh and left.type.size == t.size:
                fn = _in_place(_UFUNCS[op], 0)
            elif right.fresh and right.type.size == t.size:
                fn = _in_place(_UFUNCS[op], 1)
        if op in ("*", "/") and t.base == "float" and not t.is_matrix and componentwise:
            zero = self.constant_zeros(op, left, right, t)
            if all(zero) and not (left.effects or right.effects):
                const = (_ZERO,) * t.size
                return Expr(t, lambda f: const, const)
            if any(zero):
                inner = fn
                fn = lambda x, y: tuple(_ZERO if z else v for z, v in zip(zero, inner(x, y), strict=True))  # noqa: E731
        return self.make(t, fn, [left, right], fresh=t.base == "float")

    @staticmethod
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

    def x_binary_expression(self, node: Node) -> Expr:
        op_node = node.child_by_field_name("operator")
        op = self.text(op_node)
        if op == "||" and self.has_xor(node):
            return self.or_xor_chain(node)
        if op in ("&&", "||"):
            return self.logical(op, node.child_by_field_name("left"), node.child_by_field_name("right"), node)
        left = self.expr(node.child_by_field_name("left"))
        right = self.expr(node.child_by_field_name("right"))
        if op in _ARITH or op in _BITWISE or op == "%":
            return self.arithmetic(op, left, right, node)
        if op in _COMPARE:
            a, b = left.type, right.type
            if not (a.is_scalar and b.is_scalar and a.is_numeric and b.is_numeric):
                raise self.error(f"operator '{op}' needs scalar numbers, not {a} and {b} (use lessThan etc.)", node)
            fn = _COMPARE[op]
            return self.make(BOOL, lambda x, y: (fn(x[0], y[0]),), [left, right])
        if op in ("==", "!="):
            return self.equality(op, left, right, node)
        raise self.error(f"unsupported operator '{op}'", node)

    def equality(self, op: str, left: Expr, right: Expr, node: Node) -> Expr:
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
        while node.type == "binary_expression" and self.text(node.child_by_field_name("operator")) == "||":
            if node.child_by_field_name("operator").start_byte in self.source.xor_offsets:
                return True
            node = node.child_by_field_name("left")
        return False

    def or_xor_chain(self, node: Node) -> Expr:
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

    def x_conditional_expression(self, node: Node) -> Expr:
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
            p = a(f) if f.mask is not False else _zeros(yes.type)
            f.mask = mask_and_not(saved, x)
            q = b(f) if f.mask is not False else _zeros(yes.type)
            f.mask = saved
            return tuple(map(np.where, [x] * yes.type.size, p, q))

        return Expr(yes.type, run, effects=cond.effects or masked)

    # lvalues, assignment, ++/--

    def lvalue(self, node: Node) -> LValue:
        kind = node.type
        if kind == "parenthesized_expression":
            return self.lvalue(node.named_children[0])
        if kind == "identifier":
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
            return LValue(var, var.type, _Path(tuple(range(var.type.size))))
        if kind == "field_expression":
            base = self.lvalue(node.child_by_field_name("argument"))
            picks = self.swizzle(base.type, node.child_by_field_name("field"))
            if len(set(picks)) != len(picks):
                raise self.error("cannot assign to a swizzle that repeats a component", node)
            return LValue(
                base.var,
                Type(base.type.base, len(picks)) if len(picks) > 1 else Type(base.type.base),
                base.path.map(lambda idx: tuple(idx[p] for p in picks)),
            )
        if kind == "subscript_expression":
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
                        k = int(i)
                        if 0 <= k < len(groups):
                            out.append((cond, tuple(idx[p] for p in groups[k])))
                        continue
                    for k, group in enumerate(groups):
                        hit = i == k
                        out.append((hit if cond is None else np.logical_and(cond, hit), tuple(idx[p] for p in group)))
                return out

            return LValue(base.var, element, _Path(resolve=resolve))
        raise self.error("expression is not assignable", node)

    def x_assignment_expression(self, node: Node) -> Expr:
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

    def x_update_expression(self, node: Node) -> Expr:
        op_node = node.child_by_field_name("operator")
        op = self.text(op_node)
        arg = node.child_by_field_name("argument")
        prefix = op_node.start_byte < arg.start_byte
        if not prefix and arg.type == "unary_expression":
            # tree-sitter-glsl parses -x++ as (-x)++; GLSL's postfix operators bind tighter: -(x++).
            inner = self.update(arg.child_by_field_name("argument"), op, False, node)
            return self.apply_unary(self.text(arg.child_by_field_name("operator")), inner, arg)
        return self.update(arg, op, prefix, node)

    def apply_unary(self, op: str, e: Expr, node: Node) -> Expr:
        if op == "-" and e.type.is_numeric:
            return self.make(e.type, lambda a: tuple(-x for x in a), [e])
        if op == "+" and e.type.is_numeric:
            return e
        if op == "!" and e.type == BOOL:
            return self.make(BOOL, lambda a: (np.logical_not(a[0]),), [e])
        raise self.error(f"unary '{op}' cannot be applied to {e.type}", node)

    def update(self, arg: Node, op: str, prefix: bool, node: Node) -> Expr:
        target = self.lvalue(arg)
        t = target.type
        if not (t.is_numeric or t.is_matrix) or t.is_array:
            raise self.error(f"'{op}' needs a number, not {t}", node)
        delta = 1.0 if op == "++" else -1.0

        def run(f):
            old = target.get(f)
            new = tuple(x + delta for x in old)
            target.set(f, new)
            return new if prefix else old

        return Expr(t, run, effects=True)

    # swizzles and subscripts

    def swizzle(self, t: Type, field_node: Node) -> list[int]:
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

    def x_field_expression(self, node: Node) -> Expr:
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
            k = int(index.const[0])
            if not 0 <= k < count:
                raise self.error(f"index {k} is out of range for {t}", index_node)
            return element, groups, k
        return element, groups, index

    def x_subscript_expression(self, node: Node) -> Expr:
        base = self.expr(node.child_by_field_name("argument"))
        element, groups, index = self.subscript(base.type, node)
        if isinstance(index, int):
            group = groups[index]
            return self.make(element, lambda a: tuple(a[p] for p in group), [base])
        zeros = _zeros(element)
        return self.make(
            element, lambda a, i: select(i[0], [tuple(a[p] for p in g) for g in groups], zeros), [base, index]
        )

    # calls

    def x_call_expression(self, node: Node) -> Expr:
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
        arity = builtins.ARITY[name]
        if len(args) not in arity:
            expected = " or ".join(str(n) for n in arity)
            raise self.error(f"wrong number of arguments to '{name}': expected {expected}, got {len(args)}", fnode)
        self.uses.add(name)
        types = [a.type for a in args]
        if name == "modf":
            return self.modf(args, arg_nodes, fnode)
        overrides = self.constant_overrides(name, args)
        resolved = builtins.resolve(name, types, [] if overrides else [a.fresh for a in args])
        if resolved is None:
            raise self.error(f"no matching overload for '{name}({', '.join(map(str, types))})'", fnode)
        t, impl = resolved
        if overrides:
            impl = _override(impl, overrides, t.size)
        if name == "pow":
            x, y = args
            n = t.size
            fns = [
                builtins.pow_impl(
                    None if x.const is None else x.const[i if len(x.const) > 1 else 0],
                    None if y.const is None else y.const[i if len(y.const) > 1 else 0],
                )
                for i in range(n)
            ]
            if any(fn is not builtins.pow_runtime for fn in fns):

                def impl(a, b, fns=fns):  # noqa: E306
                    return tuple(fn(a[i], b[i]) for i, fn in enumerate(fns))

        # an override may pass an argument through: the result is then no temporary of ours
        fresh = name in builtins.FRESH and t.base == "float" and not overrides
        return self.make(t, impl, args, fresh=fresh)

    @staticmethod
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

    def modf(self, args: list[Expr], arg_nodes: list[Node], fnode: Node) -> Expr:
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
                zeros = _zeros(p.type)
                evs.append(target.get if p.qualifier == "inout" else (lambda f, z=zeros: z))
                outs.append((target, k))
        ret_zeros = _zeros(fn.ret)

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
        args = [self.expr(a) for a in arg_nodes]
        if not args:
            raise self.error(f"constructor {t} needs arguments", node)
        for a, an in zip(args, arg_nodes, strict=False):
            if a.type.is_array or a.type == VOID:
                raise self.error(f"cannot construct {t} from {a.type}", an)
        bases = [a.type.base for a in args]
        convert = _convert_component
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
                    a[j * src_t.rows + i] if i < src_t.rows and j < src_t.cols else (1.0 if i == j else 0.0)
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
                        convert(a[0], src, "float") if i == j else 0.0 for j in range(cols) for i in range(rows)
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
        if len(arg_nodes) != t.length:
            raise self.error(f"array constructor {t} needs {t.length} arguments, got {len(arg_nodes)}", node)
        args = [self.convert(self.expr(a), t.element, a) for a in arg_nodes]
        return self.make(t, lambda *values: tuple(x for v in values for x in v), args)


def _sum(terms):
    it = iter(terms)
    total = next(it)
    for x in it:
        total = total + x
    return total


def _nothing(f: Frame) -> None:
    return None


def _sequence(stmts: list) -> Callable[[Frame], None]:
    stmts = [s for s in stmts if s is not None]
    if not stmts:
        return _nothing
    if len(stmts) == 1:
        return stmts[0]

    def run(f):
        for s in stmts:
            s(f)
            if f.mask is False:
                return

    return run


def _break(f: Frame) -> None:
    state = f.loops[-1]
    state.broken = mask_or(state.broken, f.mask)
    f.mask = False


def _continue(f: Frame) -> None:
    state = next(s for s in reversed(f.loops) if not s.switch)
    state.continued = mask_or(state.continued, f.mask)
    f.mask = False


def _mask_minus(mask, other):
    """Lanes of ``mask`` not in ``other``."""
    if other is False or mask is False:
        return mask
    if other is None:
        return False
    return mask_and_not(mask, other)


class Program:
    """A compiled shader: ``brdf(L, V, N, X, Y, uniforms)`` evaluates its ``BRDF`` function in float64.

    ``uniforms`` maps each uniform's name to its GLSL type name; ``uses`` is the set of built-in
    functions called and uniforms read by the shader.
    """

    def __init__(self, compiler: Compiler, entry: Function) -> None:
        self._entry = entry
        self._inits = compiler.global_inits
        self._nglobals = compiler.globals_count
        self._uniforms = dict(compiler.uniforms)
        self.uniforms: dict[str, str] = {name: str(t) for name, (t, *_) in compiler.uniforms.items()}
        self.uses: frozenset[str] = frozenset(compiler.uses)
        self.path = compiler.path
        self._used_params = sorted(entry.used_params)

    def _uniform_value(self, name: str, t: Type, value) -> tuple:
        where = f"{self.path}: uniform '{name}'"
        if t.base == "bool":
            arr = np.asarray(value)
            if arr.dtype != bool and not np.issubdtype(arr.dtype, np.number):
                raise EvaluationError(f"expected a bool value, got {value!r}", where)
            comp = bool(arr) if arr.ndim == 0 else arr != 0
            return (comp,) * t.size if t.is_scalar else tuple(arr[..., i] != 0 for i in range(t.rows))
        try:
            arr = np.asarray(value, dtype=np.float64)
        except (TypeError, ValueError):
            raise EvaluationError(f"expected a number, got {value!r}", where) from None
        if t.is_integer:
            arr = np.trunc(arr)
        if t.is_scalar:
            return (np.float64(arr) if arr.ndim == 0 else arr,)
        if arr.ndim == 0 or arr.shape[-1] != t.size:
            raise EvaluationError(f"expected {t.size} components for a {t}, got shape {arr.shape}", where)
        return tuple(arr[..., i] for i in range(t.size))

    def brdf(self, L, V, N, X, Y, uniforms: Mapping[str, object] | None = None) -> np.ndarray:
        """Evaluate ``vec3 BRDF(L, V, N, X, Y)`` for (..., 3) direction arrays; returns (..., 3) float64."""
        uniforms = uniforms or {}
        directions = [np.asarray(d, dtype=np.float64) for d in (L, V, N, X, Y)]
        for name, d in zip("LVNXY", directions, strict=False):
            if d.ndim == 0 or d.shape[-1] != 3:
                raise EvaluationError(f"{name} must have shape (..., 3), got {d.shape}", self.path)
        globals_ = [None] * self._nglobals
        for name, (t, slot, caller, default) in self._uniforms.items():
            if name in uniforms:
                globals_[slot] = self._uniform_value(name, t, uniforms[name])
            elif caller:
                raise EvaluationError(f"no value given for uniform '{name}'", self.path)
            else:
                globals_[slot] = default  # its initializer, else zero as OpenGL does
        budget = [0]
        entry = self._entry
        frame = Frame(entry.nslots, globals_, None, budget)
        for k in self._used_params:
            d = directions[k]
            frame.slots[entry.param_slots[k]] = (d[..., 0], d[..., 1], d[..., 2])
        with np.errstate(all="ignore"):
            init_frame = Frame(0, globals_, None, budget)
            try:
                for init in self._inits:
                    init(init_frame)
                entry.body(frame)
            except RecursionError:  # closures nest like the syntax tree
                raise EvaluationError("shader is nested too deeply to evaluate", self.path) from None
        result = frame.ret if frame.ret is not None else (0.0, 0.0, 0.0)
        shapes = [d.shape[:-1] for d in directions]
        for value in globals_:
            shapes.extend(np.shape(c) for c in value or ())
        shape = np.broadcast_shapes(*shapes, *(np.shape(c) for c in result))
        out = np.empty(shape + (3,))
        for i, c in enumerate(result):
            out[..., i] = c
        return out


_SIGNATURE = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"


def compile_shader(
    source: str,
    *,
    path: str = "<shader>",
    first_line: int = 1,
    first_column: int = 1,
    uniforms: Mapping[str, str] | None = None,
) -> Program:
    """Compile the GLSL text of a ``.brdf`` shader section into a :class:`Program`.

    ``first_line``/``first_column`` place the text's first character in the file ``path`` so that
    every error is reported as ``FILE:LINE:COL`` of the file; ``uniforms`` declares the parameters
    (name → ``"float"``, ``"bool"`` or ``"vec3"``) as BRDF Explorer does. Raises
    :class:`~brdfnorm.errors.BrdfFileError` for any problem in the text.
    """
    try:
        compiler = Compiler(source, path, first_line, first_column, uniforms or {})
        compiler.compile()
    except RecursionError:  # the compiler recurses along the syntax tree
        raise BrdfFileError("shader is nested too deeply", path, first_line, first_column) from None
    for fn, node, src in compiler.global_calls:
        if fn.body_node is None:
            raise src.error(f"function '{fn.signature()}' is declared but never defined", node)
    overloads = compiler.functions.get("BRDF")
    if not overloads:
        raise compiler.src.error(f"no BRDF function: the shader must define {_SIGNATURE}", None)
    for fn in overloads:
        if fn.ret == VEC3 and [p.type for p in fn.params] == [VEC3] * 5 and fn.body_node is not None:
            if any(p.qualifier != "in" for p in fn.params):
                raise fn.source.error(f"BRDF's parameters must be 'in': expected {_SIGNATURE}", fn.node)
            return Program(compiler, fn)
    fn = overloads[0]
    if fn.body_node is None:
        raise fn.source.error(f"BRDF is declared but never defined: expected {_SIGNATURE}", fn.node)
    raise fn.source.error(f"BRDF has the wrong signature '{fn.signature()}': expected {_SIGNATURE}", fn.node)
