"""Seed 003 (the Gaussian Blinn-Phong BRDF Explorer shader): its fitted linear factor against a re-fit of the
exact factor, its small-n error, and the commenter's hyperbola."""

from __future__ import annotations

import numpy as np

from ..engine.machinery.interval import adaptive_gauss_legendre
from ..models import closed_forms
from . import GAUSSIAN_RANGE, SOURCES, TWO_PI, Claim, rel_error


def gaussian_factor(n: np.ndarray) -> np.ndarray:
    """Exact factor 1/E at L = N of seed 003's lobe exp(−((N·H − 1)/(c − 1))²), c = 0.04^(1/n).

    At L = N, N·H = cos(θ/2) (seed 003); E = 2π∫ D(cos(θ/2)) cos θ sin θ dθ, by adaptive Gauss–Legendre in
    θ with breakpoints at the lobe width √(8(1 − c)).
    """
    from ..models.blinn_phong_gaussian import threshold_cosine

    n = np.asarray(n, dtype=float).ravel()
    c = threshold_cosine(n)
    width = np.minimum(np.pi / 2, np.sqrt(8.0 * (1.0 - c)))
    points = np.clip(width[:, None] * np.array([0.0, 1.0, 3.0, 8.0, 1e9]), 0.0, np.pi / 2)
    a, b = points[:, :-1].ravel(), points[:, 1:].ravel()
    case = np.repeat(np.arange(n.size), 4)
    keep = b > a

    def integrand(index, theta):
        x = (np.cos(0.5 * theta) - 1.0) / (c[index, None] - 1.0)
        return np.exp(-x * x) * np.cos(theta) * np.sin(theta)

    value = adaptive_gauss_legendre(integrand, a[keep], b[keep], case[keep], n.size, rtol=1e-13).value
    return 1.0 / (TWO_PI * value)


def _gaussian_data() -> tuple[np.ndarray, np.ndarray]:
    n = np.arange(GAUSSIAN_RANGE[0], GAUSSIAN_RANGE[1] + 1.0)
    return n, gaussian_factor(n)


def _fit(x: np.ndarray, y: np.ndarray, form: str):
    """Least-squares fit on absolute residuals, as seed 003's author did (brdfnorm.fit; the hyperbola is
    a + c·√((n − n0)² + b²), the commenter's scaled √(x² + 1) with its asymptote a line)."""
    from ..fit import fit

    return fit(x, y, form=form, metric="abs-lsq")


def gaussian_fit(_: np.ndarray) -> Claim:
    n, factor = _gaussian_data()
    result = _fit(n, factor, "linear")
    refit = np.asarray(result.coefficients, dtype=float)
    seed = np.array(closed_forms.SEED_003_LINE)
    errors = rel_error(seed, refit)
    return Claim(
        "gaussian-fit", SOURCES["003"], "least-squares line through the exact factor on n ∈ [1, 512]: "
        + closed_forms.SEED_003_TEXT,
        float(seed[1]), float(refit[1]), float(errors.max()), bool(np.all(np.abs(refit - seed) <= 5e-9)),
        f"least-squares re-fit of the exact factor at n = 1, 2, …, 512 gives {refit[0]:.10f} + {refit[1]:.10f}·n: "
        f"the seed's 8 printed decimals (ok when within half a unit of the 8th); relative differences "
        f"{errors[0]:.2g} (intercept), {errors[1]:.2g} (slope)",
        criterion="|A − B| ≤ 5e-9 (half a unit of the 8th decimal), both coefficients",
    )  # fmt: skip


def gaussian_small_n(_: np.ndarray) -> Claim:
    n = np.array([1.0])
    exact = float(gaussian_factor(n)[0])
    seed = closed_forms.SEED_003_LINE[0] + closed_forms.SEED_003_LINE[1] * 1.0
    error = float(rel_error(seed, exact))
    return Claim(
        "gaussian-fit-small-n-error", SOURCES["003"], "the fitted factor is inaccurate at small n: ≈42 % at n = 1",
        seed, exact, error, abs(error - 0.42) <= 0.01,
        "numeric: exact factor 1/E at L = N by adaptive Gauss–Legendre; ok when the error is 42 % ± 1 %",
        relation="differ", criterion="|A − B| / |B| = 0.42 ± 0.01",
    )  # fmt: skip


def gaussian_hyperbola(_: np.ndarray) -> Claim:
    n, factor = _gaussian_data()
    line = _fit(n, factor, "linear")
    hyperbola = _fit(n, factor, "hyperbola")
    return Claim(
        "gaussian-hyperbola-beats-line", SOURCES["003"], "the commenter's scaled hyperbola fits better than the line",
        float(hyperbola.max_rel_error), float(line.max_rel_error),
        float(hyperbola.max_rel_error / line.max_rel_error), bool(hyperbola.max_rel_error < line.max_rel_error),
        "formula: max relative error of the fitted hyperbola over n ∈ [1, 512]; numeric: of the fitted line "
        "(both least squares on absolute residuals); rel_error column: their ratio",
        relation="less", criterion="A < B",
    )  # fmt: skip


#: The checks in display order: id -> function of the exponents (parametric checks use them).
