"""Closed-form albedos and normalization factors from the seed articles, and the folklore ones.

Sources
-------
* Seed 000, "Phong Normalization Factor derivation": original Phong ∫cos^n θ dω = 2π/(n+1) (Eq. 1-2), so the
  factor (n+1)/2π; the modified (BRDF) Phong ∫cos^(n+1) θ dω = 2π/(n+2), factor (n+2)/2π; Blinn-Phong at
  L = N, ∫cos^n(θ/2) cos θ dω = 8π(2^(−n/2)+n)/((n+2)(n+4)) (Eq. 3 and the last display), "not (n+8)/8π".
* (n+2)/2π normalizes the *distribution* (N·H)^n over projected half-vector solid angle,
  ∫(N·H)^n (N·H) dω_h = 2π/(n+2) — a different quantity from the albedo, often confused with it.

Every entry here is checked against quadrature in the tests; approximations are labelled as such.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np


def phong_original_albedo_normal(n: np.ndarray | float) -> np.ndarray:
    """Albedo of the original Phong lobe max(0,R·V)^n/(N·L) at V = N: 2π/(n+1) (seed 000, Eq. 2)."""
    return 2.0 * np.pi / (np.asarray(n, dtype=float) + 1.0)


def phong_modified_albedo_normal(n: np.ndarray | float) -> np.ndarray:
    """Albedo of the modified Phong lobe max(0,R·V)^n at normal incidence: 2π/(n+2) (seed 000)."""
    return 2.0 * np.pi / (np.asarray(n, dtype=float) + 2.0)


def blinn_phong_albedo_normal(n: np.ndarray | float) -> np.ndarray:
    """Albedo of max(0,N·H)^n at L = N (equivalently V = N): 8π(2^(−n/2)+n)/((n+2)(n+4)) (seed 000)."""
    n = np.asarray(n, dtype=float)
    return 8.0 * np.pi * (np.exp2(-n / 2.0) + n) / ((n + 2.0) * (n + 4.0))


def blinn_phong_folklore_factor(n: np.ndarray | float) -> np.ndarray:
    """The folklore Blinn-Phong factor (n+8)/8π — an *approximation* of 1/blinn_phong_albedo_normal."""
    return (np.asarray(n, dtype=float) + 8.0) / (8.0 * np.pi)


@functools.cache
def blinn_phong_folklore_worst() -> tuple[float, float]:
    """Where the folklore factor is furthest from the exact one, and how far: (n, relative error), the maximum
    of |(n+8)/8π · E(L = N) − 1| by bounded Brent to 1e-9 in n (n = 8.7637, 7.52 %; mpmath at 30 digits puts the
    root of its derivative at 8.76374141906). The report, the figure and the claims table all quote this one
    number (a sampled grid gave 8.66, 8.7 and 8.859 in three places)."""
    from scipy.optimize import minimize_scalar

    def error(n: float) -> float:
        return float(blinn_phong_folklore_factor(n) * blinn_phong_albedo_normal(n) - 1.0)

    # |error| has one maximum on [1, 100] (0 at n → 0, decaying like 2/n for large n)
    found = minimize_scalar(lambda n: -abs(error(n)), bounds=(1.0, 100.0), method="bounded",
                            options={"xatol": 1e-9})
    return float(found.x), error(float(found.x))


def ndf_normalization_factor(n: np.ndarray | float) -> np.ndarray:
    """(n+2)/2π, which makes (N·H)^n integrate to 1 against (N·H) dω_h (a distribution, not an albedo)."""
    return (np.asarray(n, dtype=float) + 2.0) / (2.0 * np.pi)


#: Seed 003's fitted factor of the Gaussian Blinn-Phong lobe, α(n) ≈ 0.17287429 + 0.01388682·n (intercept,
#: slope), fitted "over range [1;512]" (:data:`SEED_003_RANGE`) by least squares — an approximation.
SEED_003_LINE = (0.17287429, 0.01388682)
SEED_003_RANGE = (1.0, 512.0)
#: The line as seed 003 prints it.
SEED_003_TEXT = f"{SEED_003_LINE[0]} + {SEED_003_LINE[1]}·n"


def seed003_factor(n: np.ndarray | float) -> np.ndarray:
    """Seed 003's linear normalization factor of the Gaussian Blinn-Phong lobe (an approximation)."""
    return SEED_003_LINE[0] + SEED_003_LINE[1] * np.asarray(n, dtype=float)


@dataclass(frozen=True)
class ClosedForm:
    """A named formula: what it gives, whether it is exact, and where it comes from."""

    name: str
    formula: str
    quantity: str  # "albedo" or "factor"
    exact: bool
    source: str
    function: Callable[[np.ndarray | float], np.ndarray]


CLOSED_FORMS: dict[str, ClosedForm] = {
    form.name: form
    for form in (
        ClosedForm("phong-original", "2π/(n+1)", "albedo", True, "seed 000", phong_original_albedo_normal),
        ClosedForm("phong-modified", "2π/(n+2)", "albedo", True, "seed 000", phong_modified_albedo_normal),
        ClosedForm(
            "blinn-phong-normal", "8π(2^(−n/2)+n)/((n+2)(n+4))", "albedo", True, "seed 000",
            blinn_phong_albedo_normal,
        ),
        ClosedForm(
            "blinn-phong-folklore", "(n+8)/(8π)", "factor", False, "folklore (seed 000 refutes it)",
            blinn_phong_folklore_factor,
        ),
        ClosedForm("ndf-normalization", "(n+2)/(2π)", "factor", True, "NDF normalization",
                   ndf_normalization_factor),
        ClosedForm("gaussian-blinn-phong-seed003", SEED_003_TEXT, "factor", False,
                   "seed 003's least-squares line over n ∈ [1, 512]", seed003_factor),
    )
}
