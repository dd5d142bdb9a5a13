"""Marks in the caches that say "a process is compiling these kernels now", so that a second process needing
them waits for the first instead of compiling them again beside it.

:mod:`brdfnorm.parallel.warm`'s child compiles, on the second core, the kernels a command will need later; where the
command reaches a lobe the child is still compiling, compiling it too would cost the command the whole compile, where
waiting costs what is left of the child's. Whoever compiles a lobe's kernels — the child, or the command reaching a
lobe first — holds a mark (:func:`holding`: a file holding its process id, written by an atomic rename, removed when
done) while it does: :func:`brdfnorm.engine.compiled.drivers.native_integrand` waits (:func:`await_other`) while a
mark is held by a live process, then loads what it wrote, and the child skips a lobe whose mark another process
holds. The shaders' fused global rule (:func:`brdfnorm.engine.compiled.global_rule.shader_kernel`, ~9 s of CPU, one
compile per machine) and their rectangle integrand (:func:`brdfnorm.engine.compiled.slopes.shader_grid_kernel`, ~2 s,
one compile per machine, by whichever process reaches it first) are compiled under marks of their own beside Numba's
caches of them. A mark left by a process that died (a child stopped mid-compile), or older than any compile takes,
is ignored; :func:`release` removes those of a stopped child.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import threading
import time
from collections.abc import Iterator
from pathlib import Path

#: The longest wait for another process's compile (seconds): a lobe compiles in 2-4 s on an idle machine; beyond
#: this the waiting process compiles the kernels itself (Numba's atomic cache writes keep either result whole).
PATIENCE = 60.0
_POLL = 0.02


@contextlib.contextmanager
def holding(mark: Path) -> Iterator[None]:
    """Within the block, ``mark`` holds this process's id."""
    temporary = mark.with_name(f"{mark.name}.{os.getpid()}.{threading.get_ident()}.tmp")  # (a table's threads too)
    temporary.write_text(str(os.getpid()), encoding="ascii")
    os.replace(temporary, mark)
    try:
        yield
    finally:
        with contextlib.suppress(FileNotFoundError):
            mark.unlink()


def holder(mark: Path) -> int | None:
    """The live process other than this one that holds ``mark``, or None."""
    try:
        pid = int(mark.read_text(encoding="ascii"))
        age = time.time() - mark.stat().st_mtime
    except (OSError, ValueError):  # no mark (or one being replaced): nobody holds it now
        return None
    if pid == os.getpid() or age > PATIENCE:  # older than any compile: left by a process stopped, its pid reused
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except PermissionError:  # alive, another user's (a shared cache directory)
        return pid
    with contextlib.suppress(OSError, IndexError):  # a child that died unreaped (Linux: state Z) holds nothing
        if Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z":
            return None
    return pid


#: The Numba event (:mod:`numba.core.event`) around each wait on another process's mark, with the mark's name as
#: its data: benchmarks/bench_report.py's timeline records it beside the ``numba:compile`` events.
AWAIT_EVENT = "brdfnorm:await"


def await_other(mark: Path, patience: float = PATIENCE) -> float:
    """Wait while another live process holds ``mark``, at most ``patience`` seconds; returns the seconds waited
    (within an :data:`AWAIT_EVENT` where it waits at all)."""
    start = time.monotonic()
    if holder(mark) is None:
        return 0.0
    from numba.core import event

    with event.trigger_event(AWAIT_EVENT, data={"mark": mark.name}):
        while holder(mark) is not None and time.monotonic() - start < patience:
            time.sleep(_POLL)
    return time.monotonic() - start


def release(directory: Path, pid: int) -> None:
    """Remove the marks in ``directory`` that process ``pid`` (stopped) left."""
    for mark in directory.glob("*.compiling"):
        with contextlib.suppress(OSError, ValueError):
            if int(mark.read_text(encoding="ascii")) == pid:
                mark.unlink()


def first_class_argtypes(arguments: list, shader: int, outputs: int) -> tuple:
    """Numba's types of ``arguments``, the one at index ``shader`` (a jitted shader of ``outputs`` outputs) typed as a
    first-class function f(6 × float64, u (P,)) -> ``outputs`` float64s: called with the jitted function itself,
    Numba would type a kernel by that function object and compile it anew in every process."""
    import numba
    from numba import types

    signature = types.UniTuple(types.float64, outputs)(*(types.float64,) * 6, types.Array(types.float64, 1, "C"))
    return tuple(types.FunctionType(signature) if i == shader else numba.typeof(a) for i, a in enumerate(arguments))


def cache_mark(kernel, name: str, argtypes: tuple) -> Path | None:
    """The mark a process holds while it compiles ``kernel`` (a Numba dispatcher) for ``argtypes``, beside Numba's
    cache of it, named ``name`` and a digest of the types (None where Numba caches nothing)."""
    directory = getattr(kernel._cache, "_cache_path", None)
    if directory is None:
        return None
    digest = hashlib.sha256(str(argtypes).encode()).hexdigest()[:16]
    return Path(directory) / f"{name}-{digest}.compiling"


def in_cache(kernel, argtypes: tuple) -> bool:
    """Whether Numba's disk cache holds ``kernel`` (a dispatcher) for ``argtypes``, fresh: whether a call would load
    it rather than compile it (False where Numba caches nothing, or keeps its index otherwise than 0.6x does)."""
    cache = getattr(kernel, "_cache", None)
    try:
        return cache._index_key(argtypes, kernel.targetctx.codegen()) in cache._cache_file._load_index()
    except Exception:  # noqa: BLE001 - a Numba without this index: "not cached" only costs loading what is cached
        return False


def compile_marked(kernel, name: str, argtypes: tuple) -> None:
    """Compile ``kernel`` for ``argtypes`` under its :func:`cache_mark`: where another process is compiling the same
    signature, wait for it first (Numba then loads its result from the cache instead of compiling it beside it)."""
    mark = cache_mark(kernel, name, argtypes)
    if mark is None:
        kernel.compile(argtypes)
        return
    await_other(mark)
    with holding(mark):
        kernel.compile(argtypes)
