"""Lookup-table files, chosen by extension, each written atomically and read back by :func:`load`.

========  ===========================================================================  =====================
format    layout                                                                        values read back
========  ===========================================================================  =====================
``.npz``  numpy archive: one array per table and per axis, ``meta`` (JSON text)         float64, bit-exact
``.json`` ``{"axes": {...}, "tables": {...}, "meta": {...}}``, nested lists             float64, bit-exact
``.csv``  long form: ``# brdfnorm-lut {meta}`` line, header, one row per cell: axis     float64, bit-exact
          columns then tables (tables without an axis repeated along it)
``.exr``  OpenEXR, one channel per table over the grid (rows: the first axes, columns:  float32 (``half``:
          the last), ZIP; axes and meta in the ``brdfnorm`` header attribute           float16), nearest
``.h``    C/C++ header: ``static const float lut_E[32][32] = {...};`` per table,       float32, nearest
          axes in a comment, meta as a JSON comment
``.glsl`` ``const float lut_E[1024] = float[1024](...);`` (row-major, flattened),       float32, nearest
          ``const int`` sizes; passes glslangValidator
``.hlsl`` ``static const float lut_E[1024] = {...};`` (row-major, flattened)            float32, nearest
``.png``  16-bit greyscale of ONE table (``E`` unless another is chosen), code =        within (hi − lo)/131070
          round((v − lo)/(hi − lo)·65535); lo, hi, axes and meta in a ``tEXt`` chunk
========  ===========================================================================  =====================

PNG holds one table of one or two axes (a 1-axis table is one row); tables of three or more axes are refused
(use EXR or npz). Identifiers in code are ``lut_`` + the table name with every other character than letters,
digits and ``_`` replaced (``1-E`` -> ``lut_one_minus_E``), the mapping kept in the meta comment. Text from the
meta (model names, parameters) only ever appears inside JSON with every non-ASCII character, ``*``, ``/``,
``?`` and ``\\`` escaped, so no comment can be closed or continued by it. Written with zlib + struct (no imaging
library is a dependency). Readers (:mod:`.readers`) are bounded before they allocate and report ``FILE:LINE``
(or the file) on a bad file.
"""

from __future__ import annotations

import io
import json
import re
import struct
import tempfile
import zlib
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..output import write_file
from .readers import MAGIC, PNG_SIGNATURE, READERS, read
from .readers import openexr as _openexr
from .table import Lut

TEXT_FORMATS = ("json", "csv", "h", "glsl", "hlsl")


# -- shared pieces ------------------------------------------------------------------------------------------

def _meta_json(lut: Lut, extra: dict | None = None) -> str:
    """One line of JSON, ASCII, with the characters that could end or continue a comment escaped."""
    payload = {"meta": lut.meta, **(extra or {})}
    text = json.dumps(payload, ensure_ascii=True, allow_nan=False, separators=(",", ":"))
    for char in "*/?":
        text = text.replace(char, f"\\u{ord(char):04x}")
    return text


def _identifier(name: str) -> str:
    body = "one_minus_E" if name == "1-E" else re.sub(r"[^A-Za-z0-9_]", "_", name)
    return "lut_" + re.sub(r"_+", "_", body).strip("_")  # GLSL reserves names with "__"


def _identifiers(lut: Lut, tables: Sequence[str]) -> dict[str, str]:
    names = {name: _identifier(name) for name in tables}
    if len(set(names.values())) != len(names):
        raise ArgumentError(f"table names {', '.join(tables)} do not give distinct identifiers", where="tables")
    return names


def _float32_text(value: float, suffix: str = "") -> str:
    text = f"{float(np.float32(value)):.9g}"  # 9 significant digits name every float32 exactly
    if not re.search(r"[.eE]", text):
        text += ".0"
    return text + suffix


def _check_finite(lut: Lut, tables: Sequence[str], fmt: str) -> None:
    for name in tables:
        if not np.all(np.isfinite(lut[name])):
            raise ArgumentError(f"table {name} has non-finite values, which {fmt} cannot hold", where="tables")


# -- npz ---------------------------------------------------------------------------------------------------

def _write_npz(lut: Lut, tables: Sequence[str], half: bool) -> bytes:
    clash = set(tables) & set(lut.axes)
    if clash or "meta" in set(tables) | set(lut.axes):
        raise ArgumentError(f"names used twice in one archive: {', '.join(sorted(clash) or ['meta'])}",
                            where="tables")
    buffer = io.BytesIO()
    arrays = {name: lut[name] for name in tables} | dict(lut.axes)
    np.savez_compressed(buffer, meta=np.array(json.dumps(_subset_meta(lut, tables))), **arrays)
    return buffer.getvalue()


def _subset_meta(lut: Lut, tables: Sequence[str]) -> dict:
    meta = dict(lut.meta)
    meta["tables"] = {name: list(lut.table_axes[name]) for name in tables}
    return meta


# -- json --------------------------------------------------------------------------------------------------

def _write_json(lut: Lut, tables: Sequence[str], half: bool) -> str:
    _check_finite(lut, tables, "JSON")
    document = {"format": MAGIC, "axes": {n: v.tolist() for n, v in lut.axes.items()},
                "tables": {n: lut[n].tolist() for n in tables}, "meta": _subset_meta(lut, tables)}
    return json.dumps(document, indent=1, allow_nan=False) + "\n"


# -- csv ---------------------------------------------------------------------------------------------------

def _write_csv(lut: Lut, tables: Sequence[str], half: bool) -> str:
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


# -- C, GLSL, HLSL -----------------------------------------------------------------------------------------

def _axes_comment(lut: Lut, prefix: str) -> list[str]:
    lines = [f"{prefix} brdfnorm lookup table: {len(lut.axes)} axes, indexed in this order"]
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


def _write_code(language: str) -> Callable[[Lut, Sequence[str], bool], str]:
    def write(lut: Lut, tables: Sequence[str], half: bool) -> str:
        _check_finite(lut, tables, language)
        ids = _identifiers(lut, tables)
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


# -- OpenEXR -----------------------------------------------------------------------------------------------

def _image_shape(shape: tuple[int, ...]) -> tuple[int, int]:
    if len(shape) == 0:
        return 1, 1
    return int(np.prod(shape[:-1])), int(shape[-1])


def _write_exr(lut: Lut, tables: Sequence[str], half: bool) -> bytes:
    OpenEXR = _openexr()  # noqa: N806 - the module, by its own name

    shape = tuple(len(v) for v in lut.axes.values())
    dtype = np.float16 if half else np.float32
    if half:
        big = [n for n in tables if np.any(np.abs(lut[n]) > np.finfo(np.float16).max)]
        if big:
            raise ArgumentError(f"table {big[0]} exceeds the float16 range", where="half")
    channels = {name: np.ascontiguousarray(np.asarray(lut.full(name)).reshape(_image_shape(shape)), dtype=dtype)
                for name in tables}
    meta = _subset_meta(lut, tables)
    meta["axis_values"] = {n: v.tolist() for n, v in lut.axes.items()}
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "brdfnorm": json.dumps(meta, ensure_ascii=True)}
    with tempfile.TemporaryDirectory() as scratch:  # the bindings write to a path; the caller renames atomically
        target = Path(scratch) / "lut.exr"
        with OpenEXR.File(header, channels) as image:
            image.write(str(target))
        return target.read_bytes()


# -- PNG ---------------------------------------------------------------------------------------------------

def _chunk(kind: bytes, body: bytes) -> bytes:
    return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body) & 0xFFFFFFFF)


def _write_png(lut: Lut, tables: Sequence[str], half: bool) -> bytes:
    if len(tables) != 1:
        raise ArgumentError(f"a PNG holds one table; choose one of {', '.join(tables)}", where="tables")
    (name,) = tables
    values = lut[name]
    if values.ndim > 2:
        raise ArgumentError(f"a PNG image holds a table of one or two axes; {name} has {values.ndim} (use .exr or "
                            ".npz)", where="tables")
    _check_finite(lut, tables, "PNG")
    image = values.reshape(_image_shape(values.shape))
    lo, hi = float(image.min()), float(image.max())
    scale = (hi - lo) if hi > lo else 1.0
    codes = np.rint((image - lo) / scale * 65535.0).astype(">u2")
    meta = _subset_meta(lut, tables)
    meta["axis_values"] = {n: v.tolist() for n, v in lut.axes.items()}
    meta["png"] = {"table": name, "lo": lo, "hi": hi, "value": "lo + code / 65535 * (hi - lo)"}
    height, width = image.shape
    raw = b"".join(b"\x00" + row.tobytes() for row in codes)  # filter type 0 on every row
    text = MAGIC.encode("latin-1") + b"\x00" + json.dumps(meta, ensure_ascii=True).encode("latin-1")
    return (PNG_SIGNATURE + _chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 16, 0, 0, 0, 0))
            + _chunk(b"tEXt", text) + _chunk(b"IDAT", zlib.compress(raw, 9)) + _chunk(b"IEND", b""))


# -- registry ----------------------------------------------------------------------------------------------

#: extension -> (writer(lut, tables, half) -> str | bytes, reader(bytes, path) -> Lut, float precision kept)
FORMATS: dict[str, tuple[Callable, Callable[[bytes, str], Lut], str]] = {
    "npz": (_write_npz, READERS["npz"], "float64"),
    "json": (_write_json, READERS["json"], "float64"),
    "csv": (_write_csv, READERS["csv"], "float64"),
    "exr": (_write_exr, READERS["exr"], "float32 (float16 with half)"),
    "h": (_write_code("c"), READERS["h"], "float32"),
    "glsl": (_write_code("glsl"), READERS["h"], "float32"),
    "hlsl": (_write_code("hlsl"), READERS["h"], "float32"),
    "png": (_write_png, READERS["png"], "16-bit fixed point over [min, max]"),
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
        return ["E"] if fmt == "png" and "E" in lut else list(lut)
    unknown = [t for t in tables if t not in lut]
    if unknown:
        raise ArgumentError(f"no table {unknown[0]!r} (tables: {', '.join(lut)})", where="tables")
    return list(dict.fromkeys(tables))


def dumps(lut: Lut, fmt: str, *, tables: Sequence[str] | None = None, half: bool = False) -> str | bytes:
    """The file's content in format ``fmt`` (text for json/csv/h/glsl/hlsl, bytes otherwise)."""
    fmt = format_of("", fmt, where="format")
    if half and fmt != "exr":
        raise ArgumentError("half precision applies to .exr only", where="half")
    writer, _, _ = FORMATS[fmt]
    return writer(lut, _tables(lut, tables, fmt), half)


def save(lut: Lut, path: str | Path, *, fmt: str | None = None, tables: Sequence[str] | None = None,
         half: bool = False) -> Path:
    """Write ``lut`` to ``path`` (format from the extension unless ``fmt``), atomically."""
    save_bytes(path, dumps(lut, format_of(path, fmt), tables=tables, half=half))
    return Path(path)


def save_bytes(path: str | Path, data: str | bytes) -> None:
    """:func:`brdfnorm.output.write_file`, the one atomic writer (``-`` is stdout)."""
    write_file(path, data)


def load(path: str | Path, *, fmt: str | None = None) -> Lut:
    """Read a table written by :func:`save` (any format): a :class:`Lut` mapping table name -> float64 array.

    Bounded and guarded by :mod:`brdfnorm.lut.readers`: any problem with the file is one
    :class:`~brdfnorm.errors.TableFileError` naming it."""
    return read(path, format_of(path, fmt))
