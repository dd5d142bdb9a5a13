"""Reading lookup-table files back (:func:`brdfnorm.lut.load`), bounded before anything is allocated (issue 35).

Every reader gets its bytes from :func:`brdfnorm.inputs.read_bounded` (regular files only — a FIFO or
``/dev/zero`` is refused before it is opened — at most :data:`MAX_FILE_BYTES` of its format), checks every shape a
header declares with :func:`brdfnorm.inputs.element_count` before an array of that shape exists, and runs inside
:func:`brdfnorm.inputs.parsing`, so that any failure is one :class:`~brdfnorm.errors.TableFileError` naming the
file:

* ``.npz``: the zip's central directory is bounded from its end record, then each member's ``.npy`` header is read
  with :func:`numpy.lib.format.read_array_header_1_0` (or ``2_0``) from the member itself, its shape and dtype
  checked, and exactly the declared bytes read (the members' declared sizes bound what is inflated);
* PNG (16-bit greyscale, RGB or RGBA, channels mapped to tables by ``meta["png"]``), decoded by :mod:`.pngio`
  (which ``brdfnorm audit`` reads engines' PNGs with too): the IHDR chunk is 13 bytes, width and height each ≥ 1
  and width × height × samples capped before anything is inflated (and inflating is capped at the expected size);
* CSV: rows are read one at a time into a flat float64 buffer, counted as they come, and a header without rows is
  refused;
* C/GLSL/HLSL: declarations are found by an anchored head pattern and ``str.find`` of their ``;`` (no
  backtracking over the file), their sizes have at most 9 digits, every token of an initializer is a number;
* EXR (one or more parts, channels R, G, B, A mapped to tables by ``meta["exr"]["parts"]``), opened by
  :func:`exr_parts` (the audit's EXR reader too): the headers are read first (every part's data window and its
  channels' values checked), the library's diagnostics kept off stdout and stderr.

Cells must be finite real numbers: NaN, ±inf, complex values and text are refused with the table's name and the
cell's index (or the file's line and column). Tables keep the precision the file holds: float32 from EXR and code
(float16 from a ``half`` EXR), float64 otherwise. The layout a file was written in (:mod:`.layout`) is undone by
:func:`brdfnorm.lut.load`, not here.
"""

from __future__ import annotations

import io
import json
import math
import os
import re
import sys
import tempfile
from array import array as float_buffer
from contextlib import contextmanager

import numpy as np

from ..errors import ArgumentError, TableFileError
from ..inputs import element_count, npz_arrays, parsing, read_bounded
from . import pngio
from .images import RGBA
from .images import _openexr as openexr
from .layout import MAGIC
from .table import Lut

#: Refuse tables larger than this many cells on reading (a 1024³ float64 table is 8 GB).
MAX_CELLS = 50_000_000
_MIB = 1024**2
#: Bytes of one table file, by format. Text formats cost several times their size once parsed (JSON builds a
#: Python float per number), so their caps are lower: 64 MiB of JSON as brdfnorm writes it is about 3 million cells.
MAX_FILE_BYTES = {"npz": 512 * _MIB, "exr": 512 * _MIB, "png": 256 * _MIB, "json": 64 * _MIB, "csv": 128 * _MIB,
                  "h": 32 * _MIB, "glsl": 32 * _MIB, "hlsl": 32 * _MIB}
#: Bytes of all the arrays an ``.npz`` declares, decompressed (a 1.5 MB archive can declare gigabytes).
MAX_ARRAY_BYTES = 512 * _MIB


# -- shared pieces ------------------------------------------------------------------------------------------

def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a finite number")


def load_json(text: str | bytes, path: str, what: str = "metadata", line: int | None = None) -> object:
    """JSON without NaN/Infinity (deep nesting ends as :func:`parsing`'s "nested too deeply", never a traceback)."""
    try:
        return json.loads(text, parse_constant=_no_constant)
    except json.JSONDecodeError as error:
        raise TableFileError(f"{what} is not JSON: {error.msg} (line {error.lineno}, column {error.colno})",
                             path, line) from None
    except ValueError as error:  # NaN or Infinity: say where the first one is
        raw = text.decode("utf-8", "replace") if isinstance(text, bytes) else text
        found = re.search(r"-?\b(?:NaN|Infinity)\b", raw)
        at = f" (line {raw.count(chr(10), 0, found.start()) + 1})" if found else ""
        raise TableFileError(f"{what}: {error}{at}; tables hold finite numbers only", path, line) from None


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
                raise TableFileError(f"{name}, cell {_index_text(index)}: {str(cell)[:30]!r} is not a number",
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
        if array.size > MAX_CELLS:
            raise TableFileError(f"{name} has {array.size} values, more than {MAX_CELLS}", path)
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
    arrays = npz_arrays(data, path, max_elements=MAX_CELLS, max_bytes=MAX_ARRAY_BYTES)
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

def _text_line(raw: bytes, path: str, number: int) -> str:
    try:
        return raw.decode("utf-8").rstrip("\r\n")
    except UnicodeDecodeError:
        raise TableFileError("not UTF-8 text", path, number) from None


def read_csv(data: bytes, path: str) -> Lut:
    lines = iter(io.BytesIO(data))  # one line at a time: no list of every line, no list of rows
    first = _text_line(next(lines, b""), path, 1)
    if not first.startswith(f"# {MAGIC} "):
        raise TableFileError(f"the first line must be '# {MAGIC} {{metadata}}'", path, 1)
    meta, table_axes = meta_from({"meta": load_json(first[len(MAGIC) + 3:], path, line=1)}, path)
    header = _text_line(next(lines, b""), path, 2).split(",")
    if header != [*meta["axes"], *table_axes]:
        raise TableFileError(f"header must be {','.join([*meta['axes'], *table_axes])}", path, 2)
    values, rows = float_buffer("d"), 0
    for number, raw in enumerate(lines, start=3):
        line = _text_line(raw, path, number)
        if not line.strip():
            continue
        fields = line.split(",")
        if len(fields) != len(header):
            raise TableFileError(f"expected {len(header)} fields, got {len(fields)}", path, number)
        for column, field in enumerate(fields):
            try:
                value = float(field)
            except ValueError:
                raise TableFileError(f"column {header[column]}: {field.strip()[:30]!r} is not a number", path,
                                     number) from None
            if not math.isfinite(value):
                raise TableFileError(f"column {header[column]}: {field.strip()[:30]!r} is not a finite number",
                                     path, number)
            values.append(value)
        rows += 1
        if rows > MAX_CELLS:
            raise TableFileError(f"more than {MAX_CELLS} rows", path, number)
    if rows == 0:
        raise TableFileError("a header but no rows: a table has at least one cell", path, 3)
    table = np.frombuffer(values, dtype=float).reshape(-1, len(header))
    k = len(meta["axes"])
    axes = {name: _unique_in_order(table[:, i]) for i, name in enumerate(meta["axes"])}
    shape = tuple(len(a) for a in axes.values())
    if rows != math.prod(shape) or any(
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

# The head of a declaration, anchored on its words: each quantifier is followed by a character it cannot match,
# so a failed attempt costs at most the run it scanned; the initializer is then found with str.find(";").
_HEAD = re.compile(r"(?:static[ \t]+)?const[ \t]+float[ \t]+([A-Za-z_][A-Za-z0-9_]{0,200})[ \t]*"
                   r"((?:\[[0-9]+\])+)[ \t]*=")
_GLSL_CONSTRUCTOR = re.compile(r"\s*float\[[0-9]{1,9}\]\s*\(")
_TOKEN = re.compile(r"[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][-+]?[0-9]+)?[fF]?")
_SEPARATORS = str.maketrans("{}(),", "     ")
_MAX_DIGITS = 9


def _declarations(code: str, path: str) -> dict[str, np.ndarray]:
    found, position, line, counted = {}, 0, 1, 0
    while (match := _HEAD.search(code, position)) is not None:
        line += code.count("\n", counted, match.start())  # line numbers counted incrementally: linear in the file
        counted = match.start()
        name = match.group(1)
        digits = re.findall(r"[0-9]+", match.group(2))
        if any(len(d) > _MAX_DIGITS for d in digits):
            raise TableFileError(f"{name}: an array size of more than {_MAX_DIGITS} digits", path, line)
        count = element_count([int(d) for d in digits], MAX_CELLS, where=f"{path}:{line}", what=f"{name}'s size")
        end = code.find(";", match.end())
        if end < 0:
            raise TableFileError(f"{name}: the declaration has no ';'", path, line)
        body = code[match.end():end]
        constructor = _GLSL_CONSTRUCTOR.match(body)
        if constructor is not None:
            body = body[constructor.end():]
        tokens = body.translate(_SEPARATORS).split()
        for index, token in enumerate(tokens):  # every token a number: 'nan' or 'junk' is never skipped
            if len(token) > 40 or _TOKEN.fullmatch(token) is None:
                raise TableFileError(f"{name}, element {index}: {token[:30]!r} is not a number", path, line)
        if len(tokens) != count:
            raise TableFileError(f"{name}: {len(tokens)} values for {count} elements", path, line)
        values = np.array([float(token.rstrip("fF")) for token in tokens])
        # the file declares float32: its decimals name float32 values (9 digits name each one exactly); a value
        # past float32's range becomes inf here and is refused by cells() naming it
        with np.errstate(over="ignore"):
            found[name] = values.astype(np.float32)
        position = end + 1
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
    # declarations are read outside comments (the meta line's text is the user's); line numbers are kept
    code = "\n".join("" if line.lstrip().startswith("//") else line for line in lines)
    found = _declarations(code, path)
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

@contextmanager
def _quiet_library():
    """File descriptors 1 and 2 pointed at a scratch file while a C library runs: OpenEXR prints its diagnostics
    on stdout (machine output only) and stderr, which would add lines to the one error line; what it says is in
    the exception it raises."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = os.dup(1), os.dup(2)
    try:
        with tempfile.TemporaryFile() as scratch:
            os.dup2(scratch.fileno(), 1)
            os.dup2(scratch.fileno(), 2)
            try:
                yield
            finally:
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
    finally:
        os.close(saved[0])
        os.close(saved[1])


def _exr_bounded(image, path: str) -> None:
    """Every part's data window (width, height ≥ 1, at most :data:`MAX_CELLS` pixels) and the values of all its
    channels together (at most :data:`MAX_ARRAY_BYTES` as float32), from the headers, before any pixel is read."""
    parts = list(image.parts)
    values = 0
    for number, part in enumerate(parts):
        (x0, y0), (x1, y1) = (tuple(int(v) for v in corner) for corner in part.header["dataWindow"])
        what = "the image's data window" if len(parts) == 1 else f"the data window of part {number}"
        pixels = element_count([y1 - y0 + 1, x1 - x0 + 1], MAX_CELLS, where=path, what=what)
        values += pixels * len(part.header["channels"])
    if values * 4 > MAX_ARRAY_BYTES:
        raise TableFileError(f"the image's {len(parts)} part(s) declare {values} values, more than "
                             f"{MAX_ARRAY_BYTES // 4}", path)


def exr_parts(data: bytes, path: str) -> tuple[list[dict], list[dict[str, np.ndarray]]]:
    """(header, {channel name: pixels}) of every part of an OpenEXR file, bounded from the headers before any
    pixel is read (:func:`_exr_bounded`), the library's diagnostics kept off stdout and stderr, any failure one
    :class:`~brdfnorm.errors.TableFileError` naming the file. Pixels keep their type (float32, or float16)."""
    OpenEXR = openexr()  # noqa: N806 - the module, by its own name

    if data[:4] != b"\x76\x2f\x31\x01":
        raise TableFileError("not an OpenEXR file", path)
    try:
        with _quiet_library():
            with OpenEXR.File(io.BytesIO(data), header_only=True) as image:
                _exr_bounded(image, path)  # inside the block: the headers' dicts are emptied when the file closes
            # separate_channels: otherwise the bindings merge R, G, B (and A) into one RGB(A) array
            with OpenEXR.File(io.BytesIO(data), separate_channels=True) as image:
                headers = [dict(part.header) for part in image.parts]
                images = [{n: np.array(c.pixels) for n, c in part.channels.items()} for part in image.parts]
    except TableFileError:
        raise
    except Exception as error:  # noqa: BLE001 — the bindings raise bare RuntimeErrors on bad files
        raise TableFileError(f"unreadable OpenEXR ({str(error)[:200]})", path) from None
    return headers, images


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
    codes, depth, text = pngio.decode(data, path, max_samples=MAX_CELLS)  # bounded before inflating
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
    data = read_bounded(where, MAX_FILE_BYTES[fmt])
    with parsing(where):
        return READERS[fmt](data, where)
