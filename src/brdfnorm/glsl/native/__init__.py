"""The native backend of ``.brdf`` shaders: a shader's ``BRDF`` as one scalar Numba function (issue 39).

:func:`native_kernel` gives a :class:`~brdfnorm.models.base.NativeKernel` for a parsed ``.brdf`` file:
``function(lx, ly, lz, vx, vy, vz, u) -> (r, g, b)`` is f(L, V) with N = +z, X = +x, Y = +y, the same float64
values as the numpy backend (:mod:`..compiler`) to rounding of the transcendental functions; ``pack(params)``
puts the parameter values in ``u``. The source is generated from the numpy backend's compiled program by
tracing (:mod:`.generate`, :mod:`.tracer`): generated identifiers and printed literals only, nothing of the
shader's text. Modules are cached on disk per user (:mod:`.cache`). A shader the backend cannot express gives
None (the numpy backend evaluates it), as does a missing or failing Numba.

Where the numpy backend raises an :class:`~brdfnorm.errors.EvaluationError` (a loop bound of :mod:`..limits`),
the compiled function returns NaN in every channel (an exception would be lost inside a Numba ``prange``): the
caller reports it as today by evaluating that direction pair with the numpy backend.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Mapping

import numpy as np

from ...models.base import NativeKernel

_kernels: dict[tuple, NativeKernel | None] = {}  # (path, shader text, place, uniforms) -> kernel
_MAKING = threading.RLock()


def _pack_function(layout: tuple, size: int):
    def pack(params: Mapping[str, object]) -> np.ndarray:
        """The parameter values as the compiled function's ``u`` (bools as 1.0 / 0.0, colours as 3 values)."""
        u = np.empty(size)
        for name, kind, offset in layout:
            value = params[name]
            if kind == "bool":  # (a case's own value arrives as shape (1,) from a table's per-case parameters)
                u[offset] = 1.0 if bool(np.asarray(value).reshape(())) else 0.0
            elif kind == "float":
                u[offset] = float(np.asarray(value, dtype=float).reshape(()))
            else:
                u[offset : offset + 3] = np.asarray(value, dtype=float).reshape(3)
        return u

    return pack


def native_kernel(brdf) -> NativeKernel | None:
    """The compiled kernel of a parsed ``.brdf`` file (:class:`~brdfnorm.brdffile.BrdfFile`), or None where the
    native backend cannot express the shader or Numba is missing (made once per process and file)."""
    uniforms = brdf.uniforms
    key = (brdf.path, brdf.shader.text, brdf.shader.line, brdf.shader.column, tuple(uniforms.items()))
    with _MAKING:  # (a table's threads reach it at once; the None below is no answer for another thread)
        if key not in _kernels:
            _kernels[key] = None  # also what a failure below leaves: it is not retried
            _kernels[key] = _make(brdf, uniforms)
        return _kernels[key]


def _make(brdf, uniforms: dict[str, str]) -> NativeKernel | None:
    try:
        import numba  # noqa: F401 - the backend needs it; without it the numpy backend serves
    except Exception:  # noqa: BLE001 - ImportError, or a Numba built for another numpy failing as it loads
        return None
    from .cache import cache_key, load
    from .generate import Unsupported, generate

    try:
        generated = generate(
            brdf.shader.text, path=brdf.path, first_line=brdf.shader.line, first_column=brdf.shader.column,
            uniforms=uniforms,
        )
    except Unsupported:
        return None
    except Exception as error:  # noqa: BLE001 - a path of the numpy code the trace does not foresee
        return _failed(brdf, "trace", error)
    digest = cache_key(generated.source)
    try:
        function = load(generated.source, digest)
        # compiled here (or read from the disk cache), not inside the first engine kernel that calls it
        function(0.0, 0.0, 1.0, 0.0, 0.0, 1.0, np.zeros(generated.size))
    except Exception as error:  # noqa: BLE001 - any failure of Numba's leaves the shader to the numpy backend
        return _failed(brdf, "compile", error)
    return NativeKernel(function, 3, _pack_function(generated.layout, generated.size), digest)


def _failed(brdf, stage: str, error: Exception) -> None:
    """A one-line notice that the shader stays with the numpy backend (a defect of this backend's, not of the
    shader's: the numpy backend compiled it)."""
    warnings.warn(f"{brdf.path}: the compiled backend failed to {stage} this shader ({type(error).__name__}); "
                  "numpy evaluates it", RuntimeWarning, stacklevel=5)


__all__ = ["native_kernel"]
