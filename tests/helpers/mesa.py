"""Test helper: evaluate a ``.brdf`` shader on Mesa's llvmpipe, the reference GLSL compiler of the tests.

The file's shader text goes unchanged into a ``#version 430`` compute shader (GLSL 4.30 is a superset of
the 4.1 that BRDF Explorer files are written in; compute shaders need 4.30) that declares the file's
parameters as uniforms, exactly as BRDF Explorer does, reads direction pairs (L, V) from a storage buffer and
writes ``BRDF(L, V, N, X, Y)`` with the fixed frame N = +z, X = +x, Y = +y to another. The context is a
headless EGL one created through moderngl, so no display is needed; where EGL cannot start at all,
:func:`context` raises :class:`MesaUnavailable` with the reason and callers skip.
"""

from __future__ import annotations

import functools
from collections.abc import Mapping

import numpy as np

from brdfnorm.brdffile import BrdfFile

LOCAL_SIZE = 64
UNWRITTEN = np.float32(-12345.0)  # the shader writes w = 0

_HEADER = """#version 430
layout(local_size_x = {local_size}) in;
layout(std430, binding = 0) readonly buffer BrdfnormPairs {{ vec4 brdfnorm_pairs[]; }};
layout(std430, binding = 1) writeonly buffer BrdfnormValues {{ vec4 brdfnorm_values[]; }};
uniform uint brdfnorm_count;
{uniforms}
"""

_MAIN = """
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= brdfnorm_count) return;
    vec3 L = brdfnorm_pairs[2u * i].xyz;
    vec3 V = brdfnorm_pairs[2u * i + 1u].xyz;
    brdfnorm_values[i] = vec4(BRDF(L, V, vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)), 0.0);
}
"""


class MesaUnavailable(RuntimeError):
    """No OpenGL 4.3 context could be created (no EGL, no Mesa drivers)."""


class MesaCompileError(RuntimeError):
    """Mesa refused the shader (the message is Mesa's info log)."""


@functools.cache
def _context_or_reason() -> object:
    try:
        import moderngl
    except ImportError as exc:
        return f"moderngl is not installed ({exc})"
    try:
        return moderngl.create_context(standalone=True, backend="egl", require=430)
    except Exception as exc:  # moderngl/glcontext raise plain Exceptions for a missing libEGL or driver
        return f"cannot create a headless EGL OpenGL 4.3 context: {exc}"


def context():
    """The shared moderngl context (created once), or :class:`MesaUnavailable` with the reason."""
    found = _context_or_reason()
    if isinstance(found, str):
        raise MesaUnavailable(found)
    return found


def renderer() -> str:
    """The GL renderer string, e.g. ``llvmpipe (LLVM 15.0.6, 256 bits)``."""
    return context().info["GL_RENDERER"]


def compute_source(brdf: BrdfFile) -> str:
    """The compute shader wrapping the file's shader text (its lines keep the file's numbering)."""
    uniforms = "\n".join(f"uniform {glsl_type} {name};" for name, glsl_type in brdf.uniforms.items())
    # '#line N' makes the next line N in GLSL 4.30 (the 3.30+ rule), and padding keeps the column of a
    # shader that starts mid-line, so Mesa's messages point into the .brdf file itself.
    body = f"#line {brdf.shader.line}\n" + " " * (brdf.shader.column - 1) + brdf.shader.text
    return _HEADER.format(local_size=LOCAL_SIZE, uniforms=uniforms) + body + _MAIN


class MesaBrdf:
    """A ``.brdf`` shader compiled by Mesa: call it with (L, V) pairs and uniform values."""

    def __init__(self, brdf: BrdfFile) -> None:
        self.brdf = brdf
        self.source = compute_source(brdf)
        ctx = context()
        try:
            self.program = ctx.compute_shader(self.source)
        except Exception as exc:  # moderngl.Error carries Mesa's info log
            raise MesaCompileError(f"{brdf.path}: Mesa rejected the shader:\n{exc}") from None

    def __call__(self, L: np.ndarray, V: np.ndarray, uniforms: Mapping[str, object]) -> np.ndarray:
        """BRDF(L, V) for float32 directions (count, 3) -> (count, 3) float32 values as float64."""
        ctx = context()
        count = len(L)
        pairs = np.zeros((count, 2, 4), dtype=np.float32)
        pairs[:, 0, :3] = L
        pairs[:, 1, :3] = V
        for name, value in uniforms.items():
            if name in self.program:  # unused uniforms are optimized away
                self.program[name].value = value
        self.program["brdfnorm_count"].value = count
        source = ctx.buffer(pairs.tobytes())
        # Pre-fill with a sentinel: llvmpipe writes nothing for some shaders (a division by a constant 0.0),
        # and an unwritten zero must not pass for a result.
        target = ctx.buffer(np.full((count, 4), UNWRITTEN, dtype=np.float32).tobytes())
        try:
            source.bind_to_storage_buffer(0)
            target.bind_to_storage_buffer(1)
            self.program.run(group_x=(count + LOCAL_SIZE - 1) // LOCAL_SIZE)
            written = np.frombuffer(target.read(), dtype=np.float32).reshape(count, 4)
        finally:
            source.release()
            target.release()
        if np.any(written[:, 3] == UNWRITTEN):
            raise RuntimeError("Mesa wrote no result for some direction pairs (undefined shader behaviour)")
        return written[:, :3].astype(np.float64)


def uniform_values(parameters, values: Mapping[str, object]) -> dict[str, object]:
    """Bound parameter values as moderngl uniform values: float, bool, or an (R, G, B) tuple."""
    out: dict[str, object] = {}
    for p in parameters:
        value = values[p.name]
        if p.kind == "bool":
            out[p.name] = bool(value)
        elif p.kind == "color":
            out[p.name] = tuple(float(c) for c in np.broadcast_to(np.asarray(value, dtype=float), (3,)))
        else:
            out[p.name] = float(value)
    return out
