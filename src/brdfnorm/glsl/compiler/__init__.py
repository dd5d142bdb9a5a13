"""Compilation of a tree-sitter GLSL syntax tree into closures over numpy arrays.

Every expression node becomes an :class:`.values.Expr` (static type, optional compile-time constant, and a
closure ``ev(frame) -> tuple of components``); every statement a closure ``run(frame)``. Nothing is ever
turned into Python source: identifiers of the shader only ever index the compiler's own symbol tables, so
a shader variable named ``__import__`` or ``exec`` is just a slot in a list.

Semantics follow the OpenGL Shading Language 4.10 specification: §5.8–5.10 (operators, implicit
int → float conversion, int division truncating toward zero, 32-bit integer wrap-around), §5.4
(constructors), §5.5 (swizzles), §6.1 (functions, overloading, in/out/inout copy semantics; built-ins hidden
by a user function of the same name), §6.2–6.4 (switch, loops, jumps), with Mesa llvmpipe's choices where
the specification leaves results undefined (:mod:`..builtins`, :mod:`.folds`). A float division by a
constant 0 keeps IEEE semantics (±inf, NaN): llvmpipe writes no result at all for a shader doing it, so
there is nothing to match. Not imitated: float32 overflow and underflow.

The compiler is one class assembled from the parts a reader looks for:

* :mod:`.base` — state, symbol tables, errors, the node-type dispatch and the compile budgets;
* :mod:`.declarations` — the translation unit, functions, variables, scopes, the preprocessor, call checks;
* :mod:`.statements` — blocks, ``if``, loops, ``switch``, jumps, ``return``;
* :mod:`.expressions` — literals, identifiers and macros, ``?:``, swizzles, subscripts;
* :mod:`.operators` — unary, arithmetic, relational and logical operators;
* :mod:`.lvalues` — assignments, ``++``/``--`` and what they assign to;
* :mod:`.calls` — user and built-in function calls, constructors;
* :mod:`.folds` — Mesa's constant folds; :mod:`.components` — run-time component arithmetic;
* :mod:`.program` — :class:`Compiler` (the parts assembled), :class:`Program` and :func:`compile_shader`.

Every bound on the work and memory a shader may cost is in :mod:`..limits`.
"""

from __future__ import annotations

from .program import Compiler, Program, compile_shader

__all__ = ["Compiler", "Program", "compile_shader"]
