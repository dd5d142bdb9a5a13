"""Which backend computes the albedos: ``"numpy"`` (the reference, vectorized over nodes) or ``"compiled"`` (Numba
kernels fused over cells, :mod:`brdfnorm.engine.compiled.kernels`).

The choice: the ``backend`` argument where given, else the innermost :func:`scope` (how a table passes its
``backend`` to every albedo it computes), else the ``BRDFNORM_BACKEND`` environment variable (which worker processes
inherit), else ``"compiled"`` where Numba imports. Where Numba cannot be imported, or a kernel does not compile,
the numpy backend takes over with one line on stderr (once per process and cause): the answers are the same either
way, within their error estimates.
"""

from __future__ import annotations

import contextlib
import os
import sys
import threading
from collections.abc import Iterator
from contextvars import ContextVar
from functools import cache

from ...errors import ArgumentError
from . import staleness

BACKENDS = ("numpy", "compiled")
#: The environment variable that chooses the backend where no argument does.
ENVIRONMENT = "BRDFNORM_BACKEND"

_TOLD: set[str] = set()
_TOLD_LOCK = threading.Lock()
_SCOPE: ContextVar[str | None] = ContextVar("brdfnorm_backend", default=None)


@contextlib.contextmanager
def scope(backend: str | None) -> Iterator[None]:
    """Within the block, albedos given no ``backend`` use this one (None: no change)."""
    if backend is not None:
        requested(backend)  # validated here, where the caller's argument is named
    token = _SCOPE.set(backend if backend is not None else _SCOPE.get())
    try:
        yield
    finally:
        _SCOPE.reset(token)


def tell_once(message: str) -> None:
    """``message`` as one line on stderr, once per process, however many threads reach it at once (a table's
    cells run on a thread per core: :mod:`brdfnorm.parallel.threads`)."""
    with _TOLD_LOCK:
        if message in _TOLD:
            return
        _TOLD.add(message)
    print(message, file=sys.stderr)


def notice(message: str) -> None:
    """Why the numpy backend computes, once per process (:func:`tell_once`)."""
    tell_once(f"brdfnorm: {message}; using the numpy backend")


@cache
def numba_available() -> bool:
    """Whether Numba imports (the notice is printed where it does not); where it does, the package's stale cached
    kernels are removed first (:func:`brdfnorm.engine.compiled.staleness.refresh`)."""
    try:
        import numba  # noqa: F401
    except Exception as error:  # noqa: BLE001 - any failure to import means: no compiled backend
        notice(f"Numba cannot be imported ({type(error).__name__}: {error})")
        return False
    # Before any kernel loads: Numba's cache of the package's kernels is dropped where a source compiled into them
    # changed (Numba itself compares only each kernel's own file).
    staleness.refresh()
    return True


def requested(backend: str | None = None) -> str:
    """The backend asked for: ``backend``, else ``$BRDFNORM_BACKEND``, else "compiled" (validated)."""
    where = "backend"
    if backend is None:
        backend = _SCOPE.get()
    if backend is None:
        backend, where = os.environ.get(ENVIRONMENT, "").strip() or "compiled", ENVIRONMENT
    if backend not in BACKENDS:
        raise ArgumentError(f"unknown backend {backend!r} (known: {', '.join(BACKENDS)})", where=where)
    return backend


def resolve(backend: str | None = None) -> str:
    """The backend that will compute: :func:`requested`, with "numpy" where Numba is not available."""
    chosen = requested(backend)
    return "compiled" if chosen == "compiled" and numba_available() else "numpy"
