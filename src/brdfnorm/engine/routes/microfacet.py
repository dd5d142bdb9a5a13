"""The albedo methods of the microfacet lobes, and Kulla & Conty's energy-compensation tables they use.

Methods (registered in :mod:`brdfnorm.engine.methods`): ``"azimuthal"`` — isotropic GGX with F = 1 by the 1-D
integral of :mod:`brdfnorm.engine.routes.azimuthal` — and ``"microfacet"`` — every ``ggx``/``beckmann`` lobe by the
half-vector
cubature of :mod:`brdfnorm.engine.routes.halfvector`. Both add, with ``ms=kulla-conty``, the compensation lobe of Kulla
& Conty
2017 ("Revisiting physically based shading at Imageworks") in closed form (:func:`with_compensation`), from the
tables :func:`compensation` builds: E(μ, α) and E_avg(α) of the F = 1 lobe (by
:func:`brdfnorm.engine.routes.azimuthal.white_albedo`), read as a renderer reads them or exact.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ...models.microfacet import (
    BeckmannDistribution,
    Distribution,
    GGXDistribution,
    MicrofacetModel,
    fresnel_multiple_scattering,
    fresnel_normal,
)
from ...validate import DEFAULT_MAX_EVALUATIONS, DEFAULT_RTOL
from ..compiled import backend as compiled_backend
from ..machinery.interval import GaussLegendre, adaptive_interval
from ..machinery.result import RouteResult
from .azimuthal import white_albedo
from .halfvector import MU_MIN, require_mu_min, single_scattering_albedo

#: The μ = 0 row of a table is evaluated here (a renderer clamps μ there too).
MU_CLAMP = 1e-4
#: Tables are read with interpolation errors ≥ 1e-6 (N ≤ 64), so 1e-8 is ample; exact values are for checks.
_TABLE_RTOL = 1e-8
_EXACT_RTOL = 1e-11


# -- the albedo methods -----------------------------------------------------------------------------------

def _albedo_method(single_scattering, compiles: bool = False):
    """A ``brdfnorm.albedo`` method that integrates a :class:`brdfnorm.albedo.Problem`'s batch by
    ``single_scattering(distribution, fixed, params, rtol=, atol=, max_evaluations=)`` and adds the compensation
    lobe (:func:`with_compensation`). The lobe is reciprocal (f(L, V) = f(V, L), also f_ms), so the integral
    over the view with the light fixed is the same integral at the fixed direction. With ``compiles``,
    ``single_scattering`` takes ``compiled=`` (the compiled backend asked for, and Numba there)."""
    def run(problem, *, rtol: float, atol: float = 0.0, max_evaluations: int = DEFAULT_MAX_EVALUATIONS, **_: object):
        model: MicrofacetModel = problem.model
        require_mu_min(problem.fixed[:, 2])
        params = problem.case_params(np.arange(problem.fixed.shape[0]))
        options = {"compiled": problem.compiled and compiled_backend.numba_available()} if compiles else {}
        result = single_scattering(model.distribution, problem.fixed, params, rtol=rtol, atol=atol,
                                   max_evaluations=max_evaluations, **options)
        value, error = with_compensation(model, problem.fixed, params, result.value, result.error)
        return result.with_(value=value, error=error)
    return run


#: Method ``"microfacet"``: every ggx/beckmann lobe by the half-vector cubature.
halfvector_method = _albedo_method(single_scattering_albedo, compiles=True)
#: Method ``"azimuthal"``: isotropic lobes with F = 1 by :mod:`brdfnorm.engine.routes.azimuthal`'s 1-D integral.
azimuthal_method = _albedo_method(
    lambda distribution, fixed, params, **options: white_albedo(distribution, params["shadowing"], fixed,
                                                                params["alpha"], **options))


def with_compensation(model: MicrofacetModel, fixed: np.ndarray, params: Mapping[str, object], value: np.ndarray,
                      error: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(value, error) of the single-scattering albedo (K, C) plus, with ``ms=kulla-conty``, the compensation
    lobe's albedo in closed form: ∫ f_ms (N·L) dL = F_ms (1 − E(μ_V)) · 2∫₀¹(1 − E(μ))μ dμ / (1 − E_avg), the inner
    integral exact for the table as read (piecewise linear in μ); with ``ms=turquin`` the single-scattering albedo
    times 1 + F0 (1/E(μ_V) − 1) (the factor depends on the fixed view only; over the light this is exact)."""
    if params["ms"] == "none":
        return value, error
    if model._anisotropic(params):
        return _anisotropic_compensation(model, fixed, params, value, error)
    K = fixed.shape[0]
    table = compensation(model.distribution, params["shadowing"], int(np.asarray(params["ms_table"])))
    alpha = np.broadcast_to(np.asarray(params["alpha"], dtype=float), (K,))
    e_v = table.albedo(fixed[:, 2], alpha)
    if params["ms"] == "turquin":
        return _turquin(params, value, error, e_v, table.error)
    e_avg = table.average_albedo(alpha)
    lost = 1.0 - e_avg
    colour = np.broadcast_to(fresnel_multiple_scattering(params, e_avg), value.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        compensated = np.where(lost > 0, (1.0 - e_v) * table.missing_energy(alpha) / lost, 0.0)
        # The table entries' own quadrature errors, through a ratio of sums of at most a few of them.
        propagated = np.where(lost > 0, 4.0 * table.error / lost, 0.0)
    return value + compensated[:, None] * colour, error + propagated[:, None] * np.abs(colour)


def _turquin(params, value, error, e_v, table_error):
    """Turquin's scaling f·(1 + F0(1/E(V) − 1)) of the single-scattering albedo ``value`` and its ``error``, E(V)
    read from a table (isotropic or anisotropic) whose entries carry ``table_error``."""
    f0 = np.broadcast_to(fresnel_normal(params), value.shape)
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = 1.0 + f0 * (1.0 / e_v[:, None] - 1.0)
        # d(factor)/dE = −F0/E²: the table entries' errors (a bilinear read mixes four of them) through it.
        propagated = np.abs(value) * f0 * 4.0 * table_error / (e_v[:, None] ** 2)
    return value * factor, error * np.abs(factor) + propagated


def _anisotropic_compensation(model, fixed, params, value, error):
    """:func:`with_compensation` for one anisotropic lobe: E at the view's (μ, φ) from its own table; the
    compensation lobe's albedo is (1 − E(V))·F_ms exactly, its denominator being the table's own missing energy
    (:mod:`brdfnorm.engine.routes.anisotropic_compensation`)."""
    table = model.anisotropic_table(params)
    e_v = table.albedo(fixed[:, 2], np.arctan2(fixed[:, 1], fixed[:, 0]))
    if params["ms"] == "turquin":
        return _turquin(params, value, error, e_v, table.error)
    colour = np.broadcast_to(fresnel_multiple_scattering(params, table.average), value.shape)
    compensated = np.where(table.missing > 0, 1.0 - e_v, 0.0)
    # A bilinear read mixes four entries, and the missing energy is a weighted mean of entries: errors through both.
    propagated = np.where(table.missing > 0, 4.0 * table.error * (1.0 + 1.0 / max(table.missing, 1e-300)), 0.0)
    return value + compensated[:, None] * colour, error + propagated * np.abs(colour)


# -- Kulla & Conty's compensation tables -------------------------------------------------------------------

def _albedo_grid(distribution: Distribution, shadowing: str, mu: np.ndarray, alpha: np.ndarray,
                 rtol: float = _TABLE_RTOL, atol=0.0) -> RouteResult:
    """Single-scattering E (F = 1, isotropic) at the pairs (μ, α) of two equal-shape arrays, flattened."""
    mu = np.clip(np.ravel(mu), MU_MIN, 1.0)
    fixed = np.stack([np.sqrt(1.0 - mu * mu), np.zeros_like(mu), mu], axis=-1)
    return white_albedo(distribution, shadowing, fixed, np.ravel(alpha), rtol=rtol, atol=atol)


#: E_avg's integral starts here; the dropped ∫₀^μ 2μE dμ ∈ [0, μ²] is added as half of that ± half.
_AVERAGE_MU_MIN = 1e-6


def average_albedo(distribution: Distribution, shadowing: str, alpha, *, rtol: float = DEFAULT_RTOL):
    """E_avg(α) = 2∫₀¹ E(μ, α) μ dμ, every E by the half-vector integral; returns (value, error) arrays.

    In x = ln μ the integrand 2μ²E(e^x) is smooth at every scale (E has a boundary layer at grazing μ, of
    width ~α) and negligible towards μ → 0, so :func:`brdfnorm.engine.machinery.interval.adaptive_interval` over
    x ∈ [ln 1e-6, 0] converges fast; each node's E is computed to an absolute accuracy scaled by its weight,
    and the nodes' errors are added to the outer estimate (bounded by max(2μ²·err_E) times the x-range).
    """
    alpha = np.atleast_1d(np.asarray(alpha, dtype=float)).ravel()
    K = alpha.size
    edges = np.log([_AVERAGE_MU_MIN, 0.05, 1.0])
    a = np.tile(edges[:-1], K)
    b = np.tile(edges[1:], K)
    case = np.repeat(np.arange(K), edges.size - 1)
    inner_error = np.zeros(K)
    span = -edges[0]

    def integrand(index: np.ndarray, x: np.ndarray) -> np.ndarray:
        mu = np.exp(x)
        weight = 2.0 * mu * mu
        result = _albedo_grid(distribution, shadowing, mu, np.broadcast_to(alpha[index][:, None], mu.shape),
                              rtol=rtol / 10, atol=(rtol / (100.0 * span)) / weight.ravel()[:, None])
        np.maximum.at(inner_error, index, np.max(weight * result.error[:, 0].reshape(mu.shape), axis=1))
        return weight * result.value[:, 0].reshape(mu.shape)

    result = adaptive_interval(GaussLegendre(integrand), a, b, case, K, rtol=rtol)
    dropped = _AVERAGE_MU_MIN**2 / 2
    return result.value + dropped, result.error + span * inner_error + dropped


@dataclass(frozen=True)
class Compensation:
    """E(μ, α) and E_avg(α) of one lobe (F = 1): tabulated on an N × N node grid (``size`` N ≥ 2) and read
    as a renderer reads them (bilinear in (μ, α), linear in α), or exact (``size`` 0, an integral per value)."""

    distribution: Distribution
    shadowing: str
    size: int
    mu: np.ndarray | None = None  # (N,) nodes
    alpha: np.ndarray | None = None  # (N,)
    table: np.ndarray | None = None  # (N, N) E[μ_i, α_j]
    average: np.ndarray | None = None  # (N,) E_avg[α_j]
    error: float = 0.0  # largest quadrature error of any table entry

    def albedo(self, mu: np.ndarray, alpha: np.ndarray) -> np.ndarray:
        mu, alpha = np.broadcast_arrays(np.asarray(mu, dtype=float), np.asarray(alpha, dtype=float))
        if self.size == 0:
            exact = _albedo_grid(self.distribution, self.shadowing, mu, alpha, rtol=_EXACT_RTOL)
            return exact.value[:, 0].reshape(mu.shape)
        return bilinear(self.table, self.mu, self.alpha, mu, alpha)

    def average_albedo(self, alpha: np.ndarray) -> np.ndarray:
        alpha = np.asarray(alpha, dtype=float)
        if self.size == 0:
            unique, inverse = np.unique(alpha, return_inverse=True)
            exact = average_albedo(self.distribution, self.shadowing, unique, rtol=_EXACT_RTOL)[0]
            return exact[inverse].reshape(alpha.shape)
        return np.interp(alpha, self.alpha, self.average)

    def energies(self, mu_l, mu_v, alpha):
        """(E(μ_L), E(μ_V), E_avg(α)) broadcast together."""
        mu_l, mu_v, alpha = np.broadcast_arrays(mu_l, mu_v, alpha)
        e = self.albedo(np.concatenate([mu_l.ravel(), mu_v.ravel()]), np.concatenate([alpha.ravel()] * 2))
        return e[:mu_l.size].reshape(mu_l.shape), e[mu_l.size:].reshape(mu_l.shape), self.average_albedo(alpha)

    def missing_energy(self, alpha: np.ndarray) -> np.ndarray:
        """2∫₀¹ (1 − E(μ)) μ dμ of E as this compensation reads it (exact for the piecewise-linear table)."""
        alpha = np.asarray(alpha, dtype=float)
        if self.size == 0:
            return 1.0 - self.average_albedo(alpha)
        # Along μ the bilinear read is linear between nodes: 2-point Gauss–Legendre per segment is exact.
        lo, hi = self.mu[:-1], self.mu[1:]
        nodes = (lo + hi)[:, None] / 2 + (hi - lo)[:, None] / 2 * np.array([-1.0, 1.0]) / np.sqrt(3.0)
        weights = (hi - lo)[:, None] / 2
        e = bilinear(self.table, self.mu, self.alpha, nodes[None], alpha[..., None, None])
        return np.sum(weights * 2.0 * nodes * (1.0 - e), axis=(-2, -1))


def bilinear(table, mu_nodes, alpha_nodes, mu, alpha):
    """Bilinear interpolation on a node grid (clamped to its edges), as a GPU samples a texture: ``table``
    (μ nodes, second-axis nodes) read at (mu, alpha) — α for the isotropic tables, φ_v for the anisotropic ones."""
    def locate(nodes, x):
        x = np.clip(x, nodes[0], nodes[-1])
        i = np.clip(np.searchsorted(nodes, x, side="right") - 1, 0, nodes.size - 2)
        return i, (x - nodes[i]) / (nodes[i + 1] - nodes[i])

    i, fu = locate(mu_nodes, mu)
    j, fa = locate(alpha_nodes, alpha)
    return ((1 - fu) * (1 - fa) * table[i, j] + fu * (1 - fa) * table[i + 1, j]
            + (1 - fu) * fa * table[i, j + 1] + fu * fa * table[i + 1, j + 1])


@lru_cache(maxsize=16)
def _compensation(distribution_name: str, shadowing: str, size: int) -> Compensation:
    distribution = {"ggx": GGXDistribution, "beckmann": BeckmannDistribution}[distribution_name]()
    if size == 0:
        # Exact values are integrals to rtol _EXACT_RTOL: their error, ten times that, is what callers propagate.
        return Compensation(distribution, shadowing, 0, error=10 * _EXACT_RTOL)
    nodes = np.linspace(0.0, 1.0, size)
    mu_grid, alpha_grid = np.meshgrid(nodes, nodes, indexing="ij")
    grid = _albedo_grid(distribution, shadowing, np.maximum(mu_grid, MU_CLAMP), alpha_grid)
    table = grid.value[:, 0].reshape(size, size)
    average, average_error = average_albedo(distribution, shadowing, nodes, rtol=_TABLE_RTOL)
    error = float(max(grid.error.max(), average_error.max()))
    return Compensation(distribution, shadowing, size, nodes, nodes, table, average, error)


def compensation(distribution: Distribution, shadowing: str, size: int) -> Compensation:
    """The (cached) Kulla-Conty tables of a lobe; ``size`` 0 for exact values."""
    return _compensation(distribution.name, shadowing, int(size))
