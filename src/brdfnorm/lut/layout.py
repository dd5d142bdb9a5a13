"""How a table file lays its axes out for an engine: which axis is x (u, image columns), which is y (v, image rows),
whether v runs top-down, and which tables a file holds by default.

The common engine layout (Karis 2013's DFG texture, Kulla & Conty 2017's E(μ, roughness) table, Filament, Unreal)
puts N·V on x and roughness (or α) on y. A file written in a layout stores every table as ``[other axes…][y][x]``
(row-major: x varies fastest), with the y values reversed when ``v=up``; its metadata says so (``meta["layout"]``:
``x``, ``y``, ``v``, ``file_axes``, ``axis_order`` and one sentence), and :func:`restore` gives back a :class:`Lut`
indexed in the order of its ``--axis`` flags, as every table in brdfnorm is. ``--layout axes`` keeps that order in the
file as well (the default for the data formats npz, json and csv, which name their axes).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError, TableFileError
from .axes import DIRECTION_AXES
from .table import Lut

#: Formats an engine loads as an image or as code: written in the engine layout unless told otherwise.
ENGINE_FORMATS = ("exr", "png", "h", "glsl", "hlsl")
MAGIC = "brdfnorm-lut"
#: What "keep the --axis order" is called on the command line.
AXES_ORDER = "axes"
V_DIRECTIONS = ("down", "up")
#: The default y axis where present (else the first other axis in the --axis order).
ROUGHNESS_AXES = ("roughness", "alpha")


def parse(text: str | None) -> dict | None:
    """``x=NAME,y=NAME,v=down|up`` (each part optional) or ``axes``; None means the format's default."""
    if text is None:
        return None
    text = text.strip()
    if text == AXES_ORDER:
        return {"order": AXES_ORDER}
    spec: dict[str, str] = {}
    for part in filter(None, (p.strip() for p in text.split(","))):
        key, sep, value = part.partition("=")
        key, value = key.strip(), value.strip()
        if not sep or key not in ("x", "y", "v", "u") or not value:
            raise ArgumentError(f"expected x=AXIS,y=AXIS,v=down|up or 'axes', got {part!r}", where="layout")
        key = {"u": "x"}.get(key, key)
        if key in spec:
            raise ArgumentError(f"{key} given twice", where="layout")
        if key == "v" and value not in V_DIRECTIONS:
            raise ArgumentError(f"v is down (row 0, the image's top, holds the first y value) or up, got {value!r}",
                                where="layout")
        spec[key] = value
    return spec


def resolve(lut: Lut, spec: Mapping[str, str] | None, fmt: str) -> dict | None:
    """The layout a file of format ``fmt`` gets (None: the --axis order), checked against the lut's axes."""
    if spec is None:
        spec = {} if fmt in ENGINE_FORMATS else {"order": AXES_ORDER}
    if spec.get("order") == AXES_ORDER:
        return None
    names = list(lut.axes)
    direction = next((n for n in names if n in DIRECTION_AXES), names[0] if names else None)
    x = spec.get("x", direction)
    others = [n for n in names if n != x]
    preferred = [n for n in ROUGHNESS_AXES if n in others] + others  # engines index rows by roughness
    y = spec.get("y", preferred[0] if preferred else None)
    for key, name in (("x", x), ("y", y)):
        if name is not None and name not in names:
            raise ArgumentError(f"{key}={name}: no axis of that name (axes: {', '.join(names)})", where="layout")
    if x is not None and x == y:
        raise ArgumentError(f"x and y are both {x}", where="layout")
    if "y" in spec and y is None:
        raise ArgumentError("a y axis needs a second axis", where="layout")
    v = spec.get("v", "down")
    file_axes = [n for n in names if n not in (x, y)] + [n for n in (y, x) if n is not None]
    text = f"x (u, columns): {x}"
    if y is not None:
        text += (f"; y (v, rows): {y}, row 0 (the top) holds {y}[0]" if v == "down" else
                 f"; y (v, rows): {y} reversed, the last row (the bottom) holds {y}[0]")
    if len(file_axes) > 2:
        text += f"; further axes ({', '.join(file_axes[:-2])}): blocks of rows, slowest first"
    return {"x": x, "y": y, "v": v, "file_axes": file_axes, "axis_order": names, "text": text}


def apply(lut: Lut, layout: Mapping | None) -> Lut:
    """The lut with its axes in the file's order (and y reversed for ``v=up``); ``meta["layout"]`` records it."""
    if layout is None:
        return lut
    order = layout["file_axes"]
    flip = layout["v"] == "up" and layout["y"] is not None
    axes = {n: (lut.axes[n][::-1] if flip and n == layout["y"] else lut.axes[n]) for n in order}
    tables, table_axes = {}, {}
    for name in lut:
        own = lut.table_axes[name]
        target = [a for a in order if a in own]
        array = np.transpose(lut[name], [own.index(a) for a in target])
        if flip and layout["y"] in target:
            array = np.flip(array, axis=target.index(layout["y"]))
        tables[name], table_axes[name] = np.array(array, order="C"), target
    meta = {**lut.meta, "layout": dict(layout)}
    return Lut(tables, axes, meta, table_axes)


def restore(lut: Lut, path: str = "") -> Lut:
    """A lut read from a file, indexed again in the order of its ``--axis`` flags (``meta["layout"]``)."""
    layout = lut.meta.get("layout")
    if not layout:
        return lut
    try:
        order = list(layout["axis_order"])
        y, flip = layout.get("y"), layout.get("v") == "up" and layout.get("y") is not None
        if sorted(order) != sorted(lut.axes):
            raise KeyError("axis_order")
    except (KeyError, TypeError, AttributeError) as error:
        raise TableFileError(f"the layout in the metadata does not name the file's axes ({error})", path) from None
    axes = {n: (lut.axes[n][::-1] if flip and n == y else lut.axes[n]) for n in order}
    tables, table_axes = {}, {}
    for name in lut:
        own = lut.table_axes[name]
        array = np.flip(lut[name], axis=own.index(y)) if flip and y in own else lut[name]
        target = [a for a in order if a in own]
        tables[name], table_axes[name] = np.array(np.transpose(array, [own.index(a) for a in target]), order="C"), \
            target
    return Lut(tables, axes, lut.meta, table_axes)


def default_tables(lut: Lut, fmt: str) -> list[str]:
    """The tables a file holds when none are named: every table in npz/json/csv; in the engine formats the values
    an engine samples (E, E_avg, DFG_*, E_R, E_T), without error estimates, bounds or 1 − E."""
    if fmt not in ENGINE_FORMATS:
        return list(lut)
    chosen = [n for n in lut if not n.endswith(("_error", "_lower", "_upper")) and n != "1-E"]
    if fmt == "png":  # one image: the tables over the most axes (E and its companions; E_avg is its own file)
        most = max(len(lut.table_axes[n]) for n in chosen)
        chosen = [n for n in chosen if len(lut.table_axes[n]) == most]
    return chosen


def split_tables(text: Sequence[str]) -> list[str] | None:
    """``--tables E,E_avg`` (repeatable, comma lists) as one list; None when none were named."""
    names = [n.strip() for item in text for n in item.split(",") if n.strip()]
    return names or None


@dataclass(frozen=True)
class WriteOptions:
    """How a writer lays out what engines read: float16 EXR, the code identifiers' prefix, the image channels'
    names (``rgba``: R, G, B, A with the mapping in the metadata; ``brdfnorm``: the table names) and whether
    tables over fewer axes (E_avg) are broadcast into the grid's image instead of written as their own."""

    half: bool = False
    prefix: str = "lut_"
    channel_names: str = "rgba"
    broadcast_average: bool = False


def check_finite(lut: Lut, tables: Sequence[str], fmt: str) -> None:
    """Refuse ``tables`` holding a non-finite value for a format ``fmt`` that cannot store one (every writer's)."""
    for name in tables:
        if not np.all(np.isfinite(lut[name])):
            raise ArgumentError(f"table {name} has non-finite values, which {fmt} cannot hold", where="tables")


def subset_meta(lut: Lut, tables: Sequence[str]) -> dict:
    """The table file's metadata for the written ``tables`` only (every writer's header)."""
    meta = dict(lut.meta)
    meta["tables"] = {name: list(lut.table_axes[name]) for name in tables}
    return meta
