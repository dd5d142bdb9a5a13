"""E_avg of the rough-dielectric (glass) tables seen from outside (η > 1): 2∫₀¹ E(μ) μ dμ by tanh-sinh.

The generic route of :func:`brdfnorm.lut.table.average_over_mu` integrates in x = √μ with nested Clenshaw–Curtis
and falls back to adaptive G7/K15. A dielectric's E(μ) has a multi-scale grazing behaviour — E − E(0) grows like a
small, drifting power of μ (≈ μ^0.15 for GGX at α = 0.5, η = 1.5, from the transmitted part) — which no fixed
power map makes smooth: Clenshaw–Curtis in x, and in t with μ = t⁴, both gained only ~25× per doubling there
(measured: 16 → 256 intervals, differences 1e-7, 5e-9, 1.6e-10, 3e-11), and the table's E_avg took 270–360
albedos per value of the other axes. The tanh-sinh rule (Takahasi & Mori 1974), μ = (1 + tanh(π/2 sinh u))/2,
absorbs any such endpoint behaviour: 45 nodes reached 3e-12 on that case, and a level's error
|Q_h − Q_2h| (the coarser level's, pessimistic for the finer one, which is kept) settles rtol 1e-9 with ~85
albedos. Levels are nested (step halving reuses the nodes); node albedos are computed to rtol/4, looser where
their weight is small (as :func:`brdfnorm.lut.table._node_albedos` does); nodes of negligible weight are not
evaluated and their bound joins the error, as do the tails |u| > DE_RANGE and MU_FLOOR's bound. A combination
not settled by the last level goes to the globally adaptive G7/K15 rule in t, μ = t⁴ (error |K15 − G7|).

Seen from inside (η < 1) E(μ) also has the critical angle μ_c = √(1 − η²) inside (a square-root kink in the
smooth limit, spread over ~α) and further edges (μ = η, where the cap of transmitting facets meets the facets'
horizon); tanh-sinh on segments cut there did not converge (GGX, α = 0.5, η = 0.9: 1323 albedos against the
generic route's 814), so those combinations stay on the generic route (:func:`average_split` dispatches).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ..models.base import Model
from . import table as T

#: G7/K15 panels a combination's fallback may split into before it gives up.
MAX_PANELS = 200


#: Double-exponential levels: steps DE_FIRST_STEP / 2^k for k < DE_LEVELS, nodes |u| ≤ DE_RANGE.
DE_FIRST_STEP = 0.5
DE_LEVELS = 6
DE_RANGE = 3.5
#: Nodes whose weight h·ρ is below this (times rtol) are not evaluated; their bound joins the error.
DE_SKIP = 1e-4


def _de_nodes(u):
    """tanh-sinh nodes μ(u) on [0, 1] and the density ρ = 2μ dμ/du, computed from the nearer end (no cancellation
    next to either end)."""
    s = 0.5 * np.pi * np.sinh(u)
    e = np.exp(-2.0 * np.abs(s))
    gap = e / (1.0 + e)  # distance from the nearer end
    mu = np.where(u < 0, gap, 1.0 - gap)
    dmu = 0.25 * np.pi * np.cosh(u) * 4.0 * e / (1.0 + e) ** 2  # (π/4) cosh u / cosh² s
    return mu, 2.0 * mu * dmu


def _double_exponential(model, params, rtol, method):
    """tanh-sinh per combination, step halving (nested): (value, error, settled, albedos ok, max|E|, integrals).

    The error of a level is |Q_h − Q_2h| (the coarser level's error, pessimistic for Q_h, which is kept) plus the
    albedo errors through the weights, plus 2·S_h + S_2h for the skipped nodes (S: their weights times the bound
    max(1, max|E|) on E — a single-scattering BSDF scatters at most what arrives), plus the tails beyond |u| =
    DE_RANGE, bounded in closed form (below 1e-22 of the integral's range)."""
    S = len(next(iter(params.values())))
    value, error = np.zeros(S), np.full(S, np.inf)
    previous, previous_skip = np.full(S, np.nan), np.zeros(S)
    ok, largest = np.ones(S, dtype=bool), np.zeros(S)
    open_ = np.ones(S, dtype=bool)
    sums = np.zeros(S)  # Σ ρ E over the nodes so far (the step multiplies it)
    sums_error, sums_skip = np.zeros(S), np.zeros(S)
    integrals = 0
    for level in range(DE_LEVELS):
        step = DE_FIRST_STEP / 2**level
        j = np.arange(-int(DE_RANGE / step), int(DE_RANGE / step) + 1)
        u = j * step if level == 0 else (j * step)[j % 2 == 1]
        rows = np.flatnonzero(open_)
        mu, rho = _de_nodes(np.broadcast_to(u, (rows.size, u.size)))
        skip = rho * step < DE_SKIP * rtol
        live = ~skip & (rho > 0)
        E, E_error = np.zeros(mu.shape), np.zeros(mu.shape)
        good = np.ones(mu.shape, dtype=bool)
        # Node albedo tolerances by the weight ρ·2·DE_RANGE (Σ h ρ ≈ the integral's range).
        which = np.broadcast_to(rows[:, None], mu.shape)[live]
        E[live], E_error[live], good[live] = T._node_albedos(
            model, mu[live], rho[live] * 2.0 * DE_RANGE, {n: v[which] for n, v in params.items()}, rtol, method)
        integrals += int(live.sum())
        ok[rows] &= good.all(axis=1)
        largest[rows] = np.maximum(largest[rows], np.abs(E).max(axis=1))
        sums[rows] += (rho * E).sum(axis=1)
        sums_error[rows] += (rho * E_error).sum(axis=1)
        sums_skip[rows] += np.where(skip, rho, 0.0).sum(axis=1)
        q, skipped = step * sums[rows], step * sums_skip[rows] * np.maximum(1.0, largest[rows])
        value[rows] = q
        if level:
            error[rows] = (np.abs(q - previous[rows]) + step * sums_error[rows] + 2.0 * skipped
                           + previous_skip[rows])
            open_[rows] = error[rows] > rtol * np.abs(q)
        previous[rows], previous_skip[rows] = q, skipped
    # Beyond |u| = DE_RANGE: μ within e^{−2s} of an end, s = (π/2) sinh(DE_RANGE) ≈ 26: ∫ 2μ E dμ there
    # ≤ 2 e^{−2s} max(1, max|E|).
    tail = 2.0 * np.exp(-np.pi * np.sinh(DE_RANGE)) * np.maximum(1.0, largest)
    error = error + tail
    return value, error, ~open_, ok, largest, integrals


def _adaptive(model, params, rtol, method):
    """Globally adaptive G7/K15 in t, μ = t⁴ (dμ 2μ = 8t⁷ dt: the grazing end graded), per combination
    (:func:`brdfnorm.lut.table.kronrod_in_mu`): (value, error, settled, ok, max|E|, integrals)."""
    S = len(next(iter(params.values())))
    total, total_error, ok, largest, integrals = T.kronrod_in_mu(
        model, params, S, lambda t: (t**4, 2.0 * t**4 * (4.0 * t**3)), rtol=rtol, method=method,
        max_panels=MAX_PANELS)
    return total, total_error, total_error <= rtol * np.abs(total), ok, largest, integrals


def average(model: Model, params: Mapping[str, np.ndarray], *, rtol: float, method: str = "auto"
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """E_avg for M parameter combinations (name -> (M,)), every η > 1: (value, error, converged, albedo integrals
    computed), as :func:`brdfnorm.lut.table.average_over_mu` returns them."""
    M = len(next(iter(params.values())))
    flat = {n: np.broadcast_to(np.asarray(v, dtype=float).ravel(), (M,)) for n, v in params.items()}
    value, error, settled, ok, largest, integrals = _double_exponential(model, flat, rtol, method)
    rest = np.flatnonzero(~settled)
    if rest.size:
        v, e, s, o, big, n = _adaptive(model, {k: x[rest] for k, x in flat.items()}, rtol, method)
        value[rest], error[rest], settled[rest], ok[rest] = v, e, s, o
        largest[rest] = np.maximum(largest[rest], big)
        integrals += n
    error = error + T.MU_FLOOR**2 * largest  # nodes below MU_FLOOR evaluated there
    return value, error, settled & ok, integrals


def average_split(model: Model, params: Mapping[str, np.ndarray], *, rtol: float, method: str = "auto"
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """E_avg of a dielectric: combinations with η > 1 by :func:`average`, those with η < 1 by the generic
    :func:`brdfnorm.lut.table.average_over_mu` (module docstring)."""
    M = len(next(iter(params.values()))) if params else 1
    flat = {n: np.broadcast_to(np.asarray(v, dtype=float).ravel(), (M,)) for n, v in params.items()}
    eta = flat.get("eta", np.full(M, float(model.params["eta"])))
    value, error, converged = np.empty(M), np.empty(M), np.empty(M, dtype=bool)
    integrals = 0
    for rows, route in ((np.flatnonzero(eta > 1.0), average), (np.flatnonzero(eta <= 1.0), T.average_over_mu)):
        if rows.size:
            v, e, c, n = route(model, {k: x[rows] for k, x in flat.items()}, rtol=rtol, method=method)
            value[rows], error[rows], converged[rows] = v, e, c
            integrals += n
    return value, error, converged, integrals


T.AVERAGE_ROUTES["transmits"] = average_split
