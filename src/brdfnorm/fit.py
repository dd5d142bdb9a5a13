"""Cheap closed formulas fitted to sampled normalization factors, with their error known.

Seed 003 integrated the Gaussian Blinn-Phong normalization numerically and fitted α(n) ≈ 0.17287429 +
0.01388682·n over n ∈ [1, 512] by ordinary least squares ("not accurate for small specular power values"); its
commenter suggested a scaled, shifted hyperbola √(x² + 1). Seed 002 leaves the view-dependent Blinn-Phong
normalization open. This module fits such formulas to samples (x, y) or, in two variables, (x, t, y) — it does
not care how the samples were computed (:mod:`brdfnorm.normalize` in the command line).

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

Linear forms are solved by numpy.linalg.lstsq; rational and hyperbola forms by a linearized least squares start
refined with scipy.optimize.least_squares. Internally x (or √x) and t are scaled to at most 1 in magnitude for
conditioning; the reported coefficients are for the unscaled variables, in the order the expression uses them.
"""

from __future__ import annotations

import re
from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares, minimize

from . import validate
from .errors import ArgumentError, ArgumentTypeError, EvaluationError
from .registry import Registry

METRICS = ("abs-lsq", "rel-lsq", "minimax-rel")
#: Lawson iterations for minimax (each one weighted least-squares solve; the polish finishes the job).
LAWSON_ITERATIONS = 300
#: Candidate forms of ``auto`` never exceed this many coefficients unless asked (``max_coefficients``).
AUTO_MAX_COEFFICIENTS = 10


def _fmt(value: float) -> str:
    return f"{value:.9g}"


def _term(coefficient: float, power: int, var: str) -> str:
    """``c``, ``c·v`` or ``c·v^k`` with the coefficient to 9 significant digits."""
    if power == 0:
        return _fmt(coefficient)
    return f"{_fmt(coefficient)}·{var}" + (f"^{power}" if power > 1 else "")


def _join(terms: Sequence[str]) -> str:
    text = " + ".join(terms)
    return text.replace("+ -", "- ")


# ---------------------------------------------------------------------------------------------------------
# Forms
# ---------------------------------------------------------------------------------------------------------


class Form(ABC):
    """A family member with a fixed number of coefficients: fit, evaluate, describe, count operations."""

    spec: str
    n_coefficients: int
    two_d: bool = False

    @abstractmethod
    def evaluate(self, c: np.ndarray, x: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
        """The formula with coefficients ``c`` at x (and t)."""

    @abstractmethod
    def fit(self, x: np.ndarray, t: np.ndarray | None, y: np.ndarray, metric: str) -> np.ndarray:
        """Coefficients minimizing ``metric`` over the samples."""

    @abstractmethod
    def expression(self, c: Sequence[float], x: str, t: str) -> str:
        """Human-readable formula with the coefficients to 9 significant digits."""

    @abstractmethod
    def operations(self) -> dict[str, int]:
        """Arithmetic of the emitted evaluation, by kind."""

    def denominator(self, c: np.ndarray, x: np.ndarray, t: np.ndarray | None = None) -> np.ndarray | None:
        """The denominator's values (to detect poles), or None for forms without one."""
        return None


@dataclass(frozen=True)
class RationalForm(Form):
    """(Σ p_ik v^k u^i)/(Σ q_jk v^k u^j), q_00 = 1, u = x or √x, i ≤ P, j ≤ Q, k ≤ D (D = 0 in one variable).

    v is t, or τ = t·u with ``tau``. ``poly``/``linear`` have no denominator; a ``rational`` form in two
    variables keeps the denominator's t-polynomial even for Q = 0.
    """

    P: int
    Q: int
    sqrt: bool = False
    D: int = 0
    two_d: bool = False
    tau: bool = False
    family: str = "rational"

    @property
    def spec(self) -> str:  # type: ignore[override]
        if self.family == "linear":
            base = "linear"
        elif self.family == "poly":
            base = f"poly:{self.P}"
        else:
            base = f"{'rational-sqrt' if self.sqrt else 'rational'}:{self.P}/{self.Q}"
        if self.two_d:
            base += f"@{self.D}" + ("~tau" if self.tau else "")
        return base

    @property
    def has_denominator(self) -> bool:
        return self.family == "rational" and (self.Q > 0 or self.D > 0)

    @property
    def n_coefficients(self) -> int:  # type: ignore[override]
        k = self.D + 1
        return (self.P + 1) * k + ((self.Q + 1) * k - 1 if self.has_denominator else 0)

    def split(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Numerator p[i, k] and denominator q[j, k] (q[0, 0] = 1) from the flat vector (i or j major)."""
        c = np.asarray(c, dtype=float)
        k = self.D + 1
        num = c[: (self.P + 1) * k].reshape(self.P + 1, k)
        if not self.has_denominator:
            return num, np.ones((1, 1))
        den = np.concatenate([[1.0], c[(self.P + 1) * k :]]).reshape(self.Q + 1, k)
        return num, den

    def variables(self, x: np.ndarray, t: np.ndarray | None) -> tuple[np.ndarray, np.ndarray]:
        u = np.sqrt(x) if self.sqrt else np.asarray(x, dtype=float)
        if not self.two_d:
            return u, np.zeros_like(u)
        v = np.asarray(t, dtype=float)
        return u, (v * u if self.tau else v)

    @staticmethod
    def _horner2(coef: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Σ_i (Σ_k coef[i, k] v^k) u^i by Horner in v (inner) and u (outer)."""
        total = np.zeros(np.broadcast_shapes(np.shape(u), np.shape(v)))
        for row in coef[::-1]:
            inner = np.zeros_like(total)
            for a in row[::-1]:
                inner = inner * v + a
            total = total * u + inner
        return total

    def evaluate(self, c, x, t=None):
        num, den = self.split(c)
        u, v = self.variables(np.asarray(x, dtype=float), t)
        value = self._horner2(num, u, v)
        return value / self._horner2(den, u, v) if self.has_denominator else value

    def denominator(self, c, x, t=None):
        if not self.has_denominator:
            return None
        u, v = self.variables(np.asarray(x, dtype=float), t)
        return self._horner2(self.split(c)[1], u, v)

    def _basis(self, u: np.ndarray, v: np.ndarray, degree: int) -> np.ndarray:
        return np.stack([u**i * v**k for i in range(degree + 1) for k in range(self.D + 1)], axis=1)

    def fit(self, x, t, y, metric):
        u, v = self.variables(x, t)
        su = float(np.max(np.abs(u))) or 1.0
        sv = (float(np.max(np.abs(v))) or 1.0) if self.two_d else 1.0
        us, vs = u / su, v / sv
        phi = self._basis(us, vs, self.P)
        scale = np.ones_like(y) if metric == "abs-lsq" else np.abs(y)
        if self.has_denominator:
            c = _fit_rational(phi, self._basis(us, vs, self.Q)[:, 1:], y, scale, metric)
        else:
            c = _fit_linear(phi, y, scale, metric)
        # Undo the scaling: the coefficient of u^i v^k was fitted for (u/su)^i (v/sv)^k.
        k = self.D + 1
        powers = [(i, j) for i in range(self.P + 1) for j in range(k)]
        if self.has_denominator:
            powers += [(i, j) for i in range(self.Q + 1) for j in range(k)][1:]
        return c * np.array([su**-i * sv**-j for i, j in powers])

    def expression(self, c, x, t):
        num, den = self.split(c)
        u = f"√{x}" if self.sqrt else x
        v = f"({t}·{u})" if self.tau else t

        def poly2(coef: np.ndarray, fixed_one: bool) -> str:
            terms = []
            for i, row in enumerate(coef):
                parts = ["1" if fixed_one and i == 0 and k == 0 else _term(a, k, v) for k, a in enumerate(row)]
                if self.D == 0:
                    terms.append(parts[0] if i == 0 else f"{parts[0]}·{u}" + (f"^{i}" if i > 1 else ""))
                else:
                    terms.append(f"({_join(parts)})" + (f"·{u}" + (f"^{i}" if i > 1 else "") if i else ""))
            return _join(terms)

        top = poly2(num, False)
        return f"({top}) / ({poly2(den, True)})" if self.has_denominator else top

    def operations(self) -> dict[str, int]:
        """Horner in v for every coefficient polynomial, then in u: one fused multiply-add per step."""
        rows = self.P + 1 + (self.Q + 1 if self.has_denominator else 0)
        fma = rows * self.D + self.P + (self.Q if self.has_denominator else 0)
        return {"fma": fma, "mul": int(self.tau), "div": int(self.has_denominator), "sqrt": int(self.sqrt)}


@dataclass(frozen=True)
class HyperbolaForm(Form):
    """y = a + c·√((x − x0)² + b²): seed 003's commenter's scaled, shifted √(x² + 1); b ≥ 0 reported."""

    spec: str = "hyperbola"
    n_coefficients: int = 4

    def evaluate(self, c, x, t=None):
        a, s, x0, b = c
        return a + s * np.sqrt((np.asarray(x, dtype=float) - x0) ** 2 + b * b)

    def fit(self, x, t, y, metric):
        scale = np.ones_like(y) if metric == "abs-lsq" else np.abs(y)
        xs = float(np.max(np.abs(x))) or 1.0
        ys = float(np.max(np.abs(y))) or 1.0
        X, Y = x / xs, y / ys
        # Start from the line through the upper half (the asymptote) and a few vertex positions/curvatures.
        upper = X >= np.median(X)
        slope, intercept = np.polyfit(X[upper], Y[upper], 1) if upper.sum() >= 2 else np.polyfit(X, Y, 1)
        span = float(X.max() - X.min()) or 1.0

        def model(p: np.ndarray, X: np.ndarray) -> np.ndarray:
            return p[0] + p[1] * np.sqrt((X - p[2]) ** 2 + p[3] ** 2)

        best: tuple[float, np.ndarray] | None = None
        for x0 in (X.min() - 0.1 * span, X.min(), X.min() + 0.05 * span):
            for b in (0.01 * span, 0.1 * span, 0.5 * span):
                p0 = np.array([intercept + slope * x0, slope, x0, b])
                result = least_squares(lambda p: (model(p, X) - Y) * ys / scale, p0, method="lm", x_scale="jac")
                cost = float(np.sum(result.fun**2))
                if best is None or cost < best[0]:
                    best = (cost, result.x)
        assert best is not None
        p = best[1]
        if metric == "minimax-rel":
            p = _minimax(lambda q: model(q, X) * ys / y - 1.0, p, None)
        a, s, x0, b = p
        # y = ys·(a + s·√((x/xs − x0)² + b²)) = ys·a + (ys·s/xs)·√((x − x0·xs)² + (b·xs)²)
        return np.array([a * ys, s * ys / xs, x0 * xs, abs(b) * xs])

    def expression(self, c, x, t):
        a, s, x0, b = c
        shift = f"{x} - {_fmt(x0)}" if x0 >= 0 else f"{x} + {_fmt(-x0)}"
        return _join([_fmt(a), f"{_fmt(s)}·√(({shift})² + {_fmt(b)}²)"])

    def operations(self) -> dict[str, int]:
        return {"add": 1, "fma": 2, "sqrt": 1}


# ---------------------------------------------------------------------------------------------------------
# Solvers
# ---------------------------------------------------------------------------------------------------------


def _lstsq(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """numpy.linalg.lstsq with column equilibration (the monomial columns differ by orders of magnitude)."""
    norms = np.linalg.norm(A, axis=0)
    norms[norms == 0] = 1.0
    return np.linalg.lstsq(A / norms, b, rcond=None)[0] / norms


def _fit_linear(phi: np.ndarray, y: np.ndarray, scale: np.ndarray, metric: str) -> np.ndarray:
    c = _lstsq(phi / scale[:, None], y / scale)
    if metric != "minimax-rel":
        return c
    # Lawson: weights ∝ weight·|error| drive the weighted least-squares solution to the minimax one.
    w = np.full(y.shape, 1.0 / y.size)
    best = c
    best_err = np.max(np.abs(phi @ c / y - 1.0))
    for _ in range(LAWSON_ITERATIONS):
        e = phi @ c / y - 1.0
        w = w * np.abs(e)
        total = w.sum()
        if not np.isfinite(total) or total == 0:
            break
        w /= total
        root = np.sqrt(w)
        c = _lstsq(phi * (root / y)[:, None], root)
        err = np.max(np.abs(phi @ c / y - 1.0))
        if err < best_err:
            best, best_err = c, err
    return _minimax(lambda q: phi @ q / y - 1.0, best, lambda q: phi / y[:, None])


def _fit_rational(phi: np.ndarray, psi: np.ndarray, y: np.ndarray, scale: np.ndarray, metric: str) -> np.ndarray:
    kp = phi.shape[1]
    A = np.hstack([phi, -y[:, None] * psi])

    def split(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return phi @ c[:kp], 1.0 + psi @ c[kp:]

    # Sanathanan–Koerner: minimize Σ ((P − yQ)/(s·Q_previous))², linear in the coefficients.
    den = np.ones_like(y)
    c = np.zeros(A.shape[1])
    for _ in range(12):
        row = 1.0 / (scale * den)
        c = _lstsq(A * row[:, None], y * row)
        den = np.abs(split(c)[1])
        den[den == 0] = np.finfo(float).tiny

    def residual(c: np.ndarray, root_w: np.ndarray) -> np.ndarray:
        p, q = split(c)
        return root_w * (p / q - y) / scale

    def jacobian(c: np.ndarray, root_w: np.ndarray) -> np.ndarray:
        p, q = split(c)
        return (root_w / scale)[:, None] * np.hstack([phi / q[:, None], -(p / q**2)[:, None] * psi])

    ones = np.ones_like(y)
    c = _refine(residual, jacobian, c, ones)
    if metric != "minimax-rel":
        return c

    def rel(c: np.ndarray) -> np.ndarray:
        p, q = split(c)
        return p / q / y - 1.0

    def no_pole(c: np.ndarray) -> bool:
        q = split(c)[1]
        return bool(np.all(q > 0) or np.all(q < 0))

    # Lawson on the nonlinear problem: every step a weighted least-squares refit, warm-started.
    w = ones.copy()
    best, best_err = c, float(np.max(np.abs(rel(c))))
    for _ in range(40):
        e = rel(c)
        w = w * np.abs(e)
        w /= w.mean()
        if not np.all(np.isfinite(w)):
            break
        c = _refine(lambda c, r: residual(c, r) * scale / y, lambda c, r: jacobian(c, r) * (scale / y)[:, None],
                    c, np.sqrt(w))
        err = float(np.max(np.abs(rel(c))))
        if err < best_err and no_pole(c):
            best, best_err = c, err

    def rel_jac(c: np.ndarray) -> np.ndarray:
        return jacobian(c, ones) * (scale / y)[:, None]

    polished = _minimax(rel, best, rel_jac)
    return polished if no_pole(polished) else best


def _refine(residual, jacobian, c0: np.ndarray, root_w: np.ndarray) -> np.ndarray:
    """scipy.optimize.least_squares (Levenberg–Marquardt) from a start; the start if it does not improve."""
    try:
        result = least_squares(residual, c0, jac=jacobian, args=(root_w,), method="lm", x_scale="jac")
    except (ValueError, np.linalg.LinAlgError):
        return c0
    start = np.sum(residual(c0, root_w) ** 2)
    return result.x if np.isfinite(result.cost) and 2 * result.cost <= start else c0


def _minimax(rel: Callable[[np.ndarray], np.ndarray], c0: np.ndarray,
             jac: Callable[[np.ndarray], np.ndarray] | None) -> np.ndarray:
    """Polish to the discrete minimax: min e s.t. −e ≤ r_j(c) ≤ e (SLSQP), keeping c0 unless it improves.

    SLSQP's cost grows with the number of constraints, so it sees only the samples whose error is within a
    factor 2 of the maximum (where the extremal set must lie once IRLS is close); samples that then exceed the
    maximum join the set and the polish repeats — an exchange in the spirit of Remez, with SLSQP as the solver.
    """
    e0 = float(np.max(np.abs(rel(c0))))
    if not np.isfinite(e0):
        return c0
    n = c0.size
    best, best_e = c0, e0
    active = np.abs(rel(c0)) >= 0.5 * e0

    def objective(z: np.ndarray) -> float:
        return z[-1]

    def objective_grad(z: np.ndarray) -> np.ndarray:
        g = np.zeros_like(z)
        g[-1] = 1.0
        return g

    for _ in range(6):
        rows = np.flatnonzero(active)
        constraints: list[dict] = [
            {"type": "ineq", "fun": lambda z, r=rows: z[-1] - rel(z[:n])[r]},
            {"type": "ineq", "fun": lambda z, r=rows: z[-1] + rel(z[:n])[r]},
        ]
        if jac is not None:
            ones = np.ones((rows.size, 1))
            constraints[0]["jac"] = lambda z, r=rows, o=ones: np.hstack([-jac(z[:n])[r], o])
            constraints[1]["jac"] = lambda z, r=rows, o=ones: np.hstack([jac(z[:n])[r], o])
        # The callers fit in scaled variables, so the unknowns are of order one, as SLSQP prefers.
        try:
            result = minimize(objective, np.append(best, best_e), jac=objective_grad, constraints=constraints,
                              method="SLSQP", options={"maxiter": 100, "ftol": 1e-15})
        except (ValueError, np.linalg.LinAlgError):
            break
        c = result.x[:n]
        e = np.abs(rel(c))
        if not np.all(np.isfinite(e)):
            break
        if e.max() < best_e:
            best, best_e = c, float(e.max())
        outside = (e > result.x[-1] * (1 + 1e-9)) & ~active
        if not outside.any():
            break
        active |= e >= 0.5 * e.max()
    return best


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


#: Form families by name: ``name`` or ``name:ARG`` → the family's parameters (``auto`` is handled by :func:`fit`).
FORMS: Registry[Callable[[str | None, str], dict]] = Registry("form", "form", {
    "linear": _linear,
    "hyperbola": _hyperbola,
    "poly": _poly,
    "rational": _rational(False),
    "rational-sqrt": _rational(True),
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
    D, tau = 0, False
    if second:
        text = second["base"]
        if not _DEGREE.match(second["degree"]):
            raise ArgumentError(f"form {spec!r}: bad degree {second['degree']!r} after '@' (a whole number)",
                                where="form")
        D, tau = int(second["degree"]), bool(second["tau"])
    name, sep, arg = text.partition(":")
    FORMS.validate(name, extra=("auto",))
    if name == "auto":
        raise ArgumentError("'auto' is not one form: pass it to fit(), which tries several", where="form")
    fields = FORMS[name](arg if sep else None, spec)
    if name == "hyperbola":
        if two_d:
            raise ArgumentError("form 'hyperbola' fits one variable only", where="form")
        return HyperbolaForm()
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
