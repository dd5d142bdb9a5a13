"""A GLSL evaluator for BRDF Explorer shaders: tree-sitter-glsl syntax trees compiled to numpy closures.

``compile_shader(text, path=..., first_line=..., first_column=..., uniforms={...})`` returns a
:class:`Program` whose ``brdf(L, V, N, X, Y, uniforms)`` evaluates the shader's
``vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)`` in float64 over arrays of direction pairs, with
the semantics of GLSL 4.10 and Mesa llvmpipe's choices where the specification leaves results undefined.
Modules: :mod:`.parser` (tree-sitter, positions), :mod:`.types`, :mod:`.names` (keywords and reserved
names), :mod:`.builtins`, :mod:`.runtime` (lane masks), :mod:`.limits` (bounds on work and memory),
:mod:`.compiler` (a package: declarations, statements, expressions, operators, calls, Mesa's folds).
"""

from __future__ import annotations

from .limits import MAX_LOOP_ITERATIONS, MAX_TOTAL_ITERATIONS

__all__ = ["MAX_LOOP_ITERATIONS", "MAX_TOTAL_ITERATIONS", "Program", "compile_shader"]


def __getattr__(name: str):
    """The compiler (and tree-sitter with it) loads on first use: :mod:`.names` serves the ``.brdf`` reader
    without it."""
    if name in ("Program", "compile_shader"):
        from . import compiler

        return getattr(compiler, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
