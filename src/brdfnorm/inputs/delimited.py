"""CSV tables of numbers: leading ``#`` comment lines, an optional header row, then rows of numbers, bounded before
any row is parsed.

The header rule (issue 41): the first row after the comments is a header when every cell is a printable name that
is not a number; it is data when every cell is a number; anything else — a NUL or another control character in a
cell, a mix of names and numbers — is refused naming the line and column (a damaged first row no longer turns
silently into a header). The rows are then counted (one ``str.count``) and rows × columns checked against
:data:`~.limits.MAX_ELEMENTS` and :data:`~.limits.MAX_TEXT_NUMBERS` before the body is parsed, in one call of
numpy's C parser (:func:`numpy.loadtxt`) into one float64 array: no Python list per row. Blank lines and ``#``
lines in the body are skipped; a cell that is not a number, or a row of another width, is one error naming the
data row and column. NaN and infinities are read as such: what a table may hold is its command's business.
"""

from __future__ import annotations

import csv
import io
import re
from dataclasses import dataclass

import numpy as np

from ..errors import TableFileError
from .guard import shorten
from .limits import MAX_ELEMENTS, MAX_TEXT_NUMBERS

#: Leading comment lines read one by one (the rest of a file's comments are skipped by the C parser).
MAX_LEADING_COMMENTS = 1000
_NOT_A_NUMBER = re.compile(r"could not convert string '(.*)' to \w+ at row (\d+), column (\d+)", re.S)
_WIDTH = re.compile(r"number of columns changed from (\d+) to (\d+) at row (\d+)")


@dataclass
class Rows:
    """A CSV file's content: its leading comments (text after ``#``), its header (or None), the values
    (rows, columns) as float64, and the file line of the first data row."""

    comments: list[str]
    header: list[str] | None
    values: np.ndarray
    first_line: int


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _cells(line: str) -> list[str]:
    return next(csv.reader([line]), [])


def read_rows(data: bytes, where: str, *, header: bool | None = None) -> Rows:
    """The rows of the CSV ``data`` (see the module docstring); ``header`` True requires a header row, False
    forbids one, None decides by the header rule."""
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as error:
        raise TableFileError("not UTF-8 text", where, data.count(b"\n", 0, error.start) + 1) from None
    position, line, comments = 0, 1, []
    while True:  # leading comments and blank lines, one at a time (a bounded number of them)
        end = text.find("\n", position)
        current = text[position:] if end < 0 else text[position:end]
        stripped = current.strip()
        if stripped and not stripped.startswith("#"):
            break
        if stripped:
            comments.append(stripped[1:].lstrip())
            if len(comments) > MAX_LEADING_COMMENTS:
                raise TableFileError(f"more than {MAX_LEADING_COMMENTS} comment lines before the table", where)
        if end < 0:
            raise TableFileError("no rows", where)
        position, line = end + 1, line + 1
    first = _cells(current)
    numbers = [_is_number(cell) for cell in first]
    names = [not number and cell.strip() != "" and cell.isprintable() for cell, number in zip(first, numbers,
                                                                                              strict=True)]
    if all(numbers):
        is_header = False
    elif all(names):
        is_header = True
    else:
        odd = [k for k, (number, name) in enumerate(zip(numbers, names, strict=True)) if not (number or name)]
        column = odd[0] if odd else numbers.index(True)  # a cell neither, or a number among names
        what = "neither a number nor a column name" if odd else "a number in a row of names"
        raise TableFileError(f"column {column + 1}: {shorten(repr(first[column]))} is {what} (a header holds names "
                             "only, a row numbers only)", where, line)
    if header is not None and is_header != header:
        raise TableFileError("expected a header row" if header else "expected a row of numbers", where, line)
    body_start = position if not is_header else (len(text) if end < 0 else end + 1)
    first_line = line + 1 if is_header else line
    columns = len(first)
    rows = text.count("\n", body_start) + 1  # an upper bound on the rows (blank and comment lines included)
    if rows * columns > min(MAX_ELEMENTS, MAX_TEXT_NUMBERS):
        raise TableFileError(f"up to {rows} rows × {columns} columns, more than the "
                             f"{min(MAX_ELEMENTS, MAX_TEXT_NUMBERS)} numbers a table file may hold", where)
    body = text[body_start:]
    if not body.strip():
        raise TableFileError("a header and no rows" if is_header else "no rows", where, first_line)
    try:
        values = np.loadtxt(io.StringIO(body), delimiter=",", dtype=np.float64, comments="#", ndmin=2,
                            quotechar='"')
    except ValueError as error:
        raise _row_error(str(error), body, first_line, columns, where) from None
    if values.shape[0] == 0:
        raise TableFileError("a header and no rows" if is_header else "no rows", where, first_line)
    if values.shape[1] != columns:
        raise TableFileError(f"rows of {values.shape[1]} cells, the first row has {columns}", where, first_line)
    return Rows(comments, first if is_header else None, values, first_line)


def _row_error(message: str, body: str, first_line: int, columns: int, where: str) -> TableFileError:
    """numpy's message as one error naming the data row (and its line, when the body has no skipped lines)."""
    plain = "\n\n" not in body and "#" not in body and "\r\n\r\n" not in body

    def at(row: int) -> tuple[str, int | None]:
        return (f"row {row + 1}", first_line + row) if plain else (f"data row {row + 1}", None)

    found = _NOT_A_NUMBER.search(message)
    if found is not None:
        where_row, line = at(int(found.group(2)))
        return TableFileError(f"{where_row}, column {found.group(3)}: {shorten(repr(found.group(1).strip()))} is "
                              "not a number", where, line)
    found = _WIDTH.search(message)
    if found is not None:
        where_row, line = at(int(found.group(3)) - 1)
        return TableFileError(f"{where_row} has {found.group(2)} cells, the first has {columns}", where, line)
    return TableFileError(f"cannot parse: {shorten(message.splitlines()[0] if message else 'rows', 200)}", where)
