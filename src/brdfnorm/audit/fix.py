"""``--fix``: the exact table as a drop-in replacement — same format, array name, layout, orientation, sample
positions, storage dtype, channel order — with brdfnorm's metadata where the format has room for it.

The fix is a minimal diff: the table it is given differs from the one read only in the wrong cells
(:func:`brdfnorm.audit.api.audit`), and every other byte is kept:

* text formats (C/GLSL/HLSL/JavaScript array literals, CSV, JSON) are rewritten in place: only the numbers of
  changed cells are replaced, where they stood, in the array's own number style (hex stays hex, the digits and
  exponent style of the array's other numbers, suffixes kept); the file's bytes are read back as they are
  (undecodable bytes, Latin-1 text and a byte-order mark survive: :func:`_original_text`);
* ``.npz``: the audited member is rewritten with its dtype, shape and memory order; every other member is copied
  with its name and contents (names such as ``file`` or ``allow_pickle`` included);
* images (PNG, EXR) and raw binary are re-encoded with every unchanged cell's code as read.

Values are rounded to the storage the input used: integers to the nearest code of the same scale (clipped to the
type's range), half and single floats by numpy's round-to-nearest conversion.
"""

from __future__ import annotations

import io
import json
import re
import tempfile
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..inputs import png as pngio
from ..inputs import read_bounded
from .readers import MAX_BINARY_BYTES, MAX_TEXT_BYTES, Source
from .spans import csv_spans, json_spans


def stored_values(source: Source, table: np.ndarray) -> np.ndarray:
    """``table`` (table units) in the storage of ``source``: integer codes or floats of its dtype."""
    offset = source.layout.get("offset", 0.0) if source.fmt == "png" else 0.0  # brdfnorm PNGs: lo + code·span
    if source.stored.startswith(("uint", "int")):
        info = np.iinfo(np.dtype(source.stored))
        return np.clip(np.rint((table - offset) * source.scale), info.min, info.max).astype(np.int64)
    return np.asarray(table * source.scale, dtype=np.dtype(source.stored))


def _squeezed(source: Source, array: np.ndarray) -> np.ndarray:
    return array[..., 0] if source.channel_names == ["0"] else array


def _changed(source: Source, table: np.ndarray) -> np.ndarray:
    """Cells (*grid, channels) whose stored value the fix changes (a non-finite cell read is always changed)."""
    before = stored_values(source, np.nan_to_num(source.values, nan=0.0, posinf=0.0, neginf=0.0))
    after = stored_values(source, table)
    same = np.asarray(before == after) & np.isfinite(source.values)
    if source.stored.startswith("float"):  # NaN codes compare unequal; -0.0 == 0.0 is kept
        same &= np.signbit(np.asarray(before, dtype=float)) == np.signbit(np.asarray(after, dtype=float))
    return ~same


_SPACE = re.compile(r"[\ufeff \t\r\n]*")
_NUMBER = re.compile(r"^([+-]?)(\d*)(?:\.(\d*))?(?:([eE])([+-]?\d+))?$")


@dataclass
class _Style:
    """How an array's decimal numbers are written: fixed decimals (``%.6f``), significant digits (``%.9g``,
    shortest round trip), exponent form."""

    decimals: int | None  # every number has this many decimals (fixed style), else None
    significant: int
    exponent: bool
    upper: bool


def _style(tokens: list[str]) -> _Style:
    decimals, significant, exponent, upper = set(), 1, 0, False
    for token in tokens:
        m = _NUMBER.match(token.strip())
        if not m:
            continue
        whole, frac, e = m.group(2) or "", m.group(3) or "", m.group(4)
        decimals.add(len(frac) if e is None else -1)
        digits = (whole + frac).lstrip("0")
        significant = max(significant, len(digits) if digits else 1)
        exponent += e is not None
        upper = upper or e == "E"
    fixed = decimals.pop() if len(decimals) == 1 else None
    return _Style(fixed if fixed is not None and fixed >= 0 else None, significant,
                  exponent > len(tokens) // 2, upper)


def _decimal_text(value: float, stored: str, style: _Style) -> str:
    if stored == "float64" and style.significant >= 16:
        return repr(float(value))
    if stored == "float32":
        value = float(np.float32(value))
    if style.decimals is not None:
        text = f"{value:.{style.decimals}f}"
    elif style.exponent:
        text = f"{value:.{max(style.significant - 1, 0)}e}"
    else:
        text = f"{value:.{style.significant}g}"
        if "e" in text:  # %g turns small numbers into exponents; the array writes them out
            text = np.format_float_positional(value, precision=style.significant, unique=False, fractional=False,
                                              trim="-")
    return text.upper() if style.upper else text


def _number_text(value, stored: str, hex_: bool, width: int, style: _Style | None = None) -> str:
    if stored == "float16":  # text holds half floats as their 16-bit patterns (see readers)
        pattern = int(np.float16(value).view(np.uint16))
        return f"0x{pattern:0{width}x}" if hex_ else str(pattern)
    if stored.startswith(("uint", "int")):
        return f"0x{int(value):0{width}x}" if hex_ else str(int(value))
    if style is not None:
        return _decimal_text(float(value), stored, style)
    if stored == "float64":
        return repr(float(value))
    return str(np.float32(value))


def _original_text(path: str, decoded: str | None = None,
                   spans: list[tuple[int, int]] | None = None) -> tuple[str, int]:
    """The file's text with every byte kept (undecodable bytes as lone surrogates, written back as the same bytes),
    and the offset at which ``decoded`` (the reader's text, which may lack a byte-order mark or hold replacement
    characters where this one holds the undecodable bytes) starts in it, checked on the numbers at ``spans``."""
    raw = read_bounded(path, MAX_TEXT_BYTES).decode("utf-8", errors="surrogateescape")
    if decoded is None:
        return raw, 0
    shift = len(raw) - len(decoded)
    if shift >= 0 and (raw.endswith(decoded) or all(raw[s + shift:e + shift] == decoded[s:e]
                                                      for s, e in spans or [])):
        return raw, shift
    raise ArgumentError("cannot map the table's numbers back onto the file's bytes", where="fix")


def _splice(text: str, spans: list[tuple[int, int]], changed: np.ndarray, values: np.ndarray, stored: str,
            hex_: bool) -> str:
    """``text`` with the numbers at ``spans`` (flat, in the order of ``values``) replaced where ``changed``."""
    tokens = [text[s:e] for s, e in spans]
    width = max((len(t) - 2 for t in tokens if t.lower().startswith("0x")), default=4)
    style = None if stored == "float16" or stored.startswith(("uint", "int")) else _style(tokens)
    pieces, last = [], 0
    for k in np.flatnonzero(changed):
        start, end = spans[k]
        pieces.append(text[last:start])
        pieces.append(_number_text(values[k], stored, hex_, width, style))
        last = end
    pieces.append(text[last:])
    return "".join(pieces)


def _encoded(text: str) -> bytes:
    return text.encode("utf-8", errors="surrogateescape")


def _flat(source: Source, array: np.ndarray) -> np.ndarray:
    """``array`` (*grid, channels) in the order of the file's numbers."""
    values = _squeezed(source, array)
    shape = source.layout.get("shape")
    if shape is not None:
        return values.reshape(shape).ravel(order=source.layout.get("order", "C"))
    return values.reshape(-1)


def _json_order(source: Source, array: np.ndarray) -> np.ndarray:
    """``array`` (*grid, channels) in the reading order of the JSON document's nested lists (as the reader took
    them: reshaped with ``--shape`` in ``--order``, or as nested)."""
    values = _squeezed(source, array)
    if source.layout.get("reshaped"):
        order = source.layout.get("order", "C")
        return values.ravel(order=order).reshape(source.layout["shape"], order=order).ravel()
    return values.reshape(-1)


def write(source: Source, table: np.ndarray, output: str, meta: dict) -> bytes | str:
    """The file contents of the fixed table (``table``: (*grid, channels) in table units)."""
    writer = WRITERS.get(source.fmt)
    if writer is None:
        raise ArgumentError(f"--fix cannot write {source.fmt}", where="fix")
    return writer(source, table, meta)


def _fix_npz(source: Source, table: np.ndarray, meta: dict) -> bytes:
    data = read_bounded(source.path, MAX_BINARY_BYTES)
    member = source.name + ".npy"
    out = io.BytesIO()
    with zipfile.ZipFile(io.BytesIO(data)) as original, zipfile.ZipFile(out, "w") as fixed:
        with original.open(member) as handle:
            array = np.lib.format.read_array(handle, allow_pickle=False)
        values = _squeezed(source, stored_values(source, table))
        if source.stored == "float16" and array.dtype.kind in "iu":
            values = np.asarray(values, dtype=np.float16).view(np.uint16)
        values = np.asarray(values).astype(array.dtype)
        if source.layout.get("reshaped"):
            values = values.ravel(order=source.layout["order"]).reshape(array.shape)
        values = values.reshape(array.shape)
        body = io.BytesIO()
        np.lib.format.write_array(body, np.asfortranarray(values) if array.flags.f_contiguous and array.ndim > 1
                                  else np.ascontiguousarray(values), allow_pickle=False)
        for info in original.infolist():  # every other member copied as it is, under its own name
            if info.filename == "brdfnorm_audit.npy":
                continue
            fixed.writestr(info, body.getvalue() if info.filename == member else original.read(info))
        note = io.BytesIO()
        np.lib.format.write_array(note, np.array(json.dumps(meta)), allow_pickle=False)
        fixed.writestr(zipfile.ZipInfo("brdfnorm_audit.npy", date_time=(1980, 1, 1, 0, 0, 0)), note.getvalue(),
                       compress_type=zipfile.ZIP_DEFLATED if any(i.compress_type for i in original.infolist())
                       else zipfile.ZIP_STORED)
    return out.getvalue()


def _fix_png(source: Source, table: np.ndarray, meta: dict) -> bytes:
    codes = stored_values(source, table)
    text = dict(source.layout.get("text", {}))
    text["brdfnorm-audit"] = json.dumps(meta)
    return pngio.encode(codes, source.layout["depth"], text)


def _fix_exr(source: Source, table: np.ndarray, meta: dict) -> bytes:
    import OpenEXR

    values = stored_values(source, table)
    channels = {}
    for k, name in enumerate(source.channel_names):
        pixel = np.dtype(source.layout["pixel"][name])
        channels[name] = np.ascontiguousarray(values[..., k], dtype=pixel)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "brdfnorm_audit": json.dumps(meta)}
    with tempfile.TemporaryDirectory() as scratch:
        target = Path(scratch) / "fixed.exr"
        with OpenEXR.File(header, channels) as image:
            image.write(str(target))
        return target.read_bytes()


def _fix_json(source: Source, table: np.ndarray, meta: dict) -> bytes:
    text, _ = _original_text(source.path)
    spans = json_spans(text, source.layout["key"])
    changed = _json_order(source, _changed(source, table))
    values = _json_order(source, stored_values(source, table))
    if source.stored == "float16":
        values = np.asarray(values, dtype=np.float16).view(np.uint16)
    body = _splice(text, spans, changed, values, source.stored, False)
    opening = _SPACE.match(body).end()
    if body.startswith("{", opening) and '"brdfnorm_audit"' not in body:  # a top-level object: a key of its own
        body = body[:opening + 1] + '"brdfnorm_audit": ' + json.dumps(meta) + ", " + body[opening + 1:]
    return _encoded(body)


def _fix_csv(source: Source, table: np.ndarray, meta: dict) -> bytes:
    text, _ = _original_text(source.path)
    spans = csv_spans(text, source.layout["header"] is not None,
                      None if source.layout.get("column") is None
                      else source.layout["header"].index(source.layout["column"]))
    changed = _flat(source, _changed(source, table))
    values = _flat(source, stored_values(source, table))
    body = _splice(text, spans, changed, values, source.stored, False)
    start = len(body) - len(body.lstrip("\ufeff"))
    if "# {\"brdfnorm\":" not in body:  # a comment line the reader skips, after a byte-order mark
        body = body[:start] + "# " + json.dumps(meta) + "\n" + body[start:]
    return _encoded(body)


def _fix_text(source: Source, table: np.ndarray, meta: dict) -> bytes:
    spans = list(zip(source.layout["starts"], source.layout["ends"], strict=True))
    text, shift = _original_text(source.path, source.layout["text"], spans)
    spans = [(s + shift, e + shift) for s, e in spans]
    changed = _flat(source, _changed(source, table))
    values = _flat(source, stored_values(source, table))
    body = _splice(text, spans, changed, values, source.stored, source.layout["hex"])
    start = source.layout["start"] + shift
    comment = "/* brdfnorm audit --fix: " + json.dumps(meta).replace("*/", "* /") + " */\n"
    return _encoded(body[:start] + comment + body[start:])


def _fix_raw(source: Source, table: np.ndarray, meta: dict) -> bytes:
    """The table's bytes in the file's byte order, with the bytes before (a header, ``offset``) and after it kept."""
    values = _squeezed(source, stored_values(source, table))
    order = source.layout.get("byteorder", source.layout.get("byte_order", "<"))
    storage = np.dtype(source.stored).newbyteorder(">" if order in (">", "big", "be") else "<")
    body = np.asarray(values, dtype=storage).reshape(source.layout["shape"]).tobytes(order=source.layout["order"])
    start = int(source.layout.get("offset", 0) or 0)
    original = read_bounded(source.path, MAX_BINARY_BYTES)
    return original[:start] + body + original[start + len(body):]


WRITERS = {"npz": _fix_npz, "png": _fix_png, "exr": _fix_exr, "json": _fix_json, "csv": _fix_csv,
           "text": _fix_text, "raw": _fix_raw}
