"""Bounds on the work and memory one ``.brdf`` shader may cost (issue 14, class 3), in one place.

A shader file is data from someone else: each stage that could grow faster than the text is capped, and
hitting a cap is a :class:`~brdfnorm.errors.BrdfFileError` at ``FILE:LINE:COL`` (compile time) or an
:class:`~brdfnorm.errors.EvaluationError` naming the place (run time), never a crash or an unbounded wait.
The example shaders are 0.1–1.3 KB, compile to a few hundred nodes and hold under 100 components per
direction, so every bound below is two or more orders of magnitude above what real lobes use.
"""

from __future__ import annotations

#: Largest shader section, in bytes of UTF-8 text (BRDF Explorer's shaders are a few kilobytes; comments
#: outside the GLSL sections do not count).
MAX_SHADER_BYTES = 1024 * 1024
#: tree-sitter reports progress about every 100 parse operations; the parse is cancelled after this many
#: reports plus one per :data:`PARSE_BYTES_PER_REPORT` bytes of text (valid GLSL needs about one report per
#: 100 bytes; error recovery on junk can take far more work, and memory, per byte).
PARSE_REPORTS = 2_000
PARSE_BYTES_PER_REPORT = 32
#: CPU time one parse may take before it is cancelled, whatever its count (valid GLSL of 1 MiB parses in well
#: under a second; error recovery on junk costs up to 0.2 ms per report).
PARSE_SECONDS = 2.0
#: Stack of the thread tree-sitter parses in (address space reserved, touched only as deep as the recursion goes).
PARSE_STACK_BYTES = 256 * 1024**2
#: Deepest nesting of brackets ``( [ {`` a shader may have (checked by a linear pre-scan before tree-sitter,
#: whose error recovery on deep or mismatched brackets grows without bound and can overflow its C stack: 100 000
#: lines of ``{ ; ( ] }`` crash it). The examples nest at most 6 deep.
MAX_BRACKET_DEPTH = 256
#: Syntax nodes compiled, each macro expansion counted anew (``#define A2 (A1+A1)`` doubles the count). The
#: examples compile 8–191 nodes; compiling takes 10–30 µs a node.
MAX_COMPILED_NODES = 100_000
#: Nodes one evaluation of a function runs with every call inlined (f calling g twice costs 2·|g|): the
#: static size of the work, loops counted once; a call tree that doubles at each level is refused. The
#: examples' BRDF functions inline to 5–195 nodes.
MAX_INLINED_NODES = 200_000
#: Longest array a shader may declare (each element is held as its own component arrays).
MAX_ARRAY_LENGTH = 1024
#: Components of all variables of a shader together (uniforms, globals, parameters and locals of every function):
#: one direction's state. ``mat4 m[1024]`` alone needs 16 384.
MAX_VARIABLE_COMPONENTS = 4096
#: Lanes (direction pairs) evaluated at once are chunked so that lanes × components stays under this:
#: 2**23 float64 components are 64 MiB for one copy of every variable (temporaries add a few copies).
LANE_COMPONENTS = 2**23
#: Iterations one execution of one loop may take before evaluation stops with an EvaluationError.
MAX_LOOP_ITERATIONS = 10_000
#: Loop iterations all loops together may take in one evaluation of the shader.
MAX_TOTAL_ITERATIONS = 100_000
#: Nodes run by loop iterations in one evaluation, each iteration costing its body's size with calls
#: inlined: a loop calling a large function is bounded by its work, not only by its iteration count (a
#: node runs in 1–5 µs for a few lanes; a 1 000-iteration loop of a 100-node body is 100 000 nodes).
MAX_LOOP_NODES = 2_000_000
