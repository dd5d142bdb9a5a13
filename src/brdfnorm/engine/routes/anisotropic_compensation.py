"""Kulla & Conty's and Turquin's compensation for anisotropic GGX and Beckmann lobes, with the lobe's own
anisotropic E(μ, φ) and E_avg instead of an isotropic table read at the geometric-mean roughness (issue #45).

Kulla & Conty 2017 ("Revisiting physically based shading at Imageworks"): f_ms(L, V) = F_ms (1 − E(L))(1 − E(V)) /
(π (1 − E_avg)). The derivation needs nothing isotropic: with E(ω) the white lobe's albedo at the direction ω
(its azimuth included) and 1 − E_avg = (1/π)∫ (1 − E(ω)) cos θ dω, the compensation's albedo at V is exactly
1 − E(V), so the white furnace is 1 at every view. Turquin 2019: f = f_ss (1 + F0 (1/E(V) − 1)).

E(μ, φ) is tabulated per lobe (α_x, α_y) on an N × N node grid over μ ∈ [0, 1] (the μ = 0 row at μ = 1e-4) and
φ ∈ [0, π/2] (E is even in φ and symmetric about π/2: every azimuth folds into that quarter), read bilinearly as a
renderer reads a texture, by :func:`brdfnorm.engine.routes.anisotropic.albedo` (compiled cubature, rtol 1e-8);
``size`` 0 computes E exactly at every evaluation (slow: for checks). The 1 − E_avg in the denominator is the
missing energy of E *as read* — (2/π)∫₀^{π/2} 2∫₀¹ (1 − E(μ, φ)) μ dμ dφ, exact for the bilinear table (2-point
Gauss–Legendre per μ segment, the trapezoid rule over the φ nodes) — so that the compensation's albedo is exactly
1 − E_table(V) and the furnace's only error is the table's interpolation error at V. E_avg itself (the colour
term F_ms) is the exact hemispherical average, :func:`brdfnorm.engine.routes.anisotropic.average_albedo`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from . import anisotropic as kernel
from .microfacet import bilinear

MU_CLAMP = 1e-4
_TABLE_RTOL = 1e-8
_EXACT_RTOL = 1e-10


def fold(phi: np.ndarray) -> np.ndarray:
    """The azimuth folded into [0, π/2]: E(φ) = E(−φ) = E(π − φ) for these lobes."""
    return np.arctan2(np.abs(np.sin(phi)), np.abs(np.cos(phi)))


@dataclass(frozen=True)
class AnisotropicCompensation:
    """E(μ, φ) of one white anisotropic lobe: an N × N table read bilinearly (``size`` N ≥ 2) or exact (0)."""

    distribution: str
    shadowing: str
    alpha_x: float
    alpha_y: float
    size: int
    average: float  # E_avg, exact (to rtol 1e-8)
    missing: float  # (1/π)∫(1 − E) cos dω of E as this compensation reads it
    error: float  # the largest quadrature error of any entry (and of E_avg)
    mu: np.ndarray | None = None
    phi: np.ndarray | None = None
    table: np.ndarray | None = None  # (N, N) E[μ_i, φ_j]

    def albedo(self, mu: np.ndarray, phi: np.ndarray) -> np.ndarray:
        mu, phi = np.broadcast_arrays(np.asarray(mu, dtype=float), fold(np.asarray(phi, dtype=float)))
        if self.size == 0:
            value = kernel.albedo(self.distribution, self.shadowing, np.clip(mu, MU_CLAMP, 1.0), self.alpha_x,
                                  self.alpha_y, phi, rtol=_EXACT_RTOL)[0]
            return value.reshape(mu.shape)
        return bilinear(self.table, self.mu, self.phi, mu, phi)



def _missing(table: np.ndarray, mu: np.ndarray) -> float:
    """(1/π)∫(1 − E)cos dω for E bilinear on the grid: exact (module docstring)."""
    lo, hi = mu[:-1], mu[1:]
    t = np.array([-1.0, 1.0]) / np.sqrt(3.0)
    nodes = (lo + hi)[:, None] / 2 + (hi - lo)[:, None] / 2 * t  # (N−1, 2)
    frac = (nodes - lo[:, None]) / (hi - lo)[:, None]
    e = (1 - frac)[..., None] * table[:-1, None, :] + frac[..., None] * table[1:, None, :]  # (N−1, 2, Nφ)
    per_phi = np.sum(((hi - lo) / 2)[:, None, None] * 2.0 * nodes[..., None] * (1.0 - e), axis=(0, 1))
    return float((per_phi[0] / 2 + per_phi[1:-1].sum() + per_phi[-1] / 2) / (per_phi.size - 1))


@lru_cache(maxsize=32)
def _compensation(distribution: str, shadowing: str, size: int, ax: float, ay: float) -> AnisotropicCompensation:
    average, average_error, _, _ = kernel.average_albedo(distribution, shadowing, ax, ay, rtol=_TABLE_RTOL)
    if size == 0:
        return AnisotropicCompensation(distribution, shadowing, ax, ay, 0, float(average[0]),
                                       1.0 - float(average[0]), 10 * _EXACT_RTOL + float(average_error[0]))
    mu = np.linspace(0.0, 1.0, size)
    phi = np.linspace(0.0, np.pi / 2, size)
    grid_mu, grid_phi = np.meshgrid(np.maximum(mu, MU_CLAMP), phi, indexing="ij")
    value, error, _, _ = kernel.albedo(distribution, shadowing, grid_mu, ax, ay, grid_phi, rtol=_TABLE_RTOL)
    table = value.reshape(size, size)
    return AnisotropicCompensation(distribution, shadowing, ax, ay, size, float(average[0]), _missing(table, mu),
                                   float(max(error.max(), average_error[0])), mu, phi, table)


def anisotropic_compensation(distribution: str, shadowing: str, size: int, alpha_x: float,
                             alpha_y: float) -> AnisotropicCompensation:
    """The (cached) compensation of one anisotropic lobe; ``size`` 0 for exact values."""
    return _compensation(distribution, shadowing, int(size), float(alpha_x), float(alpha_y))
