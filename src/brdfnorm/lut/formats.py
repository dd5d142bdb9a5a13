"""Lookup-table files, chosen by extension, each written atomically and read back by :func:`load`.

========  ===========================================================================  =====================
format    layout                                                                        values read back
========  ===========================================================================  =====================
``.npz``  numpy archive: one array per table and per axis, ``meta`` (JSON text)         float64, bit-exact
``.json`` ``{"axes": {...}, "tables": {...}, "meta": {...}}``, nested lists             float64, bit-exact
``.csv``  long form: ``# brdfnorm-lut {meta}`` line, header, one row per cell: axis     float64, bit-exact
          columns then tables (tables without an axis repeated along it)
``.exr``  OpenEXR (:mod:`.images`): the grid's tables as channels R, G, B, A, E_avg as a   float32 (``half``:
          second part of one row; ZIP; axes, layout, channel mapping and meta in the   float16), nearest
          ``brdfnorm`` header attribute
``.h``    C/C++ header: ``static const float lut_E[32][32] = {...};`` per table,       float32, nearest
          ``[y][x]``; axes and layout in a comment, meta as a JSON comment
``.glsl`` ``const float lut_E[1024] = float[1024](...);`` (row-major, flattened),       float32, nearest
          ``const int`` sizes; passes glslangValidator
``.hlsl`` ``static const float lut_E[1024] = {...};`` (row-major, flattened)            float32, nearest
``.png``  16-bit greyscale, RGB or RGBA of one to four tables over the same axes       within (hi − lo)/131070
          (:mod:`.images`), code = round((v − lo)/(hi − lo)·65535) per channel; lo,
          hi, mapping, axes and meta in a ``tEXt`` chunk
========  ===========================================================================  =====================

The engine formats (exr, png, h, glsl, hlsl) are written in the engine layout, x = N·V, y = roughness
(:mod:`.layout`, ``--layout``), with only the values an engine samples unless ``tables`` names others;
:func:`load` undoes the layout. PNG holds tables of one or two axes (a 1-axis table is one row); three or more
axes are refused (use EXR or npz). Identifiers in code are ``prefix`` (``lut_``) + the table name with every
other character than letters, digits and ``_`` replaced (``1-E`` -> ``lut_one_minus_E``), the mapping kept in
the meta comment. Text from the meta (model names, parameters) only ever appears inside JSON with every
non-ASCII character, ``*``, ``/``, ``?`` and ``\\`` escaped, so no comment can be closed or continued by it.
Written with zlib + struct (no imaging library is a dependency). Readers check what they read and report
``FILE:LINE`` (or the file) on a bad file.
"""

from __future__ import annotations

import io
import json
import math
import re
import struct
import tempfile
import zipfile
import zlib
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, TableFileError
from ..output import write_file
from . import layout as layouts
from .images import PNG_SIGNATURE, RGBA, WriteOptions, _openexr, _write_exr, _write_png
from .layout import MAGIC, _check_finite, _subset_meta
from .table import Lut

#: Refuse tables larger than this many cells on reading (a 1024³ float64 table is 8 GB).
MAX_CELLS = 50_000_000
TEXT_FORMATS = ("json", "csv", "h", "glsl", "hlsl")


# -- shared pieces ------------------------------------------------------------------------------------------

def _meta_json(lut: Lut, extra: dict | None = None) -> str:
    """One line of JSON, ASCII, with the characters that could end or continue a comment escaped."""
    payload = {"meta": lut.meta, **(extra or {})}
    text = json.dumps(payload, ensure_ascii=True, allow_nan=False, separators=(",", ":"))
    for char in "*/?":
        text = text.replace(char, f"\\u{ord(char):04x}")
    return text


def _identifier(name: str, prefix: str = "lut_") -> str:
    body = "one_minus_E" if name == "1-E" else re.sub(r"[^A-Za-z0-9_]", "_", name)
    return prefix + re.sub(r"_+", "_", body).strip("_")  # GLSL reserves names with "__"


def _identifiers(lut: Lut, tables: Sequence[str], prefix: str = "lut_") -> dict[str, str]:
    names = {name: _identifier(name, prefix) for name in tables}
    if len(set(names.values())) != len(names):
        raise ArgumentError(f"table names {', '.join(tables)} do not give distinct identifiers", where="tables")
    return names


def _float32_text(value: float, suffix: str = "") -> str:
    text = f"{float(np.float32(value)):.9g}"  # 9 significant digits name every float32 exactly
    if not re.search(r"[.eE]", text):
        text += ".0"
    return text + suffix


def _meta_from(payload: dict, where: str) -> tuple[dict, dict]:
    meta = payload.get("meta")
    if not isinstance(meta, dict) or not isinstance(meta.get("axes"), list) or not isinstance(meta.get("tables"),
                                                                                              dict):
        raise TableFileError("no brdfnorm lut metadata (axes, tables)", where)
    return meta, meta["tables"]


def _build(tables: dict, axes: dict, meta: dict, path: str) -> Lut:
    for name, array in [*tables.items(), *axes.items()]:
        if array.size > MAX_CELLS:
            raise TableFileError(f"{name} has {array.size} values, more than {MAX_CELLS}", path)
    try:
        return Lut(tables, axes, meta, {name: meta["tables"][name] for name in tables})
    except (KeyError, TypeError) as error:
        raise TableFileError(f"tables and axes do not match the metadata ({error})", path) from None
    except ArgumentError as error:
        raise TableFileError(error.message, path) from None


# -- npz ---------------------------------------------------------------------------------------------------

def _write_npz(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> bytes:
    clash = set(tables) & set(lut.axes)
    if clash or "meta" in set(tables) | set(lut.axes):
        raise ArgumentError(f"names used twice in one archive: {', '.join(sorted(clash) or ['meta'])}",
                            where="tables")
    buffer = io.BytesIO()
    arrays = {name: lut[name] for name in tables} | dict(lut.axes)
    np.savez_compressed(buffer, meta=np.array(json.dumps(_subset_meta(lut, tables))), **arrays)
    return buffer.getvalue()


def _read_npz(data: bytes, path: str) -> Lut:
    try:
        with np.load(io.BytesIO(data), allow_pickle=False) as archive:
            meta = json.loads(str(archive["meta"]))
            _, table_axes = _meta_from({"meta": meta}, path)
            axes = {name: np.asarray(archive[name], dtype=float) for name in meta["axes"]}
            tables = {name: np.asarray(archive[name], dtype=float) for name in table_axes}
    except TableFileError:
        raise
    except (OSError, ValueError, KeyError, TypeError, EOFError, zlib.error, zipfile.BadZipFile) as error:
        raise TableFileError(f"not a brdfnorm npz table ({type(error).__name__}: {error})", path) from None
    return _build(tables, axes, meta, path)


# -- json --------------------------------------------------------------------------------------------------

def _write_json(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> str:
    _check_finite(lut, tables, "JSON")
    document = {"format": MAGIC, "axes": {n: v.tolist() for n, v in lut.axes.items()},
                "tables": {n: lut[n].tolist() for n in tables}, "meta": _subset_meta(lut, tables)}
    return json.dumps(document, indent=1, allow_nan=False) + "\n"


def _read_json(data: bytes, path: str) -> Lut:
    try:
        document = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        line = getattr(error, "lineno", None)
        raise TableFileError(f"not JSON: {error}", path, line) from None
    if not isinstance(document, dict) or document.get("format") != MAGIC:
        raise TableFileError(f"not a brdfnorm lut (no \"format\": \"{MAGIC}\")", path)
    meta, _ = _meta_from(document, path)
    try:
        axes = {n: np.asarray(document["axes"][n], dtype=float) for n in meta["axes"]}
        tables = {n: np.asarray(v, dtype=float) for n, v in document["tables"].items()}
    except (KeyError, TypeError, ValueError) as error:
        raise TableFileError(f"malformed axes or tables ({error})", path) from None
    return _build(tables, axes, meta, path)


# -- csv ---------------------------------------------------------------------------------------------------

def _write_csv(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> str:
    _check_finite(lut, tables, "CSV")
    names = list(lut.axes)
    grids = np.meshgrid(*lut.axes.values(), indexing="ij")
    columns = [g.ravel() for g in grids] + [np.asarray(lut.full(n)).ravel() for n in tables]
    header = [*names, *tables]
    if any("," in h or '"' in h for h in header):
        raise ArgumentError("axis and table names may not contain commas or quotes in CSV", where="tables")
    lines = [f"# {MAGIC} {json.dumps(_subset_meta(lut, tables), ensure_ascii=True, separators=(',', ':'))}",
             ",".join(header)]
    stacked = np.stack(columns, axis=1)
    lines.extend(",".join(repr(float(v)) for v in row) for row in stacked)
    return "\n".join(lines) + "\n"


def _read_csv(data: bytes, path: str) -> Lut:
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError:
        raise TableFileError("not UTF-8 text", path, 1) from None
    lines = text.splitlines()
    if not lines or not lines[0].startswith(f"# {MAGIC} "):
        raise TableFileError(f"the first line must be '# {MAGIC} {{metadata}}'", path, 1)
    try:
        meta = json.loads(lines[0][len(MAGIC) + 3:])
    except json.JSONDecodeError as error:
        raise TableFileError(f"metadata is not JSON: {error.msg}", path, 1) from None
    meta, table_axes = _meta_from({"meta": meta}, path)
    header = lines[1].split(",") if len(lines) > 1 else []
    if header != [*meta["axes"], *table_axes]:
        raise TableFileError(f"header must be {','.join([*meta['axes'], *table_axes])}", path, 2)
    rows = []
    for number, line in enumerate(lines[2:], start=3):
        fields = line.split(",")
        if len(fields) != len(header):
            raise TableFileError(f"expected {len(header)} fields, got {len(fields)}", path, number)
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            raise TableFileError("a field is not a number", path, number) from None
        if len(rows) > MAX_CELLS:
            raise TableFileError(f"more than {MAX_CELLS} rows", path, number)
    values = np.array(rows, dtype=float).reshape(-1, len(header))
    k = len(meta["axes"])
    axes = {name: _unique_in_order(values[:, i]) for i, name in enumerate(meta["axes"])}
    shape = tuple(len(a) for a in axes.values())
    grids = np.meshgrid(*axes.values(), indexing="ij") if axes else []
    if values.shape[0] != int(np.prod(shape)) or any(
            not np.array_equal(g.ravel(), values[:, i]) for i, g in enumerate(grids)):
        raise TableFileError("rows are not one per cell of the axes' grid in row-major order", path)
    tables = {}
    for j, name in enumerate(table_axes):
        full = values[:, k + j].reshape(shape)
        index = tuple(slice(None) if a in table_axes[name] else 0 for a in meta["axes"])
        tables[name] = full[index]
    return _build(tables, axes, meta, path)


def _unique_in_order(column: np.ndarray) -> np.ndarray:
    _, first = np.unique(column, return_index=True)
    return column[np.sort(first)]


# -- C, GLSL, HLSL -----------------------------------------------------------------------------------------

def _axes_comment(lut: Lut, prefix: str) -> list[str]:
    lines = [f"{prefix} brdfnorm lookup table: {len(lut.axes)} axes, indexed in this order"]
    if lut.meta.get("layout"):
        text = re.sub(r"[^A-Za-z0-9_.,;:()\[\] -]", "_", lut.meta["layout"]["text"])  # nothing that ends a comment
        lines.append(f"{prefix} layout: {text}")
    for name, values in lut.axes.items():
        safe = re.sub(r"[^A-Za-z0-9_.-]", "_", name)
        lines.append(f"{prefix}   {safe}: {len(values)} values from {values[0]:.9g} to {values[-1]:.9g}")
    return lines


def _c_nested(array: np.ndarray) -> str:
    if array.ndim == 0:
        return _float32_text(array, "f")
    if array.ndim == 1:
        return "{" + ", ".join(_float32_text(v, "f") for v in array) + "}"
    return "{\n" + ",\n".join(_c_nested(sub) for sub in array) + "}"


def _write_code(language: str) -> Callable[[Lut, Sequence[str], WriteOptions], str]:
    def write(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> str:
        _check_finite(lut, tables, language)
        ids = _identifiers(lut, tables, opts.prefix)
        lines = _axes_comment(lut, "//")
        lines.append(f"// {MAGIC} " + _meta_json(_SubsetLut(lut, tables), {"identifiers": ids}))
        if language == "c":
            lines += ["#pragma once", ""]
        lines.extend(_declare(language, ident, lut[name]) for name, ident in ids.items())
        return "\n".join(lines) + "\n"

    return write


def _declare(language: str, ident: str, array: np.ndarray) -> str:
    if language == "c":
        dims = "".join(f"[{n}]" for n in array.shape) or "[1]"
        body = _c_nested(array if array.ndim else array.reshape(1))
        return f"static const float {ident}{dims} = {body};"
    flat = np.atleast_1d(array).ravel()
    values = ", ".join(_float32_text(v, "" if language == "glsl" else "f") for v in flat)
    sizes = "\n".join(f"{'static ' if language == 'hlsl' else ''}const int {ident}_size{i} = {n};"
                      for i, n in enumerate(array.shape))
    head = (sizes + "\n") if sizes else ""
    if language == "glsl":
        return f"{head}const float {ident}[{flat.size}] = float[{flat.size}]({values});"
    return f"{head}static const float {ident}[{flat.size}] = {{{values}}};"


class _SubsetLut:
    """A view of a lut with only some tables in its meta (for the code writers' meta comment)."""

    def __init__(self, lut: Lut, tables: Sequence[str]) -> None:
        self.meta = _subset_meta(lut, tables)
        self.meta["axis_values"] = {n: v.tolist() for n, v in lut.axes.items()}


_DECLARATION = re.compile(r"(?:static\s+)?const\s+float\s+([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])+)\s*=\s*"
                          r"(?:float\[\d+\]\s*\()?([^;]*?)\)?\s*;", re.S)
_NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def _read_code(data: bytes, path: str) -> Lut:
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        raise TableFileError("not ASCII text (not a brdfnorm lut header)", path, 1) from None
    marker = f"// {MAGIC} "
    meta_line = next((i for i, line in enumerate(text.splitlines()) if line.startswith(marker)), None)
    if meta_line is None:
        raise TableFileError(f"no '{marker}{{metadata}}' comment line", path)
    try:
        payload = json.loads(text.splitlines()[meta_line][len(marker):])
    except json.JSONDecodeError as error:
        raise TableFileError(f"metadata is not JSON: {error.msg}", path, meta_line + 1) from None
    meta, table_axes = _meta_from(payload, path)
    ids = payload.get("identifiers", {})
    found = {}
    for match in _DECLARATION.finditer(text):
        line = text.count("\n", 0, match.start()) + 1
        numbers = _NUMBER.findall(match.group(3))
        count = math.prod(int(n) for n in re.findall(r"\d+", match.group(2)))
        if len(numbers) != count:
            raise TableFileError(f"{match.group(1)}: {len(numbers)} values for {count} elements", path, line)
        # the file declares float32: its decimals name float32 values (9 digits name each one exactly)
        found[match.group(1)] = np.array([float(n) for n in numbers], dtype=float).astype(np.float32)
    try:
        axis_values = meta.pop("axis_values")
        axes = {n: np.asarray(axis_values[n], dtype=float) for n in meta["axes"]}
        tables = {}
        for name in table_axes:
            shape = tuple(len(axes[a]) for a in table_axes[name])
            tables[name] = found[ids[name]].reshape(shape) if shape else found[ids[name]].reshape(())
    except (KeyError, ValueError, TypeError) as error:
        raise TableFileError(f"arrays do not match the metadata (missing or misshapen: {error})", path) from None
    return _build(tables, axes, meta, path)


# -- OpenEXR -----------------------------------------------------------------------------------------------

def _read_exr(data: bytes, path: str) -> Lut:
    OpenEXR = _openexr()  # noqa: N806 - the module, by its own name

    if data[:4] != b"\x76\x2f\x31\x01":
        raise TableFileError("not an OpenEXR file", path)
    with tempfile.TemporaryDirectory() as scratch:
        source = Path(scratch) / "lut.exr"
        source.write_bytes(data)
        try:
            with OpenEXR.File(str(source), separate_channels=True) as image:
                text = image.header().get("brdfnorm")
                # the channels' own precision (float32, or float16 with half) is what the file holds
                images = [{n: np.array(c.pixels) for n, c in part.channels.items()} for part in image.parts]
        except Exception as error:  # noqa: BLE001 — the bindings raise bare RuntimeErrors on bad files
            raise TableFileError(f"unreadable OpenEXR ({error})", path) from None
    try:
        meta = json.loads(str(text))
    except json.JSONDecodeError:
        raise TableFileError("no brdfnorm metadata in the EXR header", path) from None
    meta, table_axes = _meta_from({"meta": meta}, path)
    try:
        axis_values = meta.pop("axis_values")
        axes = {n: np.asarray(axis_values[n], dtype=float) for n in meta["axes"]}
        exr = meta.pop("exr", None) or {"parts": [{"axes": meta["axes"], "channels": {n: n for n in table_axes}}]}
        tables = {}
        for part, channels in zip(exr["parts"], images, strict=True):
            shape = tuple(len(axes[a]) for a in part["axes"])
            for channel, name in part["channels"].items():
                full = channels[channel].reshape(shape)
                tables[name] = full[tuple(slice(None) if a in table_axes[name] else 0 for a in part["axes"])]
        tables = {name: tables[name] for name in table_axes}  # in the metadata's order, not the parts'
    except (KeyError, ValueError, TypeError) as error:
        raise TableFileError(f"channels do not match the metadata ({error})", path) from None
    return _build(tables, axes, meta, path)


# -- PNG ---------------------------------------------------------------------------------------------------

def _read_png(data: bytes, path: str) -> Lut:
    if not data.startswith(PNG_SIGNATURE):
        raise TableFileError("not a PNG file", path)
    position, header, text, idat = len(PNG_SIGNATURE), None, None, []
    while position + 12 <= len(data):
        (length,) = struct.unpack(">I", data[position:position + 4])
        kind, body = data[position + 4:position + 8], data[position + 8:position + 8 + length]
        (crc,) = struct.unpack(">I", data[position + 8 + length:position + 12 + length] or b"\0\0\0\0")
        if len(body) != length or zlib.crc32(kind + body) & 0xFFFFFFFF != crc:
            raise TableFileError(f"corrupt PNG chunk {kind!r} at byte {position}", path)
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"tEXt" and body.startswith(MAGIC.encode() + b"\x00"):
            text = body[len(MAGIC) + 1:]
        elif kind == b"IDAT":
            idat.append(body)
        position += 12 + length
    if header is None or text is None:
        raise TableFileError("no brdfnorm metadata (tEXt) in this PNG", path)
    width, height, depth, colour, _, _, interlace = header
    samples = {0: 1, 2: 3, 6: 4}.get(colour)
    if depth != 16 or samples is None or interlace != 0:
        raise TableFileError("expected a 16-bit greyscale, RGB or RGBA non-interlaced PNG", path)
    if width * height > MAX_CELLS:
        raise TableFileError(f"image of {width}×{height} pixels is too large", path)
    expected = height * (1 + 2 * samples * width)
    inflate = zlib.decompressobj()
    try:
        raw = inflate.decompress(b"".join(idat), expected + 1)
    except zlib.error as error:
        raise TableFileError(f"corrupt image data ({error})", path) from None
    if len(raw) != expected:
        raise TableFileError(f"image data holds {len(raw)} bytes, expected {expected}", path)
    rows = np.frombuffer(raw, dtype=np.uint8).reshape(height, 1 + 2 * samples * width)
    if np.any(rows[:, 0] != 0):
        raise TableFileError("only PNG filter type 0 is read (as brdfnorm writes it)", path)
    codes = rows[:, 1:].copy().view(">u2").astype(float).reshape(height, width, samples)
    try:
        meta = json.loads(text.decode("latin-1"))
        _, table_axes = _meta_from({"meta": meta}, path)
        info = meta.pop("png")
        axis_values = meta.pop("axis_values")
        axes = {n: np.asarray(axis_values[n], dtype=float) for n in meta["axes"]}
        if "channels" not in info:  # one greyscale table (files before the R, G, B, A mapping)
            info = {"axes": table_axes[info["table"]], "channels": {"R": info}}
        shape = tuple(len(axes[a]) for a in info["axes"])
        tables = {}
        for position, (channel, entry) in enumerate(info["channels"].items()):
            if channel != RGBA[position]:
                raise ValueError(f"channel {channel} in place {position}")
            lo, hi, name = float(entry["lo"]), float(entry["hi"]), entry["table"]
            full = (lo + codes[..., position] / 65535.0 * ((hi - lo) if hi > lo else 1.0)).reshape(shape)
            tables[name] = full[tuple(slice(None) if a in table_axes[name] else 0 for a in info["axes"])]
    except (KeyError, TypeError, ValueError, IndexError, json.JSONDecodeError) as error:
        raise TableFileError(f"metadata does not describe the image ({error})", path) from None
    return _build(tables, axes, meta, path)


# -- registry ----------------------------------------------------------------------------------------------

#: extension -> (writer(lut, tables, WriteOptions) -> str | bytes, reader(bytes, path) -> Lut, float precision kept)
FORMATS: dict[str, tuple[Callable, Callable[[bytes, str], Lut], str]] = {
    "npz": (_write_npz, _read_npz, "float64"),
    "json": (_write_json, _read_json, "float64"),
    "csv": (_write_csv, _read_csv, "float64"),
    "exr": (_write_exr, _read_exr, "float32 (float16 with half)"),
    "h": (_write_code("c"), _read_code, "float32"),
    "glsl": (_write_code("glsl"), _read_code, "float32"),
    "hlsl": (_write_code("hlsl"), _read_code, "float32"),
    "png": (_write_png, _read_png, "16-bit fixed point over [min, max]"),
}


def format_of(path: str | Path, fmt: str | None = None, *, where: str = "path") -> str:
    """The format named by ``fmt`` or by the file's extension."""
    name = (fmt or Path(str(path)).suffix.lstrip(".")).lower()
    if name not in FORMATS:
        raise ArgumentError(f"unknown table format {name or '(no extension)'!r} (known: .{', .'.join(FORMATS)})",
                            where=where)
    return name


def _tables(lut: Lut, tables: Sequence[str] | None, fmt: str) -> list[str]:
    if tables is None:
        return layouts.default_tables(lut, fmt)
    unknown = [t for t in tables if t not in lut]
    if unknown:
        raise ArgumentError(f"no table {unknown[0]!r} (tables: {', '.join(lut)})", where="tables")
    return list(dict.fromkeys(tables))


def dumps(lut: Lut, fmt: str, *, tables: Sequence[str] | None = None, half: bool = False,
          layout: str | Mapping[str, str] | None = None, prefix: str = "lut_", channel_names: str = "rgba",
          broadcast_average: bool = False) -> str | bytes:
    """The file's content in format ``fmt`` (text for json/csv/h/glsl/hlsl, bytes otherwise).

    ``tables``: which tables (default: all in npz/json/csv; in the engine formats the values without error
    estimates and 1 − E, :func:`.layout.default_tables`). ``layout``: ``x=AXIS,y=AXIS,v=down|up`` or ``axes``
    (default: x = the view axis, y = the next axis in the engine formats; the ``--axis`` order in the others),
    :mod:`.layout`. ``prefix``: of the identifiers in code. ``channel_names``: ``rgba`` or ``brdfnorm`` (EXR).
    ``broadcast_average``: E_avg repeated over μ inside the grid's image (EXR, PNG) instead of its own image.
    """
    fmt = format_of("", fmt, where="format")
    if half and fmt != "exr":
        raise ArgumentError("half precision applies to .exr only", where="half")
    if prefix and not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", prefix) or "__" in prefix:
        raise ArgumentError(f"prefix {prefix!r} is not the start of an identifier (letters, digits, _; no __)",
                            where="prefix")
    writer, _, _ = FORMATS[fmt]
    chosen = _tables(lut, tables, fmt)
    spec = layouts.parse(layout) if isinstance(layout, str) else layout
    laid = layouts.apply(lut, layouts.resolve(lut, spec, fmt))
    options = WriteOptions(half=half, prefix=prefix, channel_names=channel_names, broadcast_average=broadcast_average)
    return writer(laid, chosen, options)


def save(lut: Lut, path: str | Path, *, fmt: str | None = None, tables: Sequence[str] | None = None,
         half: bool = False, **options) -> Path:
    """Write ``lut`` to ``path`` (format from the extension unless ``fmt``), atomically; ``options`` as
    :func:`dumps` takes them (layout, prefix, channel_names, broadcast_average)."""
    save_bytes(path, dumps(lut, format_of(path, fmt), tables=tables, half=half, **options))
    return Path(path)


def save_bytes(path: str | Path, data: str | bytes) -> None:
    """:func:`brdfnorm.output.write_file`, the one atomic writer (``-`` is stdout)."""
    write_file(path, data)


def load(path: str | Path, *, fmt: str | None = None) -> Lut:
    """Read a table written by :func:`save` (any format): a :class:`Lut` mapping table name -> array, indexed in
    the order of its ``--axis`` flags whatever the file's layout; float64 from npz/json/csv/png, float32 from
    .h/.glsl/.hlsl/.exr (float16 from a ``half`` EXR), the precision the file holds."""
    name = format_of(path, fmt)
    try:
        with open(path, "rb") as handle:
            data = handle.read(4 * MAX_CELLS * 8 + 1)
    except OSError as error:
        raise TableFileError(f"cannot read: {error.strerror}", str(path)) from None
    _, reader, _ = FORMATS[name]
    return layouts.restore(reader(data, str(path)), str(path))  # indexed in the --axis order again
