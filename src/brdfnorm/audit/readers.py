"""Read a table someone else made: .npz, .exr, .png, .csv, .json, C/C++/GLSL/HLSL/JavaScript array literals, raw.

Every reader goes through :mod:`brdfnorm.inputs` (regular file, size capped before reading, declared shapes
checked by :func:`~brdfnorm.inputs.element_count` before an array exists, every parse failure one error naming
the file). What comes back is a :class:`Source`: the values as floats, shaped (*grid, channels), with what
:mod:`.fix` needs to write a drop-in replacement (storage dtype, scale, format and its layout details).

Storage: integer data are normalized by their type's maximum (uint8 / 255, uint16 / 65535) unless ``scale`` is
given; ``dtype="float16"`` reads 16-bit integers (or raw bytes) as half-float bit patterns, as engines upload
them (``new Uint16Array([0x30b5, ...])`` with a half-float texture).
"""

from __future__ import annotations

import csv
import io
import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, TableFileError
from ..inputs import element_count, npz_arrays, parsing, read_bounded, regular_file
from ..lut import pngio
from ..lut.readers import exr_parts
from .textarrays import find_literals

#: The most elements a table may hold.
MAX_ELEMENTS = 16 * 1024 * 1024
#: Byte caps per kind of file (text numbers take ~10 bytes each).
MAX_BINARY_BYTES = 256 * 1024**2
MAX_TEXT_BYTES = 64 * 1024**2
DTYPES = ("float16", "float32", "float64", "uint8", "uint16", "uint32", "int8", "int16", "int32")
TEXT_EXTENSIONS = {"h": "text", "hpp": "text", "c": "text", "cpp": "text", "cc": "text", "inl": "text",
                   "glsl": "text", "hlsl": "text", "frag": "text", "vert": "text", "fx": "text", "fxh": "text",
                   "js": "text", "mjs": "text", "ts": "text", "cs": "text"}
FORMATS = {"npz": "npz", "exr": "exr", "png": "png", "csv": "csv", "json": "json", "bin": "raw", "raw": "raw",
           **TEXT_EXTENSIONS}


@dataclass
class Source:
    """A table as read: ``values`` (*grid, channels) floats; how it was stored; what a rewrite needs."""

    path: str
    fmt: str
    name: str  # the array / declaration / key it came from ('' for single-array formats)
    values: np.ndarray
    channel_names: list[str]
    stored: str  # storage dtype: float16/float32/float64/uint8/uint16/...
    scale: float  # stored value = table value × scale (integers)
    notes: list[str] = field(default_factory=list)
    layout: dict = field(default_factory=dict)  # format details for .fix (spans, keys, order, ...)

    @property
    def grid_shape(self) -> tuple[int, ...]:
        return self.values.shape[:-1]

    def step(self) -> float:
        """The storage's resolution near 1 in table units: half a code for integers, half an ulp at 1 for
        floats (the largest rounding error a stored value in [0, 1] carries)."""
        if self.stored.startswith(("uint", "int")):
            return 0.5 / self.scale
        return 0.5 * float(np.finfo(np.dtype(self.stored)).eps)


def format_of(path: str, fmt: str | None) -> str:
    if fmt is not None:
        if fmt not in FORMATS and fmt not in FORMATS.values():
            raise ArgumentError(f"unknown format {fmt!r} (known: {', '.join(sorted(set(FORMATS.values())))})",
                                where="--format")
        return FORMATS.get(fmt, fmt)
    extension = Path(path).suffix.lower().lstrip(".")
    if extension not in FORMATS:
        raise TableFileError(f"unknown extension .{extension} (give --format: "
                             f"{', '.join(sorted(set(FORMATS.values())))})", path)
    return FORMATS[extension]


def _type_max(dtype: str) -> float:
    return float(np.iinfo(np.dtype(dtype)).max)


def _normalize(raw: np.ndarray, stored: str, scale: float | None, where: str) -> tuple[np.ndarray, float]:
    if stored == "float16" and raw.dtype.kind in "iu":
        if np.any((raw < 0) | (raw > 0xFFFF)) or np.any(raw != np.floor(raw)):
            raise TableFileError("float16 bit patterns must be integers in 0..0xFFFF", where)
        raw = np.asarray(raw, dtype=np.uint16).view(np.float16)
    if stored.startswith(("uint", "int")):
        factor = scale if scale is not None else _type_max(stored)
        return np.asarray(raw, dtype=float) / factor, factor
    factor = scale if scale is not None else 1.0
    return np.asarray(raw, dtype=float) / factor, factor


def _shaped(flat: np.ndarray, shape: tuple[int, ...] | None, order: str, where: str) -> np.ndarray:
    if shape is None:
        return flat
    count = element_count(shape, MAX_ELEMENTS, where=where, what="--shape")
    if flat.size != count:
        raise TableFileError(f"holds {flat.size} values; --shape {','.join(map(str, shape))} needs {count}", where)
    return flat.reshape(shape, order=order)


def _with_channels(array: np.ndarray, names: list[str] | None = None) -> tuple[np.ndarray, list[str]]:
    """(*grid, channels): a last axis of at most 4 after at least two larger ones is channels."""
    if names is not None:
        return array, names
    if array.ndim >= 3 and array.shape[-1] <= 4 and min(array.shape[:-1]) > 4:
        return array, [str(i) for i in range(array.shape[-1])]
    return array[..., None], ["0"]


def read_table(path: str | os.PathLike, *, fmt: str | None = None, array: str | None = None,
               shape: tuple[int, ...] | None = None, dtype: str | None = None, order: str = "C",
               scale: float | None = None, channels: bool | None = None) -> Source:
    """Read the table in ``path`` (see the module docstring); ``array`` picks one of several; ``channels``
    overrides the guess whether the last axis holds channels (True) or is a grid axis (False)."""
    where = os.fspath(path)
    regular_file(where)  # a missing file or a directory is said so before its extension is judged
    kind = format_of(where, fmt)
    if dtype is not None and dtype not in DTYPES:
        raise ArgumentError(f"unknown dtype {dtype!r} (known: {', '.join(DTYPES)})", where="--dtype")
    if order not in ("C", "F"):
        raise ArgumentError("--order is C (last index fastest) or F (first index fastest)", where="--order")
    if shape is not None:
        element_count(shape, MAX_ELEMENTS, where="--shape", error=ArgumentError, what="--shape")
    data = read_bounded(where, MAX_TEXT_BYTES if kind in ("text", "csv", "json") else MAX_BINARY_BYTES)
    with parsing(where):
        source = READERS[kind](data, where, array=array, shape=shape, dtype=dtype, order=order, scale=scale)
    if channels is False and source.channel_names != ["0"] and kind not in ("png", "exr"):
        source.values, source.channel_names = source.values[..., None], ["0"]
    elif channels is True and source.channel_names == ["0"] and source.values.ndim >= 3:
        source.values = source.values[..., 0]
        source.channel_names = [str(i) for i in range(source.values.shape[-1])]
    finite = np.isfinite(source.values)
    if not finite.any():
        raise TableFileError("no finite values in the table", where)
    size = source.values.shape[0]
    if source.values.ndim == 2 and shape is None and size >= 16:
        for power in (2, 3):
            root = round(size ** (1 / power))
            if root**power == size:
                source.notes.append(f"a 1-D array of {size} values: if it is a flattened table, give --shape "
                                    f"{','.join([str(root)] * power)}")
    return source


def _pick(names: list[str], array: str | None, where: str) -> str:
    if array is not None:
        if array not in names:
            raise TableFileError(f"no array {array!r} (it holds: {', '.join(names) or 'none'})", where)
        return array
    if len(names) != 1:
        raise TableFileError(f"holds {len(names)} arrays ({', '.join(names[:12])}); choose one with --array", where)
    return names[0]


def _read_npz(data, where, *, array, shape, dtype, order, scale) -> Source:
    arrays = npz_arrays(data, where, max_elements=MAX_ELEMENTS, max_bytes=MAX_BINARY_BYTES)
    numeric = [n for n, a in arrays.items() if a.dtype.kind in "fiu" and a.size > 1]
    name = _pick(numeric, array, where)
    raw = arrays[name]
    stored = dtype or raw.dtype.name
    if stored == "float16" and raw.dtype.kind == "f":
        raw = raw.astype(np.float16)
    values, factor = _normalize(_shaped(raw.ravel(order=order), shape, order, where) if shape else raw,
                                stored, scale, where)
    values, names = _with_channels(values)
    return Source(where, "npz", name, values, names, stored, factor,
                  layout={"arrays": list(arrays), "dtype": raw.dtype.str, "shape": raw.shape, "order": order,
                          "reshaped": shape is not None})


def _read_exr(data, where, *, array, shape, dtype, order, scale) -> Source:
    headers, parts = exr_parts(data, where)  # the first part: an engine's image (brdfnorm's E_avg is a second)
    header, channels = headers[0], parts[0]
    window = header.get("dataWindow")
    names = sorted(channels, key=lambda n: ("RGBAXYZ".find(n[-1]) if n[-1] in "RGBAXYZ" else 99, n))
    if array is not None:
        names = [_pick(names, array, where)]
    stacked = np.stack([channels[n] for n in names], axis=-1)
    element_count(stacked.shape, MAX_ELEMENTS, where=where, what="the image")
    stored = dtype or ("float16" if stacked.dtype == np.float16 else stacked.dtype.name)
    values, factor = _normalize(stacked, stored, scale, where)
    return Source(where, "exr", array or "", values, names, stored, factor,
                  layout={"pixel": {n: channels[n].dtype.name for n in names}, "all": list(channels),
                          "window": str(window)})


def _read_png(data, where, *, array, shape, dtype, order, scale) -> Source:
    codes, depth, text = pngio.decode(data, where)
    names = pngio.NAMES[codes.shape[-1]]
    stored = f"uint{depth}"
    own = pngio.brdfnorm_scaling(text)
    if own is not None and scale is None and own[0].size == codes.shape[-1]:  # brdfnorm's own: lo + code/65535·span
        lo, hi = own
        span = np.where(hi > lo, hi - lo, 1.0)
        values = lo + codes / 65535.0 * span  # per channel (R, G, B, A each its own lo, hi)
        one = lo.size == 1
        source = Source(where, "png", "", values, names, stored, 65535.0 / float(span.max()),  # the coarsest step
                        notes=["brdfnorm PNG: values lo + code/65535·(hi − lo), "
                               + ", ".join(f"lo={a:g}, hi={b:g}" for a, b in zip(lo, hi, strict=True))],
                        layout={"depth": depth, "text": text, "offset": float(lo[0]) if one else lo})
        return source
    values, factor = _normalize(codes, stored, scale, where)
    return Source(where, "png", "", values, names, stored, factor, layout={"depth": depth, "text": text})


def _numbers(rows: list[list[str]], where: str) -> np.ndarray:
    out = np.empty((len(rows), len(rows[0])))
    for i, row in enumerate(rows):
        if len(row) != len(rows[0]):
            raise TableFileError(f"row {i + 1} has {len(row)} cells, the first has {len(rows[0])}", where)
        for j, cell in enumerate(row):
            try:
                out[i, j] = float(cell)
            except ValueError:
                raise TableFileError(f"cell ({i + 1}, {j + 1}) is not a number: {cell.strip()[:30]!r}",
                                     where) from None
    return out


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_csv(data, where, *, array, shape, dtype, order, scale) -> Source:
    text = data.decode("utf-8-sig")
    rows = [r for r in csv.reader(io.StringIO(text)) if r and not r[0].lstrip().startswith("#")]
    if not rows:
        raise TableFileError("no rows", where)
    header = None
    if not all(_is_number(c) for c in rows[0]):
        header, rows = rows[0], rows[1:]
    if not rows:
        raise TableFileError("a header and no rows", where)
    element_count((len(rows), len(rows[0])), MAX_ELEMENTS, where=where, what="the rows × columns")
    matrix = _numbers(rows, where)
    stored = dtype or "float64"
    if array is not None:  # one column by name, reshaped by --shape
        if header is None or array not in header:
            raise TableFileError(f"no column {array!r}", where)
        raw = matrix[:, header.index(array)]
        values = _shaped(raw, shape, order, where)
    else:
        values = _shaped(matrix.ravel(), shape, order, where) if shape else matrix
    values, factor = _normalize(values, stored, scale, where)
    values, names = _with_channels(values)
    return Source(where, "csv", array or "", values, names, stored, factor,
                  layout={"header": header, "rows": matrix.shape, "column": array, "order": order,
                          "shape": shape})


def _json_arrays(node, path: tuple, found: dict, depth: int = 0) -> None:
    """Numeric (nested) lists in a JSON document by key path."""
    if depth > 64:
        raise RecursionError  # inputs.parsing: "nested too deeply to read", naming the file
    if isinstance(node, list) and node and all(isinstance(v, (int, float, list)) and not isinstance(v, bool)
                                               for v in node):
        found[path] = node
    elif isinstance(node, dict):
        for key, value in node.items():
            _json_arrays(value, (*path, key), found, depth + 1)


def _read_json(data, where, *, array, shape, dtype, order, scale) -> Source:
    document = json.loads(data.decode("utf-8"))
    found: dict[tuple, list] = {}
    _json_arrays(document, (), found)
    names = {".".join(map(str, p)) or "(root)": p for p in found}
    name = _pick(list(names), array, where)
    try:
        raw = np.array(found[names[name]], dtype=float)
    except ValueError:
        raise TableFileError(f"array {name!r} is not a regular nested list of numbers", where) from None
    if raw.dtype == object or not np.issubdtype(raw.dtype, np.number):
        raise TableFileError(f"array {name!r} is not numeric", where)
    element_count(raw.shape, MAX_ELEMENTS, where=where, what=f"array {name}")
    stored = dtype or "float64"
    integers = stored.startswith(("uint", "int")) or stored == "float16"
    values, factor = _normalize(_shaped(raw.ravel(order=order), shape, order, where) if shape else
                                (raw.astype(np.int64) if integers else raw), stored, scale, where)
    values, names_ = _with_channels(values)
    return Source(where, "json", name, values, names_, stored, factor,
                  layout={"key": list(names[name]), "shape": raw.shape, "order": order, "reshaped": shape is not None})


def _read_text(data, where, *, array, shape, dtype, order, scale) -> Source:
    text = data.decode("utf-8", errors="replace")
    literals = [lit for lit in find_literals(text, where) if len(lit.values) > 1]
    if not literals:
        raise TableFileError("no numeric array literal found", where)
    by_name = {lit.name or f"#{i}": lit for i, lit in enumerate(literals)}
    name = _pick(list(by_name), array, where)
    literal = by_name[name]
    flat = np.frombuffer(literal.values, dtype=np.float64)
    if literal.declared and all(d > 0 for d in literal.declared):
        declared = element_count(literal.declared, MAX_ELEMENTS, where=where, what=f"the declared shape of {name}")
        if flat.size < declared:
            raise TableFileError(f"{name} declares {declared} elements; its initializer holds {flat.size} "
                                 "(truncated?)", where)
        if flat.size % declared:
            raise TableFileError(f"{name} declares {declared} elements; its initializer holds {flat.size}", where)
    stored = dtype or literal.dtype or "float32"
    if shape is None:
        if literal.declared and int(np.prod(literal.declared)) == flat.size:
            shape = literal.declared
        elif literal.nested is not None and len(literal.nested) > 1:
            shape = literal.nested
        elif literal.declared and flat.size % int(np.prod(literal.declared)) == 0:  # float2 t[256]: 2 per element
            shape = (*literal.declared, flat.size // int(np.prod(literal.declared)))
        else:
            raise TableFileError(f"{name} is a flat list of {flat.size} numbers; give its --shape (e.g. 64,64 or "
                                 "64,64,4 for four interleaved channels)", where)
    raw = _shaped(flat, tuple(shape), order, where)
    if stored.startswith(("uint", "int")) or stored == "float16":
        if np.any(raw != np.floor(raw)):
            if stored == "float16" or dtype is not None:
                raise TableFileError(f"{name}: --dtype {stored} needs integer literals", where)
            stored = "float32"
        else:
            raw = raw.astype(np.int64)
    values, factor = _normalize(raw, stored, scale, where)
    values, names = _with_channels(values)
    return Source(where, "text", name, values, names, stored, factor,
                  layout={"text": text, "starts": literal.starts, "ends": literal.ends, "hex": literal.hex,
                          "suffix": literal.suffix, "order": order, "shape": tuple(shape), "start": literal.start})


def _read_raw(data, where, *, array, shape, dtype, order, scale) -> Source:
    if shape is None:
        raise TableFileError("raw binary needs --shape (and --dtype, default float32)", where)
    stored = dtype or "float32"
    storage = np.dtype(stored).newbyteorder("<")
    count = element_count(shape, MAX_ELEMENTS, where=where, what="--shape")
    if len(data) != count * storage.itemsize:
        raise TableFileError(f"{len(data)} bytes; --shape {','.join(map(str, shape))} of {stored} needs "
                             f"{count * storage.itemsize}", where)
    raw = np.frombuffer(data, dtype=storage).reshape(shape, order=order)
    values, factor = _normalize(raw, stored, scale, where)
    values, names = _with_channels(values)
    return Source(where, "raw", "", values, names, stored, factor, layout={"order": order, "shape": tuple(shape)})


READERS = {"npz": _read_npz, "exr": _read_exr, "png": _read_png, "csv": _read_csv, "json": _read_json,
           "text": _read_text, "raw": _read_raw}


def parse_shape(text: str | None) -> tuple[int, ...] | None:
    """``64,64,4`` -> (64, 64, 4) (checked against MAX_ELEMENTS before anything is allocated)."""
    if text is None:
        return None
    try:
        shape = tuple(int(part) for part in text.replace("x", ",").split(","))
    except ValueError:
        raise ArgumentError(f"expected sizes like 64,64,4, got {text!r}", where="--shape") from None
    element_count(shape, MAX_ELEMENTS, where="--shape", error=ArgumentError, what="--shape")
    return shape
