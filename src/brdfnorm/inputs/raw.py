"""Raw binary tables: ``shape`` values of ``dtype`` in ``byteorder`` (``<`` little-endian, ``>`` big-endian),
starting ``offset`` bytes into the file, laid out in ``order`` (C: last index fastest; F: first index fastest).
The size the shape and dtype need is checked against the file's length (and :data:`~.limits.MAX_ELEMENTS`)
before a value is read; a file longer than offset + size must say so by its shape, not be silently cut."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError, TableFileError
from .guard import element_count

#: The element types a raw file (or ``dtype=``) may name.
DTYPES = ("float16", "float32", "float64", "uint8", "uint16", "uint32", "int8", "int16", "int32")
BYTE_ORDERS = {"little": "<", "big": ">", "<": "<", ">": ">"}


def byte_order(text: str) -> str:
    """``little``/``<`` or ``big``/``>`` as numpy's ``<`` or ``>``."""
    if text not in BYTE_ORDERS:
        raise ArgumentError(f"byte order {text!r}: little (<) or big (>)", where="byteorder")
    return BYTE_ORDERS[text]


def decode(data: bytes, where: str, *, shape: tuple[int, ...], dtype: str = "float32", byteorder: str = "<",
           offset: int = 0, order: str = "C", max_elements: int) -> np.ndarray:
    """The array of ``shape`` in ``data`` (see the module docstring), in native byte order."""
    if dtype not in DTYPES:
        raise ArgumentError(f"unknown dtype {dtype!r} (known: {', '.join(DTYPES)})", where="dtype")
    if isinstance(offset, bool) or not isinstance(offset, int) or offset < 0:
        raise ArgumentError(f"offset {offset!r}: a number of bytes ≥ 0", where="offset")
    storage = np.dtype(dtype).newbyteorder(byte_order(byteorder))
    count = element_count(shape, max_elements, where=where, what="the shape")
    need = count * storage.itemsize
    if offset > len(data):
        raise TableFileError(f"{len(data)} bytes; the offset {offset} is past its end", where)
    if len(data) - offset != need:
        raise TableFileError(f"{len(data) - offset} bytes after offset {offset}; shape {','.join(map(str, shape))} "
                             f"of {dtype} needs {need}", where)
    raw = np.frombuffer(data, dtype=storage, count=count, offset=offset)
    return raw.astype(storage.newbyteorder("=")).reshape(shape, order=order)
