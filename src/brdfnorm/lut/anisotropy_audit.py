"""The geometric-mean lookup audited, and a drop-in fix: what engines compensate anisotropic GGX/Beckmann with.

Cycles (``microfacet_ggx_preserve_energy``: ``sqrtf(sqrtf(alpha_x * alpha_y))``), MaterialX (``mx_average_alpha``),
the MDL SDK and OSPRay read their isotropic E(μ, α) table at α_g = √(α_x α_y). For a lobe of aspect a
(α_x = α_g/a, α_y = α_g·a) this module compares that read with the lobe's own albedo averaged over the view azimuth
(:func:`brdfnorm.engine.routes.anisotropic.albedo`), and the white furnace of the compensations built on the read:

* Turquin 2019 (Cycles' form, F0 = 1): f = f_ss / E_iso → furnace Ē(V)/E_iso(μ);
* Kulla & Conty 2017 with isotropic tables at α_g: the compensation lobe's albedo is 1 − E_iso(μ) → furnace
  Ē(V) + 1 − E_iso(μ);

averaged over the view azimuth (the extremes over φ_v are in :func:`geometric_mean_audit`'s ``spread``).

The fix (:func:`effective_alpha`): the α_eff with E_iso(μ, α_eff) = Ē(μ; α_x, α_y) — an engine that keeps its
2-D table and changes the one line that computes the lookup roughness. :func:`fit_effective_alpha` fits the ratio
α_eff/α_g over (μ, ℓ = ln(α_x/α_y)) at each α_g as a polynomial (:mod:`brdfnorm.fit`'s 2-D forms) — emitted by
``brdfnorm fit --lut`` from the table :func:`effective_alpha_table` writes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from ..engine.routes import anisotropic as kernel

#: E_iso(α) is searched over this α range (white E decreases with α over it at every μ).
ALPHA_SEARCH = (1e-6, 30.0)


@dataclass(frozen=True)
class AuditRow:
    """One (μ, aspect, α_g) cell: the truth, the geometric-mean read and the furnaces built on it."""

    mu: float
    aspect: float
    alpha: float
    exact: float  # Ē: the anisotropic albedo averaged over the view azimuth
    exact_error: float
    lookup: float  # E_iso(μ, α_g)
    spread: tuple[float, float]  # min, max of E(μ, φ_v) over φ_v
    turquin: float  # Ē / E_iso
    kulla_conty: float  # Ē + 1 − E_iso

    @property
    def error(self) -> float:
        return self.lookup - self.exact


def geometric_mean_audit(distribution: str, shadowing: str, mu, aspect, alpha, *, rtol: float = 1e-6
                         ) -> list[AuditRow]:
    """The audit over the grid mu × aspect × alpha (α_g), one :class:`AuditRow` per cell (μ fastest last)."""
    rows = []
    grid = [(m, a, g) for a in np.atleast_1d(aspect) for g in np.atleast_1d(alpha) for m in np.atleast_1d(mu)]
    m, a, g = (np.array(v, dtype=float) for v in zip(*grid, strict=True))
    exact, exact_error, _, _ = kernel.albedo(distribution, shadowing, m, g / a, g * a, rtol=rtol)
    lookup, _, _, _ = kernel.albedo(distribution, shadowing, m, g, g, 0.0, rtol=rtol)
    phi = np.linspace(0.0, np.pi / 2, 9)
    views = kernel.albedo(distribution, shadowing, np.repeat(m, phi.size), np.repeat(g / a, phi.size),
                          np.repeat(g * a, phi.size), np.tile(phi, m.size), rtol=rtol)[0].reshape(m.size, -1)
    for i in range(m.size):
        rows.append(AuditRow(float(m[i]), float(a[i]), float(g[i]), float(exact[i]), float(exact_error[i]),
                             float(lookup[i]), (float(views[i].min()), float(views[i].max())),
                             float(exact[i] / lookup[i]), float(exact[i] + 1.0 - lookup[i])))
    return rows


def effective_alpha(distribution: str, shadowing: str, mu: float, alpha_x: float, alpha_y: float, *,
                    rtol: float = 1e-8) -> float:
    """α_eff with E_iso(μ, α_eff) = Ē(μ; α_x, α_y) (Brent's method on the isotropic albedo, to rtol)."""
    target = kernel.albedo(distribution, shadowing, mu, alpha_x, alpha_y, rtol=rtol)[0][0]

    def gap(log_alpha: float) -> float:
        a = float(np.exp(log_alpha))
        return kernel.albedo(distribution, shadowing, mu, a, a, 0.0, rtol=rtol)[0][0] - target

    lo, hi = np.log(ALPHA_SEARCH[0]), np.log(ALPHA_SEARCH[1])
    if gap(lo) <= 0:
        return ALPHA_SEARCH[0]
    if gap(hi) >= 0:
        return ALPHA_SEARCH[1]
    return float(np.exp(brentq(gap, lo, hi, xtol=1e-10, rtol=1e-10)))


def effective_alpha_table(distribution: str, shadowing: str, mu, log_aspect, alpha, *, rtol: float = 1e-8
                          ) -> np.ndarray:
    """α_eff/α_g over mu × ℓ × α_g, ℓ = ln(α_x/α_y) = −2 ln(aspect): (len(mu), len(ℓ), len(α))."""
    mu, log_aspect, alpha = (np.atleast_1d(np.asarray(v, dtype=float)) for v in (mu, log_aspect, alpha))
    out = np.empty((mu.size, log_aspect.size, alpha.size))
    for i, m in enumerate(mu):
        for j, ell in enumerate(log_aspect):
            for k, g in enumerate(alpha):
                ax, ay = g * np.exp(ell / 2), g * np.exp(-ell / 2)
                out[i, j, k] = effective_alpha(distribution, shadowing, m, ax, ay, rtol=rtol) / g
    return out
