"""Statements (GLSL 4.10 §6): blocks, declarations, ``if``, loops, ``switch``, jumps and ``return``.

Each statement compiles to a closure ``run(frame)``. Per-lane control flow runs under lane masks
(:mod:`..runtime`); a condition that is the same in every lane runs only the branch taken. Loops are
bounded at run time by :data:`..limits.MAX_LOOP_ITERATIONS` per loop, and per evaluation by
:data:`..limits.MAX_TOTAL_ITERATIONS` iterations and :data:`..limits.MAX_LOOP_NODES` nodes run in loops
(calls inlined).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from ...errors import EvaluationError
from ..limits import MAX_LOOP_ITERATIONS, MAX_LOOP_NODES, MAX_TOTAL_ITERATIONS
from ..parser import PREPROCESSOR_NODES
from ..runtime import Frame, LoopState, blend, is_uniform, mask_and, mask_and_not, mask_or
from ..types import BOOL, VOID
from .base import CompilerBase
from .values import Node, Scope, Statement

#: Statement node type -> method.
STATEMENT_RULES = {
    "compound_statement": "block",
    "comment": "no_statement",
    "declaration": "declaration_statement",
    "expression_statement": "expression_statement",
    "if_statement": "if_statement",
    "for_statement": "loop",
    "while_statement": "loop",
    "do_statement": "loop",
    "return_statement": "return_statement",
    "break_statement": "break_statement",
    "continue_statement": "continue_statement",
    "switch_statement": "switch",
    "goto_statement": "refuse_jump",
    "labeled_statement": "refuse_jump",
    **{kind: "preprocessor_statement" for kind in PREPROCESSOR_NODES},
}


def nothing(f: Frame) -> None:
    """The empty statement."""
    return None


def sequence(stmts: list) -> Statement:
    """Statements run in order, stopping when no lane is left active (after return, break, continue)."""
    stmts = [s for s in stmts if s is not None]
    if not stmts:
        return nothing
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


@dataclass(frozen=True)
class LoopParts:
    """A compiled loop's pieces: initializer, condition (None: none), update, body, whether the condition is
    tested before the first iteration (not for ``do``), its place, and what one iteration costs."""

    init: Statement | None
    cond: Callable[[Frame], object] | None
    update: Statement | None
    body: Statement
    test_first: bool
    where: str
    own_nodes: int
    callees: list

    def cost(self) -> int:
        """Nodes one iteration runs with its calls inlined (known once every function is compiled)."""
        return self.own_nodes + sum(c.inlined_size for c in self.callees)


def mask_minus(mask, other):
    """Lanes of ``mask`` not in ``other``."""
    if other is False or mask is False:
        return mask
    if other is None:
        return False
    return mask_and_not(mask, other)


class StatementsMixin(CompilerBase):
    """Compiles statements into ``run(frame)`` closures."""

    def statement(self, node: Node) -> Statement | None:
        """Compile one statement (None when it does nothing)."""
        return self.dispatch(STATEMENT_RULES, node, self.unsupported_statement)

    def unsupported_statement(self, node: Node):
        """The error for a statement kind GLSL does not have."""
        return self.error(f"unsupported statement ({node.type.replace('_', ' ')})", node)

    def block(self, node: Node, new_scope: bool = True) -> Statement:
        """A ``{ ... }`` block, with its own scope unless it is a function body."""
        if new_scope:
            self.scopes.append(Scope())
        stmts = [s for s in (self.statement(child) for child in node.named_children) if s is not None]
        if new_scope:
            self.scopes.pop()
        return sequence(stmts)

    def no_statement(self, node: Node) -> None:
        """Comments."""
        return None

    def declaration_statement(self, node: Node) -> Statement | None:
        """A local declaration (function prototypes are not allowed in a body)."""
        if self.is_prototype(node):
            raise self.error("functions cannot be declared inside a function", node)
        return self.local_declaration(node)

    def expression_statement(self, node: Node) -> Statement | None:
        """An expression evaluated for its effects (``;`` alone does nothing)."""
        if not node.named_children:
            return None
        return self.expression_effect(node.named_children[0])

    def break_statement(self, node: Node) -> Statement:
        """``break`` leaves the innermost loop or switch."""
        if self.loop_depth == 0 and self.switch_depth == 0:
            raise self.error("'break' outside a loop or switch", node)
        return _break

    def continue_statement(self, node: Node) -> Statement:
        """``continue`` skips to the innermost loop's next iteration."""
        if self.loop_depth == 0:
            raise self.error("'continue' outside a loop", node)
        return _continue

    def preprocessor_statement(self, node: Node) -> None:
        """A preprocessor line inside a function body."""
        self.preprocessor(node)

    def refuse_jump(self, node: Node) -> None:
        """``goto`` and labels are C, not GLSL."""
        raise self.error(f"unsupported feature: {node.type.split('_')[0]} (not GLSL)", node)

    def condition(self, node: Node) -> Callable[[Frame], object]:
        """A bool condition as a closure returning a scalar or a per-lane bool array."""
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

    def if_statement(self, node: Node) -> Statement:
        """``if``/``else``: uniform conditions run one branch, per-lane ones both under masks."""
        cond = self.condition(node.child_by_field_name("condition"))
        then = self.statement(node.child_by_field_name("consequence")) or nothing
        alternative = node.child_by_field_name("alternative")
        other = nothing
        if alternative is not None:
            inner = [c for c in alternative.named_children if c.type != "comment"]
            other = self.statement(inner[0]) or nothing

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

    def loop(self, node: Node) -> Statement:
        """``for``, ``while`` and ``do``-``while`` loops, bounded per loop and per evaluation."""
        self.scopes.append(Scope())
        init = update = None
        if node.type == "for_statement":
            initializer = node.child_by_field_name("initializer")
            if initializer is not None:
                init = (
                    self.local_declaration(initializer)
                    if initializer.type == "declaration"
                    else self.expression_effect(initializer)
                )
        nodes_before, calls_before = self.compiled_nodes, len(self.function.calls)
        if node.type == "for_statement":
            cond_node = node.child_by_field_name("condition")
            cond = self.condition(cond_node) if cond_node is not None else None
            upd = node.child_by_field_name("update")
            update = self.expression_effect(upd) if upd is not None else None
        else:
            cond = self.condition(node.child_by_field_name("condition"))
        self.loop_depth += 1
        body = self.statement(node.child_by_field_name("body")) or nothing
        self.loop_depth -= 1
        self.scopes.pop()
        test_first = node.type != "do_statement"
        where = self.where(node)
        # Nodes one iteration runs with its calls inlined; the callees' sizes are known once all are compiled.
        own_nodes, callees = self.compiled_nodes - nodes_before, [c for c, *_ in self.function.calls[calls_before:]]
        return self.loop_runner(LoopParts(init, cond, update, body, test_first, where, own_nodes, callees))

    def loop_runner(self, parts: LoopParts) -> Statement:
        """The closure running a compiled loop over lane masks (the native backend runs its own)."""
        init, cond, update, body, test_first, where = (
            parts.init, parts.cond, parts.update, parts.body, parts.test_first, parts.where
        )
        cost: list[int] = []

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
                    if not cost:
                        cost.append(parts.cost())
                    f.budget[1] += cost[0]
                    if count > MAX_LOOP_ITERATIONS:
                        raise EvaluationError(f"loop exceeded {MAX_LOOP_ITERATIONS} iterations", where)
                    if f.budget[0] > MAX_TOTAL_ITERATIONS:
                        raise EvaluationError(
                            f"loops exceeded {MAX_TOTAL_ITERATIONS} iterations in total in one evaluation", where
                        )
                    if f.budget[1] > MAX_LOOP_NODES:
                        raise EvaluationError(
                            f"loops ran more than {MAX_LOOP_NODES} nodes in one evaluation "
                            f"({cost[0]} per iteration of this loop, calls inlined)",
                            where,
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

    def switch(self, node: Node) -> Statement:
        """``switch`` with fall-through (GLSL 4.10 §6.2): each case label adds its lanes to the running set."""
        cond_node = node.child_by_field_name("condition")
        selector = self.expr(cond_node.named_children[0] if cond_node.type == "parenthesized_expression" else cond_node)
        if not (selector.type.is_integer and selector.type.is_scalar):
            raise self.error(f"switch needs an int or uint selector, not {selector.type}", cond_node)
        self.scopes.append(Scope())
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
            groups.append((value, sequence([self.statement(c) for c in body])))
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
                    new = mask_and(entry, sel == value) if value is not None else mask_minus(entry, matched)
                    new = mask_minus(new, activated)
                    activated = mask_or(activated, new)
                    f.mask = mask_or(f.mask, new)
                    if f.mask is not False:
                        statements(f)
            finally:
                f.loops.pop()
            f.mask = mask_or(f.mask, state.broken)

        return run

    def expression_effect(self, node: Node) -> Statement | None:
        """An expression statement: kept only if it has effects."""
        e = self.expr(node)
        if not e.effects:
            return None
        ev = e.ev

        def run(f):
            ev(f)

        return run

    def return_statement(self, node: Node) -> Statement:
        """``return``: the value is kept for the active lanes, which then stop."""
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
