"""BRDF Explorer ``.brdf`` files: reading them, and the model that evaluates their GLSL in float64.

Disney's BRDF Explorer (Burley 2012) stores an analytic lobe as a small text file; seed 003 prints one (its
Gaussian Blinn-Phong lobe, on a single line). The format, as BRDF Explorer reads it::

    analytic
    # a comment: from a word starting with '#' to the end of the line, outside the GLSL sections
    ::begin parameters
    float NAME MIN MAX DEFAULT     # uniform float in the shader; MIN/MAX are the UI slider's range
    bool NAME DEFAULT              # uniform bool, DEFAULT is 0 or 1
    color NAME R G B               # uniform vec3
    ::end parameters
    ::begin shader
    ... GLSL defining vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y), helpers and const globals ...
    ::end shader
    ::begin isFunc                 # optional importance-sampling code: kept, never required or compiled
    ...
    ::end isFunc

The reader works on whitespace-separated tokens, so the one-line form of seed 003 (every token on one line,
the shader starting mid-line) reads the same as the multi-line form; a parameter declaration must lie on one
line. A parameter name must be a GLSL identifier that is no keyword, reserved word, type name, built-in
function or ``BRDF`` (it becomes a uniform of the shader). Every problem is a
:class:`~brdfnorm.errors.BrdfFileError` at ``FILE:LINE:COL`` in the file's own numbering (1-based, columns in
characters). Parsing is a single linear scan, so megabytes of comments cost milliseconds; files over
:data:`MAX_BYTES` are refused unread, and the shader's own bounds are in :mod:`brdfnorm.glsl.limits`. The
shader text is handed to :func:`brdfnorm.glsl.compile_shader`, which compiles it to numpy operations;
nothing from the file is ever executed as Python (:mod:`brdfnorm.glsl.native` writes Python source for Numba
from the compiled program, of generated names and printed numbers only).
"""

from __future__ import annotations

import bisect
import os
import re
import warnings
from array import array
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .engine.machinery.directions import random_hemisphere, rotation_about_normal
from .errors import BrdfFileError, ModelNotFoundError
from .glsl.names import ENTRY_POINT, reserved_kind
from .inputs import parsing, read_bounded
from .models.base import Model, NativeKernel, Origin
from .parameters import Parameter

#: Refuse files larger than this before reading them whole (a .brdf is a few kilobytes; 16 MiB leaves room
#: for megabytes of comments while the reader's memory stays far below 1 GB).
MAX_BYTES = 16 * 1024 * 1024

#: Most parameters a file may declare (each is a slider in BRDF Explorer and a uniform of the shader; the
#: examples declare 1–8).
MAX_PARAMETERS = 256

SECTIONS = ("parameters", "shader", "isFunc")
#: Parameter kind -> (number of values after NAME, GLSL uniform type, what the values are).
KINDS = {
    "float": (3, "float", "MIN MAX DEFAULT"),
    "bool": (1, "bool", "DEFAULT (0 or 1)"),
    "color": (3, "vec3", "R G B"),
}
#: The fixed local frame BRDF(L, V, N, X, Y) is evaluated in (see brdfnorm.models.base).
FRAME_N = np.array([0.0, 0.0, 1.0])
FRAME_X = np.array([1.0, 0.0, 0.0])
FRAME_Y = np.array([0.0, 1.0, 0.0])

_TOKEN = re.compile(r"\S+")
_DIRECTIVE = re.compile(r"(?<!\S)::(?:begin|end)(?!\S)")
_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# A plain decimal number, as C's strtod reads BRDF Explorer's values (no nan/inf, no Python underscores).
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?\Z")
# Control characters other than tab/newline/vertical tab/form feed/carriage return: a binary file.
_BINARY = re.compile(r"[\x00-\x08\x0e-\x1f\x7f]")


@dataclass(frozen=True)
class SourceText:
    """The text of a GLSL section and where its first character lies in the file (1-based)."""

    text: str
    line: int
    column: int


@dataclass(frozen=True)
class BrdfFile:
    """A parsed ``.brdf`` file: declared parameters and the text of its sections."""

    path: str
    parameters: tuple[Parameter, ...]
    shader: SourceText
    is_func: SourceText | None = None
    #: The whole text as parsed (what a model sent to another process is rebuilt from).
    text: str = field(default="", repr=False)

    @property
    def uniforms(self) -> dict[str, str]:
        """Parameter name -> GLSL uniform type ("float", "bool" or "vec3")."""
        return {p.name: KINDS[p.kind][1] for p in self.parameters}


@dataclass(frozen=True)
class _Token:
    text: str
    start: int
    end: int


class _Scanner:
    """Tokens of the file in order, with comments skipped and offsets mapped to (line, column)."""

    def __init__(self, text: str, path: str) -> None:
        self.text = text
        self.path = path
        self.pos = 0
        # 8 bytes per line (a list of ints would take 36): a file of newlines stays small in memory.
        self._newlines = array("q", (m.start() for m in re.finditer("\n", text)))

    def where(self, offset: int) -> tuple[int, int]:
        index = bisect.bisect_left(self._newlines, offset)  # newlines strictly before offset
        line_start = self._newlines[index - 1] + 1 if index else 0
        return index + 1, offset - line_start + 1

    def line_of(self, offset: int) -> int:
        return bisect.bisect_left(self._newlines, offset) + 1

    def error(self, message: str, offset: int) -> BrdfFileError:
        return BrdfFileError(message, self.path, *self.where(offset))

    def next(self) -> _Token | None:
        while True:
            match = _TOKEN.search(self.text, self.pos)
            if match is None:
                self.pos = len(self.text)
                return None
            # '#' starts a comment running to the end of the line: whole comment lines, as BRDF Explorer's
            # files have, and also trailing notes after a parameter declaration.
            if match.group().startswith("#"):
                newline = self.text.find("\n", match.start())
                self.pos = len(self.text) if newline < 0 else newline + 1
                continue
            self.pos = match.end()
            return _Token(match.group(), match.start(), match.end())


def _refuse_binary(text: str, path: str) -> None:
    """Control characters other than whitespace (NUL first of all) mean a binary file: say where."""
    binary = _BINARY.search(text)
    if binary is not None:
        scanner = _Scanner(text[: binary.start() + 1], path)
        name = "NUL byte" if binary.group() == "\0" else f"control character U+{ord(binary.group()):04X}"
        raise scanner.error(f"{name}: this looks like binary data, not a .brdf text file", binary.start())


def _decode(data: bytes, path: str) -> str:
    """UTF-8 text, refusing invalid bytes at the line and column where they occur."""
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        _refuse_binary(data[: exc.start].decode("utf-8"), path)  # binary data before the bad byte says more
        line = data.count(b"\n", 0, exc.start) + 1
        line_start = data.rfind(b"\n", 0, exc.start) + 1
        column = len(data[line_start : exc.start].decode("utf-8", errors="replace")) + 1
        raise BrdfFileError(
            f"not UTF-8 text: invalid byte 0x{data[exc.start]:02x} (a .brdf file is UTF-8 text)",
            path,
            line,
            column,
        ) from None
    return text


def _read_bytes(path: str) -> bytes:
    """The file's bytes through :func:`brdfnorm.inputs.read_bounded`: regular files only (a FIFO would block, a
    device never ends), at most :data:`MAX_BYTES`, refused from ``stat`` before a byte is read."""
    if not os.path.lexists(path):
        raise ModelNotFoundError("no such file (and not a built-in model name)", where=path)
    try:
        return read_bounded(path, MAX_BYTES, error=BrdfFileError)
    except BrdfFileError as error:
        if error.message == "a directory, not a file":
            raise BrdfFileError("is a directory, not a .brdf file", path) from None
        raise BrdfFileError(f"{error.message}; not a .brdf file" if "allows" in error.message else error.message,
                            path) from None


def _number(scanner: _Scanner, token: _Token, what: str) -> float:
    if not _NUMBER.match(token.text):
        raise scanner.error(f"{what} must be a number, got {token.text!r}", token.start)
    value = float(token.text)
    if not np.isfinite(value):
        raise scanner.error(f"{what} must be finite, got {token.text!r}", token.start)
    return value


def _parse_parameter(scanner: _Scanner, kind: _Token, name: _Token, values: list[_Token]) -> Parameter:
    """One declaration ``KIND NAME VALUES...`` (values already counted)."""
    label = f"parameter {name.text!r}"
    if kind.text == "bool":
        if values[0].text not in ("0", "1"):
            raise scanner.error(f"bool {label}: DEFAULT must be 0 or 1, got {values[0].text!r}", values[0].start)
        return Parameter(name.text, "bool", values[0].text == "1", strict=False)
    if kind.text == "color":
        rgb = tuple(_number(scanner, v, f"color {label}: {c}") for v, c in zip(values, "RGB", strict=True))
        return Parameter(name.text, "color", rgb, strict=False)
    low, high, default = (
        _number(scanner, v, f"float {label}: {w}") for v, w in zip(values, ("MIN", "MAX", "DEFAULT"), strict=True)
    )
    if low > high:
        raise scanner.error(f"float {label}: MIN {low:g} is greater than MAX {high:g}", values[0].start)
    if not low <= default <= high:
        line, column = scanner.where(values[2].start)
        warnings.warn(
            f"{scanner.path}:{line}:{column}: float {label}: DEFAULT {default:g} outside the slider range "
            f"[{low:g}, {high:g}]",
            stacklevel=2,
        )
    return Parameter(name.text, "float", default, low, high, strict=False)


def _parse_parameters(scanner: _Scanner, begin: _Token) -> list[Parameter]:
    """The declarations up to ``::end parameters``; each lies on one line, several may share one."""
    parameters: list[Parameter] = []
    declared: dict[str, int] = {}  # name -> line
    previous: str | None = None  # name declared just before on the same line
    token = scanner.next()
    while True:
        if token is None:
            raise scanner.error("section 'parameters' is never closed (missing '::end parameters')", begin.start)
        if token.text == "::end":
            closing = scanner.next()
            if closing is None or closing.text != "parameters":
                got = "end of file" if closing is None else repr(closing.text)
                raise scanner.error(f"expected '::end parameters', got '::end' followed by {got}", token.start)
            return parameters
        if token.text == "::begin":
            raise scanner.error("missing '::end parameters' before this '::begin'", token.start)
        if token.text not in KINDS:
            if previous is not None:
                message = f"unexpected {token.text!r} after the declaration of {previous!r}"
            else:
                message = f"expected a parameter declaration (float, bool or color), got {token.text!r}"
            raise scanner.error(message, token.start)
        kind = token
        if len(parameters) == MAX_PARAMETERS:
            raise scanner.error(f"too many parameters: at most {MAX_PARAMETERS}", kind.start)
        count, _, shape = KINDS[kind.text]
        line = scanner.line_of(kind.start)
        fields: list[_Token] = []
        token = scanner.next()
        while token is not None and len(fields) < count + 1 and scanner.line_of(token.start) == line:
            if token.text in ("::end", "::begin"):
                break
            fields.append(token)
            token = scanner.next()
        if len(fields) < count + 1:
            raise scanner.error(
                f"malformed {kind.text} parameter: expected '{kind.text} NAME {shape}', "
                f"got {' '.join(t.text for t in [kind, *fields])[:80]!r}",
                kind.start,
            )
        name = fields[0]
        if not _IDENTIFIER.match(name.text):
            raise scanner.error(f"parameter name {name.text[:40]!r} is not a GLSL identifier", name.start)
        reserved = reserved_kind(name.text)
        if reserved is not None or name.text == ENTRY_POINT:
            what = reserved or "the shader's entry point BRDF"
            raise scanner.error(f"parameter name {name.text!r} is {what}: it cannot name a uniform", name.start)
        if name.text in declared:
            raise scanner.error(
                f"duplicate parameter {name.text!r} (first declared on line {declared[name.text]})",
                name.start,
            )
        parameters.append(_parse_parameter(scanner, kind, name, fields[1:]))
        declared[name.text] = line
        previous = name.text
        if token is not None and scanner.line_of(token.start) != line:
            previous = None


def _parse_code(scanner: _Scanner, begin: _Token, name: _Token) -> SourceText:
    """A GLSL section: the raw text up to its ``::end NAME`` (a '::' token is never GLSL)."""
    text = scanner.text
    start = name.end
    rest_of_line = text.find("\n", start)
    if rest_of_line >= 0 and not text[start:rest_of_line].strip():
        start = rest_of_line + 1  # multi-line form: the code starts on the next line, column 1
    directive = _DIRECTIVE.search(text, start)
    if directive is None:
        raise scanner.error(f"section {name.text!r} is never closed (missing '::end {name.text}')", begin.start)
    if directive.group() == "::begin":
        raise scanner.error(f"missing '::end {name.text}' before this '::begin'", directive.start())
    scanner.pos = directive.end()
    closing = scanner.next()
    if closing is None or closing.text != name.text:
        got = "end of file" if closing is None else repr(closing.text)
        raise scanner.error(f"expected '::end {name.text}', got '::end' followed by {got}", directive.start())
    line, column = scanner.where(start)
    return SourceText(text[start : directive.start()], line, column)


def parse_brdf(text: str, path: str = "<string>") -> BrdfFile:
    """Parse the text of a ``.brdf`` file (already decoded); see the module docstring for the format."""
    if text.startswith("\ufeff"):  # a byte-order mark some editors write; not part of the text
        text = text[1:]
    text = text.replace("\r\n", "\n")
    _refuse_binary(text, path)
    scanner = _Scanner(text, path)
    first = scanner.next()
    if first is None:
        raise BrdfFileError("empty file: expected 'analytic' and a shader section", path, 1, 1)
    if first.text != "analytic":
        raise scanner.error(
            f"not a BRDF Explorer analytic file: expected 'analytic' first, got {first.text[:40]!r}",
            first.start,
        )
    parameters: list[Parameter] = []
    sections: dict[str, SourceText | None] = {}
    opened: dict[str, int] = {}
    while (token := scanner.next()) is not None:
        if token.text != "::begin":
            if token.text == "::end":
                raise scanner.error("'::end' without a matching '::begin'", token.start)
            raise scanner.error(
                f"unexpected {token.text[:40]!r} outside a section (comments start with '#')", token.start
            )
        name = scanner.next()
        if name is None:
            raise scanner.error("'::begin' needs a section name (parameters, shader or isFunc)", token.start)
        if name.text not in SECTIONS:
            raise scanner.error(f"unknown section {name.text[:40]!r} (known: {', '.join(SECTIONS)})", name.start)
        if name.text in opened:
            raise scanner.error(
                f"duplicate section {name.text!r} (first opened on line {opened[name.text]})", token.start
            )
        opened[name.text] = scanner.line_of(token.start)
        if name.text == "parameters":
            parameters = _parse_parameters(scanner, token)
            sections["parameters"] = None
        else:
            sections[name.text] = _parse_code(scanner, token, name)
    shader = sections.get("shader")
    if shader is None:
        raise BrdfFileError(
            "no '::begin shader' section: nothing defines BRDF(L, V, N, X, Y)",
            path,
            *scanner.where(len(text)),
        )
    return BrdfFile(path, tuple(parameters), shader, sections.get("isFunc"), text)


def read_brdf(path: str | Path) -> BrdfFile:
    """Read and parse a ``.brdf`` file.

    Raises :class:`~brdfnorm.errors.ModelNotFoundError` for a missing file and
    :class:`~brdfnorm.errors.BrdfFileError` (with line and column) for anything wrong inside it.
    """
    path = str(path)
    data = _read_bytes(path)
    with parsing(path, error=BrdfFileError):  # whatever fails inside the parse is one error naming the file
        return parse_brdf(_decode(data, path), path)


class BrdfModel(Model):
    """A lobe read from a ``.brdf`` file: its GLSL ``BRDF`` compiled to float64 numpy operations.

    RGB (3 channels), anisotropic in general (``X`` and ``Y`` are available to the shader). The integrator
    estimates the lobe's peak itself; nothing about the shader is assumed.
    """

    channels = 3

    def __init__(self, brdf: BrdfFile, program: object, **values: object) -> None:
        self.name = Path(brdf.path).stem
        self.formula = f"GLSL BRDF(L, V, N, X, Y) from {brdf.path}"
        self.parameters = brdf.parameters
        self.brdf_file = brdf
        self.program = program
        super().__init__(**values)

    @property
    def source_path(self) -> str:
        """The ``.brdf`` file this model was read from."""
        return self.brdf_file.path

    def origin(self) -> Origin:
        """The file's display path and text (``brdfnorm.load_text`` compiles the same shader from them)."""
        return Origin(self.brdf_file.path, self.brdf_file.text)

    @property
    def has_is_func(self) -> bool:
        """Whether the file carries an ``isFunc`` (importance sampling) section."""
        return self.brdf_file.is_func is not None

    @property
    def isotropic(self) -> bool:
        """Whether f is unchanged by rotating L and V together about N, on a sample of pairs at the bound
        parameter values (then the albedo does not depend on φ, and ``normalize(at="max")`` searches θ only).

        Anisotropy in real lobes is of order one; the 1e-6 threshold only absorbs rounding in ill-conditioned
        shaders, and a lobe misjudged anisotropic merely costs a search over φ.
        """
        return rotation_asymmetry(self) <= 1e-6

    def native_kernel(self) -> NativeKernel | None:
        """The shader as one compiled scalar function (:mod:`brdfnorm.glsl.native`: generated from the same
        syntax tree, cached on disk per user), or None where that backend cannot express it or Numba is
        missing."""
        from .glsl.native import native_kernel

        return native_kernel(self.brdf_file)

    def evaluate(self, L, V, params):
        frame = [np.broadcast_to(axis, np.shape(L)) for axis in (FRAME_N, FRAME_X, FRAME_Y)]
        return self.evaluate_in_frame(L, V, *frame, params)

    def evaluate_in_frame(
        self,
        L: np.ndarray,
        V: np.ndarray,
        N: np.ndarray,
        X: np.ndarray,
        Y: np.ndarray,
        params: Mapping[str, object] | None = None,
    ) -> np.ndarray:
        """BRDF(L, V, N, X, Y) with an explicit frame (all (..., 3)) at ``params`` (default: the bound ones).

        :meth:`evaluate` is this with N = +z, X = +x, Y = +y; another frame serves, e.g., to check a shader's
        conditioning under perturbed frame vectors.
        """
        params = self._params if params is None else params
        shape = np.broadcast_shapes(*(np.shape(a)[:-1] for a in (L, V, N, X, Y)))
        uniforms: dict[str, object] = {}
        for p in self.parameters:
            value = params[p.name]
            if p.kind == "bool":
                uniforms[p.name] = bool(value)
                continue
            value = np.asarray(value, dtype=float)
            uniforms[p.name] = value
            shape = np.broadcast_shapes(shape, value.shape[:-1] if p.kind == "color" else value.shape)
        result = self.program.brdf(L, V, N, X, Y, uniforms)
        if result.shape == shape + (3,):
            return result  # a new C-contiguous float64 array of the program's: the caller owns it
        # A shader whose result does not depend on the directions (e.g. a constant) comes back smaller.
        # A writable array the caller owns (broadcast_to alone would give a read-only view).
        return np.require(np.broadcast_to(result, shape + (3,)), dtype=float, requirements=["C", "W"])


def load_brdf(path: str | Path, **params: object) -> BrdfModel:
    """Read a ``.brdf`` file, compile its shader, and bind parameter values (defaults for the others).

    Parameter values outside a file's slider range are accepted with a warning; a value of the wrong type
    raises :class:`~brdfnorm.errors.ParameterError`.
    """
    return compile_brdf(read_brdf(path), **params)


def compile_brdf(brdf: BrdfFile, **params: object) -> BrdfModel:
    """The model of a parsed file (:func:`parse_brdf` on a text sent elsewhere, or :func:`read_brdf`)."""
    from .glsl import compile_shader  # the GLSL toolchain (tree-sitter) loads only for a readable file

    with parsing(brdf.path, error=BrdfFileError):  # a RecursionError or MemoryError in the compiler names the file
        program = compile_shader(
            brdf.shader.text,
            path=brdf.path,
            first_line=brdf.shader.line,
            first_column=brdf.shader.column,
            uniforms=brdf.uniforms,
        )
    return BrdfModel(brdf, program, **params)


@dataclass(frozen=True)
class Reciprocity:
    """Result of :func:`reciprocity_check`: the largest relative asymmetry seen and where."""

    max_relative: float
    L: np.ndarray
    V: np.ndarray
    samples: int
    nonfinite: int
    tolerance: float

    @property
    def reciprocal(self) -> bool:
        return bool(self.max_relative <= self.tolerance)


def rotation_asymmetry(model: Model, samples: int = 512, seed: int = 1) -> float:
    """Largest relative change of f(L, V) when both directions rotate about N (0 for an isotropic lobe)."""
    rng = np.random.default_rng(seed)
    L = random_hemisphere(rng, samples)
    V = random_hemisphere(rng, samples)
    worst = 0.0
    with np.errstate(all="ignore"):
        reference = model.eval(L, V)
        for angle in (0.7, 2.1, 4.0):
            rotation = rotation_about_normal(angle)
            rotated = model.eval(L @ rotation.T, V @ rotation.T)
            scale = np.maximum(np.abs(reference), np.abs(rotated))
            change = np.where(scale > 0, np.abs(rotated - reference) / np.where(scale > 0, scale, 1.0), 0.0)
            both_nan = np.isnan(reference) & np.isnan(rotated)
            change = np.where(both_nan, 0.0, np.where(np.isfinite(change), change, np.inf))
            worst = max(worst, float(np.max(change, initial=0.0)))
    return worst


def reciprocity_check(model: Model, samples: int = 4096, seed: int = 0, tolerance: float = 1e-9) -> Reciprocity:
    """Helmholtz reciprocity f(L, V) = f(V, L) on random direction pairs (a sample, not a proof).

    The asymmetry of a pair is max over channels of |f(L,V) − f(V,L)| / max(|f(L,V)|, |f(V,L)|); pairs where
    either value is not finite are counted separately and skipped.
    """
    rng = np.random.default_rng(seed)
    L = random_hemisphere(rng, samples)
    V = random_hemisphere(rng, samples)
    with np.errstate(all="ignore"):
        forward = model.eval(L, V)
        backward = model.eval(V, L)
        finite = np.all(np.isfinite(forward) & np.isfinite(backward), axis=-1)
        scale = np.maximum(np.abs(forward), np.abs(backward))
        asymmetry = np.where(scale > 0, np.abs(forward - backward) / np.where(scale > 0, scale, 1.0), 0.0)
    asymmetry = np.where(finite, np.max(asymmetry, axis=-1), -1.0)
    worst = int(np.argmax(asymmetry))
    value = float(max(asymmetry[worst], 0.0)) if finite.any() else float("nan")
    return Reciprocity(value, L[worst], V[worst], samples, int(samples - finite.sum()), tolerance)
