"""Emit a fitted formula (:class:`brdfnorm.fit.FitResult`) as a self-contained GLSL, HLSL, C or Python function.

Issue 4, item 5: shader writers need the cheap formula in their language. The function is named after the model
(``brdfnorm_blinn_phong_gaussian_norm``), takes the fitted variable (and, for a two-variable fit, the second one,
e.g. ``cos_theta_o``), evaluates every polynomial in Horner form — one multiply-add per coefficient, which
compilers contract to FMAs — and prints the coefficients to 9 significant digits (enough to round-trip a float32,
and within ~1e-9 relative of the fit's double-precision coefficients). A comment states the form, the fitted
range, the metric, the maximum relative error on the samples and the operation count, and — in the user's terms
(:func:`fit_context`) — the lobe's formula, the convention of the factor and the parameters held fixed. Signs are
folded into the operator (``x - 47.95``, never ``x + -47.95``).

GLSL and HLSL use ``float``; C uses ``double`` (CPU tools; the tests run it against the Python evaluation);
Python uses only arithmetic and ``** 0.5`` so it works on floats and numpy arrays alike.

Names from outside (model names, file names, parameter names) are data: identifiers are rebuilt from ASCII
letters and digits and never a keyword, type or built-in of any target (:func:`identifier`), and text quoted in
comments is reduced to printable ASCII without quotes or backslashes (:func:`comment_text`), so no name can end
a comment or a docstring and add code (issue 14, class 1).
"""

from __future__ import annotations

import keyword
import re
import textwrap
from dataclasses import dataclass

import numpy as np

from ..registry import Registry
from .exact import ExactForm
from .families import HyperbolaForm, RationalForm, SmithForm
from .fitting import FitResult

#: Words no emitted identifier may be, in any target: the keywords and reserved words of C11/C23, GLSL 4.6 and
#: HLSL (types included — a parameter named ``vec3`` or ``float``), Python's keywords, the built-in functions
#: the emitted code calls, and the function's own locals (a parameter named ``u`` would collide with the local).
RESERVED = frozenset(keyword.kwlist) | frozenset("""
    auto break case char const continue default do double else enum extern float for goto if inline int long
    register restrict return short signed sizeof static struct switch typedef union unsigned void volatile while
    bool true false alignas alignof nullptr static_assert thread_local typeof constexpr main
    attribute uniform varying buffer shared coherent volatile restrict readonly writeonly layout centroid flat
    smooth noperspective patch sample subroutine in out inout invariant precise discard lowp mediump highp
    precision uint dvec2 dvec3 dvec4 vec2 vec3 vec4 bvec2 bvec3 bvec4 ivec2 ivec3 ivec4 uvec2 uvec3 uvec4 mat2
    mat3 mat4 mat2x2 mat2x3 mat2x4 mat3x2 mat3x3 mat3x4 mat4x2 mat4x3 mat4x4 dmat2 dmat3 dmat4 sampler2D
    common partition active asm class template this resource packed goto interface long input output hvec2
    hvec3 hvec4 fvec2 fvec3 fvec4 filter sizeof cast namespace using half min16float min10float min16int
    min12int min16uint float1 float2 float3 float4 float2x2 float3x3 float4x4 double2 double3 double4 int2 int3
    int4 uint2 uint3 uint4 bool2 bool3 bool4 matrix vector string technique pass cbuffer tbuffer groupshared
    nointerpolation linear centroid row_major column_major snorm unorm export extern register packoffset
    sqrt pow abs exp log sin cos tan fma max fmax maximum numpy d u v p q l
""".split())

#: Longest piece of outside text (a model name, a file name) quoted in a generated comment.
COMMENT_QUOTE_LIMIT = 60


@dataclass(frozen=True)
class Syntax:
    """How one target language spells the few constructs the emitted function uses."""

    scalar: str
    comment: str
    declare: str  # how a local is introduced: "float ", "double ", ""
    sqrt: str
    end: str  # statement terminator
    log: str = "log"
    max: str = "max"


#: Target languages (``emit(..., language=)``).
LANGUAGES: Registry[Syntax] = Registry("language", "language", {
    "glsl": Syntax("float", "//", "float ", "sqrt", ";"),
    "hlsl": Syntax("float", "//", "float ", "sqrt", ";"),
    "c": Syntax("double", "//", "double ", "sqrt", ";", max="fmax"),
    "python": Syntax("", "#", "", "", "", max="maximum"),
})


def identifier(text: str) -> str:
    """A C/GLSL/HLSL/Python identifier from a model or parameter name.

    Runs of anything but ASCII letters and digits become one ``_`` (GLSL reserves names with ``__`` and the
    prefix ``gl_``); a leading digit gets a ``_`` before it; a :data:`RESERVED` word gets one after it.
    """
    name = re.sub(r"[^0-9A-Za-z]+", "_", str(text)).strip("_").lower()[:64].strip("_") or "x"
    if name[0].isdigit():
        name = "_" + name
    if name.startswith("gl_"):
        name = "v" + name
    return name + "_" if name in RESERVED else name


def function_name(model_name: str) -> str:
    """``blinn-phong-gaussian`` → ``brdfnorm_blinn_phong_gaussian_norm``."""
    return f"brdfnorm_{identifier(model_name).strip('_')}_norm"


#: Mathematical characters of formulas and names spelled in ASCII for comments (``N·H`` → ``N.H``).
ASCII_SPELLING = str.maketrans({
    "·": ".", "−": "-", "–": "-", "—": "-", "×": "*", "²": "^2", "³": "^3", "⁴": "^4", "⁵": "^5", "½": "1/2",
    "√": "sqrt", "π": "pi", "α": "alpha", "θ": "theta", "φ": "phi", "μ": "mu", "η": "eta", "ρ": "rho",
    "σ": "sigma", "∫": "integral ", "≈": "~", "≤": "<=", "≥": ">=", "∞": "inf", "₀": "0", "₁": "1", "₂": "2",
    "Λ": "Lambda", "λ": "lambda", "ψ": "psi", "ω": "omega", "Ω": "Omega", "∘": "o", "±": "+-", "′": "'",
})


def comment_text(text: object, limit: int = COMMENT_QUOTE_LIMIT) -> str:
    """Outside text made safe inside any generated comment or docstring: printable ASCII only (mathematical
    characters spelled out, :data:`ASCII_SPELLING`), without backslashes (a C line continuation), ``?`` (C's
    trigraph ``??/`` is a backslash) or quotes (a Python docstring's end), cut to ``limit`` characters;
    everything else becomes ``_``."""
    text = str(text).translate(ASCII_SPELLING)
    cut = text[:limit]
    safe = "".join(c if (" " <= c <= "~" and c not in "\\\"'`?") else "_" for c in cut)
    return safe + ("..." if len(text) > limit else "")


def literal(value: float, language: str) -> str:
    """A float literal to 9 significant digits that every target parses as floating point."""
    text = f"{float(value):.9g}"
    if "e" not in text and "." not in text and "inf" not in text and "nan" not in text:
        text += ".0"
    if "e" in text and "." not in text.split("e")[0]:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}.0e{exponent}"
    return text


def _plus(expr: str, term: str) -> str:
    """``expr + term`` with a negative literal's sign folded into the operator: ``x - 47.95``, not ``x + -47.95``."""
    return f"{expr} - {term[1:]}" if term.startswith("-") else f"{expr} + {term}"


def _minus(expr: str, term: str) -> str:
    """``expr - term`` with a negative literal folded: ``x + 1.5``, not ``x - -1.5``."""
    return f"{expr} + {term[1:]}" if term.startswith("-") else f"{expr} - {term}"


#: What a normalization factor's convention means, in the words of a comment (``at`` of brdfnorm.normalize).
CONVENTIONS = {
    "normal": "1/E with E = integral of f(L, V) (N.L) dL at V = N (normal view)",
    "max": "1/E with E the largest albedo over all view directions",
    "view": "1/E(V) at each view direction, E(V) = integral of f(L, V) (N.L) dL",
}


def fit_context(model, swept: str, at: str | None = "normal", over: str = "light") -> list[str]:
    """Comment lines that say what the function's number means: the lobe's formula, the convention of the
    factor (``at``; None for a table's values), and every parameter held at its bound value while ``swept``
    varied (the explorer's fit of a GGX holds f0 = 0.04, and the code must say so)."""
    formula = re.sub(r"\s*\((?:seed|Eq)[^)]*\)", "", getattr(model, "formula", "") or model.name)
    # a .brdf file by its name, not by the user's path
    formula = re.sub(r"(?<!\S)(?:[A-Za-z]:)?[/\\](?:[\w.-]+[/\\])+", "", formula)
    lines = textwrap.wrap(f"Lobe: {comment_text(formula, limit=400)}.", width=100, break_long_words=False)
    if at is not None:
        convention = CONVENTIONS.get(at, comment_text(at))
        if over == "view":
            convention = convention.replace("f(L, V) (N.L) dL", "f(L, V) (N.V) dV").replace("at V = N", "at L = N")
        lines.append(f"Convention: {convention}.")
    held = []
    for name, value in sorted(getattr(model, "params", {}).items()):
        if name == swept:
            continue
        if isinstance(value, str):
            shown = value
        else:
            values = [float(v) for v in np.ravel(value)]
            shown = ",".join(f"{v:.6g}" for v in (values[:1] if len(set(values)) == 1 else values))
        held.append(f"{comment_text(name)} = {comment_text(shown)}")
    if held:
        lines += textwrap.wrap(f"Held fixed: {', '.join(held)}.", width=100, break_long_words=False,
                               break_on_hyphens=False)
    return lines


def _horner(coefficients: list[str], var: str) -> str:
    """Σ c_i var^i as ((c_k·var + c_{k−1})·var + …)·var + c_0: one multiply-add per step."""
    expr = coefficients[-1]
    for i in range(len(coefficients) - 2, -1, -1):
        expr = _plus(f"{expr} * {var}", coefficients[i])
        if i:
            expr = f"({expr})"
    return expr


def _body(result: FitResult, language: str, x: str, t: str) -> list[str]:
    form = result.form_object
    syn = LANGUAGES[language]
    lit = [literal(c, language) for c in result.coefficients]
    sqrt = (lambda e: f"({e}) ** 0.5") if language == "python" else (lambda e: f"{syn.sqrt}({e})")
    lines: list[str] = []
    if isinstance(form, HyperbolaForm):
        a, s, x0, b = result.coefficients
        b2 = literal(b * b, language)
        lines.append(f"{syn.declare}d = {_minus(x, literal(x0, language))}{syn.end}")
        lines.append(f"return {_plus(lit[0], lit[1] + ' * ' + sqrt(f'd * d + {b2}'))}{syn.end}")
        return lines
    if isinstance(form, SmithForm):
        return _smith_body(form, result, language, x, t)
    if isinstance(form, ExactForm):
        power = (lambda b, e: f"{b} ** ({e})") if language == "python" else (lambda b, e: f"pow({b}, {e})")
        return [f"return {form.code(x, lambda v: literal(v, language), power)}{syn.end}"]
    assert isinstance(form, RationalForm)
    u = x
    if form.sqrt:
        lines.append(f"{syn.declare}u = {sqrt(x)}{syn.end}")
        u = "u"
    v = t
    if form.two_d and form.tau:
        lines.append(f"{syn.declare}v = {t} * {u}{syn.end}")
        v = "v"
    k = form.D + 1
    rows_num = [lit[i * k:(i + 1) * k] for i in range(form.P + 1)]
    polys = [("p", rows_num)]
    if form.has_denominator:
        rest = ["1.0"] + lit[(form.P + 1) * k:]
        polys.append(("q", [rest[j * k:(j + 1) * k] for j in range(form.Q + 1)]))
    for name, rows in polys:
        if form.D:
            terms = [f"({_horner(row, v)})" for row in rows]
        else:
            terms = [row[0] for row in rows]
        lines.append(f"{syn.declare}{name} = {_horner(terms, u) if len(terms) > 1 else terms[0]}{syn.end}")
    lines.append(f"return p / q{syn.end}" if form.has_denominator else f"return p{syn.end}")
    return lines


def _smith_body(form: SmithForm, result: FitResult, language: str, mu: str, alpha: str) -> list[str]:
    """E = 1 − u·(N + l·L)/Q with u = μ/√(μ² + α²(1 − μ²)), v = α², l = ln u (:class:`SmithForm`).

    The guards keep μ = 0 exact: u = 0 there (also when α = 0), ln is taken of max(u, 1e-30) — a float32
    normal — and u·(…) vanishes, so E = 1 as the lobe's own limit says.
    """
    syn = LANGUAGES[language]
    lit = [literal(c, language) for c in result.coefficients]
    k = form.D + 1
    sqrt = (lambda e: f"({e}) ** 0.5") if language == "python" else (lambda e: f"{syn.sqrt}({e})")
    lines = ["from numpy import log, maximum  # arrays and floats alike"] if language == "python" else []
    tiny = literal(1e-30, language)
    lines += [
        f"{syn.declare}v = {alpha} * {alpha}{syn.end}",
        f"{syn.declare}u = {mu} / {syn.max}({sqrt(f'{mu} * {mu} + v * (1.0 - {mu} * {mu})')}, {tiny}){syn.end}",
        f"{syn.declare}l = {syn.log}({syn.max}(u, {tiny})){syn.end}",
    ]
    n = (form.P + 1) * k
    numerator = [f"({_horner(lit[i * k:(i + 1) * k], 'v')})" for i in range(form.P + 1)]
    log_row = f"({_horner(lit[n:n + k], 'v')})"
    den = ["1.0"] + lit[n + k:]
    kq = form.dq + 1
    denominator = [f"({_horner(den[j * kq:(j + 1) * kq], 'v')})" for j in range(form.Q + 1)]
    top = _horner(numerator, "u") if len(numerator) > 1 else numerator[0]
    bottom = _horner(denominator, "u") if len(denominator) > 1 else denominator[0]
    lines.append(f"{syn.declare}p = {top} + l * {log_row}{syn.end}")  # parenthesised rows: no sign to fold
    lines.append(f"{syn.declare}q = {bottom}{syn.end}")
    lines.append(f"return 1.0 - u * p / q{syn.end}")
    return lines


def emit(result: FitResult, language: str, model_name: str, *, variable: str | None = None,
         second: str = "cos_theta_o", quantity: str = "Normalization factor", suffix: str = "norm",
         context: list[str] | tuple[str, ...] = ()) -> str:
    """Source text of one self-contained function evaluating ``result`` in ``language`` (``quantity`` names
    what was fitted in the comment, ``suffix`` ends the function's name, ``context`` adds comment lines after
    the first: :func:`fit_context`'s lobe, convention and held parameters)."""
    from ..version import __version__

    syn = LANGUAGES[LANGUAGES.validate(language)]
    x = identifier(variable or result.variables[0])
    t = identifier(second)
    if x == t:
        t = t + "_2"
    two_d = result.form_object.two_d
    name = function_name(model_name).removesuffix("_norm") + f"_{identifier(suffix)}"
    ops = ", ".join(f"{n} {c}" for n, c in result.operations.items() if c)
    ranges = "; ".join(f"{comment_text(k)} in [{lo:.9g}, {hi:.9g}]" for k, (lo, hi) in result.range.items())
    where = ", ".join(f"{comment_text(k)} = {v:.6g}" for k, v in result.argmax.items())
    how = (f"the exact closed form, checked against quadrature at {result.samples} samples."
           if result.form == "closed-form" else f"{result.form} fit ({result.metric}) over {result.samples} samples.")
    comment = [
        f"{comment_text(quantity)} of {comment_text(model_name)}: {how}",
        f"Fitted over {ranges}.",
        *context,
        f"Max relative error {result.max_rel_error:.3g} (at {where}); max absolute error "
        f"{result.max_abs_error:.3g}.",
        f"Operations: {ops or 'none'}. Generated by brdfnorm {__version__} (brdfnorm fit).",
    ]
    if two_d:
        second_line = f"Second argument {t}: the fit's variable {comment_text(result.variables[1])}."
        comment.insert(2 + len(context), second_line)
    body = _body(result, language, x, t)
    if language == "python":
        args = f"{x}, {t}" if two_d else x
        lines = [f"def {name}({args}):", f'    """{comment[0]}', *(f"    {c}" for c in comment[1:]), '    """']
        lines += [f"    {line}" for line in body]
        return "\n".join(lines) + "\n"
    args = f"{syn.scalar} {x}, {syn.scalar} {t}" if two_d else f"{syn.scalar} {x}"
    lines = [f"{syn.comment} {c}" for c in comment]
    lines.append(f"{syn.scalar} {name}({args})")
    lines.append("{")
    lines += [f"    {line}" for line in body]
    lines.append("}")
    if language == "c":
        lines.insert(0, "#include <math.h>\n")
    return "\n".join(lines) + "\n"

