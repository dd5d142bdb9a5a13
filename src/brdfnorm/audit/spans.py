"""Where a table's numbers stand in a JSON or CSV file (character spans), so that ``--fix`` can replace the
numbers of changed cells in place and keep every other byte (:mod:`.fix`).

Both scanners are linear and follow the readers' reading of the file (:mod:`.readers`): JSON by RFC 8259's
grammar, the array at a key path (a list of keys from the root); CSV by rows of comma-separated cells, empty
lines and lines starting with ``#`` skipped, an optional header row, quoted cells unquoted.
"""

from __future__ import annotations

import json
import re

import numpy as np

from ..errors import ArgumentError

_JSON_NUMBER = re.compile(r"-?(?:0|[1-9]\d*)(?:\.\d+)?(?:[eE][+-]?\d+)?")
_JSON_STRING = re.compile(r'"(?:[^"\\]|\\.)*"', re.DOTALL)
_SPACE = re.compile(r"[ \t\n\r\ufeff]*")


class _Json:
    def __init__(self, text: str, key: list) -> None:
        self.text, self.key, self.i = text, list(key), 0
        self.spans: list[tuple[int, int]] | None = None

    def space(self) -> None:
        self.i = _SPACE.match(self.text, self.i).end()

    def fail(self) -> None:
        raise ArgumentError(f"--fix: the JSON file does not parse at offset {self.i}", where="fix")

    def value(self, path: list, collect: list | None, depth: int) -> None:
        if depth > 64:
            self.fail()
        self.space()
        c = self.text[self.i:self.i + 1]
        if c == "{":
            self.i += 1
            self.space()
            if self.text.startswith("}", self.i):
                self.i += 1
                return
            while True:
                self.space()
                m = _JSON_STRING.match(self.text, self.i)
                if not m:
                    self.fail()


                name = json.loads(m.group(0))
                self.i = m.end()
                self.space()
                if not self.text.startswith(":", self.i):
                    self.fail()
                self.i += 1
                self.value([*path, name], None, depth + 1)
                self.space()
                if self.text.startswith(",", self.i):
                    self.i += 1
                elif self.text.startswith("}", self.i):
                    self.i += 1
                    return
                else:
                    self.fail()
        elif c == "[":
            if collect is None and path == self.key:
                collect = self.spans = []
            self.i += 1
            self.space()
            if self.text.startswith("]", self.i):
                self.i += 1
                return
            index = 0
            while True:
                self.value([*path, index], collect, depth + 1)
                index += 1
                self.space()
                if self.text.startswith(",", self.i):
                    self.i += 1
                elif self.text.startswith("]", self.i):
                    self.i += 1
                    return
                else:
                    self.fail()
        elif c == '"':
            m = _JSON_STRING.match(self.text, self.i)
            if not m:
                self.fail()
            self.i = m.end()
        else:
            m = _JSON_NUMBER.match(self.text, self.i)
            if m and m.end() > self.i:
                if collect is not None:
                    collect.append((m.start(), m.end()))
                self.i = m.end()
                return
            for word in ("NaN", "Infinity", "-Infinity"):  # Python's json reads (and writes) these
                if self.text.startswith(word, self.i):
                    if collect is not None:
                        collect.append((self.i, self.i + len(word)))
                    self.i += len(word)
                    return
            for word in ("true", "false", "null"):
                if self.text.startswith(word, self.i):
                    self.i += len(word)
                    return
            self.fail()


def json_spans(text: str, key: list) -> list[tuple[int, int]]:
    """Spans of the numbers of the (nested) array at ``key`` in a JSON document, in reading (C) order."""
    scanner = _Json(text, key)
    scanner.value([], None, 0)
    if scanner.spans is None:
        raise ArgumentError(f"--fix: no array at {'.'.join(map(str, key)) or '(root)'}", where="fix")
    return scanner.spans


def csv_spans(text: str, header: bool, column: int | None) -> list[tuple[int, int]]:
    """Spans of the numbers of a CSV file's body (row by row), or of one column's, quotes and spaces excluded."""
    spans = []
    first = True
    position = 0
    for line in text.splitlines(keepends=True):
        start, position = position, position + len(line)
        body = line.rstrip("\r\n")
        stripped = body.lstrip("\ufeff")
        if not stripped.strip() or stripped.lstrip().startswith("#"):
            continue
        if first and header:
            first = False
            continue
        first = False
        cells, offset = [], start + (len(body) - len(stripped))
        for cell in stripped.split(","):
            left = len(cell) - len(cell.lstrip(' \t"'))
            right = len(cell.rstrip(' \t"'))
            cells.append((offset + left, offset + max(right, left)))
            offset += len(cell) + 1
        spans.extend(cells if column is None else [cells[column]])
    return spans


_DECIMAL = re.compile(r"^[+-]?(\d*)(?:\.(\d*))?(?:[eE]([+-]?\d+))?$")


def written_step(source) -> tuple[float, bool] | None:
    """Half a unit in the last written digit of a typical number of a text table (the median over its numbers), in
    table units: the precision a table written as ``%.6f`` or ``%.9g`` was stored at, which its float dtype does
    not say; and whether the numbers are single-precision values written out in full (8 or 9 digits that a
    float32 prints back), whose step is then float32's. None for a table that is not decimal text (integer codes,
    half-float bit patterns, binary formats)."""
    if source.fmt not in ("text", "csv", "json") or not source.stored.startswith("float") or source.stored == "float16":
        return None
    layout = source.layout
    try:
        if source.fmt == "text":
            text = layout["text"]
            spans = list(zip(layout["starts"], layout["ends"], strict=True))
        else:
            from ..inputs import read_bounded
            from .readers import MAX_TEXT_BYTES

            text = read_bounded(source.path, MAX_TEXT_BYTES).decode("utf-8", errors="surrogateescape")
            spans = (json_spans(text, layout["key"]) if source.fmt == "json" else
                     csv_spans(text, layout["header"] is not None,
                               None if layout.get("column") is None else layout["header"].index(layout["column"])))
    except (ArgumentError, KeyError, ValueError):
        return None
    units, single = [], True
    for start, end in spans:
        token = text[start:end].strip()
        m = _DECIMAL.match(token)
        if not m or (m.group(2) is None and m.group(3) is None):
            continue  # an integer literal ("0", "1") is exact whatever the writer's precision
        places = len(m.group(2) or "") - int(m.group(3) or 0)
        units.append(0.5 * 10.0 ** (-places))
        digits = len(((m.group(1) or "") + (m.group(2) or "")).lstrip("0"))
        if single and digits >= 8:  # single-precision values printed with 8-9 digits print back the same
            value = float(token)
            single = float(f"{float(np.float32(value)):.{digits}g}") == float(f"{value:.{digits}g}")
    if not units:
        return None
    step = float(np.median(units))
    single = single and step < 0.5 * float(np.finfo(np.float32).eps)  # float32 data written out in full
    if single:
        step = 0.5 * float(np.finfo(np.float32).eps)
    return step / source.scale, single
