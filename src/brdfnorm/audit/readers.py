"""Read a table someone else made: .npz, .exr, .png, .csv, .json, C/C++/GLSL/HLSL/JavaScript array literals, raw.

The bytes are decoded by the reader core, :mod:`brdfnorm.inputs` (one bounded decoder per format, the limits of
:mod:`brdfnorm.inputs.limits`, every parse failure one error naming the file); this module keeps what an audit
needs: which array is the table, its storage (dtype, scale) and channels. What comes back is a :class:`Source`:
the values as floats, shaped (*grid, channels), with what :mod:`.fix` needs to write a drop-in replacement
(storage dtype, scale, format and its layout details). Raw binary takes an ``offset``, a ``shape``, a ``dtype``
and a ``byteorder``; a C declaration's size expression (``g_dfg[32 * 32 * 2]``) is its shape.

Storage: integer data are normalized by their type's maximum (uint8 / 255, uint16 / 65535) unless ``scale`` is
given; ``dtype="float16"`` reads 16-bit integers (or raw bytes) as half-float bit patterns, as engines upload
them (``new Uint16Array([0x30b5, ...])`` with a half-float texture).
"""

from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, TableFileError
from ..inputs import element_count, npz_arrays, parsing, png, read_bounded, regular_file, shorten
from ..inputs import raw as raw_binary
from ..inputs.delimited import read_rows
from ..inputs.exr import exr_parts
from ..inputs.jsonio import at_path, load_json, numeric_arrays, to_array
from ..inputs.limits import MAX_ARRAY_BYTES, MAX_ELEMENTS, MAX_FILE_BYTES
from ..inputs.literals import find_literals
from ..inputs.raw import DTYPES

#: Byte caps :mod:`.fix` reads a source back with (the reader core's, by kind of file).
MAX_BINARY_BYTES = MAX_FILE_BYTES["raw"]
MAX_TEXT_BYTES = MAX_FILE_BYTES["text"]
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
                                where="fmt")
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
               scale: float | None = None, channels: bool | None = None, offset: int = 0,
               byteorder: str = "<") -> Source:
    """Read the table in ``path`` (see the module docstring); ``array`` picks one of several; ``channels``
    overrides the guess whether the last axis holds channels (True) or is a grid axis (False); ``offset`` and
    ``byteorder`` (``<``/``little``, ``>``/``big``) place a raw file's values."""
    where = os.fspath(path)
    regular_file(where)  # a missing file or a directory is said so before its extension is judged
    kind = format_of(where, fmt)
    if dtype is not None and dtype not in DTYPES:
        raise ArgumentError(f"unknown dtype {shorten(repr(dtype))} (known: {', '.join(DTYPES)})", where="dtype")
    if order not in ("C", "F"):
        raise ArgumentError("--order is C (last index fastest) or F (first index fastest)", where="order")
    if shape is not None:
        element_count(shape, MAX_ELEMENTS, where="shape", error=ArgumentError, what="--shape")
    if (offset or byteorder not in ("<", "little")) and kind != "raw":
        raise ArgumentError("--offset and --byte-order place a raw binary file's values (format raw)",
                            where="offset")
    byteorder = raw_binary.byte_order(byteorder)
    data = read_bounded(where, MAX_FILE_BYTES[kind])
    with parsing(where):
        source = READERS[kind](data, where, array=array, shape=shape, dtype=dtype, order=order, scale=scale,
                               offset=offset, byteorder=byteorder)
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
            shown = ", ".join(shorten(n, 40) for n in names[:12]) + (", …" if len(names) > 12 else "")
            raise TableFileError(f"no array {shorten(repr(array))} (it holds: {shown or 'none'})", where)
        return array
    if len(names) != 1:
        shown = ", ".join(shorten(n, 40) for n in names[:12]) + (", …" if len(names) > 12 else "")
        raise TableFileError(f"holds {len(names)} arrays ({shown}); choose one with --array", where)
    return names[0]


def _read_npz(data, where, *, array, shape, dtype, order, scale, **_) -> Source:
    arrays = npz_arrays(data, where, max_elements=MAX_ELEMENTS, max_bytes=MAX_ARRAY_BYTES)
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


def _read_exr(data, where, *, array, shape, dtype, order, scale, **_) -> Source:
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


def _read_png(data, where, *, array, shape, dtype, order, scale, **_) -> Source:
    codes, depth, text = png.decode(data, where)
    names = png.NAMES[codes.shape[-1]]
    stored = f"uint{depth}"
    own = _brdfnorm_scaling(text)
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


def _read_csv(data, where, *, array, shape, dtype, order, scale, **_) -> Source:
    rows = read_rows(data, where)  # bounded; the header rule: names only (a NUL in a cell is no name)
    header, matrix = rows.header, rows.values
    stored = dtype or "float64"
    if array is not None:  # one column by name, reshaped by --shape
        if header is None or array not in header:
            raise TableFileError(f"no column {shorten(repr(array))}", where)
        values = _shaped(matrix[:, header.index(array)], shape, order, where)
    else:
        values = _shaped(matrix.ravel(), shape, order, where) if shape else matrix
    values, factor = _normalize(values, stored, scale, where)
    values, names = _with_channels(values)
    return Source(where, "csv", array or "", values, names, stored, factor,
                  layout={"header": header, "rows": matrix.shape, "column": array, "order": order,
                          "shape": shape})


def _read_json(data, where, *, array, shape, dtype, order, scale, **_) -> Source:
    document = load_json(data, where, "the file", finite=False)
    names = numeric_arrays(document)
    name = _pick(list(names), array, where)
    raw = to_array(at_path(document, names[name]), name, where)
    stored = dtype or "float64"
    integers = stored.startswith(("uint", "int")) or stored == "float16"
    values, factor = _normalize(_shaped(raw.ravel(order=order), shape, order, where) if shape else
                                (raw.astype(np.int64) if integers else raw), stored, scale, where)
    values, names_ = _with_channels(values)
    return Source(where, "json", name, values, names_, stored, factor,
                  layout={"key": list(names[name]), "shape": raw.shape, "order": order, "reshaped": shape is not None})


def _read_text(data, where, *, array, shape, dtype, order, scale, **_) -> Source:
    text = data.decode("utf-8", errors="replace")
    literals = [lit for lit in find_literals(text, where) if len(lit.values) > 1 and not lit.problem]
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
        if literal.declared and math.prod(literal.declared) == flat.size:
            shape = literal.declared
        elif literal.nested is not None and len(literal.nested) > 1:
            shape = literal.nested
        elif literal.declared and flat.size % math.prod(literal.declared) == 0:  # float2 t[256]: 2 per element
            shape = (*literal.declared, flat.size // math.prod(literal.declared))
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


def _read_raw(data, where, *, array, shape, dtype, order, scale, offset=0, byteorder="<", **_) -> Source:
    if shape is None:
        raise TableFileError("raw binary needs --shape (and --dtype, default float32)", where)
    stored = dtype or "float32"
    values = raw_binary.decode(data, where, shape=shape, dtype=stored, byteorder=byteorder, offset=offset, order=order,
                        max_elements=MAX_ELEMENTS)
    values, factor = _normalize(values, stored, scale, where)
    values, names = _with_channels(values)
    return Source(where, "raw", "", values, names, stored, factor,
                  layout={"order": order, "shape": tuple(shape), "offset": offset, "byteorder": byteorder})


READERS = {"npz": _read_npz, "exr": _read_exr, "png": _read_png, "csv": _read_csv, "json": _read_json,
           "text": _read_text, "raw": _read_raw}


def parse_shape(text: str | None) -> tuple[int, ...] | None:
    """``64,64,4`` (or ``64x64x4``) -> (64, 64, 4), checked against MAX_ELEMENTS before anything is allocated;
    each size at most 18 digits (a longer one is refused before ``int`` reads it)."""
    if text is None:
        return None
    parts = [part.strip() for part in text.replace("x", ",").split(",")]
    if any(not part.isascii() or not part.isdigit() or len(part) > 18 for part in parts):
        raise ArgumentError(f"expected sizes like 64,64,4, got {shorten(repr(text))}", where="shape")
    shape = tuple(int(part) for part in parts)
    element_count(shape, MAX_ELEMENTS, where="shape", error=ArgumentError, what="--shape")
    return shape


def _brdfnorm_scaling(text: dict[str, str]) -> tuple[np.ndarray, np.ndarray] | None:
    """(lo, hi) per channel of a PNG that ``brdfnorm lut`` wrote (value = lo + code/65535·(hi − lo)), else None.
    A channel without a table (B of a two-table RGB image) is lo = 0, hi = 1."""
    payload = text.get("brdfnorm-lut")
    if payload is None:
        return None
    try:
        info = json.loads(payload)["png"]
        if "channels" not in info:  # one greyscale table (before the R, G, B, A mapping)
            return np.array([float(info["lo"])]), np.array([float(info["hi"])])
        entries = list(info["channels"].values())
        count = 1 if len(entries) == 1 else 3 if len(entries) <= 3 else 4
        entries += [{"lo": 0.0, "hi": 1.0}] * (count - len(entries))
        return (np.array([float(e["lo"]) for e in entries]), np.array([float(e["hi"]) for e in entries]))
    except (KeyError, TypeError, ValueError, AttributeError):
        return None
