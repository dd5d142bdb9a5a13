"""The image formats' writers: OpenEXR (float32 or float16 channels, one part per set of axes) and 16-bit PNG
(greyscale, RGB or RGBA, one image), both with R, G, B, A channels and the mapping in the metadata.

An image's columns are its last axis (x, u) and its rows the others (y, v; blocks of rows for further axes),
as :mod:`.layout` arranged them. A table over fewer axes (E_avg over roughness) is its own image, one row per
value of its leading axes — in EXR a second part of the same file (a multi-part OpenEXR 2 file), in PNG a file of
its own (``--tables E_avg``) — unless ``broadcast_average`` repeats it over the grid inside the first image.
Read back (bounded, guarded) by :mod:`.readers`.
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..inputs import png
from .layout import MAGIC, WriteOptions, check_finite, subset_meta
from .table import Lut

CHANNEL_NAMINGS = ("rgba", "brdfnorm")
RGBA = ("R", "G", "B", "A")


def _openexr():
    """The OpenEXR package (an optional extra), or a one-line error saying how to install it."""
    from ..extras import require

    return require("OpenEXR", "exr", where=".exr format")


def _image_shape(shape: tuple[int, ...]) -> tuple[int, int]:
    if len(shape) == 0:
        return 1, 1
    return int(np.prod(shape[:-1])), int(shape[-1])


def _image_parts(lut: Lut, tables: Sequence[str], opts: WriteOptions, fmt: str) -> list[dict]:
    """The images of a file: one per set of axes (the grid's tables, then E_avg's own, as one row per value of
    its leading axes), unless ``broadcast_average`` puts every table into the grid's image. Each part: its axes,
    tables and channel names (R, G, B, A in order, or the table names)."""
    if opts.channel_names not in CHANNEL_NAMINGS:
        raise ArgumentError(f"unknown channel naming {opts.channel_names!r} (known: {', '.join(CHANNEL_NAMINGS)})",
                            where="channel_names")
    groups: dict[tuple[str, ...], list[str]] = {}
    for name in tables:
        key = tuple(lut.axes) if opts.broadcast_average else lut.table_axes[name]
        groups.setdefault(key, []).append(name)
    parts = []
    for axes, names in sorted(groups.items(), key=lambda item: -len(item[0])):
        if opts.channel_names == "rgba" and len(names) > len(RGBA):
            raise ArgumentError(f"an RGBA {fmt} image holds at most 4 tables, not {len(names)} ({', '.join(names)})"
                                "; choose them with --tables or keep their names with --channel-names brdfnorm",
                                where="tables")
        channels = list(RGBA[:len(names)]) if opts.channel_names == "rgba" else list(names)
        parts.append({"name": "tables" if not parts else names[0], "axes": list(axes),
                      "channels": dict(zip(channels, names, strict=True))})
    return parts


def write_exr(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> bytes:
    """``tables`` as an OpenEXR file's bytes (the ``exr`` writer of :data:`brdfnorm.lut.formats.FORMATS`)."""
    OpenEXR = _openexr()  # noqa: N806 - the module, by its own name

    dtype = np.float16 if opts.half else np.float32
    if opts.half:
        big = [n for n in tables if np.any(np.abs(lut[n]) > np.finfo(np.float16).max)]
        if big:
            raise ArgumentError(f"table {big[0]} exceeds the float16 range", where="half")
    parts = _image_parts(lut, tables, opts, "EXR")
    meta = subset_meta(lut, tables)
    meta["axis_values"] = {n: v.tolist() for n, v in lut.axes.items()}
    meta["exr"] = {"parts": parts}
    images = []
    for part in parts:
        shape = _image_shape(tuple(len(lut.axes[a]) for a in part["axes"]))
        channels = {}
        for channel, name in part["channels"].items():
            values = lut.full(name) if opts.broadcast_average else lut[name]
            channels[channel] = np.ascontiguousarray(np.asarray(values).reshape(shape), dtype=dtype)
        images.append((shape, channels))
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
              "brdfnorm": json.dumps(meta, ensure_ascii=True)}
    with tempfile.TemporaryDirectory() as scratch:  # the bindings write to a path; the caller renames atomically
        target = Path(scratch) / "lut.exr"
        if len(images) == 1:
            with OpenEXR.File(header, images[0][1]) as image:
                image.write(str(target))
        else:  # a multi-part file: every part shares the first part's display window (OpenEXR requires it)
            rows, columns = images[0][0]
            window = (np.array([0, 0], dtype=np.int32), np.array([columns - 1, rows - 1], dtype=np.int32))
            others = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage, "displayWindow": window}
            files = [OpenEXR.Part(header if i == 0 else others, channels, part["name"])
                     for i, ((_, channels), part) in enumerate(zip(images, parts, strict=True))]
            with OpenEXR.File(files) as image:
                image.write(str(target))
        return target.read_bytes()


# -- PNG -------------------------------------------------------------------------------------------------------

def write_png(lut: Lut, tables: Sequence[str], opts: WriteOptions) -> bytes:
    """``tables`` as a 16-bit PNG file's bytes (the ``png`` writer of :data:`brdfnorm.lut.formats.FORMATS`)."""
    parts = _image_parts(lut, tables, opts, "PNG")
    if len(parts) != 1:
        other, first = (", ".join(p["channels"].values()) for p in parts[:2])
        raise ArgumentError(f"a PNG holds one image: {other} has other axes than {first}; write it to its own "
                            "PNG (--tables E_avg) or broadcast it (--broadcast-average)", where="tables")
    (part,) = parts
    if len(part["axes"]) > 2:
        raise ArgumentError(f"a PNG image holds a table of one or two axes; {', '.join(tables)} has "
                            f"{len(part['axes'])} (use .exr or .npz)", where="tables")
    check_finite(lut, tables, "PNG")
    shape = _image_shape(tuple(len(lut.axes[a]) for a in part["axes"]))
    samples, mapping = [], {}
    for channel, name in zip(RGBA, part["channels"].values(), strict=False):  # PNG channels are R, G, B, A by place
        image = (lut.full(name) if opts.broadcast_average else lut[name]).reshape(shape)
        lo, hi = float(image.min()), float(image.max())
        scale = (hi - lo) if hi > lo else 1.0
        samples.append(np.rint((image - lo) / scale * 65535.0).astype(np.int64))
        mapping[channel] = {"table": name, "lo": lo, "hi": hi}
    if len(samples) == 2:  # no two-channel colour PNG: RGB with B = 0
        samples.append(np.zeros(shape, dtype=np.int64))
    colour = {1: 0, 3: 2, 4: 6}[len(samples)]  # greyscale, RGB, RGBA
    codes = np.stack(samples, axis=-1)
    meta = subset_meta(lut, tables)
    meta["axis_values"] = {n: v.tolist() for n, v in lut.axes.items()}
    meta["png"] = {"axes": part["axes"], "channels": mapping, "value": "lo + code / 65535 * (hi - lo)",
                   "colour": {0: "greyscale (read as R)", 2: "RGB", 6: "RGBA"}[colour]}
    return png.encode(codes, 16, {MAGIC: json.dumps(meta, ensure_ascii=True)})


