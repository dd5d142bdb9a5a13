"""A GLSL evaluator for BRDF Explorer shaders: tree-sitter-glsl syntax trees compiled to numpy closures.

``compile_shader(text, path=..., first_line=..., first_column=..., uniforms={...})`` returns a
:class:`Program` whose ``brdf(L, V, N, X, Y, uniforms)`` evaluates the shader's
``vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)`` in float64 over arrays of direction pairs, with
the semantics of GLSL 4.10 and Mesa llvmpipe's choices where the specification leaves results undefined.
Modules: :mod:`.parser` (tree-sitter, positions), :mod:`.types`, :mod:`.names` (keywords and reserved
names), :mod:`.builtins`, :mod:`.runtime` (lane masks), :mod:`.limits` (bounds on work and memory),
:mod:`.compiler` (a package: declarations, statements, expressions, operators, calls, Mesa's folds).
"""

from .compiler import Program, compile_shader
from .limits import MAX_LOOP_ITERATIONS, MAX_TOTAL_ITERATIONS

__all__ = ["MAX_LOOP_ITERATIONS", "MAX_TOTAL_ITERATIONS", "Program", "compile_shader"]
