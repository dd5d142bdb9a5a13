"""The lookup table object (:class:`Lut`: named arrays over named axes, with metadata), the axis grids a table is
sampled on (:func:`grid_values`) and parameter values as metadata (:func:`plain_params`); computed by
:mod:`brdfnorm.lut.table`, written and read by :mod:`brdfnorm.lut.formats`."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..errors import ArgumentError

GRIDS = ("node", "texel")


def grid_values(start: float, stop: float, count: int, grid: str = "node") -> np.ndarray:
    """``count`` values over [start, stop]: at i/(N−1) (``node``, the default) or at (i + ½)/N (``texel``,
    where a GPU samples texel i of an N-texel texture)."""
    if grid not in GRIDS:
        raise ArgumentError(f"unknown grid {grid!r} (known: {', '.join(GRIDS)})", where="grid")
    if count < 1:
        raise ArgumentError(f"an axis needs at least one value, got {count}", where="axes")
    if grid == "node":
        return np.linspace(start, stop, count)
    return start + (np.arange(count) + 0.5) / count * (stop - start)


class Lut(Mapping):
    """A lookup table: a mapping table name (``E``, ``E_error``, ``E_avg``, ``1-E``, ``DFG_f0`` …) -> array.

    ``axes`` maps axis name -> values in the order the arrays are indexed (the nominal grid values; clamped
    values are what was evaluated, see ``meta["clamp"]``); ``table_axes`` names the axes of each table (E_avg
    lacks the direction axis); ``meta`` holds the model, parameters, grid, clamps, tolerance and version.
    """

    def __init__(self, tables: Mapping[str, np.ndarray], axes: Mapping[str, Sequence[float]], meta: Mapping,
                 table_axes: Mapping[str, Sequence[str]] | None = None) -> None:
        self.axes = {name: np.asarray(values, dtype=float) for name, values in axes.items()}
        self.table_axes = {name: tuple(table_axes[name]) if table_axes else tuple(self.axes) for name in tables}
        self._tables = {}
        for name, array in tables.items():
            if list(self.table_axes[name]) != [a for a in self.axes if a in self.table_axes[name]]:
                raise ArgumentError(f"table {name!r}: its axes {self.table_axes[name]} must be some of "
                                    f"{tuple(self.axes)} in that order", where="tables")
            expected = tuple(len(self.axes[a]) for a in self.table_axes[name])
            array = np.asarray(array)  # a float32 file's tables stay float32
            array = array if array.dtype in (np.float16, np.float32) else array.astype(float)
            if array.shape != expected:
                raise ArgumentError(f"table {name!r} has shape {array.shape}, its axes "
                                    f"{self.table_axes[name]} need {expected}", where="tables")
            self._tables[name] = array
        self.meta = dict(meta)
        self.meta["axes"] = list(self.axes)
        self.meta["tables"] = {name: list(self.table_axes[name]) for name in self._tables}

    def __getitem__(self, name: str) -> np.ndarray:
        return self._tables[name]

    def __iter__(self):
        return iter(self._tables)

    def __len__(self) -> int:
        return len(self._tables)

    def __repr__(self) -> str:
        axes = ", ".join(f"{n}[{len(v)}]" for n, v in self.axes.items())
        return f"Lut({self.meta.get('model', '?')}; axes {axes}; tables {', '.join(self._tables)})"

    def full(self, name: str) -> np.ndarray:
        """Table ``name`` broadcast over every axis of the lut (E_avg repeated along μ)."""
        index = tuple(slice(None) if a in self.table_axes[name] else None for a in self.axes)
        return np.broadcast_to(self._tables[name][index], tuple(len(v) for v in self.axes.values()))


def plain_params(params: Mapping[str, object]) -> dict:
    """Parameter values as JSON data for a table's metadata (bools as bools, numbers as floats or lists)."""
    out = {}
    for name, value in params.items():
        if isinstance(value, (bool, np.bool_)):
            out[name] = bool(value)
        elif isinstance(value, (tuple, list, np.ndarray)):
            out[name] = [float(v) for v in np.ravel(value)]
        elif isinstance(value, (int, float, np.number)):
            out[name] = float(value)
        else:
            out[name] = str(value)
    return out
