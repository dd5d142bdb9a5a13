"""Numba's on-disk cache of the package's kernels, kept in step with every source file compiled into them.

Numba keys a cached kernel on its own source file only (its content hash, in the ``.nbi`` index beside the
``.nbc`` machine code: numba.core.caching). A kernel's machine code also holds what it calls from other modules
(``inline="always"`` or not: slopes.py's node maps inside global_rule.py's kernels, models/native.py's Λ and Fresnel
inside slopes.py's) and the module globals it reads, frozen as constants (machinery/tensor_rule.py's FLOOR and
SAFETY in global_rule.py, machinery/kronrod.py's nodes in routes/anisotropic.py). An edit there leaves the cached
kernel as it was: a process would run the old code. So :func:`refresh`, called once where the compiled backend loads
(:func:`brdfnorm.engine.compiled.backend.numba_available`, before any kernel loads), keeps a stamp — a SHA-256 of
:data:`SOURCES`, the cached modules (:data:`CACHED`) and every module of the package they import — in the cache
directory Numba uses for the compiled modules, and where it differs, removes the cache entries (``*.nbi``,
``*.nbc``) of :data:`CACHED` from their cache directories, so that Numba compiles them anew.

- Cheap: the stamp also records each source's (mtime, size); where they match, nothing is read or hashed
  (0.15–0.3 ms: a stat per source and the locator). Otherwise the sources are hashed (~0.7 ms); a checkout that
  changed only times rewrites the stamp and removes nothing.
- Safe with two processes at once (a command and :mod:`brdfnorm.parallel.warm`'s child): the slow path holds an
  exclusive lock (``fcntl.flock`` on a file beside the stamp) and reads the stamp again under it, so one process
  removes and the other then finds the new stamp; the entries are removed before the stamp is written (a process
  stopped in between leaves the old stamp: the next one removes again) and the stamp is written by an atomic rename.
  A process loading a kernel whose files are removed meanwhile compiles it (Numba's loader treats a missing index or
  data file as no entry).
- Narrow: only files named ``<module>.<function>-<line>.py<version>.nbi|nbc`` of the modules of :data:`CACHED`, in
  the directory Numba's own locators choose for each (``__pycache__`` beside it, a subdirectory of
  ``$NUMBA_CACHE_DIR`` named after its directory, or the user-wide cache), are ever removed.

The per-shader copies of :mod:`.kernels` (:mod:`.drivers`) are named after a hash of their sources, and the GLSL
shaders' generated modules (:mod:`brdfnorm.glsl.native`) after theirs: neither is this module's concern.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
from collections.abc import Callable, Iterable
from pathlib import Path

#: The package's root (src/brdfnorm).
PACKAGE = Path(__file__).resolve().parents[2]
#: The modules whose kernels Numba caches (``cache=True``), relative to :data:`PACKAGE`.
CACHED = (
    "engine/compiled/global_rule.py",
    "engine/compiled/hemimap.py",
    "engine/compiled/kernels.py",
    "engine/compiled/rules.py",
    "engine/compiled/slopes.py",
    "engine/routes/anisotropic.py",
    "models/native.py",
    "models/zeltner_native.py",
)
#: What the stamp hashes: :data:`CACHED` and every module of the package one of them imports (what their machine code
#: may hold: tests/engine/test_kernel_staleness.py keeps the list complete).
SOURCES = CACHED + (
    "engine/compiled/backend.py",
    "engine/compiled/marks.py",
    "engine/machinery/grid_estimate.py",
    "engine/machinery/kronrod.py",
    "engine/machinery/tensor_rule.py",
    "errors.py",
    "models/base.py",
    "models/fresnel.py",
    "models/microfacet.py",
)
#: The stamp's and the lock's names in the cache directory of :mod:`brdfnorm.engine.compiled`.
STAMP = "brdfnorm-sources.stamp"
LOCK = "brdfnorm-sources.lock"

#: (source file) -> the directory Numba caches its kernels in (None: none, e.g. no writable place).
Locator = Callable[[Path], Path | None]


def numba_cache_directory(source: Path) -> Path | None:
    """The directory Numba's cache locators choose for kernels defined in ``source`` (as ``numba.core.caching`` does
    for a function: the first of its locator classes that accepts the file), or None."""
    from numba.core import caching

    # (CacheImpl in current Numba, _CacheImpl in older ones; other internals: no directory known, nothing removed)
    kinds = getattr(getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl", None), "_locator_classes", ())

    def probe() -> None:  # a function "defined in" source: the locators read only its code's first line
        pass

    for kind in kinds:
        with contextlib.suppress(Exception):  # a locator that cannot serve this file declines
            locator = kind.from_function(probe, str(source))
            if locator is not None:
                return Path(locator.get_cache_path())
    return None


def entries(directory: Path, source: Path) -> list[Path]:
    """Numba's cache files (index and data) of the kernels of module ``source`` in ``directory``."""
    stem = source.stem
    return [path for path in directory.glob(f"{stem}.*.nb[ic]")
            if path.name.endswith((".nbi", ".nbc")) and ".py" in path.name[len(stem):]]


def _stats(sources: Iterable[Path]) -> list[list]:
    out = []
    for path in sources:
        status = path.stat()
        out.append([str(path), status.st_mtime_ns, status.st_size])
    return out


def _digest(sources: Iterable[Path]) -> str:
    digest = hashlib.sha256()
    for path in sources:
        digest.update(path.name.encode() + b"\0" + path.read_bytes() + b"\0")
    return digest.hexdigest()


def _read(stamp: Path) -> dict:
    try:
        return json.loads(stamp.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}


@contextlib.contextmanager
def _locked(path: Path):
    """An exclusive lock on ``path`` for the block (none where ``fcntl`` is missing: Windows)."""
    try:
        import fcntl
    except ImportError:
        yield
        return
    with open(path, "a+b") as handle:
        fcntl.flock(handle, fcntl.LOCK_EX)
        try:
            yield
        finally:
            fcntl.flock(handle, fcntl.LOCK_UN)


def refresh(sources: Iterable[Path] | None = None, cached: Iterable[Path] | None = None,
            locate: Locator = numba_cache_directory) -> list[Path]:
    """Remove the cache entries of ``cached`` (default :data:`CACHED`) where the stamp of ``sources`` (default
    :data:`SOURCES`) differs from the one kept in the cache directory of the first of ``cached``; returns the files
    removed (none where the stamp matches or no cache directory is found)."""
    sources = [PACKAGE / s for s in SOURCES] if sources is None else [Path(s) for s in sources]
    cached = [PACKAGE / s for s in CACHED] if cached is None else [Path(s) for s in cached]
    home = locate(cached[0])
    if home is None:
        return []
    stamp = home / STAMP
    try:
        stats = _stats(sources)
    except OSError:  # a source missing (a partial install): nothing to compare
        return []
    if _read(stamp).get("stats") == stats:
        return []
    removed: list[Path] = []
    with contextlib.suppress(OSError), _locked(home / LOCK):  # (a read-only cache: Numba writes nothing there either)
        digest = _digest(sources)
        if _read(stamp).get("digest") != digest:
            for source in cached:
                directory = locate(source)
                for path in entries(directory, source) if directory is not None else ():
                    with contextlib.suppress(FileNotFoundError):
                        path.unlink()
                        removed.append(path)
        temporary = stamp.with_name(f"{STAMP}.{os.getpid()}.tmp")
        temporary.write_text(json.dumps({"digest": digest, "stats": stats}), encoding="utf-8")
        os.replace(temporary, stamp)
    return removed
