"""JSON documents of tables: strict JSON (no NaN or Infinity, unless the caller reads a table whose non-finite
cells are findings, as the audit does), bounded before :func:`json.loads` builds a Python
object per value — the values counted from the commas (a value after the first needs one) against
:data:`~.limits.MAX_TEXT_NUMBERS` — and nested at most :data:`~.limits.MAX_JSON_DEPTH` deep where a table is
looked for (deeper nesting inside ``json.loads`` ends as :func:`~.guard.parsing`'s "nested too deeply"). Names
(keys) quoted in errors are elided in the middle."""

from __future__ import annotations

import json
import re

import numpy as np

from ..errors import TableFileError
from .guard import element_count, shorten
from .limits import MAX_ELEMENTS, MAX_JSON_DEPTH, MAX_TEXT_NUMBERS


def _no_constant(name: str) -> float:
    raise ValueError(f"{name} is not a finite number")


def load_json(text: str | bytes, path: str, what: str = "metadata", line: int | None = None, *,
              finite: bool = True) -> object:
    """The JSON document ``text``, refused (naming ``path``, ``what`` and the place) if it is not strict JSON or
    holds more values than a table file may. ``finite=False`` accepts the NaN and ±Infinity that JavaScript's and
    Python's JSON writers emit (a shipped table's non-finite cells are what an audit reports, not bad input)."""
    values = (text.count(b",") if isinstance(text, bytes) else text.count(",")) + 1
    if values > MAX_TEXT_NUMBERS:
        raise TableFileError(f"{what}: up to {values} values, more than the {MAX_TEXT_NUMBERS} a table file may hold",
                             path, line)
    try:
        return json.loads(text, parse_constant=_no_constant) if finite else json.loads(text)
    except json.JSONDecodeError as error:
        raise TableFileError(f"{what} is not JSON: {error.msg} (line {error.lineno}, column {error.colno})",
                             path, line) from None
    except UnicodeDecodeError:
        raise TableFileError(f"{what} is not UTF-8 text", path, line) from None
    except ValueError as error:  # NaN or Infinity: say where the first one is
        raw = text.decode("utf-8", "replace") if isinstance(text, bytes) else text
        found = re.search(r"-?\b(?:NaN|Infinity)\b", raw)
        at = f" (line {raw.count(chr(10), 0, found.start()) + 1})" if found else ""
        raise TableFileError(f"{what}: {error}{at}; tables hold finite numbers only", path, line) from None


def numeric_arrays(document: object) -> dict[str, tuple]:
    """Every (nested) list of numbers in ``document``, by its dotted key path ("(root)" for the document itself)
    -> the path as a tuple of keys."""
    found: dict[str, tuple] = {}

    def walk(node: object, path: tuple, depth: int) -> None:
        if depth > MAX_JSON_DEPTH:
            raise RecursionError  # guard.parsing: "nested too deeply to read", naming the file
        if isinstance(node, list) and node and all(isinstance(v, (int, float, list)) and not isinstance(v, bool)
                                                   for v in node):
            found[".".join(map(str, path)) or "(root)"] = path
        elif isinstance(node, dict):
            for key, value in node.items():
                walk(value, (*path, key), depth + 1)

    walk(document, (), 0)
    return found


def at_path(document: object, path: tuple) -> object:
    for key in path:
        document = document[key]
    return document


def to_array(nested: object, name: str, path: str) -> np.ndarray:
    """A regular nested list of numbers as a float64 array (integers beyond float range refused), else an error
    naming the array."""
    try:
        raw = np.array(nested, dtype=float)
    except OverflowError:
        raise TableFileError(f"array {shorten(name)!r}: an integer beyond float range", path) from None
    except (ValueError, TypeError):
        raise TableFileError(f"array {shorten(name)!r} is not a regular nested list of numbers", path) from None
    element_count(raw.shape, MAX_ELEMENTS, where=path, what=f"array {shorten(name)}")
    return raw
