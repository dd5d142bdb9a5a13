"""The guard every reader of a user's file goes through: bounded before anything is allocated.

A reader asks :func:`read_bounded` for the bytes of a file (regular files only — a FIFO would block, a device such
as ``/dev/zero`` never ends — with the size checked against the format's cap from ``stat`` before a byte is
read), checks any shape a header declares with :func:`element_count` (the product computed without overflow,
before an array exists), and wraps its whole parse in :func:`parsing`, so that whatever goes wrong inside —
a ``struct.error``, a ``RecursionError`` from deep nesting, a ``MemoryError``, numpy's own complaints — ends as
one :class:`~brdfnorm.errors.BrdfnormError` naming the file, never as an internal error. :func:`npz_arrays`
reads a numpy archive (table files, checkpoint chunks) with every ``.npy`` header checked before its array exists.
"""

from __future__ import annotations

import os
import stat
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

from ..errors import BrdfnormError, TableFileError
from .limits import DEFAULT_FILE_BYTES, MAX_ERROR_TEXT


def shorten(text: object, limit: int = MAX_ERROR_TEXT) -> str:
    """``text`` of at most ``limit`` characters: a longer one keeps its start and end around " … "."""
    text = str(text)
    if len(text) <= limit:
        return text
    keep = (limit - 3) // 2
    return f"{text[:keep]} … {text[-keep:]}"


def _size_text(count: int) -> str:
    for unit, scale in (("GiB", 1024**3), ("MiB", 1024**2), ("KiB", 1024)):
        if count >= scale:
            return f"{count / scale:.3g} {unit}"
    return f"{count} bytes"


def regular_file(path: str | os.PathLike, *, error: type[BrdfnormError] = TableFileError) -> Path:
    """``path`` with symbolic links resolved, if it is an existing regular file; else ``error`` naming it.

    Checked with ``stat`` before the file is opened: opening a FIFO blocks until a writer comes."""
    where = os.fspath(path)
    try:
        info = os.stat(where)  # follows symbolic links: the target is what would be read
    except FileNotFoundError:
        raise error("no such file", where) from None
    except OSError as failure:
        raise error(f"cannot read: {failure.strerror or failure}", where) from None
    if stat.S_ISDIR(info.st_mode):
        raise error("a directory, not a file", where)
    if not stat.S_ISREG(info.st_mode):
        raise error("not a regular file (a FIFO, device or socket)", where)
    return Path(where).resolve()


def read_bounded(path: str | os.PathLike, max_bytes: int = DEFAULT_FILE_BYTES, *,
                 error: type[BrdfnormError] = TableFileError) -> bytes:
    """The bytes of a regular file of at most ``max_bytes``, refused from its size before it is read.

    The read itself is capped too (a file that grows while it is read is refused, not read to its end)."""
    where = os.fspath(path)
    resolved = regular_file(path, error=error)
    size = resolved.stat().st_size
    if size > max_bytes:
        raise error(f"{_size_text(size)}, more than the {_size_text(max_bytes)} this format allows", where)
    try:
        with open(resolved, "rb") as handle:
            data = handle.read(max_bytes + 1)
    except OSError as failure:
        raise error(f"cannot read: {failure.strerror or failure}", where) from None
    if len(data) > max_bytes:
        raise error(f"more than the {_size_text(max_bytes)} this format allows", where)
    return data


def element_count(shape: Iterable[object], limit: int, *, where: str,
                  error: type[BrdfnormError] = TableFileError, what: str = "the declared shape") -> int:
    """The number of elements of ``shape`` if every dimension is an integer ≥ 1 and their product is at most
    ``limit``; computed dimension by dimension, so that a shape of 5 000-digit sizes fails at once, without
    overflow and without building the product."""
    count = 1
    dims = list(shape)
    for dim in dims:
        if isinstance(dim, bool) or not isinstance(dim, int):
            raise error(f"{what} has a dimension that is not an integer: {str(dim)[:40]!r}", where)
        if dim < 1:
            raise error(f"{what} has a dimension of {dim}; every dimension must be at least 1", where)
        if dim > limit or count * dim > limit:
            shown = " × ".join(str(d) if isinstance(d, int) and d <= limit else f"{_big(d)}" for d in dims)
            raise error(f"{what} ({shown}) holds more than {limit} elements", where)
        count *= dim
    return count


def _big(dim: object) -> str:
    """A dimension too large to print in full (``str`` of a 5 000-digit integer raises)."""
    return f"~2^{dim.bit_length()}" if isinstance(dim, int) else "?"


@contextmanager
def parsing(path: str | os.PathLike, *, error: type[BrdfnormError] = TableFileError) -> Iterator[None]:
    """Turn any failure inside a parse into one ``error`` naming the file (a :class:`BrdfnormError` raised
    inside keeps its message and place)."""
    where = os.fspath(path)
    try:
        yield
    except BrdfnormError:
        raise
    except RecursionError:
        raise error("nested too deeply to read", where) from None
    except MemoryError:
        raise error("too large to read in memory", where) from None
    except Exception as failure:  # noqa: BLE001 — the point of the guard: every parse failure is the file's
        text = shorten(str(failure).splitlines()[0], 200) if str(failure) else type(failure).__name__
        raise error(f"cannot parse: {text}", where) from None
