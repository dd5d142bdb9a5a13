"""The compiler's state and the helpers every part uses: symbol tables, errors, dispatch, budgets.

Each syntactic category (top-level items, statements, expressions, assignable expressions, preprocessor
lines) has a table from tree-sitter node type to the method compiling it; :meth:`CompilerBase.dispatch`
is the one place that looks a node up, and counts it against :data:`..limits.MAX_COMPILED_NODES`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from ...errors import BrdfFileError
from ..limits import MAX_ARRAY_LENGTH, MAX_COMPILED_NODES, MAX_VARIABLE_COMPONENTS
from ..parser import Source, parse
from ..types import Type, converts, parse_type_name, unsupported_type_feature
from .folds import written_names
from .values import Expr, Function, Node, Scope, Statement, Var, zeros


class CompilerBase:
    """Symbol tables, the source stack (macro bodies are parsed on their own), errors and budgets."""

    def __init__(self, source: str, path: str, first_line: int, first_column: int, uniforms: Mapping[str, str]):
        self.tree, self.src = parse(source, path, first_line, first_column)
        self.path = path
        self.sources: list[Source] = [self.src]
        self.scopes: list[Scope] = [Scope()]  # scopes[0]: globals
        self.globals_count = 0
        self.global_inits: list[Statement] = []
        self.global_defaults: dict[int, tuple] = {}  # slot -> zeros, what a global holds before its initializer
        # name -> (type, slot, declared by the caller, value when none is given)
        self.uniforms: dict[str, tuple[Type, int, bool, tuple]] = {}
        self.functions: dict[str, list[Function]] = {}
        self.macros: dict[str, tuple[str, Node, Source] | None] = {}
        self.macro_bodies: dict[tuple[int, int], tuple[Node, Source]] = {}  # parsed macro bodies, per definition
        self.uses: set[str] = set()
        self.function: Function | None = None
        self.nslots = 0
        self.loop_depth = 0
        self.switch_depth = 0
        self.written = written_names(self.tree.root_node, self.text)
        self.global_calls: list[tuple[Function, Node, Source]] = []
        self.expanding: list[str] = []
        self.compiled_nodes = 0  # nodes dispatched so far, macro expansions included
        self.components = 0  # components of every variable declared so far (one direction's state)
        for name, kind in uniforms.items():
            t = parse_type_name(kind)
            if t is None or t.length is not None or t.base == "void":
                raise BrdfFileError(f"unsupported uniform type '{kind}' for '{name}'", path, first_line, first_column)
            self.declare_uniform(name, t, None, caller=True)

    @property
    def source(self) -> Source:
        """The text being compiled now: the shader, or the body of the macro being expanded."""
        return self.sources[-1]

    def text(self, node: Node) -> str:
        """The source text of ``node``."""
        return self.source.text_of(node)

    def error(self, message: str, node: Node | None) -> BrdfFileError:
        """A :class:`BrdfFileError` at ``node``'s FILE:LINE:COL."""
        return self.source.error(message, node)

    def where(self, node: Node) -> str:
        """``FILE:LINE:COL`` of ``node``, for errors raised at run time."""
        line, column = self.source.position(node)
        return f"{self.path}:{line}:{column}"

    def dispatch(self, rules: Mapping[str, str], node: Node, unknown: Callable[[Node], BrdfFileError]):
        """Compile ``node`` with the method ``rules`` names for its type; ``unknown`` builds the error else."""
        self.compiled_nodes += 1
        if self.compiled_nodes > MAX_COMPILED_NODES:
            raise self.error(
                f"shader too large: more than {MAX_COMPILED_NODES} syntax nodes to compile "
                "(macro expansions counted each time)",
                node,
            )
        method = rules.get(node.type)
        if method is None:
            raise unknown(node)
        return getattr(self, method)(node)

    def lookup(self, name: str) -> Var | None:
        """The innermost variable named ``name`` in scope, or None."""
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return None

    def declare_uniform(
        self, name: str, t: Type, node: Node | None, caller: bool = False, default: tuple | None = None
    ) -> None:
        """Declare a uniform (a parameter from the ``.brdf`` file when ``caller``), once per name and type."""
        if name in self.uniforms:
            previous = self.uniforms[name][0]
            if previous != t:
                raise self.error(f"uniform '{name}' declared as {t}, but the parameter is {previous}", node)
            return
        self.reserve_components(t, node)
        slot = self.new_global()
        self.uniforms[name] = (t, slot, caller, default if default is not None else zeros(t))
        self.scopes[0][name] = Var(name, t, slot, True, readonly="uniform")

    def new_global(self) -> int:
        """A new slot in the globals list."""
        self.globals_count += 1
        return self.globals_count - 1

    def new_slot(self) -> int:
        """A new slot in the current function's frame."""
        self.nslots += 1
        return self.nslots - 1

    def reserve_components(self, t: Type, node: Node) -> None:
        """Count a variable's components against :data:`..limits.MAX_VARIABLE_COMPONENTS` (memory per lane)."""
        self.components += t.size
        if self.components > MAX_VARIABLE_COMPONENTS:
            raise self.error(
                f"variables too large: the shader's variables hold more than {MAX_VARIABLE_COMPONENTS} "
                f"components per direction ({t} adds {t.size})",
                node,
            )

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

    def convert(self, e: Expr, t: Type, node: Node) -> Expr:
        """Implicit conversion of ``e`` to ``t`` (a no-op at run time: ints are held as floats)."""
        if e.type == t:
            return e
        if converts(e.type, t):
            return Expr(t, e.ev, e.const, e.effects)
        raise self.error(f"cannot convert {e.type} to {t}", node)

    def type_of(self, node: Node) -> Type:
        """The type a type specifier names; unsupported and unknown types are errors."""
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
        """The constant, positive, bounded length of an array declarator (or array constructor)."""
        size = declarator.child_by_field_name("size") or declarator.child_by_field_name("index")
        if size is None:
            raise self.error("arrays need an explicit constant size", declarator)
        e = self.expr(size)
        if e.const is None or not e.type.is_integer or not e.type.is_scalar:
            raise self.error("array size must be a constant integer expression", size)
        value = float(e.const[0])
        if not np.isfinite(value):
            raise self.error("array size must be a finite constant integer expression", size)
        n = int(value)
        if n <= 0:
            raise self.error("array size must be positive", size)
        if n > MAX_ARRAY_LENGTH:
            raise self.error(f"array size {n} exceeds the supported maximum of {MAX_ARRAY_LENGTH}", size)
        return n
