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
Written with zlib + struct (no imaging library is a dependency). Readers (:mod:`.readers`) are bounded before
they allocate and report ``FILE:LINE`` (or the file) on a bad file.
"""


from __future__ import annotations

import io
import json
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..output import write_file
from . import layout as layouts
from .images import WriteOptions, write_exr, write_png
from .layout import MAGIC, check_finite, subset_meta
from .readers import READERS, read
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


# -- npz ---------------------------------------------------------------------------------------------------

def _write_npz(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> bytes:
    clash = set(tables) & set(lut.axes)
    if clash or "meta" in set(tables) | set(lut.axes):
        raise ArgumentError(f"names used twice in one archive: {', '.join(sorted(clash) or ['meta'])}",
                            where="tables")
    buffer = io.BytesIO()
    arrays = {name: lut[name] for name in tables} | dict(lut.axes)
    np.savez_compressed(buffer, meta=np.array(json.dumps(subset_meta(lut, tables))), **arrays)
    return buffer.getvalue()


# -- json --------------------------------------------------------------------------------------------------

def _write_json(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> str:
    check_finite(lut, tables, "JSON")
    document = {"format": MAGIC, "axes": {n: v.tolist() for n, v in lut.axes.items()},
                "tables": {n: lut[n].tolist() for n in tables}, "meta": subset_meta(lut, tables)}
    return json.dumps(document, indent=1, allow_nan=False) + "\n"


# -- csv ---------------------------------------------------------------------------------------------------

def _write_csv(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> str:
    check_finite(lut, tables, "CSV")
    names = list(lut.axes)
    grids = np.meshgrid(*lut.axes.values(), indexing="ij")
    columns = [g.ravel() for g in grids] + [np.asarray(lut.full(n)).ravel() for n in tables]
    header = [*names, *tables]
    if any("," in h or '"' in h for h in header):
        raise ArgumentError("axis and table names may not contain commas or quotes in CSV", where="tables")
    lines = [f"# {MAGIC} {json.dumps(subset_meta(lut, tables), ensure_ascii=True, separators=(',', ':'))}",
             ",".join(header)]
    stacked = np.stack(columns, axis=1)
    lines.extend(",".join(repr(float(v)) for v in row) for row in stacked)
    return "\n".join(lines) + "\n"


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
        check_finite(lut, tables, language)
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
        self.meta = subset_meta(lut, tables)
        self.meta["axis_values"] = {n: v.tolist() for n, v in lut.axes.items()}


# -- registry ----------------------------------------------------------------------------------------------

#: extension -> (writer(lut, tables, WriteOptions) -> str | bytes, reader(bytes, path) -> Lut, float precision kept)
FORMATS: dict[str, tuple[Callable, Callable[[bytes, str], Lut], str]] = {
    "npz": (_write_npz, READERS["npz"], "float64"),
    "json": (_write_json, READERS["json"], "float64"),
    "csv": (_write_csv, READERS["csv"], "float64"),
    "exr": (write_exr, READERS["exr"], "float32 (float16 with half)"),
    "h": (_write_code("c"), READERS["h"], "float32"),
    "glsl": (_write_code("glsl"), READERS["h"], "float32"),
    "hlsl": (_write_code("hlsl"), READERS["h"], "float32"),
    "png": (write_png, READERS["png"], "16-bit fixed point over [min, max]"),
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
    .h/.glsl/.hlsl/.exr (float16 from a ``half`` EXR), the precision the file holds.

    Bounded and guarded by :mod:`brdfnorm.lut.readers`: any problem with the file is one
    :class:`~brdfnorm.errors.TableFileError` naming it."""
    return layouts.restore(read(path, format_of(path, fmt)), str(path))  # indexed in the --axis order again
