"""Result formats — ``table``, ``json``, ``csv`` — and the one value formatter of the product.

A result (:class:`~brdfnorm.engine.methods.AlbedoResult`, :class:`~brdfnorm.normalization.NormalizationResult`)
describes itself as :class:`Records`: a title, top-level fields (model, parameters, tolerances), the columns
and one row per point. Each format of :data:`FORMATS` renders Records to text, so the command line, the report
and the benchmarks print the same numbers the same way:

* ``json`` — one object: ``brdfnorm`` (the version), the top-level fields and ``results`` (the rows); non-finite
  floats become ``null``.
* ``csv`` — a header row and one row per point; parameters get one column each; full precision (``repr``).
* ``table`` — a rich table for people: 12 significant digits for values, 3 for error estimates (rounded *up*).

:func:`format_value` is the one formatter of a parameter or result value (bools as 0/1, colors and channels
comma-joined), used by the tables, ``brdfnorm info`` and the report. An error estimate shown with fewer digits
is rounded up, never to nearest (:func:`round_up`, :func:`format_error`, :func:`format_with_error`): a printed
error smaller than the estimate would claim an accuracy the computation did not establish.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from ..registry import Registry


@dataclass(frozen=True)
class Column:
    """One column: ``key`` in every row (``params.NAME`` for a parameter), its header and its precision."""

    key: str
    header: str
    digits: int | None = 12  # significant digits in a table; None: the value's own text
    in_table: bool = True
    bound: bool = False  # an error estimate: shortened by rounding up, never to nearest


@dataclass(frozen=True)
class Records:
    """What every format needs of a result: see the module docstring."""

    title: str
    meta: dict
    columns: tuple[Column, ...]
    rows: list[dict] = field(default_factory=list)

    def cell(self, row: dict, column: Column):
        """The row's value for ``column`` (``params.NAME`` looks into the row's parameters)."""
        if column.key.startswith("params."):
            return row["params"][column.key[len("params."):]]
        return row[column.key]


def format_value(value: object, digits: int | None = None, *, bound: bool = False) -> str:
    """A parameter or result value as text: ``digits`` significant digits (None: full precision, ``repr``);
    bools as 0/1; sequences (colors, channels) comma-joined; text as it is. ``bound``: the value is an error
    estimate, shortened by rounding up (:func:`format_error`)."""
    if isinstance(value, (bool, np.bool_)):
        return str(int(value))
    if isinstance(value, str):
        return value
    if isinstance(value, (Sequence, np.ndarray)):
        return ",".join(format_value(v, digits, bound=bound) for v in np.ravel(np.asarray(value, dtype=object)))
    if isinstance(value, (int, np.integer)):
        return str(int(value))
    number = float(value)  # type: ignore[arg-type]
    if digits is None:
        return repr(number)
    return format_error(number, digits) if bound else f"{number:.{digits}g}"


def round_up(error: float, digits: int = 1) -> float:
    """``error`` to ``digits`` significant digits, rounded *up*: the shown error is never below the estimate."""
    if not (math.isfinite(error) and error > 0):
        return error
    step = 10.0 ** (math.floor(math.log10(error)) - digits + 1)
    shown = math.ceil(error / step) * step
    # 10**k is inexact for k < 0 (3e-10 / 1e-10 = 2.9999999999999996 → ceil 3 is right, but 3.0000000000000004
    # → 4 would not be): step back when the float just below the next step already covers the error.
    lower = (math.ceil(error / step) - 1) * step
    return lower if lower >= error else shown


def format_error(error: float, digits: int = 1) -> str:
    """An error estimate as text with ``digits`` significant digits, rounded up (:func:`round_up`)."""
    return f"{round_up(error, digits):.{digits}g}"


def format_with_error(value: float, error: float) -> str:
    """``value ± error`` with the value's digits down to the error's first significant digit (rounded up)."""
    if not math.isfinite(value):
        return "not finite"
    if not (math.isfinite(error) and error > 0):
        return f"{value:.12g}" + ("" if error == 0 else " ± ?")
    shown = round_up(error)
    leading = math.floor(math.log10(abs(value))) if value else math.floor(math.log10(shown))
    digits = min(15, max(1, leading - math.floor(math.log10(shown)) + 1))
    # '#' keeps trailing zeros (they are digits shown); a bare trailing point is dropped.
    return f"{value:#.{digits}g}".replace(".e", "e").rstrip(".") + f" ± {shown:.1g}"


def degrees(radians: float) -> float:
    """An angle in degrees for output, to 12 significant digits: an angle given in degrees on the command line
    (60) comes back as given, not as its round trip through radians (59.99999999999999)."""
    return float(f"{np.degrees(float(radians)):.12g}")


def channel_value(values: np.ndarray) -> float | list[float]:
    """A number for a single-channel value, a list for a multi-channel one (rows of JSON, CSV and tables)."""
    values = np.asarray(values)
    return float(values.ravel()[0]) if values.size == 1 else [float(v) for v in values.ravel()]


def jsonable(value):
    """numpy scalars/arrays to plain Python; non-finite floats to None (JSON has no NaN)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def to_json(obj) -> str:
    """Indented JSON text of ``obj`` (through :func:`jsonable`)."""
    return json.dumps(jsonable(obj), indent=2, ensure_ascii=False)


def _json(records: Records) -> str:
    from ..version import __version__  # every file brdfnorm writes says which release wrote it

    return to_json({"brdfnorm": __version__, **records.meta, "results": records.rows}) + "\n"


def _csv(records: Records) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([c.key.removeprefix("params.") for c in records.columns])
    for row in records.rows:
        writer.writerow([format_value(records.cell(row, c)) for c in records.columns])
    return buffer.getvalue()


def _same_channels(records: Records, column: Column) -> bool:
    """Whether every row's value in ``column`` is several channels that are all equal (a grey colour model)."""
    if not records.rows:
        return False
    for row in records.rows:
        value = records.cell(row, column)
        if not isinstance(value, (list, tuple, np.ndarray)) or len(value) < 2:
            return False
        first = value[0]
        if any(not (v == first or (v != v and first != first)) for v in value[1:]):
            return False
    return True


def _table(records: Records, width: int | None = None) -> str:
    """A table for people. ``width``: the terminal's columns (the table fits them, numbers wrap rather than
    lose digits); None (not a terminal): the table's natural width, nothing cut. Columns whose channels agree
    on every row show one value, the header saying so."""
    from rich.console import Console  # rich loads only when a table is drawn, not with the library
    from rich.markup import escape
    from rich.table import Table

    # Names from outside (a file called "[bold]x.brdf") are text, never rich markup.
    table = Table(title=escape(records.title))
    shown = [c for c in records.columns if c.in_table]
    collapsed = {c.key for c in shown if _same_channels(records, c)}
    for column in shown:
        header = column.header + (" (all channels)" if column.key in collapsed else "")
        table.add_column(escape(header), justify="right", overflow="fold")
    for row in records.rows:
        cells = []
        for c in shown:
            value = records.cell(row, c)
            cells.append(escape(format_value(value[0] if c.key in collapsed else value, c.digits, bound=c.bound)))
        table.add_row(*cells)
    buffer = io.StringIO()
    if width is None:
        natural = Console(file=buffer, width=100_000).measure(table).maximum
        width = max(natural, 40)
    Console(file=buffer, width=width).print(table)
    return buffer.getvalue()


@dataclass(frozen=True)
class Format:
    """A result format: renders :class:`Records` to text."""

    name: str
    render: Callable[[Records], str]
    description: str


#: Result formats by name (``--json`` and ``--csv`` on the command line pick ``json`` and ``csv``).
FORMATS: Registry[Format] = Registry("format", "format", {
    "table": Format("table", _table, "a table for people (rich)"),
    "json": Format("json", _json, "one JSON object: the result's fields and `results`, one entry per point"),
    "csv": Format("csv", _csv, "a header row and one row per point, full precision"),
})


def validate_format(name: object) -> Format:
    """The format called ``name``, or an ArgumentError listing the known ones."""
    return FORMATS[FORMATS.validate(name)]


def render(records: Records, format_name: str = "table", width: int | None = None) -> str:
    """``records`` as text in the named format; ``width`` (tables only): the terminal's columns, or None for
    the table's natural width (when the text goes to a file or a pipe)."""
    chosen = validate_format(format_name)
    return chosen.render(records, width) if chosen.name == "table" else chosen.render(records)
