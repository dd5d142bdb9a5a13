"""The translation unit: functions, global and local declarations, scopes, the preprocessor, call checks.

Functions are declared in a first pass (so calls may precede definitions, GLSL 4.10 §6.1) and compiled in
source order in a second one with the globals and ``#define`` lines. Once every body is compiled, the call
graph is checked: every callee defined, no recursion (§6.1.1), and a bounded size once calls are inlined
(:data:`..limits.MAX_INLINED_NODES`).
"""

from __future__ import annotations

from collections.abc import Iterator

from ..limits import MAX_INLINED_NODES
from ..names import is_reserved
from ..parser import PREPROCESSOR_NODES
from ..runtime import Frame
from ..types import VOID, Type, parse_type_name
from .base import CompilerBase
from .statements import sequence
from .values import Function, Node, Param, Scope, Statement, Var, zeros

#: Top-level node type -> method (function definitions, declarations, preprocessor lines, stray ';').
TOP_LEVEL_RULES = {
    "function_definition": "compile_function",
    "declaration": "top_level_declaration",
    "comment": "skip",
    "struct_specifier": "refuse_struct",
    "expression_statement": "top_level_empty_statement",
    **{kind: "preprocessor" for kind in PREPROCESSOR_NODES},
}
#: Preprocessor node type -> method; any other directive is refused.
PREPROCESSOR_RULES = {
    "preproc_def": "define",
    "preproc_function_def": "refuse_function_macro",
    "preproc_extension": "skip",
    "preproc_call": "directive",
}
#: Directives with no effect on a shader's value (``#pragma`` lines are blanked before parsing).
_IGNORED_DIRECTIVES = ("#version", "#extension", "#pragma", "#line")


class DeclarationsMixin(CompilerBase):
    """Compiles the translation unit and the declarations in it."""

    def compile(self) -> None:
        """Compile the whole shader: signatures first, then globals, macros and bodies in source order."""
        root = self.tree.root_node
        for node in root.named_children:  # pass 1: function signatures, so calls may precede definitions
            if node.type == "function_definition":
                self.declare_function(node, node.child_by_field_name("declarator"), defined=True)
            elif node.type == "declaration" and self.is_prototype(node):
                self.declare_function(node, node.child_by_field_name("declarator"), defined=False)
        for node in root.named_children:  # pass 2: globals, macros and bodies in source order
            self.dispatch(TOP_LEVEL_RULES, node, self.unexpected_at_global_scope)
        self.check_calls()

    def unexpected_at_global_scope(self, node: Node):
        """The error for a node that cannot stand at global scope."""
        return self.error(f"unexpected {node.type.replace('_', ' ')} at global scope", node)

    def skip(self, node: Node) -> None:
        """Comments, ``#extension`` lines: nothing to compile."""

    def refuse_struct(self, node: Node) -> None:
        """Structs are not supported."""
        raise self.error("unsupported feature: structs", node)

    def top_level_empty_statement(self, node: Node) -> None:
        """A stray ``;`` at global scope is allowed; any other expression is not."""
        if self.text(node).strip() != ";":
            raise self.unexpected_at_global_scope(node)

    def top_level_declaration(self, node: Node) -> None:
        """A global declaration (prototypes were handled in the first pass)."""
        if not self.is_prototype(node):
            self.global_declaration(node)

    def is_prototype(self, node: Node) -> bool:
        """Whether a declaration declares a function (``float f(float x);``)."""
        declarator = node.child_by_field_name("declarator")
        return declarator is not None and declarator.type == "function_declarator"

    # --- the preprocessor ---------------------------------------------------------------------------------

    def preprocessor(self, node: Node) -> None:
        """A preprocessor line, at global scope or in a function body."""
        self.dispatch(PREPROCESSOR_RULES, node, self.unsupported_directive)

    def unsupported_directive(self, node: Node):
        """The error for ``#if``, ``#include`` and the other directives not supported."""
        words = self.text(node).split()
        return self.error(f"unsupported preprocessor directive {words[0] if words else node.type}", node)

    def define(self, node: Node) -> None:
        """An object-like ``#define NAME VALUE``: the value is parsed as an expression where NAME is used.

        Macros are expanded where an identifier is compiled as an expression; a macro named like a keyword,
        a type or a function would be expanded nowhere (``#define return discard``), so it is refused.
        """
        name_node = node.child_by_field_name("name")
        name = self.text(name_node)
        if is_reserved(name) or name in self.functions:
            raise self.error(
                f"unsupported feature: '#define {name}' redefines a GLSL keyword, type or function", name_node
            )
        value = node.child_by_field_name("value")
        # The body as written: it is parsed anew where used, with the parser's rewrites (e.g. of '^^') redone.
        self.macros[name] = (
            (self.source.original_text_of(value).strip(), value, self.source) if value is not None else None
        )

    def refuse_macro_name(self, name: str, node: Node) -> None:
        """A declaration of a name that is a macro here: the preprocessor would expand it (unsupported)."""
        if name in self.macros:
            raise self.error(
                f"unsupported feature: '{name}' is declared while a macro of that name is defined "
                "(the preprocessor would replace it here)",
                node,
            )

    def refuse_function_macro(self, node: Node) -> None:
        """Function-like macros are not supported."""
        name = self.text(node.child_by_field_name("name"))
        raise self.error(f"unsupported feature: function-like macro '{name}'", node)

    def directive(self, node: Node) -> None:
        """``#undef`` and the directives without effect; others are refused."""
        directive = self.text(node.child_by_field_name("directive")).strip()
        argument = node.child_by_field_name("argument")
        if directive == "#undef" and argument is not None:
            self.macros.pop(self.text(argument).strip(), None)
        elif directive not in _IGNORED_DIRECTIVES:
            raise self.error(f"unsupported preprocessor directive {directive}", node)

    # --- functions ----------------------------------------------------------------------------------------

    def qualifiers(self, node: Node) -> set[str]:
        """The qualifier words of a declaration (``const``, ``uniform``, ``in``, ``layout``, ...)."""
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
        """The parameters of a function declarator (``(void)`` is none)."""
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
        """Declare a function or prototype; a definition fills in an earlier prototype."""
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
        """The :class:`Function` a definition node declared in the first pass."""
        declarator = node.child_by_field_name("declarator")
        name = self.text(declarator.child_by_field_name("declarator"))
        body = node.child_by_field_name("body")
        return next(fn for fn in self.functions[name] if fn.body_node is not None and fn.body_node == body)

    def compile_function(self, node: Node) -> None:
        """Compile a function body into its :class:`Function`, counting the nodes it takes."""
        fn = self.find_defined(node)
        self.function, self.nslots, self.loop_depth, self.switch_depth = fn, 0, 0, 0
        start = self.compiled_nodes
        self.scopes.append(Scope())
        fn.param_slots = []
        for index, p in enumerate(fn.params):
            slot = self.new_slot()
            fn.param_slots.append(slot)
            self.reserve_components(p.type, fn.node)
            if p.name is not None:
                self.refuse_macro_name(p.name, fn.node)
                readonly = "const parameter" if p.const else None
                self.scopes[-1][p.name] = Var(p.name, p.type, slot, False, readonly=readonly, param_index=index)
        body = self.block(fn.body_node, new_scope=False)
        self.scopes.pop()
        fn.body = body
        fn.nslots = self.nslots
        fn.size = self.compiled_nodes - start
        self.function = None

    def check_calls(self) -> None:
        """Every callee defined, no recursion, and every function's inlined size bounded."""
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
            self.inline(fn)

        for overloads in self.functions.values():
            for fn in overloads:
                if id(fn) not in state:
                    visit(fn, [])
        total = 0  # the global initializers run once per evaluation, before BRDF
        for callee, node, src in self.global_calls:
            total += callee.inlined_size
            if total > MAX_INLINED_NODES:
                raise src.error(
                    f"shader too large: the global initializers run more than {MAX_INLINED_NODES} nodes per "
                    f"evaluation with their calls inlined (this call of '{callee.name}' alone runs "
                    f"{callee.inlined_size})",
                    node,
                )

    def inline(self, fn: Function) -> None:
        """``fn.inlined_size``: its own nodes plus its callees' inlined sizes, one per call site (callees done).

        A call tree in which each function calls the previous one twice doubles at each level: it is
        refused here, at the call that crosses :data:`..limits.MAX_INLINED_NODES`, instead of running
        2**depth calls per evaluation.
        """
        total = fn.size
        for callee, node, src in fn.calls:
            total += callee.inlined_size
            if total > MAX_INLINED_NODES:
                raise src.error(
                    f"shader too large: '{fn.name}' runs more than {MAX_INLINED_NODES} nodes per evaluation with "
                    f"its calls inlined (this call of '{callee.name}' alone runs {callee.inlined_size})",
                    node,
                )
        fn.inlined_size = total

    # --- variables ----------------------------------------------------------------------------------------

    def declarators(self, node: Node) -> Iterator[tuple[Node, int | None, Node | None]]:
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
        """A global declaration: uniforms (with their defaults) and global variables."""
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

    def local_declaration(self, node: Node) -> Statement | None:
        """A declaration in a function body; returns the initializing closure."""
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
        return sequence(runs)

    def variable(self, name_node: Node, name: str, t: Type, value: Node | None, const: bool, is_global: bool):
        """Declare a variable in the current scope; return the initializing closure (or None)."""
        if t == VOID:
            raise self.error("variables cannot be void", name_node)
        self.refuse_macro_name(name, name_node)
        self.reserve_components(t, name_node)
        init = self.convert(self.expr(value), t, value) if value is not None else None
        if const and (init is None or init.const is None):
            raise self.error(f"const variable '{name}' needs a constant initializer", value or name_node)
        effective = init.const if init is not None and (const or name not in self.written) else None
        slot = self.new_global() if is_global else self.new_slot()
        var = Var(name, t, slot, is_global, const=effective, readonly="const" if const else None)
        self.scopes[-1][name] = var
        default = zeros(t)
        ev = init.ev if init is not None else (lambda f: default)
        if is_global:
            self.global_defaults[slot] = default  # what a read before the initializer ran sees (a call in it)
            self.global_inits.append(lambda f: f.globals.__setitem__(slot, ev(f)))
            return None

        def run(f: Frame) -> None:
            f.slots[slot] = ev(f)

        return run
