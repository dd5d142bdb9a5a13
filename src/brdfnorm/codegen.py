"""Emit a fitted formula (:class:`brdfnorm.fit.FitResult`) as a self-contained GLSL, HLSL, C or Python function.

Issue 4, item 5: shader writers need the cheap formula in their language. The function is named after the model
(``brdfnorm_blinn_phong_gaussian_norm``), takes the fitted variable (and, for a two-variable fit, the second one,
e.g. ``cos_theta_o``), evaluates every polynomial in Horner form — one multiply-add per coefficient, which
compilers contract to FMAs — and prints the coefficients to 9 significant digits (enough to round-trip a float32,
and within ~1e-9 relative of the fit's double-precision coefficients). A comment states the form, the fitted
range, the metric, the maximum relative error on the samples and the operation count.

GLSL and HLSL use ``float``; C uses ``double`` (CPU tools; the tests run it against the Python evaluation);
Python uses only arithmetic and ``** 0.5`` so it works on floats and numpy arrays alike.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from .errors import ArgumentError
from .fit import FitResult, HyperbolaForm, RationalForm

LANGUAGES = ("glsl", "hlsl", "c", "python")


@dataclass(frozen=True)
class _Syntax:
    scalar: str
    comment: str
    declare: str  # how a local is introduced: "float ", "double ", ""
    sqrt: str
    end: str  # statement terminator


_SYNTAX = {
    "glsl": _Syntax("float", "//", "float ", "sqrt", ";"),
    "hlsl": _Syntax("float", "//", "float ", "sqrt", ";"),
    "c": _Syntax("double", "//", "double ", "sqrt", ";"),
    "python": _Syntax("", "#", "", "", ""),
}


def identifier(text: str) -> str:
    """A C/GLSL/Python identifier from a model or parameter name: non-alphanumerics to ``_``."""
    name = re.sub(r"[^0-9A-Za-z_]+", "_", text).strip("_").lower() or "x"
    return "_" + name if name[0].isdigit() else name


def function_name(model_name: str) -> str:
    """``blinn-phong-gaussian`` → ``brdfnorm_blinn_phong_gaussian_norm``."""
    return f"brdfnorm_{identifier(model_name)}_norm"


def literal(value: float, language: str) -> str:
    """A float literal to 9 significant digits that every target parses as floating point."""
    text = f"{float(value):.9g}"
    if "e" not in text and "." not in text and "inf" not in text and "nan" not in text:
        text += ".0"
    if "e" in text and "." not in text.split("e")[0]:
        mantissa, exponent = text.split("e")
        text = f"{mantissa}.0e{exponent}"
    return text


def _horner(coefficients: list[str], var: str) -> str:
    """Σ c_i var^i as ((c_k·var + c_{k−1})·var + …)·var + c_0: one multiply-add per step."""
    expr = coefficients[-1]
    for i in range(len(coefficients) - 2, -1, -1):
        expr = f"{expr} * {var} + {coefficients[i]}"
        if i:
            expr = f"({expr})"
    return expr


def _body(result: FitResult, language: str, x: str, t: str) -> list[str]:
    form = result.form_object
    syn = _SYNTAX[language]
    lit = [literal(c, language) for c in result.coefficients]
    sqrt = (lambda e: f"({e}) ** 0.5") if language == "python" else (lambda e: f"{syn.sqrt}({e})")
    lines: list[str] = []
    if isinstance(form, HyperbolaForm):
        a, s, x0, b = result.coefficients
        b2 = literal(b * b, language)
        lines.append(f"{syn.declare}d = {x} - {literal(x0, language)}{syn.end}")
        lines.append(f"return {lit[0]} + {lit[1]} * {sqrt(f'd * d + {b2}')}{syn.end}")
        return lines
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


def emit(result: FitResult, language: str, model_name: str, *, variable: str | None = None,
         second: str = "cos_theta_o", quantity: str = "Normalization factor", suffix: str = "norm") -> str:
    """Source text of one self-contained function evaluating ``result`` in ``language`` (``quantity`` names
    what was fitted in the comment, ``suffix`` ends the function's name)."""
    if language not in LANGUAGES:
        raise ArgumentError(f"unknown language {language!r} (known: {', '.join(LANGUAGES)})", where="--emit")
    syn = _SYNTAX[language]
    x = identifier(variable or result.variables[0])
    t = identifier(second)
    if x == t:
        t = t + "_2"
    two_d = result.form_object.two_d
    name = function_name(model_name).removesuffix("_norm") + f"_{identifier(suffix)}"
    ops = ", ".join(f"{n} {c}" for n, c in result.operations.items() if c)
    ranges = "; ".join(f"{k} in [{lo:.9g}, {hi:.9g}]" for k, (lo, hi) in result.range.items())
    where = ", ".join(f"{k} = {v:.6g}" for k, v in result.argmax.items())
    comment = [
        f"{quantity} of {model_name}: {result.form} fit ({result.metric}) over {result.samples} samples,",
        f"{ranges}.",
        f"Max relative error {result.max_rel_error:.3g} (at {where}); max absolute error "
        f"{result.max_abs_error:.3g}.",
        f"Operations: {ops or 'none'}. Generated by brdfnorm fit.",
    ]
    if two_d:
        comment.insert(2, f"Second argument {t}: the fit's variable {result.variables[1]}.")
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

