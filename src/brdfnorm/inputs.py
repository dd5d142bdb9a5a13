"""The one guard every reader of a user's file goes through: bounded before anything is allocated.

A reader asks :func:`read_bounded` for the bytes of a file (regular files only — a FIFO would block, a device such
as ``/dev/zero`` never ends — with the size checked against the format's cap from ``stat`` before a byte is
read), checks any shape a header declares with :func:`element_count` (the product computed without overflow,
before an array exists), and wraps its whole parse in :func:`parsing`, so that whatever goes wrong inside —
a ``struct.error``, a ``RecursionError`` from deep nesting, a ``MemoryError``, numpy's own complaints — ends as
one :class:`~brdfnorm.errors.BrdfnormError` naming the file, never as an internal error. :func:`npz_arrays`
reads a numpy archive (table files, checkpoint chunks) with every ``.npy`` header checked before its array exists.
"""

from __future__ import annotations

import io
import os
import stat
import struct
import zipfile
from collections.abc import Iterable, Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from .errors import BrdfnormError, TableFileError

#: Default cap on the bytes of one input file (a format may ask for less or more).
MAX_FILE_BYTES = 256 * 1024**2
#: Bytes of an ``.npz``'s central directory (brdfnorm writes a few hundred; zipfile makes one object per entry).
MAX_ZIP_DIRECTORY = 1024**2
#: Bytes of one ``.npy`` header (numpy's own default limit).
NPY_HEADER_BYTES = 10_000


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


def read_bounded(path: str | os.PathLike, max_bytes: int = MAX_FILE_BYTES, *,
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
        text = str(failure).splitlines()[0][:200] if str(failure) else type(failure).__name__
        raise error(f"cannot parse: {text}", where) from None


def _zip_directory_bounded(data: bytes, path: str, error: type[BrdfnormError]) -> None:
    """Refuse an archive whose central directory (read from its end record, before :mod:`zipfile` parses it into
    one object per entry) is larger than :data:`MAX_ZIP_DIRECTORY`, or that needs ZIP64 (never written here)."""
    end = data.rfind(b"PK\x05\x06", max(0, len(data) - 65_557))
    if end < 0 or end + 22 > len(data):
        raise error("not a numpy archive (no zip end record)", path)
    entries, size, offset = struct.unpack("<HII", data[end + 10:end + 20])
    if entries == 0xFFFF or size == 0xFFFFFFFF or offset == 0xFFFFFFFF:
        raise error("a ZIP64 archive, which brdfnorm never writes", path)
    if size > MAX_ZIP_DIRECTORY:
        raise error(f"the zip directory takes {size} bytes (more than {MAX_ZIP_DIRECTORY})", path)


def _npy_member(archive: zipfile.ZipFile, info: zipfile.ZipInfo, path: str, max_elements: int, max_bytes: int,
                error: type[BrdfnormError]) -> np.ndarray:
    """One ``.npy`` member: header first (shape and dtype checked), then exactly the declared bytes."""
    name = info.filename.removesuffix(".npy")
    with archive.open(info) as member:
        version = np.lib.format.read_magic(member)
        if version == (1, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_1_0(member, max_header_size=NPY_HEADER_BYTES)
        elif version == (2, 0):
            shape, fortran, dtype = np.lib.format.read_array_header_2_0(member, max_header_size=NPY_HEADER_BYTES)
        else:
            raise error(f"array {name!r}: .npy format version {version} (brdfnorm writes 1.0)", path)
        if dtype.hasobject or dtype.kind not in "biufcU":
            raise error(f"array {name!r}: dtype {dtype} is not numbers", path)
        count = element_count(shape, max_elements, where=path, error=error, what=f"array {name!r}'s shape")
        size = count * dtype.itemsize
        if size > max_bytes:
            raise error(f"array {name!r} declares {size} bytes (more than {max_bytes})", path)
        raw = member.read(size + 1)
    if len(raw) != size:
        raise error(f"array {name!r} holds {len(raw)} bytes of data, its header declares {size}", path)
    return np.frombuffer(raw, dtype=dtype).reshape(shape, order="F" if fortran else "C")


def npz_arrays(data: bytes, path: str, *, max_elements: int, max_bytes: int,
               error: type[BrdfnormError] = TableFileError) -> dict[str, np.ndarray]:
    """The arrays of an ``.npz`` archive (numpy's ``savez``), never pickled, each shape checked before its array
    exists: the central directory bounded from the end record, every member a ``.npy`` whose header is read from
    the member itself (:func:`numpy.lib.format.read_array_header_1_0`), at most ``max_elements`` per array and
    ``max_bytes`` in all (the members' declared sizes bound what is inflated), and exactly the declared bytes."""
    _zip_directory_bounded(data, path, error)
    with zipfile.ZipFile(io.BytesIO(data)) as archive:
        infos = archive.infolist()
        declared = sum(info.file_size for info in infos)
        if declared > max_bytes + len(infos) * NPY_HEADER_BYTES:
            raise error(f"the archive's members declare {declared} bytes (more than {max_bytes})", path)
        names = [info.filename for info in infos]
        if len(set(names)) != len(names) or not all(n.endswith(".npy") for n in names):
            raise error("not a numpy archive of arrays (members other than one .npy per array)", path)
        return {info.filename.removesuffix(".npy"): _npy_member(archive, info, path, max_elements, max_bytes, error)
                for info in infos}
