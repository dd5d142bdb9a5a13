"""The compiler assembled from its parts, the compiled shader and the entry point: :class:`Compiler`,
:class:`Program` and :func:`compile_shader`.

``Program.brdf`` evaluates ``vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)`` over arrays of direction
pairs (lanes). Lanes are evaluated in chunks of at most :data:`..limits.LANE_COMPONENTS` divided by the
shader's components per lane, so the memory a shader's variables take stays flat whatever the number of
directions.
"""

from __future__ import annotations

import gc
import math
from collections.abc import Mapping

import numpy as np

from ...errors import BrdfFileError, EvaluationError
from ..limits import LANE_COMPONENTS
from ..runtime import Frame
from ..types import VEC3, Type
from .calls import CallsMixin
from .declarations import DeclarationsMixin
from .expressions import ExpressionsMixin
from .lvalues import LValuesMixin
from .operators import OperatorsMixin
from .statements import StatementsMixin
from .values import Function

SIGNATURE = "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)"
#: Components per lane assumed at least (temporaries of the expressions come on top of the variables).
_MIN_COMPONENTS = 64


class Compiler(DeclarationsMixin, StatementsMixin, ExpressionsMixin, OperatorsMixin, LValuesMixin, CallsMixin):
    """A GLSL shader compiled to closures: construct with the text, then :meth:`compile`."""


class Program:
    """A compiled shader: ``brdf(L, V, N, X, Y, uniforms)`` evaluates its ``BRDF`` function in float64.

    ``uniforms`` maps each uniform's name to its GLSL type name; ``uses`` is the set of built-in
    functions called and uniforms read by the shader; ``chunk`` is the number of lanes evaluated at once.
    """

    def __init__(self, compiler: Compiler, entry: Function) -> None:
        self._entry = entry
        self._inits = compiler.global_inits
        self._global_defaults = [compiler.global_defaults.get(slot) for slot in range(compiler.globals_count)]
        self._uniforms = dict(compiler.uniforms)
        self.uniforms: dict[str, str] = {name: str(t) for name, (t, *_) in compiler.uniforms.items()}
        self.uses: frozenset[str] = frozenset(compiler.uses)
        self.path = compiler.path
        self._used_params = sorted(entry.used_params)
        self.chunk = max(1, LANE_COMPONENTS // max(compiler.components, _MIN_COMPONENTS))

    def _uniform_value(self, name: str, t: Type, value) -> tuple:
        """The components of a uniform from a caller value (bools, numbers, vec3 arrays)."""
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
        values: dict[int, tuple] = {}
        for name, (t, slot, caller, default) in self._uniforms.items():
            if name in uniforms:
                values[slot] = self._uniform_value(name, t, uniforms[name])
            elif caller:
                raise EvaluationError(f"no value given for uniform '{name}'", self.path)
            else:
                values[slot] = default  # its initializer, else zero as OpenGL does
        shape = np.broadcast_shapes(
            *(d.shape[:-1] for d in directions), *(np.shape(c) for v in values.values() for c in v)
        )
        if math.prod(shape) <= self.chunk:
            result, globals_ = self._run(directions, values)
            shapes = [d.shape[:-1] for d in directions]
            for value in globals_:
                shapes.extend(np.shape(c) for c in value or ())
            shape = np.broadcast_shapes(*shapes, *(np.shape(c) for c in result))
            out = np.empty(shape + (3,))
            for i, c in enumerate(result):
                out[..., i] = c
            return out
        # Many lanes: flatten every per-lane input to (lanes,) and evaluate slices of `chunk` lanes.
        lanes = math.prod(shape)
        flat_directions = [np.broadcast_to(d, shape + (3,)).reshape(lanes, 3) for d in directions]
        flat_values = {
            slot: tuple(np.broadcast_to(c, shape).reshape(lanes) if np.ndim(c) else c for c in value)
            for slot, value in values.items()
        }
        out = np.empty((lanes, 3))
        for start in range(0, lanes, self.chunk):
            part = slice(start, start + self.chunk)
            chunk_values = {slot: tuple(c[part] if np.ndim(c) else c for c in v) for slot, v in flat_values.items()}
            result, _ = self._run([d[part] for d in flat_directions], chunk_values)
            for i, c in enumerate(result):
                out[part, i] = c
        return out.reshape(shape + (3,))

    def _run(self, directions: list[np.ndarray], values: dict[int, tuple]) -> tuple[tuple, list]:
        """One evaluation over the lanes of ``directions``: the result's components and the globals."""
        globals_ = list(self._global_defaults)
        for slot, value in values.items():
            globals_[slot] = value
        budget = [0, 0]  # loop iterations, nodes run in loops
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
        return (frame.ret if frame.ret is not None else (0.0, 0.0, 0.0)), globals_


def compile_shader(
    source: str,
    *,
    path: str = "<shader>",
    first_line: int = 1,
    first_column: int = 1,
    uniforms: Mapping[str, str] | None = None,
    compiler_class: type[Compiler] = Compiler,
) -> Program:
    """Compile the GLSL text of a ``.brdf`` shader section into a :class:`Program`.

    ``first_line``/``first_column`` place the text's first character in the file ``path`` so that
    every error is reported as ``FILE:LINE:COL`` of the file; ``uniforms`` declares the parameters
    (name → ``"float"``, ``"bool"`` or ``"vec3"``) as BRDF Explorer does. Raises
    :class:`~brdfnorm.errors.BrdfFileError` for any problem in the text, a bound of :mod:`..limits` hit
    included. ``compiler_class`` is :class:`Compiler` or a subclass (the native backend's, which runs loops its
    own way).
    """
    # The compiler allocates a few objects per node, all alive until it returns: the cyclic garbage collector
    # would rescan them again and again (compile time growing faster than the shader), so it pauses.
    collecting = gc.isenabled()
    gc.disable()
    try:
        compiler = compiler_class(source, path, first_line, first_column, uniforms or {})
        compiler.compile()
    except RecursionError:  # the compiler recurses along the syntax tree
        raise BrdfFileError("shader is nested too deeply", path, first_line, first_column) from None
    finally:
        if collecting:
            gc.enable()
    for fn, node, src in compiler.global_calls:
        if fn.body_node is None:
            raise src.error(f"function '{fn.signature()}' is declared but never defined", node)
    overloads = compiler.functions.get("BRDF")
    if not overloads:
        raise compiler.src.error(f"no BRDF function: the shader must define {SIGNATURE}", None)
    for fn in overloads:
        if fn.ret == VEC3 and [p.type for p in fn.params] == [VEC3] * 5 and fn.body_node is not None:
            if any(p.qualifier != "in" for p in fn.params):
                raise fn.source.error(f"BRDF's parameters must be 'in': expected {SIGNATURE}", fn.node)
            return Program(compiler, fn)
    fn = overloads[0]
    if fn.body_node is None:
        raise fn.source.error(f"BRDF is declared but never defined: expected {SIGNATURE}", fn.node)
    raise fn.source.error(f"BRDF has the wrong signature '{fn.signature()}': expected {SIGNATURE}", fn.node)
