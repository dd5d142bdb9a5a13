"""Array literals in source text: C/C++ headers, GLSL/HLSL and JavaScript, read by one linear scanner.

What engines ship their tables as: ``static const float t[64][64] = {{...}}``, ``const float2 t[256] = {
float2(a, b), ...}``, ``float[16](...)``, ``const T = [...]``, ``new Float32Array([...])``,
``new Uint16Array([0x30b5, ...])``. The scanner walks the text once, character by character (comments and strings
skipped, no backtracking regular expression over the text), and collects every initializer that is a literal:
numbers (decimal, exponent, hex, with C/GLSL suffixes ``f``, ``u``, ``h``, ``l``), unary signs, brackets, commas
and constructor names (``float2``, ``vec4``, ``new``, ``Float32Array``). An initializer with any other
expression (an operator, a variable) is not a table and is skipped. Every number keeps its span in the text, so
that :mod:`.fix` can write exact values back in place.

Bounded before scanning (issue 41): a vectorized pass over the bytes counts the numbers and the other tokens;
more than :data:`~.limits.MAX_LITERAL_NUMBERS` numbers, or :data:`MAX_TOKENS` tokens, is refused before a list is
built. The scanner matches runs (spaces, names, numbers) with anchored regular expressions, one match per token.
An empty element (``{1,,2}``, ``{,1}``) is refused naming its line; a trailing comma is C's and allowed. A C
declaration's size may be an expression of integer factors (``g_dfg[32 * 32 * 2]``): the factors are its shape.
"""

from __future__ import annotations

import re
from array import array
from dataclasses import dataclass, field

import numpy as np

from ..errors import TableFileError
from .guard import element_count, shorten
from .limits import MAX_LITERAL_NUMBERS

#: Tokens of one file (numbers, names, punctuation): a table's numbers, their commas, and room for the code.
MAX_TOKENS = 2 * MAX_LITERAL_NUMBERS + 1024 * 1024
#: Dimensions of a regular nesting kept as a shape (numpy's own limit is 64).
MAX_NESTING = 32

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
    problem: str = ""  # why an initializer of numbers is not a table (its first token that is not a number)
    line: int = 0  # the declaration's line


_SPACE = re.compile(r"[ \t\r\n\f\v]+")
_IDENT = re.compile(r"[\w$]+")  # from a letter, "_" or "$" (the scanner checks the first character)
_HEX = re.compile(r"0[xX]([0-9a-fA-F]*)")
_DECIMAL = re.compile(r"[0-9]*(?:\.[0-9]*)?(?:[eE][-+]?[0-9]+)?")
_SUFFIX = re.compile(r"[fFhHuUlL]*")
_STRINGS = {q: re.compile(q + r"(?:[^" + q + r"\\]|\\.)*" + q + "?", re.S) for q in "\"'`"}


def _is_ident(c: str) -> bool:
    return c.isalnum() or c == "_" or c == "$"


def count_tokens(text: str) -> tuple[int, int]:
    """(numbers, tokens) of ``text``, upper bounds counted by vectorized byte comparisons (no Python loop): a
    number starts at a digit not preceded by a digit, a dot, a name's character or an exponent's sign, or at a
    dot followed by a digit; a token is a number, a name or one punctuation character."""
    b = np.frombuffer(text.encode("utf-8", "replace"), dtype=np.uint8)
    if b.size == 0:
        return 0, 0
    digit = (b >= 48) & (b <= 57)
    letter = ((b | 32) >= 97) & ((b | 32) <= 122) | (b == 95) | (b == 36) | (b >= 128)
    dot = b == 46
    before = np.zeros_like(digit)  # the previous byte continues a number or a name
    before[1:] = (digit | letter | dot)[:-1]
    exponent_sign = np.zeros_like(digit)  # '5' of '1e-5'
    exponent_sign[2:] = ((b[1:-1] == 43) | (b[1:-1] == 45)) & ((b[:-2] | 32) == 101)
    after_digit = np.zeros_like(digit)
    after_digit[:-1] = digit[1:]
    numbers = int(np.count_nonzero(digit & ~before & ~exponent_sign)
                  + np.count_nonzero(dot & after_digit & ~before))
    names = int(np.count_nonzero(letter & ~before))
    space = (b == 32) | ((b >= 9) & (b <= 13))
    punctuation = int(np.count_nonzero(~(digit | letter | dot | space)))
    return numbers, numbers + names + punctuation


class Scanner:
    """Tokens of C-like text: ('id', text, start), ('num', value, (start, end), hex, suffix), ('op', char, at);
    comments, strings and preprocessor lines skipped."""

    def __init__(self, text: str, where: str) -> None:
        self.text = text
        self.where = where
        self.i = 0
        self.numbers = 0

    def line(self, offset: int) -> int:
        return self.text.count("\n", 0, offset) + 1

    def tokens(self):
        text, n = self.text, len(self.text)
        while self.i < n:
            c = text[self.i]
            if c in " \t\r\n\f\v":
                self.i = _SPACE.match(text, self.i).end()
            elif c == "/" and text.startswith("//", self.i) or c == "#":  # a line comment, a preprocessor line
                end = text.find("\n", self.i)
                self.i = n if end < 0 else end + 1
            elif c == "/" and text.startswith("/*", self.i):
                end = text.find("*/", self.i + 2)
                self.i = n if end < 0 else end + 2
            elif c in _STRINGS:
                self.i = _STRINGS[c].match(text, self.i).end()
            elif c.isalpha() or c == "_" or c == "$":
                start = self.i
                self.i = _IDENT.match(text, start).end()
                yield ("id", text[start:self.i], start)
            elif c.isdigit() or (c == "." and self.i + 1 < n and text[self.i + 1].isdigit()):
                yield self._number()
            else:
                self.i += 1
                yield ("op", c, self.i - 1)

    def _number(self):
        text, n, start = self.text, len(self.text), self.i
        self.numbers += 1
        if self.numbers > MAX_LITERAL_NUMBERS:
            raise TableFileError(f"more than {MAX_LITERAL_NUMBERS} numbers", self.where)
        hexadecimal = _HEX.match(text, start)
        if hexadecimal is not None:
            digits, end = hexadecimal.group(1), hexadecimal.end()
            if not digits or len(digits) > 16:
                raise TableFileError(f"malformed hex number at offset {start}", self.where, self.line(start))
            value, is_hex = float(int(digits, 16)), True
        else:
            end = _DECIMAL.match(text, start).end()
            value, is_hex = float(text[start:end]), False
        number_end = end
        end = _SUFFIX.match(text, end).end()
        if end < n and _is_ident(text[end]):
            raise TableFileError(f"malformed number {shorten(text[start:end + 1][:30])!r} at offset {start}",
                                 self.where, self.line(start))
        suffix = text[number_end:end]
        self.i = end
        return ("num", value, (start, number_end), is_hex, suffix)


def find_literals(text: str, where: str) -> list[Literal]:
    """Every array initializer of ``text`` that holds numbers (see the module docstring), in order; one that
    holds anything else too (a name, an operator) comes with its ``problem`` said."""
    numbers, tokens = count_tokens(text)
    if numbers > MAX_LITERAL_NUMBERS:
        raise TableFileError(f"about {numbers} numbers, more than the {MAX_LITERAL_NUMBERS} a source file may hold",
                             where)
    if tokens > MAX_TOKENS:
        raise TableFileError(f"about {tokens} tokens, more than the {MAX_TOKENS} a source file of tables may hold",
                             where)
    scanner = Scanner(text, where)
    found: list[Literal] = []
    recent: list[tuple] = []  # tokens since the last ';' (the declaration before an '=')
    tokens = scanner.tokens()
    for token in tokens:
        if token[0] == "op" and token[1] == ";":
            recent = []
            continue
        if token[0] == "op" and token[1] == "=" and recent and not (recent[-1][0] == "op" and recent[-1][1] in "=!<>"):
            literal = _initializer(tokens, recent, scanner)
            if literal is not None and literal.values:
                found.append(literal)
            recent = []
            continue
        recent.append(token)
        if len(recent) > 64:  # a declaration is short; keep the window bounded
            recent = recent[-64:]
    return found


def _size(tokens: list[tuple]) -> list[int] | None:
    """The dimensions one ``[...]`` of a declaration gives: ``[64]`` -> [64], ``[32 * 32 * 2]`` -> [32, 32, 2]
    (a product of integers is read as a shape); None for any other expression (the shape comes from --shape)."""
    if len(tokens) % 2 == 0:
        return None
    factors = tokens[0::2]
    if any(t[0] != "num" or not float(t[1]).is_integer() for t in factors) or any(
            t[:2] != ("op", "*") for t in tokens[1::2]):
        return None
    return [int(t[1]) for t in factors]


def _declaration(recent: list[tuple], where: str) -> tuple[str, str | None, tuple[int, ...], int]:
    """Name, element type and C dimensions of the declaration ``recent`` (tokens before '=')."""
    name, dtype, dims = "", None, []
    start = recent[0][2] if recent[0][0] != "num" else recent[0][2][0]
    k = len(recent) - 1
    unknown = False  # a dimension given by another expression (C++'s [COMP+1]): the shape comes from --shape
    while k >= 0 and recent[k][0] == "op" and recent[k][1] == "]":  # trailing [a][b]
        opening = k - 1
        while opening >= 0 and not (recent[opening][0] == "op" and recent[opening][1] in "[]"):
            opening -= 1
        if opening < 0 or recent[opening][1] != "[":
            break
        size = _size(recent[opening + 1:k])
        if size is None:
            unknown = unknown or opening < k - 1  # '[]' (an open size) is no expression
        else:
            dims[:0] = size
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
    shape = tuple(dims)
    if shape:
        element_count(shape, MAX_LITERAL_NUMBERS, where=where,
                      what=f"the declared shape of {shorten(name) or 'an array'}")
    return name, dtype, shape, start


def _initializer(tokens, recent: list[tuple], scanner: Scanner) -> Literal | None:
    """Read the initializer after '=': a Literal if it is made of numbers and brackets only, else None (and the
    scan resumes after it)."""
    where = scanner.where
    name, dtype, declared, start = _declaration(recent, where)
    literal = Literal(name=name, dtype=dtype, declared=declared, start=start)
    depth = 0
    sign = 1.0
    sign_at: int | None = None
    literal_ok = True
    # the nesting: counts of children per open bracket, to find a regular shape
    stack: list[list[int]] = []
    recent_open = False
    leaf_shape: dict[int, set[int]] = {}
    opened = False
    after_type = False  # GLSL's float[16](...): the brackets after a type name are its size, not data
    skipping_size = False
    element = False  # an element since the last '(', '[', '{' or ','
    problem = ""
    for token in tokens:
        kind = token[0]
        if kind != "op" or token[1] not in ",-+":
            element = element or kind != "op" or token[1] in _CLOSE
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
                problem = problem or _not_a_number(literal, token[1], scanner.line(token[2]))
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
            element, recent_open = False, True
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
        elif char == ",":
            if not element and literal_ok and opened:  # '{1,,2}' or '{,1}': a hole in the table
                raise TableFileError(f"{shorten(name) or 'an array'}: an empty element (',' after "
                                     f"{'a bracket' if recent_open else 'a comma'})", where, scanner.line(token[2]))
            element = False
            recent_open = False
        elif char == "+":
            pass
        elif char == ";" and depth == 0:
            return None
        else:
            literal_ok = False
            problem = problem or _not_a_number(literal, char, scanner.line(token[2]))
        if not opened and depth == 0 and char not in "-+":
            return None
    if not opened:
        return None
    literal.line = scanner.line(start)
    if not literal_ok:
        literal.problem = problem
        return literal
    # A regular nesting: every bracket at each level holds the same number of children; the outermost
    # constructor (e.g. new Float32Array([...]) or float[16](...)) may wrap one child.
    levels = sorted(leaf_shape)
    if all(len(leaf_shape[level]) == 1 for level in levels):
        dims = [next(iter(leaf_shape[level])) for level in levels]
        first = 0  # leading dimensions of 1 (wrappers) skipped by an index, not by copying the list
        while first < len(dims) - 1 and dims[first] == 1:
            first += 1
        dims = dims[first:]
        if len(dims) <= MAX_NESTING and int(np.prod(dims, dtype=object)) == len(literal.values):
            literal.nested = tuple(dims)
    return literal


def _not_a_number(literal: Literal, text: str, line: int) -> str:
    return f"element {len(literal.values)} (line {line}): {shorten(repr(text))} is not a number"
