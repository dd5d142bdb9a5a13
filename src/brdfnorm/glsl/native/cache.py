"""The per-user disk cache of generated shader modules, and loading them as Numba functions.

A generated module is written once to ``<cache>/glsl/brdf_<key>.py`` (``key``: SHA-256 of the generated source,
brdfnorm's version and Numba's) and imported from there, so that Numba's own ``cache=True`` keeps the machine
code next to it (``__pycache__``): a second run of the same shader compiles nothing. ``<cache>`` is
``$BRDFNORM_CACHE_DIR``, else ``$XDG_CACHE_HOME/brdfnorm``, else ``~/.cache/brdfnorm`` (the XDG Base Directory
specification). Directories are created with mode 0700; one that is not a directory of this user's, or that
others may write to, is not used (the module is then compiled in memory, every run) — code imported from a
directory someone else controls would run as this user. A file found under the key is used only when its text
is the generated source itself.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import os
import stat
import sys
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

_loaded: dict[str, Callable] = {}
_warned: set[str] = set()


def cache_root() -> Path:
    """The cache directory named by the environment (whether usable or not)."""
    explicit = os.environ.get("BRDFNORM_CACHE_DIR")
    if explicit:
        return Path(explicit)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"  # XDG: relative paths are ignored
    return base / "brdfnorm"


def _safe_directory(path: Path) -> bool:
    """Create ``path`` (mode 0700) if missing; whether it is a real directory of this user's that no one else
    may write to."""
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        info = os.lstat(path)
    except OSError:
        return False
    if not stat.S_ISDIR(info.st_mode) or info.st_mode & 0o022:
        return False
    return not hasattr(os, "getuid") or info.st_uid == os.getuid()


def module_directory() -> Path | None:
    """``<cache>/glsl`` when it and ``<cache>`` are safe to import from (else None, with one warning)."""
    root = cache_root()
    directory = root / "glsl"
    if _safe_directory(root) and _safe_directory(directory):
        return directory
    if str(root) not in _warned:
        _warned.add(str(root))
        warnings.warn(
            f"compiled shaders are not cached: {root} is not a directory of this user's that only they may write "
            "to (set BRDFNORM_CACHE_DIR)",
            RuntimeWarning,
            stacklevel=3,
        )
    return None


def cache_key(source: str) -> str:
    """The module's key: the generated source, brdfnorm's version and Numba's."""
    import numba

    version = sys.modules[__name__.split(".")[0]].__version__  # the package this module is part of: imported
    text = "\0".join((source, version, numba.__version__))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:40]


def _write(path: Path, source: str) -> bool:
    """Write ``source`` to ``path`` atomically unless it holds exactly that already; whether it does now."""
    data = source.encode("utf-8")
    try:
        if path.read_bytes() == data:
            return True
    except OSError:
        pass
    try:
        handle, temporary = tempfile.mkstemp(dir=path.parent, prefix=".brdf_", suffix=".tmp")
        try:
            with os.fdopen(handle, "wb") as out:
                out.write(data)
            os.replace(temporary, path)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(temporary)
            raise
    except OSError:
        return False
    return True


def load(source: str, key: str) -> Callable:
    """The Numba function ``brdf`` of a generated module: from the disk cache where possible."""
    function = _loaded.get(key)
    if function is not None:
        return function
    directory = module_directory()
    name = f"brdfnorm_glsl_native_{key}"
    path = directory / f"brdf_{key}.py" if directory is not None else None
    if path is not None and _write(path, source):
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # Numba's cache pickles references by module name
        try:
            spec.loader.exec_module(module)
        except BaseException:
            sys.modules.pop(name, None)
            raise
    else:
        module = type(sys)(name)
        code = compile(source.replace("cache=True", "cache=False"), f"<brdfnorm native {key}>", "exec")
        exec(code, module.__dict__)  # noqa: S102 - generated source: generated names and printed literals only
    function = module.brdf
    _loaded[key] = function
    return function
