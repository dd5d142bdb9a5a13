"""Array literals in source text: C/C++ headers, GLSL/HLSL and JavaScript, read by one linear scanner.

What engines ship their tables as: ``static const float t[64][64] = {{...}}``, ``const float2 t[256] = {
float2(a, b), ...}``, ``float[16](...)``, ``const T = [...]``, ``new Float32Array([...])``,
``new Uint16Array([0x30b5, ...])``. The scanner walks the text once, character by character (comments and strings
skipped, no backtracking regular expression over the text), and collects every initializer that is a literal:
numbers (decimal, exponent, hex, with C/GLSL suffixes ``f``, ``u``, ``h``, ``l``), unary signs, brackets, commas
and constructor names (``float2``, ``vec4``, ``new``, ``Float32Array``). An initializer with any other
expression (an operator, a variable) is not a table and is skipped. Every number keeps its span in the text, so
that :mod:`.fix` can write exact values back in place.
"""

from __future__ import annotations

from array import array
from dataclasses import dataclass, field

import numpy as np

from ..errors import TableFileError
from ..inputs import element_count

#: The most numbers one file may hold (128³ × 4 channels; kept in typed arrays, 24 bytes a number with its span).
MAX_NUMBERS = 128**3 * 4

#: Declared element types -> the dtype their values are stored in (integers are normalized by their maximum).
C_TYPES = {
    "float": "float32", "double": "float64", "half": "float16", "float2": "float32", "float3": "float32",
    "float4": "float32", "vec2": "float32", "vec3": "float32", "vec4": "float32", "uint8_t": "uint8",
    "uint16_t": "uint16", "uint32_t": "uint32", "int": "int32", "unsigned": "uint32", "uint": "uint32",
    "short": "int16", "char": "uint8", "uint8": "uint8", "uint16": "uint16", "half2": "float16",
    "half4": "float16",
}
JS_TYPES = {
    "Float32Array": "float32", "Float64Array": "float64", "Uint8Array": "uint8", "Uint8ClampedArray": "uint8",
    "Uint16Array": "uint16", "Uint32Array": "uint32", "Int16Array": "int16", "Int32Array": "int32",
    "Float16Array": "float16",
}
_OPEN = {"{": "}", "[": "]", "(": ")"}
_CLOSE = set(_OPEN.values())
_SKIP_WORDS = {"new", "Array", "of", "from"} | set(C_TYPES) | set(JS_TYPES) | {
    "float16_t", "min16float", "uint16", "unsigned", "short", "static", "const", "constexpr"}


@dataclass
class Literal:
    """One array initializer: its name, numbers (with their text spans and spelling), nested shape if regular."""

    name: str
    values: array = field(default_factory=lambda: array("d"))
    starts: array = field(default_factory=lambda: array("q"))  # text offsets of each number (its sign included)
    ends: array = field(default_factory=lambda: array("q"))
    hex: bool = False
    suffix: str = ""
    dtype: str | None = None  # from the declaration or typed array, if any
    declared: tuple[int, ...] = ()  # C dimensions [a][b]
    nested: tuple[int, ...] | None = None  # shape of the bracket nesting when regular
    start: int = 0  # offset of the declaration's first token (a comment with metadata goes before it)


def _is_ident_start(c: str) -> bool:
    return c.isalpha() or c == "_" or c == "$"


def _is_ident(c: str) -> bool:
    return c.isalnum() or c == "_" or c == "$"


class _Scanner:
    """Tokens of C-like text: ('id', text), ('num', value, span, hex, suffix), ('op', char); comments skipped."""

    def __init__(self, text: str, where: str) -> None:
        self.text = text
        self.where = where
        self.i = 0
        self.numbers = 0

    def tokens(self):
        text, n = self.text, len(self.text)
        while self.i < n:
            c = text[self.i]
            if c in " \t\r\n\f\v":
                self.i += 1
            elif c == "/" and text.startswith("//", self.i):
                end = text.find("\n", self.i)
                self.i = n if end < 0 else end + 1
            elif c == "/" and text.startswith("/*", self.i):
                end = text.find("*/", self.i + 2)
                self.i = n if end < 0 else end + 2
            elif c in "\"'`":
                end = self.i + 1
                while end < n and text[end] != c:
                    end += 2 if text[end] == "\\" else 1
                self.i = end + 1
            elif c == "#":  # preprocessor line: skipped whole
                end = text.find("\n", self.i)
                self.i = n if end < 0 else end + 1
            elif _is_ident_start(c):
                start = self.i
                while self.i < n and _is_ident(text[self.i]):
                    self.i += 1
                yield ("id", text[start:self.i], start)
            elif c.isdigit() or (c == "." and self.i + 1 < n and text[self.i + 1].isdigit()):
                yield self._number()
            else:
                self.i += 1
                yield ("op", c, self.i - 1)

    def _number(self):
        text, n, start = self.text, len(self.text), self.i
        self.numbers += 1
        if self.numbers > MAX_NUMBERS:
            raise TableFileError(f"more than {MAX_NUMBERS} numbers", self.where)
        if text.startswith(("0x", "0X"), start):
            end = start + 2
            while end < n and (text[end] in "0123456789abcdefABCDEF"):
                end += 1
            digits = text[start + 2:end]
            if not digits or len(digits) > 16:
                raise TableFileError(f"malformed hex number at offset {start}", self.where)
            value, is_hex = float(int(digits, 16)), True
        else:
            end = start
            while end < n and text[end].isdigit():
                end += 1
            if end < n and text[end] == ".":
                end += 1
                while end < n and text[end].isdigit():
                    end += 1
            if end < n and text[end] in "eE":
                e = end + 1
                if e < n and text[e] in "+-":
                    e += 1
                if e < n and text[e].isdigit():
                    while e < n and text[e].isdigit():
                        e += 1
                    end = e
            value, is_hex = float(text[start:end]), False
        number_end = end
        while end < n and text[end] in "fFhHuUlL":
            end += 1
        if end < n and _is_ident(text[end]):
            raise TableFileError(f"malformed number {text[start:end + 1][:30]!r} at offset {start}", self.where)
        suffix = text[number_end:end]
        self.i = end
        return ("num", value, (start, number_end), is_hex, suffix)


def find_literals(text: str, where: str) -> list[Literal]:
    """Every literal array initializer in ``text`` (see the module docstring), in order."""
    scanner = _Scanner(text, where)
    found: list[Literal] = []
    recent: list[tuple] = []  # tokens since the last ';' (the declaration before an '=')
    tokens = scanner.tokens()
    for token in tokens:
        if token[0] == "op" and token[1] == ";":
            recent = []
            continue
        if token[0] == "op" and token[1] == "=" and recent and not (recent[-1][0] == "op" and recent[-1][1] in "=!<>"):
            literal = _initializer(tokens, recent, where)
            if literal is not None and literal.values:
                found.append(literal)
            recent = []
            continue
        recent.append(token)
        if len(recent) > 64:  # a declaration is short; keep the window bounded
            recent = recent[-64:]
    return found


def _declaration(recent: list[tuple], where: str) -> tuple[str, str | None, tuple[int, ...], int]:
    """Name, element type and C dimensions of the declaration ``recent`` (tokens before '=')."""
    name, dtype, dims = "", None, []
    start = recent[0][2] if recent[0][0] != "num" else recent[0][2][0]
    k = len(recent) - 1
    unknown = False  # a dimension given by an expression (C++'s [COMP*COMP]): the shape comes from --shape
    while k >= 0 and recent[k][0] == "op" and recent[k][1] == "]":  # trailing [a][b]
        if k >= 2 and recent[k - 1][0] == "num" and recent[k - 2][0] == "op" and recent[k - 2][1] == "[":
            dims.insert(0, recent[k - 1][1])
            k -= 3
            continue
        opening = k - 1
        while opening >= 0 and not (recent[opening][0] == "op" and recent[opening][1] in "[]"):
            opening -= 1
        if opening < 0 or recent[opening][1] != "[":
            break
        unknown = unknown or opening < k - 1
        k = opening - 1
    if unknown:
        dims = []
    if k >= 0 and recent[k][0] == "id":
        name = recent[k][1]
    for token in recent[:k]:
        if token[0] == "id" and token[1] in C_TYPES:
            dtype = C_TYPES[token[1]]
    if [t[1] for t in recent[:k] if t[0] == "id"][-2:] == ["unsigned", "short"]:
        dtype = "uint16"
    if [t[1] for t in recent[:k] if t[0] == "id"][-2:] == ["unsigned", "char"]:
        dtype = "uint8"
    shape = tuple(int(d) if float(d).is_integer() else -1 for d in dims)
    if shape:
        element_count(shape, MAX_NUMBERS, where=where, what=f"the declared shape of {name or 'an array'}")
    return name, dtype, shape, start


def _initializer(tokens, recent: list[tuple], where: str) -> Literal | None:
    """Read the initializer after '=': a Literal if it is made of numbers and brackets only, else None (and the
    scan resumes after it)."""
    name, dtype, declared, start = _declaration(recent, where)
    literal = Literal(name=name, dtype=dtype, declared=declared, start=start)
    depth = 0
    sign = 1.0
    sign_at: int | None = None
    literal_ok = True
    # the nesting: counts of children per open bracket, to find a regular shape
    stack: list[list[int]] = []
    leaf_shape: dict[int, set[int]] = {}
    opened = False
    after_type = False  # GLSL's float[16](...): the brackets after a type name are its size, not data
    skipping_size = False
    for token in tokens:
        kind = token[0]
        if skipping_size:
            skipping_size = not (kind == "op" and token[1] == "]")
            continue
        if after_type and kind == "op" and token[1] == "[":
            after_type = False
            skipping_size = True
            continue
        after_type = kind == "id" and token[1] in C_TYPES
        if kind == "id":
            if token[1] in C_TYPES and literal.dtype is None:
                literal.dtype = C_TYPES[token[1]]
            if token[1] in JS_TYPES:
                literal.dtype = JS_TYPES[token[1]]
            elif token[1] not in _SKIP_WORDS:
                literal_ok = False
            continue
        if kind == "num":
            if not opened:
                return None  # a scalar initializer
            literal.values.append(sign * token[1])
            literal.starts.append(token[2][0] if sign_at is None else sign_at)
            literal.ends.append(token[2][1])
            sign_at = None
            literal.hex = literal.hex or token[3]
            literal.suffix = literal.suffix or token[4]
            sign = 1.0
            if stack:
                stack[-1][0] += 1
            continue
        char = token[1]
        if char in _OPEN:
            depth += 1
            opened = True
            if stack:
                stack[-1][0] += 1
            stack.append([0, depth])
        elif char in _CLOSE:
            depth -= 1
            if depth < 0:
                return None
            count, level = stack.pop()
            leaf_shape.setdefault(level, set()).add(count)
            if depth == 0:
                break
        elif char == "-":
            sign = -sign
            sign_at = token[2] if sign_at is None else sign_at  # the rewrite replaces the sign with the number
        elif char == "+" or char == ",":
            pass
        elif char == ";" and depth == 0:
            return None
        else:
            literal_ok = False
        if not opened and depth == 0 and char not in "-+":
            return None
    if not literal_ok or not opened:
        return None
    # A regular nesting: every bracket at each level holds the same number of children; the outermost
    # constructor (e.g. new Float32Array([...]) or float[16](...)) may wrap one child.
    levels = sorted(leaf_shape)
    if all(len(leaf_shape[level]) == 1 for level in levels):
        dims = [next(iter(leaf_shape[level])) for level in levels]
        while len(dims) > 1 and dims[0] == 1:
            dims = dims[1:]
        if int(np.prod(dims)) == len(literal.values):
            literal.nested = tuple(dims)
    return literal
