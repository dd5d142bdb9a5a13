"""``--fix``: the exact table as a drop-in replacement — same format, array name, layout, orientation, sample
positions, storage dtype, channel order — with brdfnorm's metadata where the format has room for it.

Values are rounded to the storage the input used: integers to the nearest code of the same scale (clipped to
the type's range), half and single floats by numpy's round-to-nearest conversion. Text sources are rewritten
in place: every number of the audited array is replaced where it stood (its span, sign included, recorded by
:mod:`brdfnorm.inputs.literals`), spelled as before (hex stays hex, suffixes stay), and a comment with the metadata goes
before the declaration; everything else in the file is kept byte for byte. Channels that fit no meaning are
written back unchanged (requantized to the same storage).
"""

from __future__ import annotations

import csv
import io
import json
import tempfile
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..inputs import png as pngio
from ..inputs import read_bounded
from .readers import MAX_BINARY_BYTES, MAX_TEXT_BYTES, Source


def stored_values(source: Source, table: np.ndarray) -> np.ndarray:
    """``table`` (table units) in the storage of ``source``: integer codes or floats of its dtype."""
    offset = source.layout.get("offset", 0.0)
    if source.stored.startswith(("uint", "int")):
        info = np.iinfo(np.dtype(source.stored))
        return np.clip(np.rint((table - offset) * source.scale), info.min, info.max).astype(np.int64)
    return np.asarray(table * source.scale, dtype=np.dtype(source.stored))


def _squeezed(source: Source, array: np.ndarray) -> np.ndarray:
    return array[..., 0] if source.channel_names == ["0"] else array


def _number_text(value, stored: str, hex_: bool, width: int) -> str:
    if stored == "float16":  # text holds half floats as their 16-bit patterns (see readers)
        pattern = int(np.float16(value).view(np.uint16))
        return f"0x{pattern:0{width}x}" if hex_ else str(pattern)
    if stored.startswith(("uint", "int")):
        return f"0x{int(value):0{width}x}" if hex_ else str(int(value))
    if stored == "float64":
        return repr(float(value))
    return str(np.float32(value))


def write(source: Source, table: np.ndarray, output: str, meta: dict) -> bytes | str:
    """The file contents of the fixed table (``table``: (*grid, channels) in table units)."""
    writer = WRITERS.get(source.fmt)
    if writer is None:
        raise ArgumentError(f"--fix cannot write {source.fmt}", where="--fix")
    return writer(source, table, meta)


def _fix_npz(source: Source, table: np.ndarray, meta: dict) -> bytes:
    data = read_bounded(source.path, MAX_BINARY_BYTES)
    arrays = dict(np.load(io.BytesIO(data), allow_pickle=False))
    original = arrays[source.name]
    values = _squeezed(source, stored_values(source, table))
    if source.stored == "float16" and original.dtype.kind in "iu":
        values = np.asarray(values, dtype=np.float16).view(np.uint16)
    values = np.asarray(values).astype(original.dtype)
    if source.layout.get("reshaped"):
        values = values.ravel(order=source.layout["order"]).reshape(original.shape)
    arrays[source.name] = values.reshape(original.shape)
    arrays["brdfnorm_audit"] = np.array(json.dumps(meta))
    out = io.BytesIO()
    np.savez_compressed(out, **arrays)
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


def _fix_json(source: Source, table: np.ndarray, meta: dict) -> str:
    document = json.loads(read_bounded(source.path, MAX_TEXT_BYTES).decode("utf-8"))
    values = _squeezed(source, stored_values(source, table))
    if source.layout.get("reshaped"):
        values = values.ravel(order=source.layout["order"]).reshape(source.layout["shape"])
    values = values.reshape(source.layout["shape"])
    if source.stored == "float16":
        values = np.asarray(values, dtype=np.float16).view(np.uint16)
    plain = values.tolist() if values.dtype.kind in "iu" else np.asarray(values, dtype=float).tolist()
    key = source.layout["key"]
    if not key:
        document = plain
    else:
        node = document
        for part in key[:-1]:
            node = node[part]
        node[key[-1]] = plain
    if isinstance(document, dict):
        document["brdfnorm_audit"] = meta
    return json.dumps(document, indent=None) + "\n"


def _fix_csv(source: Source, table: np.ndarray, meta: dict) -> str:
    values = _squeezed(source, stored_values(source, table))
    text = read_bounded(source.path, MAX_TEXT_BYTES).decode("utf-8-sig")
    rows = [r for r in csv.reader(io.StringIO(text)) if r and not r[0].lstrip().startswith("#")]
    header = source.layout["header"]
    body = rows[1:] if header is not None else rows
    matrix = np.array([[float(c) for c in r] for r in body])
    flat = values.ravel(order=source.layout["order"]) if source.layout.get("shape") else values.reshape(-1)
    if source.layout.get("column") is not None:
        matrix[:, header.index(source.layout["column"])] = flat
    else:
        matrix = flat.reshape(matrix.shape)
    out = io.StringIO()
    out.write("# " + json.dumps(meta) + "\n")
    writer = csv.writer(out, lineterminator="\n")
    if header is not None:
        writer.writerow(header)
    integer = source.stored.startswith(("uint", "int"))
    for row in matrix:
        writer.writerow([str(int(v)) if integer else repr(float(v)) for v in row])
    return out.getvalue()


def _fix_text(source: Source, table: np.ndarray, meta: dict) -> str:
    text = source.layout["text"]
    values = _squeezed(source, stored_values(source, table))
    flat = values.reshape(source.layout["shape"]).ravel(order=source.layout["order"])
    starts, ends = source.layout["starts"], source.layout["ends"]
    width = max((e - s - 2 for s, e in zip(starts, ends, strict=True) if text[s:e].lower().startswith("0x")),
                default=4)
    pieces, last = [], 0
    for start, end, value in zip(starts, ends, flat.tolist(), strict=True):
        pieces.append(text[last:start])
        pieces.append(_number_text(value, source.stored, source.layout["hex"], width))
        last = end
    pieces.append(text[last:])
    body = "".join(pieces)
    start = source.layout["start"]
    comment = "/* brdfnorm audit --fix: " + json.dumps(meta).replace("*/", "* /") + " */\n"
    return body[:start] + comment + body[start:]


def _fix_raw(source: Source, table: np.ndarray, meta: dict) -> bytes:
    values = _squeezed(source, stored_values(source, table))
    storage = np.dtype(source.stored).newbyteorder("<")
    return np.asarray(values, dtype=storage).reshape(source.layout["shape"]).tobytes(order=source.layout["order"])


WRITERS = {"npz": _fix_npz, "png": _fix_png, "exr": _fix_exr, "json": _fix_json, "csv": _fix_csv,
           "text": _fix_text, "raw": _fix_raw}
