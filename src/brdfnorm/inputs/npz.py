"""Numpy archives (``.npz``, written by ``numpy.savez``): table files and checkpoint chunks, never unpickled, every
``.npy`` header checked before its array exists."""

from __future__ import annotations

import io
import struct
import zipfile

import numpy as np

from ..errors import BrdfnormError, TableFileError
from .guard import element_count, shorten
from .limits import MAX_ZIP_DIRECTORY, NPY_HEADER_BYTES


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
    name = shorten(info.filename.removesuffix(".npy"))
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
