"""Cheap closed formulas fitted to sampled normalization factors, with their error known.

Seed 003 integrated the Gaussian Blinn-Phong normalization numerically and fitted α(n) ≈ 0.17287429 +
0.01388682·n over n ∈ [1, 512] by ordinary least squares ("not accurate for small specular power values"); its
commenter suggested a scaled, shifted hyperbola √(x² + 1). Seed 002 leaves the view-dependent Blinn-Phong
normalization open. This module fits such formulas to samples (x, y) or, in two variables, (x, t, y) — it does
not care how the samples were computed (:mod:`brdfnorm.normalization` in the command line).

Forms (:data:`FORMS`, selected by name as colour-science selects a ``method=``)
--------------------------------------------------------------------------------
* ``linear``            y = c0 + c1·x (seed 003's form).
* ``hyperbola``         y = a + c·√((x − x0)² + b²), coefficients (a, c, x0, b), b ≥ 0: the commenter's scaled,
                        shifted √(x² + 1); its asymptotes are the lines a ± c·(x − x0).
* ``poly:D``            y = Σ_{i≤D} p_i x^i.
* ``rational:P/Q``      y = (Σ_{i≤P} p_i x^i) / (1 + Σ_{1≤j≤Q} q_j x^j).
* ``rational-sqrt:P/Q`` the same in u = √x (suited to lobes whose width goes like 1/√n).
* In two variables (x, t) — e.g. (n, cos θ_o) for a view-dependent factor — every coefficient of a poly or
  rational form becomes a polynomial of degree D in t: ``rational-sqrt:P/Q@D``; the constant term of the
  denominator's t-polynomial for u⁰ is fixed to 1. Optionally (``rational-sqrt:P/Q@D~tau``) the second
  variable is τ = t·u instead of t. Why τ: for a narrow lobe (Blinn-Phong, large n) write the half vector
  h ≈ N + h⊥ with |h⊥| ~ 1/√n; then N·L ≈ cos θ_o + 2h_x sin θ_o and dω_L = 4(h·V) dω_h, so the albedo is
  E ≈ (8π/n²)·G(τ, …) with τ = cos θ_o·√n: E ≈ 8π cos²θ_o/n while τ ≫ 1 and E ≈ 8π/n² as τ → 0 (the
  lobe cut by the horizon). α = 1/E is then nearly a rational in (√n, τ), and the fit needs far fewer
  coefficients than in (√n, cos θ_o): over n ∈ [1, 10⁴], θ_o ∈ [0°, 89°], ``rational-sqrt:5/2@4~tau`` (44
  coefficients, 43 FMAs) reaches 5·10⁻⁴ max relative error where tensor forms in (√n, cos θ_o) of similar size
  stall near 10⁻².
* ``smith:P/Q@D`` (issue 12 item 5) — the albedo E(μ, α) of a GGX lobe, x = μ and t = α:
  E = 1 − s·(N(s, α²) + ln s·L(α²)) / Q(s, α²) with s = μ/√(μ² + α²(1 − μ²)) = 1/(1 + 2Λ), N and Q of degree P
  and Q in s, N, L and Q of degree D in α² — ``smith:P/Q@D/DQ`` gives Q its own degree DQ
  (:class:`brdfnorm.fit.families.SmithForm` says why: s absorbs the boundary
  layer μ ≲ α, the factor s gives E(0, α) = 1, ln s the α²·s·ln s of the horizon). Over μ ∈ [0, 1],
  α ∈ [0.02, 1] of height-correlated GGX (F = 1), ``smith:1/1@1`` (9 coefficients) reaches 7.5·10⁻³,
  ``smith:1/1@1/2`` (11) 4.2·10⁻³ and ``smith:1/1@2`` (14) 2.0·10⁻³ max absolute error on a dense check grid,
  where rationals in √μ of ≤ 16 coefficients stall at 0.049.
* ``auto`` fits candidates in order of coefficient count and returns the first count at which one reaches the
  target maximum relative error (the best one of that count), with the list of what it tried.

Metrics
-------
* ``abs-lsq``: ordinary least squares on y − f (seed 003's choice).
* ``rel-lsq``: least squares on the relative error (f − y)/y.
* ``minimax-rel``: the smallest maximum relative error on the samples (discrete Chebyshev approximation).
  Method: *iteratively reweighted least squares* (Lawson's algorithm, Lawson 1961; in the rational case on top
  of the Sanathanan–Koerner linearization, as in Nakatsukasa & Trefethen's AAA-Lawson, SIAM J. Sci. Comput.
  42 (2020) A3157) multiplies every sample's weight by its current |error| until the error equi-oscillates;
  the result is then polished as the exact discrete minimax problem in epigraph form — minimize e subject to
  −e ≤ r_j(c) ≤ e — by scipy.optimize.minimize(method="SLSQP") started from the IRLS solution. The polish only
  replaces the IRLS result if it lowers the maximum error. At the optimum of a linear (poly) form with k
  coefficients the error equi-oscillates at ≥ k + 1 samples (Chebyshev's alternation theorem); the tests check it.
* ``minimax-abs``: the same for the absolute error f − y (the goal of a table fit, e.g. 5·10⁻³ on E).

Linear forms are solved by numpy.linalg.lstsq; rational and hyperbola forms by a linearized least squares start
refined with scipy.optimize.least_squares. Internally x (or √x) and t are scaled to at most 1 in magnitude for
conditioning; the reported coefficients are for the unscaled variables, in the order the expression uses them.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from .. import validate
from ..errors import ArgumentError, ArgumentTypeError, EvaluationError
from ..registry import Registry
from .families import Form, HyperbolaForm, RationalForm, SmithForm

METRICS = ("abs-lsq", "rel-lsq", "minimax-rel", "minimax-abs")
#: Candidate forms of ``auto`` never exceed this many coefficients unless asked (``max_coefficients``).
AUTO_MAX_COEFFICIENTS = 10


# ---------------------------------------------------------------------------------------------------------
# Registry and parsing
# ---------------------------------------------------------------------------------------------------------

_DEGREE = re.compile(r"^\d+$")
_RATIO = re.compile(r"^(\d+)/(\d+)$")
_SECOND = re.compile(r"^(?P<base>[^@]*)@(?P<degree>[^~]*)(?P<tau>~tau)?$")


def _linear(arg: str | None, spec: str) -> dict:
    if arg is not None:
        raise ArgumentError(f"form 'linear' takes no argument, got {spec!r}", where="form")
    return {"P": 1, "Q": 0, "family": "linear"}


def _poly(arg: str | None, spec: str) -> dict:
    if arg is None or not _DEGREE.match(arg):
        raise ArgumentError(f"bad form {spec!r}: expected poly:D with D a whole number, e.g. poly:3",
                            where="form")
    return {"P": int(arg), "Q": 0, "family": "poly"}


def _rational(sqrt: bool) -> Callable[[str | None, str], dict]:
    def parse(arg: str | None, spec: str) -> dict:
        match = _RATIO.match(arg or "")
        name = "rational-sqrt" if sqrt else "rational"
        if not match:
            raise ArgumentError(f"bad form {spec!r}: expected {name}:P/Q with whole numbers, e.g. {name}:2/1",
                                where="form")
        return {"P": int(match[1]), "Q": int(match[2]), "sqrt": sqrt}

    return parse


def _hyperbola(arg: str | None, spec: str) -> dict:
    if arg is not None:
        raise ArgumentError(f"form 'hyperbola' takes no argument, got {spec!r}", where="form")
    return {}


def _smith(arg: str | None, spec: str) -> dict:
    match = _RATIO.match(arg or "")
    if not match:
        raise ArgumentError(f"bad form {spec!r}: expected smith:P/Q@D with whole numbers, e.g. smith:1/1@2",
                            where="form")
    return {"P": int(match[1]), "Q": int(match[2])}


#: Form families by name: ``name`` or ``name:ARG`` → the family's parameters (``auto`` is handled by :func:`fit`).
FORMS: Registry[Callable[[str | None, str], dict]] = Registry("form", "form", {
    "linear": _linear,
    "hyperbola": _hyperbola,
    "poly": _poly,
    "rational": _rational(False),
    "rational-sqrt": _rational(True),
    "smith": _smith,
})


def parse_form(spec: str, two_d: bool = False) -> Form:
    """``linear``, ``hyperbola``, ``poly:D``, ``rational:P/Q``, ``rational-sqrt:P/Q``; in two variables with
    ``@D`` (degree in t of every coefficient) and optionally ``~tau`` (second variable τ = t·u)."""
    if not isinstance(spec, str):
        raise ArgumentTypeError(f"expected a form name such as 'rational:2/1', got {type(spec).__name__}",
                                where="form")
    text = spec.strip()
    second = _SECOND.match(text)
    if second and not two_d:
        raise ArgumentError(f"form {spec!r}: '@D' applies only to two-variable fits (samples with t, e.g. "
                            "at='view')", where="form")
    D, tau, den_degree = 0, False, None
    if second:
        text, degree = second["base"], second["degree"]
        both = _RATIO.match(degree)
        if both and text.startswith("smith:"):  # smith:P/Q@D/DQ: the denominator's own degree in α²
            degree, den_degree = both[1], int(both[2])
        if not _DEGREE.match(degree):
            raise ArgumentError(f"form {spec!r}: bad degree {degree!r} after '@' (a whole number)", where="form")
        D, tau = int(degree), bool(second["tau"])
    name, sep, arg = text.partition(":")
    FORMS.validate(name, extra=("auto",))
    if name == "auto":
        raise ArgumentError("'auto' is not one form: pass it to fit(), which tries several", where="form")
    fields = FORMS[name](arg if sep else None, spec)
    if name == "hyperbola":
        if two_d:
            raise ArgumentError("form 'hyperbola' fits one variable only", where="form")
        return HyperbolaForm()
    if name == "smith":
        if not (two_d and second) or tau:
            raise ArgumentError(f"form {spec!r}: smith:P/Q@D fits E(μ, α) (two variables, μ and α) and takes "
                                "'@D' without '~tau', e.g. smith:1/1@2", where="form")
        return SmithForm(D=D, DQ=den_degree, **fields)
    if two_d and not second:
        raise ArgumentError(f"form {spec!r} needs '@D' (the degree in the second variable) in a two-variable "
                            "fit, e.g. rational-sqrt:3/2@2", where="form")
    return RationalForm(D=D, two_d=two_d, tau=tau, **fields)


def auto_candidates(two_d: bool, max_coefficients: int) -> list[Form]:
    """``auto``'s search space, in order of coefficient count (ties: the cheaper-to-evaluate first)."""
    forms: list[Form] = []
    if not two_d:
        forms.append(HyperbolaForm())
        for P in range(max_coefficients):
            forms.append(RationalForm(P, 0, family="linear" if P == 1 else "poly"))
            for Q in range(1, max_coefficients):
                for sqrt in (False, True):
                    forms.append(RationalForm(P, Q, sqrt=sqrt))
            if P:
                forms.append(RationalForm(P, 0, sqrt=True))
    else:
        # Two variables: rationals in √x whose coefficients are polynomials in t, or in τ = t·√x (the
        # boundary-layer variable of a narrow lobe near the horizon); both with D ≥ 1.
        for D in range(1, 4):
            for P in range(1, 7):
                for Q in range(0, 5):
                    for tau in (False, True):
                        forms.append(RationalForm(P, Q, sqrt=True, D=D, two_d=True, tau=tau))
    forms = [f for f in forms if 2 <= f.n_coefficients <= max_coefficients]
    return sorted(forms, key=lambda f: (f.n_coefficients, sum(f.operations().values())))


def smith_candidates(max_coefficients: int) -> list[Form]:
    """The ``smith:P/Q@D/DQ`` forms with at most ``max_coefficients`` coefficients, fewest first (for E(μ, α));
    D, DQ ∈ {1, 2}: E depends on α at every μ, and degree 3 in α² never paid for its coefficients over
    α ∈ [0.02, 1] (GGX, dense check grid)."""
    forms: list[Form] = [SmithForm(P, Q, D, None if DQ == D else DQ) for D in (1, 2) for DQ in (1, 2)
                         for P in range(0, 5) for Q in range(0, 4)]
    forms = [f for f in forms if f.n_coefficients <= max_coefficients]
    return sorted(forms, key=lambda f: (f.n_coefficients, sum(f.operations().values())))


# ---------------------------------------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------------------------------------


@dataclass
class FitResult:
    """A fitted formula, its coefficients and its error on the samples.

    ``argmax`` maps the variable names to where the largest relative error occurs; ``range`` maps them to the
    fitted [min, max]; ``operations`` counts the arithmetic of the emitted Horner evaluation.
    """

    form: str
    expression: str
    coefficients: list[float]
    max_rel_error: float
    max_abs_error: float
    argmax: dict[str, float]
    metric: str
    samples: int
    range: dict[str, list[float]]
    variables: list[str]
    operations: dict[str, int]
    tried: list[dict] = field(default_factory=list)
    warnings: list[str] = field(default_factory=list)
    _form: Form | None = field(default=None, repr=False)

    def __call__(self, x, t=None) -> np.ndarray:
        """Evaluate the fitted formula (full-precision coefficients)."""
        assert self._form is not None
        if self._form.two_d and t is None:
            raise ArgumentError("this fit takes two variables", where="t")
        return self._form.evaluate(np.asarray(self.coefficients), np.asarray(x, dtype=float),
                                   None if t is None else np.asarray(t, dtype=float))

    @property
    def form_object(self) -> Form:
        assert self._form is not None
        return self._form

    def to_dict(self) -> dict:
        data = {k: v for k, v in self.__dict__.items() if not k.startswith("_")}
        data["operations_total"] = sum(self.operations.values())
        return data


def _check_samples(x, y, t) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    x = validate.real_array(x, "x", error=EvaluationError).ravel()
    y = validate.real_array(y, "y", error=EvaluationError).ravel()
    tt = None if t is None else validate.real_array(t, "t", error=EvaluationError).ravel()
    if x.size != y.size or (tt is not None and tt.size != x.size):
        raise ArgumentError(f"sample arrays differ in size ({x.size} x, {y.size} y"
                            + ("" if tt is None else f", {tt.size} t") + ")", where="samples")
    if x.size == 0:
        raise ArgumentError("no samples", where="samples")
    if np.any(y == 0):
        raise ArgumentError("a sample value is 0: relative errors are undefined", where="samples")
    return x, tt, y


def _fit_one(form: Form, x, t, y, metric: str, names: tuple[str, str]) -> FitResult:
    if isinstance(form, RationalForm) and form.sqrt and np.any(x < 0):
        raise ArgumentError(f"form {form.spec!r} needs x ≥ 0 (it uses √x)", where="form")
    if isinstance(form, SmithForm) and (np.any(x < 0) or np.any(x > 1) or np.any(t < 0)):
        raise ArgumentError(f"form {form.spec!r} fits E(μ, α): it needs 0 ≤ μ ≤ 1 (x) and α ≥ 0 (t)", where="form")
    if x.size < form.n_coefficients:
        raise ArgumentError(f"form {form.spec!r} has {form.n_coefficients} coefficients but there are only "
                            f"{x.size} samples", where="form")
    with np.errstate(all="ignore"):
        c = np.asarray(form.fit(x, t, y, metric), dtype=float)
        f = form.evaluate(c, x, t)
    rel = np.abs(f / y - 1.0)
    rel = np.where(np.isfinite(rel), rel, np.inf)
    j = int(np.argmax(rel))
    variables = [names[0]] + ([names[1]] if form.two_d else [])
    argmax = {names[0]: float(x[j])}
    ranges = {names[0]: [float(x.min()), float(x.max())]}
    if form.two_d:
        argmax[names[1]] = float(t[j])
        ranges[names[1]] = [float(t.min()), float(t.max())]
    warnings = _defects(form, c, x, t)
    return FitResult(
        form=form.spec, expression=form.expression(c, *names), coefficients=[float(v) for v in c],
        max_rel_error=float(rel[j]), max_abs_error=float(np.max(np.abs(f - y))), argmax=argmax, metric=metric,
        samples=int(x.size), range=ranges, variables=variables, operations=form.operations(),
        warnings=warnings, _form=form,
    )


#: A denominator this many times its fixed constant term 1 means numerator and denominator nearly cancel: the
#: normalization q_00 = 1 is then meaningless and float32 shader code would overflow.
DEGENERATE = 1e12


def _defects(form: Form, c: np.ndarray, x: np.ndarray, t: np.ndarray | None) -> list[str]:
    """A pole (the denominator changes sign on the samples or a dense grid over the fitted box) or a
    degenerate rational (see :data:`DEGENERATE`)."""
    with np.errstate(all="ignore"):
        q = form.denominator(c, x, t)
        if q is None:
            return []
        grid_x = np.linspace(x.min(), x.max(), 2049)
        if form.two_d:
            grid_x, grid_t = np.meshgrid(grid_x, np.linspace(t.min(), t.max(), 65))
            dense = form.denominator(c, grid_x.ravel(), grid_t.ravel())
        else:
            dense = form.denominator(c, grid_x)
    q = np.concatenate([q, dense])
    if not (np.all(q > 0) or np.all(q < 0)):
        return ["the denominator changes sign inside the fitted range (a pole)"]
    if not np.all(np.isfinite(q)) or np.max(np.abs(q)) > DEGENERATE:
        return [f"degenerate: the denominator exceeds {DEGENERATE:g} (numerator and denominator nearly cancel)"]
    return []


def fit(
    x,
    y,
    t=None,
    *,
    form: str | Form = "auto",
    metric: str = "minimax-rel",
    target: float = 1e-3,
    max_coefficients: int | None = None,
    names: tuple[str, str] = ("x", "t"),
) -> FitResult:
    """Fit ``form`` to the samples y(x) or y(x, t) under ``metric``.

    ``form="auto"`` tries :func:`auto_candidates` (up to ``max_coefficients``; default
    :data:`AUTO_MAX_COEFFICIENTS`, or 40 in two variables) in order of coefficient count and returns the best
    fit of the first count where one reaches max relative error ≤ ``target`` (or the best fit overall if none
    does, with a warning); ``tried`` lists every candidate with its error.
    """
    validate.choice(metric, METRICS, "metric")
    if not validate.real_number(target, "target") > 0:
        raise ArgumentError(f"target must be a positive number, got {target!r}", where="target")
    if max_coefficients is not None:
        validate.count(max_coefficients, "max_coefficients", minimum=2, maximum=1000)
    if not (isinstance(names, (tuple, list)) and len(names) == 2 and all(isinstance(n, str) for n in names)):
        raise ArgumentTypeError("expected two variable names (x, t) as text", where="names")
    x, t, y = _check_samples(x, y, t)
    two_d = t is not None
    if not (isinstance(form, str) and form.strip() == "auto"):
        chosen = form if isinstance(form, Form) else parse_form(form, two_d)
        if chosen.two_d != two_d:
            raise ArgumentError(f"form {chosen.spec!r} is for {'two variables' if chosen.two_d else 'one variable'}",
                                where="form")
        return _fit_one(chosen, x, t, y, metric, names)
    limit = max_coefficients or (40 if two_d else AUTO_MAX_COEFFICIENTS)
    tried: list[dict] = []
    best: FitResult | None = None
    candidates = [c for c in auto_candidates(two_d, min(limit, x.size))
                  if not (isinstance(c, RationalForm) and c.sqrt and np.any(x < 0))]
    for count in sorted({c.n_coefficients for c in candidates}):
        level: FitResult | None = None
        for candidate in (c for c in candidates if c.n_coefficients == count):
            result = _fit_one(candidate, x, t, y, metric, names)
            pole = bool(result.warnings)
            tried.append({"form": result.form, "coefficients": count, "max_rel_error": result.max_rel_error,
                          "pole": pole})
            if not pole and (level is None or result.max_rel_error < level.max_rel_error):
                level = result
        if level is not None and (best is None or level.max_rel_error < best.max_rel_error):
            best = level
        if level is not None and level.max_rel_error <= target:
            break
    if best is None:
        raise EvaluationError("no candidate form could be fitted without a pole", where="form")
    if best.max_rel_error > target:
        best.warnings.append(f"no form with ≤ {limit} coefficients reached the target {target:g}; "
                             "this is the best one tried")
    best.tried = tried
    return best
