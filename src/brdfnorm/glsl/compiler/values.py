"""What the compiler builds: compiled expressions, variables, parameters, functions and scopes.

Every value is a flat tuple of components (see :mod:`..types`); :class:`Expr` pairs a static type with an
evaluator ``ev(frame) -> components`` and, when the compiler could fold it, the constant components.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import tree_sitter

from ..parser import Source
from ..runtime import Frame
from ..types import Type

Node = tree_sitter.Node
#: A compiled statement: runs in a frame, for the frame's active lanes.
Statement = Callable[[Frame], None]

#: The floats 0 and 1 of unset components and of matrix constructors: numpy scalars, so that arithmetic
#: on them is IEEE arithmetic (±inf, NaN), never Python's ZeroDivisionError.
ZERO = np.float64(0.0)
ONE = np.float64(1.0)


def zeros(t: Type) -> tuple:
    """The components of a default-initialized value of type ``t`` (0, or false for bools)."""
    return (False,) * t.size if t.base == "bool" else (ZERO,) * t.size


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
    """A function parameter: name (None when unnamed), type, ``in``/``out``/``inout``, and ``const``."""

    name: str | None
    type: Type
    qualifier: str  # "in", "out" or "inout"
    const: bool = False


@dataclass(eq=False)
class Function:
    """A user function: its signature, syntax nodes, and once compiled its body and frame layout.

    ``calls`` lists the call sites in the body (callee, node, source) for the checks run once every body
    is compiled (undefined callees, recursion, inlined size); ``size`` counts the nodes compiled for the
    body itself and ``inlined_size`` the same with every call replaced by its callee's body.
    """

    name: str
    ret: Type
    params: list[Param]
    node: Node
    source: Source
    body_node: Node | None = None
    body: Statement | None = None
    nslots: int = 0
    param_slots: list[int] = field(default_factory=list)
    calls: list[tuple[Function, Node, Source]] = field(default_factory=list)
    used_params: set[int] = field(default_factory=set)
    size: int = 0
    inlined_size: int | None = None

    def signature(self) -> str:
        """The signature as GLSL writes it, e.g. ``vec3 BRDF(vec3, vec3, vec3, vec3, vec3)``."""
        return f"{self.ret} {self.name}({', '.join(str(p.type) for p in self.params)})"


class Scope(dict):
    """Names declared in one block (or at global scope), mapped to their :class:`Var`."""
