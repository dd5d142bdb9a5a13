"""The formula families :func:`brdfnorm.fit.fit` fits, and their solvers.

A :class:`Form` is one member of a family with a fixed number of coefficients (see :mod:`brdfnorm.fit` for the
families and the metrics): it fits itself to samples, evaluates, prints its expression and counts the operations
of its emitted code (:mod:`brdfnorm.fit.codegen`).

Solvers: linear forms by numpy.linalg.lstsq; rational forms by the Sanathanan–Koerner linearization refined with
scipy.optimize.least_squares; the minimax metric by Lawson's iteratively reweighted least squares (Lawson 1961;
Nakatsukasa & Trefethen, SIAM J. Sci. Comput. 42 (2020) A3157) followed by an SLSQP polish of the epigraph form.
Internally x (or √x) and t are scaled to at most 1 in magnitude for conditioning; the coefficients returned are
for the unscaled variables.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

#: Lawson iterations for minimax (each one weighted least-squares solve; the polish finishes the job).
LAWSON_ITERATIONS = 300


def _optimize():
    """scipy.optimize, imported at the first fit (not at the import of the command line: ~0.1 s of every command)."""
    import scipy.optimize

    return scipy.optimize


def metric_scale(metric: str, y: np.ndarray) -> np.ndarray:
    """What a sample's error is divided by under ``metric``: |y| for the relative metrics, 1 for the absolute."""
    return np.ones_like(y) if metric in ("abs-lsq", "minimax-abs") else np.abs(y)


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

    def error_exceeds(self, x: np.ndarray, t: np.ndarray | None, y: np.ndarray, bound: float) -> bool:
        """True only when it is proved that every member of the family without a pole on the samples has
        max |f − y| > ``bound`` over them (whatever its coefficients, so whatever a fit would find); False when
        that is not known (the default for families without such a proof)."""
        return False


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
        scale = metric_scale(metric, y)
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

    def error_exceeds(self, x, t, y, bound):
        """A linear program (scipy.optimize.linprog, HiGHS) decides it: max |p/q − y| ≤ e with q > 0 on the
        samples is, after scaling p and q together (p/q is homogeneous), the linear feasibility problem
        |p_j − y_j q_j| ≤ e·q_j, q_j ≥ 1 — the bisection step of the rational Chebyshev problem (Cheney &
        Loeb's differential correction, Numer. Math. 4 (1962) 124). The homogeneous family lets q_00 take any
        value, so it contains every fit of this form whose denominator keeps one sign on the samples (q < 0 is
        −p/−q). Infeasible means the discrete minimax error of the family exceeds ``bound``; HiGHS's feasibility
        tolerance errs towards feasible (no proof), the safe side."""
        u, v = self.variables(np.asarray(x, dtype=float), t)
        y = np.asarray(y, dtype=float)
        us = u / (float(np.max(np.abs(u))) or 1.0)
        vs = v / ((float(np.max(np.abs(v))) or 1.0) if self.two_d else 1.0)
        phi = self._basis(us, vs, self.P)
        psi = self._basis(us, vs, self.Q) if self.has_denominator else np.ones((y.size, 1))
        return _infeasible(phi, psi, y, bound)

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


def smith_variable(mu: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """x = μ/√(μ² + α²(1 − μ²)) = 1/(1 + 2Λ(μ)), GGX's Λ = (−1 + √(1 + α² tan²θ))/2 (Heitz 2014, eq. 72).

    x is 0 at the horizon, 1 at the normal, and μ/α where μ ≪ α: it stretches the boundary layer μ ≲ α, where
    E(μ, α) turns over, to a fixed part of [0, 1] whatever α is. 0 at μ = α = 0 (the mirror's horizon).
    """
    mu = np.asarray(mu, dtype=float)
    root = np.sqrt(mu * mu + np.asarray(alpha, dtype=float) ** 2 * (1.0 - mu * mu))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(root > 0, mu / np.where(root > 0, root, 1.0), 0.0)


@dataclass(frozen=True)
class SmithForm(Form):
    """E(μ, α) = 1 − x·(N(x, v) + ln x·L(v)) / Q(x, v), x = :func:`smith_variable`, v = α², for the albedo of a
    GGX lobe with height-correlated shadowing (F = 1).

    N = Σ p_ik x^i v^k (i ≤ P), L = Σ l_k v^k (k ≤ D), Q = Σ q_jk x^j v^k (j ≤ Q, k ≤ DQ, q_00 = 1); DQ = D
    unless given (spec ``smith:P/Q@D/DQ``). Why: at the
    horizon G2 → G1(V) and every reflected ray leaves upwards, so E(0, α) = 1 exactly (the factor x keeps it);
    the first correction is 2x·⟨1 + Λ(L)⟩ over the reflected directions, where Λ(L) ≈ α/(2μ_L) diverges at
    grazing L, so 1 − E ≈ x·(α² ln(1/x) + b(α)) as x → 0 (the tables show the slope α² to 1 %): the ln x term,
    which no rational in x (or √μ) follows. Fitted as the rational r = (1 − E)/x with the error of E weighted
    back in (minimax-abs on E is minimax of |r̃ − r|·x).
    """

    P: int
    Q: int
    D: int
    DQ: int | None = None
    two_d: bool = True

    @property
    def dq(self) -> int:
        """The denominator's degree in v."""
        return self.D if self.DQ is None else self.DQ

    @property
    def spec(self) -> str:  # type: ignore[override]
        return f"smith:{self.P}/{self.Q}@{self.D}" + (f"/{self.dq}" if self.dq != self.D else "")

    @property
    def n_coefficients(self) -> int:  # type: ignore[override]
        return (self.P + 2) * (self.D + 1) + (self.Q + 1) * (self.dq + 1) - 1

    def split(self, c: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """N's p[i, k], L's l[k] and Q's q[j, k] (q[0, 0] = 1) from the flat vector."""
        c = np.asarray(c, dtype=float)
        k = self.D + 1
        n = (self.P + 1) * k
        den = np.concatenate([[1.0], c[n + k:]]).reshape(self.Q + 1, self.dq + 1)
        return c[:n].reshape(self.P + 1, k), c[n:n + k], den

    @staticmethod
    def variables(mu: np.ndarray, alpha: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """x, v = α² and ln x (finite at x = 0, where x·ln x → 0 and the value is 1)."""
        x = smith_variable(mu, alpha)
        return x, np.asarray(alpha, dtype=float) ** 2, np.log(np.maximum(x, 1e-300))

    def evaluate(self, c, x, t=None):
        p, l, q = self.split(c)
        u, v, log_u = self.variables(x, t)
        numerator = RationalForm._horner2(p, u, v) + log_u * RationalForm._horner2(l[None, :], u, v)
        return 1.0 - u * numerator / self.denominator(c, x, t)

    def denominator(self, c, x, t=None):
        u, v, _ = self.variables(x, t)
        return RationalForm._horner2(self.split(c)[2], u, v)

    def fit(self, x, t, y, metric):
        u, v, log_u = self.variables(x, t)
        inside = u > 0  # at x = 0 the form is 1 whatever the coefficients: no information there
        u, v, log_u, y = u[inside], v[inside], log_u[inside], y[inside]
        vs = float(np.max(v)) or 1.0
        vv = v / vs
        powers = range(self.D + 1)
        phi = np.stack([u**i * vv**k for i in range(self.P + 1) for k in powers]
                       + [log_u * vv**k for k in powers], axis=1)
        psi = np.stack([u**j * vv**k for j in range(self.Q + 1) for k in range(self.dq + 1)], axis=1)[:, 1:]
        # E − Ẽ = x·(r̃ − r): the error of E divided by metric_scale is that of r divided by this scale.
        scale = metric_scale(metric, y) / u
        c = _fit_rational(phi, psi, (1.0 - y) / u, scale, metric)
        k, kq = self.D + 1, self.dq + 1
        undo = np.array([vs ** -(i % k) for i in range((self.P + 2) * k)]
                        + [vs ** -(i % kq) for i in range((self.Q + 1) * kq)][1:])
        return c * undo

    def error_exceeds(self, x, t, y, bound):
        """As :meth:`RationalForm.error_exceeds`: E − Ẽ = (x·(N + ln x·L) − (1 − E)·Q)/Q is linear in the
        coefficients over Q, so |E − Ẽ| ≤ e with Q ≥ 1 on the samples is a linear feasibility problem (samples
        at x = 0, where Ẽ = 1 whatever the coefficients, are left out: the bound holds on the others alone)."""
        u, v, log_u = self.variables(x, t)
        inside = u > 0
        u, v, log_u, y = u[inside], v[inside], log_u[inside], np.asarray(y, dtype=float)[inside]
        vv = v / (float(np.max(v)) or 1.0) if v.size else v
        powers = range(self.D + 1)
        phi = np.stack([u ** (i + 1) * vv**k for i in range(self.P + 1) for k in powers]
                       + [u * log_u * vv**k for k in powers], axis=1)
        psi = np.stack([u**j * vv**k for j in range(self.Q + 1) for k in range(self.dq + 1)], axis=1)
        return _infeasible(phi, psi, 1.0 - y, bound)

    def expression(self, c, x, t):
        p, l, q = self.split(c)
        v = f"({t}²)"
        u = f"s({x}, {t})"

        def poly(row: Sequence[float], fixed_one: bool = False) -> str:
            return _join(["1" if fixed_one and k == 0 else _term(a, k, v) for k, a in enumerate(row)])

        def poly2(coef: np.ndarray, fixed_one: bool) -> str:
            return _join([f"({poly(row, fixed_one and i == 0)})" + (f"·{u}" + (f"^{i}" if i > 1 else "") if i else "")
                          for i, row in enumerate(coef)])

        return (f"1 - {u}·({poly2(p, False)} + ({poly(l)})·ln {u}) / ({poly2(q, True)}), "
                f"{u} = {x}/√({x}² + {t}²(1 - {x}²))")

    def operations(self) -> dict[str, int]:
        """x (2 fma, sqrt, max, div), v, ln x; Horner in v then in x for N, L and Q; the last fma and div."""
        horner = (self.P + 2) * self.D + (self.Q + 1) * self.dq
        return {"fma": 3 + horner + self.P + self.Q + 2, "mul": 2, "div": 2, "sqrt": 1, "log": 1,
                "max": 2}


@dataclass(frozen=True)
class HyperbolaForm(Form):
    """y = a + c·√((x − x0)² + b²): seed 003's commenter's scaled, shifted √(x² + 1); b ≥ 0 reported."""

    spec: str = "hyperbola"
    n_coefficients: int = 4

    def evaluate(self, c, x, t=None):
        a, s, x0, b = c
        return a + s * np.sqrt((np.asarray(x, dtype=float) - x0) ** 2 + b * b)

    def fit(self, x, t, y, metric):
        scale = metric_scale(metric, y)
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
                result = _optimize().least_squares(lambda p: (model(p, X) - Y) * ys / scale, p0, method="lm",
                                                   x_scale="jac")
                cost = float(np.sum(result.fun**2))
                if best is None or cost < best[0]:
                    best = (cost, result.x)
        assert best is not None
        p = best[1]
        if metric.startswith("minimax"):
            p = _minimax(lambda q: (model(q, X) * ys - y) / scale, p, None)
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


def _infeasible(phi: np.ndarray, psi: np.ndarray, y: np.ndarray, bound: float) -> bool:
    """Whether no (p, q) has |φp − y·ψq| ≤ bound·ψq and ψq ≥ 1 at every sample (HiGHS says infeasible)."""
    if y.size == 0:
        return False
    A = np.vstack([np.hstack([phi, -(y + bound)[:, None] * psi]),
                   np.hstack([-phi, (y - bound)[:, None] * psi]),
                   np.hstack([np.zeros_like(phi), -psi])])
    b = np.concatenate([np.zeros(2 * y.size), -np.ones(y.size)])
    result = _optimize().linprog(np.zeros(A.shape[1]), A_ub=A, b_ub=b, bounds=(None, None), method="highs")
    return bool(result.status == 2)



def _lstsq(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """numpy.linalg.lstsq with column equilibration (the monomial columns differ by orders of magnitude)."""
    norms = np.linalg.norm(A, axis=0)
    norms[norms == 0] = 1.0
    return np.linalg.lstsq(A / norms, b, rcond=None)[0] / norms


def _fit_linear(phi: np.ndarray, y: np.ndarray, scale: np.ndarray, metric: str) -> np.ndarray:
    c = _lstsq(phi / scale[:, None], y / scale)
    if not metric.startswith("minimax"):
        return c
    # Lawson: weights ∝ weight·|error| drive the weighted least-squares solution to the minimax one of the
    # scaled error (f − y)/scale (scale = |y| for minimax-rel, 1 for minimax-abs).
    w = np.full(y.shape, 1.0 / y.size)
    best = c
    best_err = np.max(np.abs((phi @ c - y) / scale))
    for _ in range(LAWSON_ITERATIONS):
        e = (phi @ c - y) / scale
        w = w * np.abs(e)
        total = w.sum()
        if not np.isfinite(total) or total == 0:
            break
        w /= total
        root = np.sqrt(w)
        c = _lstsq(phi * (root / scale)[:, None], root * y / scale)
        err = np.max(np.abs((phi @ c - y) / scale))
        if err < best_err:
            best, best_err = c, err
    return _minimax(lambda q: (phi @ q - y) / scale, best, lambda q: phi / scale[:, None])


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
    if not metric.startswith("minimax"):
        return c

    def rel(c: np.ndarray) -> np.ndarray:
        return residual(c, ones)

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
        c = _refine(residual, jacobian, c, np.sqrt(w))
        err = float(np.max(np.abs(rel(c))))
        if err < best_err and no_pole(c):
            best, best_err = c, err

    polished = _minimax(rel, best, lambda c: jacobian(c, ones))
    return polished if no_pole(polished) else best


def _refine(residual, jacobian, c0: np.ndarray, root_w: np.ndarray) -> np.ndarray:
    """scipy.optimize.least_squares (Levenberg–Marquardt) from a start; the start if it does not improve."""
    try:
        result = _optimize().least_squares(residual, c0, jac=jacobian, args=(root_w,), method="lm", x_scale="jac")
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
            result = _optimize().minimize(objective, np.append(best, best_e), jac=objective_grad,
                                          constraints=constraints, method="SLSQP",
                                          options={"maxiter": 100, "ftol": 1e-15})
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
