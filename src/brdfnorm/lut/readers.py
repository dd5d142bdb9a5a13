"""Reading lookup-table files back (:func:`brdfnorm.lut.load`): what brdfnorm's own table files mean.

The bytes are decoded by the reader core, :mod:`brdfnorm.inputs` (one bounded decoder per format, the limits of
:mod:`brdfnorm.inputs.limits`, every failure one :class:`~brdfnorm.errors.TableFileError` naming the file); this
module keeps only what a brdfnorm table file means: the metadata (``meta``: axes, tables, and per format where
each table is: npz arrays, a JSON object, CSV columns, C/GLSL/HLSL declarations, EXR parts and channels, PNG
channels with their ``lo``/``hi`` scaling), matched against what the file holds. Metadata that does not match the
data is an error (a table the metadata declares and the file lacks, an image with fewer channels than named).

Cells must be finite real numbers: NaN, ±inf, complex values and text are refused with the table's name and the
cell's index (or the file's line and column). Axes must be 1-D and strictly monotonic. Tables keep the precision
the file holds: float32 from EXR and code (float16 from a ``half`` EXR), float64 otherwise. The layout a file was
written in (:mod:`.layout`) is undone by :func:`brdfnorm.lut.load`, not here.
"""

from __future__ import annotations

import math
import os

import numpy as np

from ..errors import ArgumentError, TableFileError
from ..inputs import npz_arrays, parsing, png, read_bounded, shorten
from ..inputs.delimited import read_rows
from ..inputs.exr import exr_parts
from ..inputs.jsonio import load_json
from ..inputs.limits import MAX_ARRAY_BYTES, MAX_ELEMENTS, MAX_FILE_BYTES
from ..inputs.literals import find_literals
from .images import RGBA
from .layout import MAGIC
from .table import Lut

#: The reader core's format of each table file extension.
CORE_FORMAT = {"npz": "npz", "exr": "exr", "png": "png", "json": "json", "csv": "csv", "h": "text",
               "glsl": "text", "hlsl": "text"}


# -- shared pieces ------------------------------------------------------------------------------------------

def meta_from(payload: object, where: str) -> tuple[dict, dict]:
    meta = payload.get("meta") if isinstance(payload, dict) else None
    if not isinstance(meta, dict) or not isinstance(meta.get("axes"), list) or not isinstance(meta.get("tables"),
                                                                                              dict):
        raise TableFileError("no brdfnorm lut metadata (axes, tables)", where)
    return meta, meta["tables"]


def _index_text(index: tuple[int, ...]) -> str:
    return "[" + ", ".join(str(int(i)) for i in index) + "]"


def cells(value: object, name: str, path: str) -> np.ndarray:
    """``value`` as float64 (float32 and float16 arrays as they are: the precision the file holds) if every cell
    is a finite real number, else an error naming ``name`` and the first bad cell's index (row-major)."""
    try:
        data = value if isinstance(value, np.ndarray) else np.asarray(value)
    except (ValueError, TypeError):
        raise TableFileError(f"{name}: not a regular array of numbers (rows of different lengths?)", path) from None
    kind = data.dtype.kind
    if kind == "c":
        imaginary = np.imag(data) != 0
        index = np.unravel_index(int(np.argmax(imaginary)), data.shape) if imaginary.any() else (0,) * data.ndim
        raise TableFileError(f"{name}, cell {_index_text(index)}: complex values ({data[index]}); tables hold real "
                             "numbers", path)
    if kind not in "fiu":
        flat = data.ravel()
        for position, cell in enumerate(flat):
            if isinstance(cell, (bool, np.bool_)) or not isinstance(cell, (int, float, np.integer, np.floating)):
                index = np.unravel_index(position, data.shape)
                raise TableFileError(f"{name}, cell {_index_text(index)}: {shorten(repr(str(cell)))} is not a number",
                                     path)
        data = np.array([float(c) for c in flat], dtype=float).reshape(data.shape)
    data = data if data.dtype in (np.float16, np.float32) else np.asarray(data, dtype=float)
    bad = ~np.isfinite(data)
    if bad.any():
        index = np.unravel_index(int(np.argmax(bad)), data.shape)
        raise TableFileError(f"{name}, cell {_index_text(index)}: {data[index]} is not a finite number", path)
    return data


def build(tables: dict, axes: dict, meta: dict, path: str) -> Lut:
    """The :class:`Lut` of arrays read from ``path``, each checked by :func:`cells`."""
    declared = list(meta.get("tables", {})) if isinstance(meta.get("tables"), dict) else []
    if sorted(tables) != sorted(declared):  # metadata that does not match the data is an error, not a drop
        raise TableFileError(f"the metadata declares tables {', '.join(map(str, declared)) or 'none'}; the file "
                             f"holds {', '.join(map(str, tables)) or 'none'}", path)
    checked_axes = {f"axis {name}": _axis(cells(array, f"axis {name}", path), name, path)
                    for name, array in axes.items()}
    checked_tables = {name: cells(array, f"table {name}", path) for name, array in tables.items()}
    for name, array in [*checked_tables.items(), *checked_axes.items()]:
        if array.size > MAX_ELEMENTS:
            raise TableFileError(f"{name} has {array.size} values, more than {MAX_ELEMENTS}", path)
    axes = {name.removeprefix("axis "): array for name, array in checked_axes.items()}
    try:
        return Lut(checked_tables, axes, meta, {name: meta["tables"][name] for name in tables})
    except (KeyError, TypeError) as error:
        raise TableFileError(f"tables and axes do not match the metadata ({error})", path) from None
    except ArgumentError as error:
        raise TableFileError(error.message, path) from None


def _axis(values: np.ndarray, name: str, path: str) -> np.ndarray:
    """An axis's values if they are one-dimensional and strictly monotonic (a grid has no repeated node)."""
    if values.ndim != 1:
        raise TableFileError(f"axis {name}: {values.ndim}-D values of shape {values.shape}; an axis is a 1-D "
                             "list", path)
    steps = np.diff(values.astype(float))
    if values.size > 1 and not (np.all(steps > 0) or np.all(steps < 0)):
        k = int(np.argmax(steps == 0)) if np.any(steps == 0) else int(np.argmax(np.sign(steps) != np.sign(steps[0])))
        what = (f"value {values[k]:g} repeated (index {k} and {k + 1})" if steps[k] == 0
                else f"not monotonic at index {k + 1}")
        raise TableFileError(f"axis {name}: {what}; an axis's values must strictly increase or decrease", path)
    return values


# -- npz ---------------------------------------------------------------------------------------------------

def read_npz(data: bytes, path: str) -> Lut:
    arrays = npz_arrays(data, path, max_elements=MAX_ELEMENTS, max_bytes=MAX_ARRAY_BYTES)
    text = arrays.get("meta")
    if text is None or text.dtype.kind != "U" or text.shape != ():
        raise TableFileError("not a brdfnorm npz table (no 'meta' text)", path)
    meta, table_axes = meta_from({"meta": load_json(str(text[()]), path)}, path)
    try:
        axes = {name: arrays[name] for name in meta["axes"]}
        tables = {name: arrays[name] for name in table_axes}
    except (KeyError, TypeError) as error:
        raise TableFileError(f"no array for {error} named in the metadata", path) from None
    return build(tables, axes, meta, path)


# -- json --------------------------------------------------------------------------------------------------

def read_json(data: bytes, path: str) -> Lut:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as error:
        raise TableFileError("not UTF-8 text", path, data.count(b"\n", 0, error.start) + 1) from None
    document = load_json(text, path, "the file")
    if not isinstance(document, dict) or document.get("format") != MAGIC:
        raise TableFileError(f"not a brdfnorm lut (no \"format\": \"{MAGIC}\")", path)
    meta, _ = meta_from(document, path)
    axes_in, tables_in = document.get("axes"), document.get("tables")
    if not isinstance(axes_in, dict) or not isinstance(tables_in, dict):
        raise TableFileError("\"axes\" and \"tables\" must be objects", path)
    try:
        axes = {n: axes_in[n] for n in meta["axes"]}
    except (KeyError, TypeError) as error:
        raise TableFileError(f"no axis {error} named in the metadata", path) from None
    return build(dict(tables_in), axes, meta, path)


# -- csv ---------------------------------------------------------------------------------------------------

def read_csv(data: bytes, path: str) -> Lut:
    if not data.startswith(f"# {MAGIC} ".encode()):
        raise TableFileError(f"the first line must be '# {MAGIC} {{metadata}}'", path, 1)
    rows = read_rows(data, path, header=True)  # bounded: rows counted before any is parsed
    meta, table_axes = meta_from({"meta": load_json(rows.comments[0][len(MAGIC) + 1:], path, line=1)}, path)
    names = [*meta["axes"], *table_axes]
    if rows.header != names:
        raise TableFileError(f"header must be {shorten(','.join(map(str, names)), 200)}", path, 2)
    table = rows.values
    bad = ~np.isfinite(table)
    if bad.any():
        row, column = (int(i) for i in np.argwhere(bad)[0])
        raise TableFileError(f"column {shorten(names[column])}: {table[row, column]} is not a finite number", path,
                             rows.first_line + row)
    k = len(meta["axes"])
    axes = {name: _unique_in_order(table[:, i]) for i, name in enumerate(meta["axes"])}
    shape = tuple(len(a) for a in axes.values())
    if len(table) != math.prod(shape) or any(
            not np.array_equal(np.broadcast_to(a.reshape((-1,) + (1,) * (k - 1 - i)), shape).ravel(), table[:, i])
            for i, a in enumerate(axes.values())):
        raise TableFileError("rows are not one per cell of the axes' grid in row-major order", path)
    tables = {}
    for j, name in enumerate(table_axes):
        full = table[:, k + j].reshape(shape)
        index = tuple(slice(None) if a in table_axes[name] else 0 for a in meta["axes"])
        tables[name] = full[index]
    return build(tables, axes, meta, path)


def _unique_in_order(column: np.ndarray) -> np.ndarray:
    _, first = np.unique(column, return_index=True)
    return column[np.sort(first)]


# -- C, GLSL, HLSL -----------------------------------------------------------------------------------------

def _declarations(text: str, path: str) -> dict[str, np.ndarray]:
    """The float32 arrays the file declares, by name: each initializer made of numbers only, its declared size
    matched (the literals are found by :func:`brdfnorm.inputs.literals.find_literals`)."""
    found = {}
    for literal in find_literals(text, path):
        name = shorten(literal.name or "an array")
        if literal.problem:
            raise TableFileError(f"{name}, {literal.problem}", path, literal.line)
        if not literal.declared:
            raise TableFileError(f"{name}: its size is not a number of elements", path, literal.line)
        count = math.prod(literal.declared)
        if len(literal.values) != count:
            raise TableFileError(f"{name}: {len(literal.values)} values for {count} elements", path, literal.line)
        # the file declares float32: its decimals name float32 values (9 digits name each one exactly); a value
        # past float32's range becomes inf here and is refused by cells() naming it
        with np.errstate(over="ignore"):
            found[literal.name] = np.frombuffer(literal.values, dtype=np.float64).astype(np.float32)
    return found


def read_code(data: bytes, path: str) -> Lut:
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError as error:
        raise TableFileError("not ASCII text (not a brdfnorm lut header)", path,
                             data.count(b"\n", 0, error.start) + 1) from None
    lines = text.splitlines()
    marker = f"// {MAGIC} "
    meta_line = next((i for i, line in enumerate(lines) if line.startswith(marker)), None)
    if meta_line is None:
        raise TableFileError(f"no '{marker}{{metadata}}' comment line", path)
    payload = load_json(lines[meta_line][len(marker):], path, line=meta_line + 1)
    meta, table_axes = meta_from(payload, path)
    ids = payload.get("identifiers", {})
    found = _declarations(text, path)  # comments (the meta line's text is the user's) are skipped by the scanner
    try:
        axis_values = meta.pop("axis_values")
        axes = {n: cells(axis_values[n], f"axis {n}", path) for n in meta["axes"]}
        tables = {}
        for name in table_axes:
            shape = tuple(len(axes[a]) for a in table_axes[name])
            tables[name] = found[ids[name]].reshape(shape) if shape else found[ids[name]].reshape(())
    except (KeyError, ValueError, TypeError) as error:
        raise TableFileError(f"arrays do not match the metadata (missing or misshapen: {error})", path) from None
    return build(tables, axes, meta, path)


# -- OpenEXR -----------------------------------------------------------------------------------------------

def read_exr(data: bytes, path: str) -> Lut:
    headers, images = exr_parts(data, path)
    text = headers[0].get("brdfnorm")
    meta, table_axes = meta_from({"meta": load_json(str(text), path)}, path)
    try:
        axis_values = meta.pop("axis_values")
        axes = {n: cells(axis_values[n], f"axis {n}", path) for n in meta["axes"]}
        # files before the R, G, B, A mapping: one part, a channel per table named by it
        exr = meta.pop("exr", None) or {"parts": [{"axes": meta["axes"], "channels": {n: n for n in table_axes}}]}
        tables = {}
        for part, channels in zip(exr["parts"], images, strict=True):
            shape = tuple(len(axes[a]) for a in part["axes"])
            for channel, name in part["channels"].items():
                full = cells(channels[channel], f"table {name}", path).reshape(shape)
                tables[name] = full[tuple(slice(None) if a in table_axes[name] else 0 for a in part["axes"])]
        tables = {name: tables[name] for name in table_axes}  # in the metadata's order, not the parts'
    except (KeyError, ValueError, TypeError, AttributeError) as error:
        raise TableFileError(f"channels do not match the metadata ({error})", path) from None
    return build(tables, axes, meta, path)


# -- PNG ---------------------------------------------------------------------------------------------------

def read_png(data: bytes, path: str) -> Lut:
    codes, depth, text = png.decode(data, path)  # bounded before inflating
    if MAGIC not in text:
        raise TableFileError("no brdfnorm metadata (tEXt) in this PNG", path)
    samples = codes.shape[-1]
    if depth != 16 or samples == 2:
        raise TableFileError("expected a 16-bit greyscale, RGB or RGBA PNG (as brdfnorm writes it)", path)
    codes = codes.astype(float)
    meta = load_json(text[MAGIC], path)
    _, table_axes = meta_from({"meta": meta}, path)
    try:
        info = meta.pop("png")
        axis_values = meta.pop("axis_values")
        axes = {n: cells(axis_values[n], f"axis {n}", path) for n in meta["axes"]}
        if "channels" not in info:  # one greyscale table (files before the R, G, B, A mapping)
            info = {"axes": table_axes[info["table"]], "channels": {"R": info}}
        shape = tuple(len(axes[a]) for a in info["axes"])
        if len(info["channels"]) > samples:
            raise ValueError(f"{len(info['channels'])} channels named, the image has {samples}")
        tables = {}
        for position, (channel, entry) in enumerate(info["channels"].items()):
            if channel != RGBA[position]:
                raise ValueError(f"channel {channel} in place {position}")
            lo, hi, name = float(entry["lo"]), float(entry["hi"]), entry["table"]
            if not (math.isfinite(lo) and math.isfinite(hi)):
                raise ValueError(f"channel {channel}: lo and hi must be finite numbers")
            full = (lo + codes[..., position] / 65535.0 * ((hi - lo) if hi > lo else 1.0)).reshape(shape)
            tables[name] = full[tuple(slice(None) if a in table_axes[name] else 0 for a in info["axes"])]
    except (KeyError, TypeError, ValueError, IndexError, AttributeError) as error:
        raise TableFileError(f"metadata does not describe the image ({error})", path) from None
    return build(tables, axes, meta, path)


READERS = {"npz": read_npz, "json": read_json, "csv": read_csv, "exr": read_exr, "h": read_code,
           "glsl": read_code, "hlsl": read_code, "png": read_png}


def read(path: str | os.PathLike, fmt: str) -> Lut:
    """The table in ``path`` read as ``fmt``: bounded (:func:`read_bounded`), guarded (:func:`parsing`)."""
    where = os.fspath(path)
    data = read_bounded(where, MAX_FILE_BYTES[CORE_FORMAT[fmt]])
    with parsing(where):
        return READERS[fmt](data, where)
