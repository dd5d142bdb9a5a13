"""One copy of :mod:`brdfnorm.engine.compiled.kernels` per shader, cached on disk, and the compiled integrand of a
batch of albedo cases (:class:`NativeIntegrand`) that the routes call instead of the numpy integrand.

Why copies: Numba caches a compiled function by its source file and argument types; a kernel that received the
shader as an argument would be typed by that dispatcher object and compiled again in every process. Each copy is the
kernels' source with its own module-level ``shader``, written once into ``<cache>/kernels/`` (the per-user cache
directory, created 0700: ``$BRDFNORM_CACHE_DIR``, else ``$XDG_CACHE_HOME/brdfnorm``, else ``~/.cache/brdfnorm``)
under a name that hashes the kernels' source, the shader's key and the versions of brdfnorm and Numba, so a second
run of the same model loads machine code and compiles nothing.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.metadata
import importlib.util
import os
import sys
import threading
import time
from functools import cache
from pathlib import Path
from types import ModuleType

import numpy as np

from ...models.base import NativeKernel
from .backend import notice
from .marks import await_other, holding

_TEMPLATE = Path(__file__).with_name("kernels.py")


def cache_directory() -> Path:
    """The per-user cache directory of compiled kernels (created 0700 where missing)."""
    root = os.environ.get("BRDFNORM_CACHE_DIR") or (
        Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "brdfnorm")
    Path(root).mkdir(mode=0o700, parents=True, exist_ok=True)
    path = Path(root) / "kernels"
    path.mkdir(mode=0o700, exist_ok=True)
    return path


def _version() -> str:
    try:
        return importlib.metadata.version("brdfnorm")
    except importlib.metadata.PackageNotFoundError:
        return "source"


def kernels_file(key: str, numba_version: str) -> Path:
    """The path of the kernels' copy for shader ``key`` (Numba's cache of it lies beside it)."""
    source = _TEMPLATE.read_text(encoding="utf-8")
    # the helpers the kernels inline are part of their machine code: a change there is a new copy too
    helpers = "\0".join(_TEMPLATE.with_name(name).read_text(encoding="utf-8") for name in ("hemimap.py",))
    digest = hashlib.sha256("\0".join((source, helpers, key, _version(), numba_version)).encode()).hexdigest()[:24]
    return cache_directory() / f"brdfnorm_kernels_{digest}.py"


def kernels_compiled(key: str) -> bool:
    """Whether every kernel of shader ``key`` was compiled into the disk cache by an earlier run (the mark
    :func:`_warm` leaves once they all are)."""
    import numba

    return kernels_file(key, numba.__version__).with_suffix(".compiled").exists()


def compiling_mark(key: str) -> Path:
    """The mark a process holds while it compiles the kernels of shader ``key`` (:mod:`.marks`)."""
    import numba

    return kernels_file(key, numba.__version__).with_suffix(".compiling")


@cache
def _module(key: str, numba_version: str) -> tuple[ModuleType, Path]:
    source = _TEMPLATE.read_text(encoding="utf-8")
    path = kernels_file(key, numba_version)
    if not path.exists():
        temporary = path.with_suffix(f".{os.getpid()}.tmp")
        temporary.write_text(f"# brdfnorm compiled kernels for shader key {key!r} (generated; safe to delete)\n"
                             + source, encoding="utf-8")
        os.replace(temporary, path)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module
    spec.loader.exec_module(module)
    return module, path


def kernels_for(kernel: NativeKernel) -> ModuleType:
    """The kernels module whose ``shader`` is ``kernel.function`` (one per key and process)."""
    import numba

    module, _ = _module(kernel.key, numba.__version__)
    module.shader = kernel.function
    return module


class NativeIntegrand:
    """f·(N·ω) of K albedo cases as compiled kernels: called as ``(omega (M, 3), case (M,)) -> (M, C)`` like the
    numpy integrand, with the fused panel kernels of :mod:`.kernels` alongside (``kernels``)."""

    def __init__(self, kernel: NativeKernel, fixed: np.ndarray, U: np.ndarray, over_light: bool) -> None:
        self.kernels = kernels_for(kernel)
        self.channels = kernel.channels
        self.fixed = np.ascontiguousarray(fixed, dtype=float)
        self.U = np.ascontiguousarray(U, dtype=float)
        self.over_light = bool(over_light)

    def __call__(self, omega: np.ndarray, case: np.ndarray) -> np.ndarray:
        omega = np.ascontiguousarray(omega, dtype=float).reshape(-1, 3)
        out = np.empty((omega.shape[0], self.channels))
        self.kernels.integrand_nodes(omega, np.ascontiguousarray(case, dtype=np.int64).ravel(), self.fixed, self.U,
                                     self.over_light, out)
        return out

    def take(self, index: np.ndarray) -> NativeIntegrand:
        """The integrand of the cases ``index`` (repeats allowed): case i of the copy is case ``index[i]`` of this
        one (the generic route's split of a batch into its single- and multi-peak cases)."""
        copy = object.__new__(NativeIntegrand)
        copy.__dict__.update(self.__dict__, fixed=np.ascontiguousarray(self.fixed[index]),
                             U=np.ascontiguousarray(self.U[index]))
        return copy


#: Seconds this process spent compiling (or loading from the disk cache) kernels: work budgets in seconds
#: (:mod:`brdfnorm.check`) leave it out, so that a first run, which compiles, searches as far as a later one.
COMPILING = {"seconds": 0.0}
_WARM: set[str] = set()
_FIRST = threading.Lock()


def compile_seconds() -> float:
    """Seconds spent so far in this process compiling or loading kernels (:data:`COMPILING`)."""
    return COMPILING["seconds"]


def _warm(native: NativeIntegrand, key: str) -> None:
    """Every kernel of ``native``'s copy once on the smallest input (compiled or loaded now, not in a route)."""
    from ..machinery.kronrod import GAUSS, KRONROD, NODES
    from .global_rule import integrate
    from .rules import tensor_sums
    from .slopes import SLOPE_MAP

    one, zero, unit = np.zeros(1, dtype=np.int64), np.zeros(1), np.ones(1)
    frame = (np.array([[0.0, 0.0, 1.0]]), np.array([[1.0, 0.0, 0.0]]), np.array([[0.0, 1.0, 0.0]]))
    bounds = (zero, unit, zero, unit)
    hemisphere_panels(native, one, *bounds, frame, unit, np.full(1, np.pi), NODES, KRONROD, GAUSS)
    hemisphere_sums(native, one, *bounds, frame, unit, np.full(1, np.pi), NODES[:1], NODES[:1], unit, unit)
    geometry = dict.fromkeys(SLOPE_MAP, np.ones(1))
    rectangle = slope_rectangle(native, geometry, np.array([[0.0, 0.0, 1.0]]), one, np.zeros(1, dtype=bool), True,
                                True)
    rectangle(one, np.full((1, 1, 1), 0.5), np.full((1, 1, 1), 0.5), one)
    # the fused global rule (compiled once per channel count for every shader; loaded, and the shader's first-class
    # function compiled, here): the first grid alone, whose 2^3 × 15 nodes are the node cap
    integrate(one, unit, zero, np.zeros(1, dtype=bool), unit, unit, unit, 120, 0, rectangle.fused)
    tensor_sums(np.zeros((1, 4, 3, native.channels)), np.ones(3), np.ones(1), np.zeros(0))
    _WARM.add(key)
    Path(native.kernels.__file__).with_suffix(".compiled").touch()  # the mark kernels_compiled reads


def native_integrand(kernel: NativeKernel | None, fixed: np.ndarray, rows: list[np.ndarray],
                     over_light: bool) -> NativeIntegrand | None:
    """The compiled integrand of the cases whose packed parameters are ``rows`` (K,), compiled (or loaded) and run
    once; None with a notice where it does not compile (the numpy integrand then computes)."""
    if kernel is None:
        return None
    width = max((r.size for r in rows), default=0)
    U = np.zeros((len(rows), max(width, 1)))
    for k, r in enumerate(rows):
        U[k, :r.size] = r
    start = time.perf_counter()
    # (the first use of a shader's kernels in this process, by one thread: a table's threads reach it at once)
    first = _FIRST if kernel.key not in _WARM else contextlib.nullcontext()
    with first:
        try:
            hold = contextlib.nullcontext()
            if kernel.key not in _WARM:  # another process compiling them (parallel.warm's child): its result, not ours
                mark = compiling_mark(kernel.key)
                await_other(mark)
                if not kernels_compiled(kernel.key):  # and ours marked, for the child to skip them
                    hold = holding(mark)
            with hold:
                native = NativeIntegrand(kernel, fixed, U, over_light)
                native(np.array([[0.0, 0.0, 1.0]]), np.zeros(1, dtype=np.int64))
                if kernel.key not in _WARM:
                    _warm(native, kernel.key)
        except Exception as error:  # noqa: BLE001 - any failure to compile means: the numpy backend computes
            notice(f"the compiled kernel of {kernel.key} does not compile ({type(error).__name__}: "
                   f"{str(error).splitlines()[0] if str(error) else ''})")
            return None
        finally:
            COMPILING["seconds"] += time.perf_counter() - start
    return native


def _flat(*arrays: np.ndarray) -> list[np.ndarray]:
    """Contiguous float64 copies of arrays broadcast against each other, raveled."""
    return [np.ascontiguousarray(a, dtype=float).ravel() for a in np.broadcast_arrays(*arrays)]


def hemisphere_panels(native: NativeIntegrand, case, b0, b1, u0, u1, frame, widths, supports, nodes, kronrod,
                      gauss):
    """The fused K15⊗K15 estimates of hemisphere panels (:func:`.kernels.hemisphere_panels`): value, err_b, err_u,
    magnitude (R, C), bad (R,), first_bad (R,)."""
    R, C = case.size, native.channels
    out = [np.empty((R, C)) for _ in range(4)]
    bad, first_bad = np.empty(R), np.empty(R, dtype=np.int64)
    P, T, B = (np.ascontiguousarray(a, dtype=float) for a in frame)
    native.kernels.hemisphere_panels(np.ascontiguousarray(case, dtype=np.int64), *_flat(b0), *_flat(b1),
                                     *_flat(u0), *_flat(u1), P, T, B, *_flat(widths), *_flat(supports), native.fixed,
                                     native.U, native.over_light, nodes, kronrod, gauss, *out, bad, first_bad)
    return (*out, bad, first_bad)


def hemisphere_sums(native: NativeIntegrand, case, b0, b1, u0, u1, frame, widths, supports, nodes_b, nodes_u,
                    weights_b, weights_u) -> np.ndarray:
    """Σ g·J w_b w_u of each hemisphere panel under a tensor rule (:func:`.kernels.hemisphere_sums`): (R, C)."""
    total = np.empty((case.size, native.channels))
    P, T, B = (np.ascontiguousarray(a, dtype=float) for a in frame)
    native.kernels.hemisphere_sums(np.ascontiguousarray(case, dtype=np.int64), *_flat(b0), *_flat(b1), *_flat(u0),
                                   *_flat(u1), P, T, B, *_flat(widths), *_flat(supports), native.fixed, native.U,
                                   native.over_light, *_flat(nodes_b), *_flat(nodes_u), *_flat(weights_b),
                                   *_flat(weights_u), total)
    return total


def slope_rectangle(native: NativeIntegrand, geometry: dict, F: np.ndarray, rows: np.ndarray, failed: np.ndarray,
                    linear: bool, log_horizon: bool):
    """The half-vector route's rectangle integrand (case, φ (R, n, 1), v (R, 1, m), piece (R,)) -> (R, n, m, C + 1)
    as one kernel (:func:`.slopes.shader_grid`, compiled once per machine for every shader, the shader a first-class
    function); ``geometry`` holds the per-case arrays of the slope map (vz, cos_offset, sin_offset, amplitude, ax,
    ay, layer, delta, kappa, multiplicity), ``failed`` (local cases) marks non-finite values."""
    from .global_rule import PADDED
    from .slopes import rectangle_grids, shader_grid_kernel, slope_arrays

    per_case = slope_arrays(geometry, len(rows))
    F = np.ascontiguousarray(F, dtype=float)
    rows = np.ascontiguousarray(rows, dtype=np.int64)
    # (a shader of fewer than PADDED channels padded: one compile of the package's kernels for one to three channels)
    shader = native.kernels.padded_shader if native.channels < PADDED else native.kernels.shader
    # the kernel's compiled entry points, by what of the grids' types can change from call to call (a grid is a
    # read-only view where it was one already): the entry point itself does not check its arguments' types
    entries = {}

    def integrand(case, phi, v, piece):
        phi, v = rectangle_grids(case, phi, v)
        case, piece = (np.ascontiguousarray(a, dtype=np.int64).ravel() for a in (case, piece))
        out = np.empty((case.size, phi.shape[1], v.shape[1], native.channels + 1))
        flags = np.zeros(failed.size, dtype=np.bool_)
        arguments = [case, phi, v, piece, linear, log_horizon, *per_case, F, rows, native.fixed, native.U,
                     native.over_light, shader, out, flags]
        key = tuple(a.flags.writeable for a in (case, phi, v, piece))
        if key not in entries:
            entries[key] = shader_grid_kernel(arguments, len(arguments) - 3, max(native.channels, PADDED))
        entries[key](*arguments)
        failed[:] |= flags
        return out

    integrand.compiled = True  # the route's sums run compiled too
    # and its whole global rule, one kernel for every shader (compiled.global_rule.shader_global)
    integrand.fused = ("shader", native.channels + 1, (linear, log_horizon, *per_case, F, rows, native.fixed, native.U,
                                                       native.over_light, shader, failed))
    return integrand
