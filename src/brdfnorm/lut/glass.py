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
from .adaptive import adaptive_unit_interval

#: The adaptive fallback's map μ = t⁴ (dμ 2μ = 8t⁷ dt: the grazing end graded).
MAPS = {(4, 1): (lambda t: t**4, lambda t: 4.0 * t**3)}
#: G7/K15 panels a segment may split into before it gives up.
MAX_PANELS = 200


class _Nodes:
    """Albedos at μ(t) of many segments: batched per (map, rtol level), with the density ρ(t) = 2μ dμ/dt."""

    def __init__(self, model: Model, params: Mapping[str, np.ndarray], rtol: float, method: str) -> None:
        self.model, self.params, self.rtol, self.method = model, params, rtol, method
        self.integrals = 0

    def __call__(self, owner, a, b, maps, t):
        """owner, a, b (S,), maps (S,) list, t (S, n): (ρ·E, ρ·E_error, converged (S,), max|E| (S,))."""
        mu, density = np.empty_like(t), np.empty_like(t)
        for key in set(maps):
            rows = np.array([m == key for m in maps])
            h, dh = MAPS[key]
            width = (b - a)[rows, None]
            mu[rows] = a[rows, None] + width * h(t[rows])
            density[rows] = 2.0 * mu[rows] * width * dh(t[rows])
        # A node's albedo enters through ρ (≤ 1 almost everywhere): rtol/(4·min(1, ρ)) keeps Σ w ρ error within
        # (rtol/4) max E, rounded down to powers of NODE_RTOL_STEP so the nodes go in a few batched calls.
        ratio = 1.0 / np.minimum(1.0, np.maximum(density, 1e-300))
        cap = np.log(T.NODE_RTOL_MAX / (self.rtol / 4)) / np.log(T.NODE_RTOL_STEP)
        level = np.clip(np.floor(np.log(ratio) / np.log(T.NODE_RTOL_STEP)), 0, max(np.ceil(cap), 0))
        theta = np.arccos(np.clip(np.maximum(mu, T.MU_FLOOR), 0.0, 1.0))
        value, error = np.zeros_like(t), np.zeros_like(t)
        ok = np.ones(t.shape, dtype=bool)
        per_node = {n: np.broadcast_to(v[owner][:, None], t.shape) for n, v in self.params.items()}
        live = density > 0  # t = 0: weight 0, never evaluated
        for step in np.unique(level[live]):
            nodes = live & (level == step)
            cells = T.compute_cells(self.model, theta[nodes], {n: v[nodes] for n, v in per_node.items()},
                                    rtol=max(self.rtol / 4, min(self.rtol / 4 * T.NODE_RTOL_STEP**step,
                                                                T.NODE_RTOL_MAX)), method=self.method)
            value[nodes], error[nodes] = T._single_channel(cells.value, cells.error, self.model)
            ok[nodes] = cells.converged
            self.integrals += int(nodes.sum())
        return density * value, density * error, ok.all(axis=1), np.abs(value).max(axis=1)


#: Double-exponential levels: steps DE_FIRST_STEP / 2^k for k < DE_LEVELS, nodes |u| ≤ DE_RANGE.
DE_FIRST_STEP = 0.5
DE_LEVELS = 6
DE_RANGE = 3.5
#: Nodes whose weight h·ρ is below this (times rtol) are not evaluated; their bound joins the error.
DE_SKIP = 1e-4


def _de_nodes(a, b, u):
    """tanh-sinh nodes μ(u) on [a, b] (per segment rows, u (S, n)) and the density ρ = 2μ dμ/du, computed
    from the nearer end (no cancellation next to either end)."""
    s = 0.5 * np.pi * np.sinh(u)
    e = np.exp(-2.0 * np.abs(s))
    gap = (b - a)[:, None] * e / (1.0 + e)  # distance from the nearer end
    mu = np.where(u < 0, a[:, None] + gap, b[:, None] - gap)
    dmu = (b - a)[:, None] * 0.25 * np.pi * np.cosh(u) * 4.0 * e / (1.0 + e) ** 2  # (π/4) cosh u / cosh² s
    return mu, 2.0 * mu * dmu


def _double_exponential(model, params, owner, a, b, rtol, method):
    """tanh-sinh per segment, step halving (nested): (value, error, settled, albedos ok, max|E|, integrals).

    The error of a level is |Q_h − Q_2h| (the coarser level's error, pessimistic for Q_h, which is kept) plus the
    albedo errors through the weights, plus 2·S_h + S_2h for the skipped nodes (S: their weights times the bound
    max(1, max|E|) on E — a single-scattering BSDF scatters at most what arrives), plus the tails beyond |u| =
    DE_RANGE, bounded in closed form (below 1e-22 of the segment)."""
    S = owner.size
    flat = {n: np.asarray(v, dtype=float)[owner] for n, v in params.items()}
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
        mu, rho = _de_nodes(a[rows], b[rows], np.broadcast_to(u, (rows.size, u.size)))
        skip = rho * step < DE_SKIP * rtol
        live = ~skip & (rho > 0)
        # Node albedo tolerances as in table._node_albedos, by the weight ρ·2·DE_RANGE (Σ h ρ ≈ the segment).
        ratio = 1.0 / np.minimum(1.0, np.maximum(rho * 2.0 * DE_RANGE, 1e-300))
        cap = np.log(T.NODE_RTOL_MAX / (rtol / 4)) / np.log(T.NODE_RTOL_STEP)
        tier = np.clip(np.floor(np.log(ratio) / np.log(T.NODE_RTOL_STEP)), 0, max(np.ceil(cap), 0))
        E, E_error = np.zeros(mu.shape), np.zeros(mu.shape)
        good = np.ones(mu.shape, dtype=bool)
        theta = np.arccos(np.clip(np.maximum(mu, T.MU_FLOOR), 0.0, 1.0))
        for t in np.unique(tier[live]):
            nodes = live & (tier == t)
            which = np.broadcast_to(rows[:, None], mu.shape)[nodes]
            cells = T.compute_cells(model, theta[nodes], {n: v[which] for n, v in flat.items()},
                                    rtol=max(rtol / 4, min(rtol / 4 * T.NODE_RTOL_STEP**t, T.NODE_RTOL_MAX)),
                                    method=method)
            E[nodes], E_error[nodes] = T._single_channel(cells.value, cells.error, model)
            good[nodes] = cells.converged
            integrals += int(nodes.sum())
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
    # Beyond |u| = DE_RANGE: μ within (b − a)·e^{−2s} of an end, s = (π/2) sinh(DE_RANGE) ≈ 26: ∫ 2μ E dμ there
    # ≤ 2 (b − a) e^{−2s} max(1, max|E|).
    tail = 2.0 * (b - a) * np.exp(-np.pi * np.sinh(DE_RANGE)) * np.maximum(1.0, largest)
    error = error + tail
    return value, error, ~open_, ok, largest, integrals


def _adaptive(nodes: _Nodes, owner, a, b, maps, rtol):
    """Globally adaptive G7/K15 in t per segment (as table._average_adaptive): (value, error, settled, ok, max|E|)."""
    S = owner.size
    ok, largest = np.ones(S, dtype=bool), np.zeros(S)

    def evaluate(seg, left, width):
        t = left[:, None] + 0.5 * width[:, None] * (T.KRONROD_NODES + 1.0)
        g, g_error, ok_p, big = nodes(owner[seg], a[seg], b[seg], [maps[s] for s in seg], t)
        ok[seg[~ok_p]] = False
        np.maximum.at(largest, seg, big)
        half = 0.5 * width
        kronrod = half * (g @ T.KRONROD_WEIGHTS)
        difference = np.abs(kronrod - half * (g @ T.GAUSS_WEIGHTS))
        return kronrod, difference + half * (g_error @ np.abs(T.KRONROD_WEIGHTS))

    total, total_error = adaptive_unit_interval(evaluate, S, rtol=rtol, max_panels=MAX_PANELS)
    return total, total_error, total_error <= rtol * np.abs(total), ok, largest


def average(model: Model, params: Mapping[str, np.ndarray], *, rtol: float, method: str = "auto"
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """E_avg for M parameter combinations (name -> (M,)), every η > 1: (value, error, converged, albedo integrals
    computed), as :func:`brdfnorm.lut.table.average_over_mu` returns them."""
    M = len(next(iter(params.values())))
    flat = {n: np.broadcast_to(np.asarray(v, dtype=float).ravel(), (M,)) for n, v in params.items()}
    owner, a, b, maps = np.arange(M), np.zeros(M), np.ones(M), [(4, 1)] * M
    value, error, settled, ok, largest, integrals = _double_exponential(model, flat, owner, a, b, rtol, method)
    nodes = _Nodes(model, flat, rtol, method)
    rest = np.flatnonzero(~settled)
    if rest.size:
        v, e, s, o, big = _adaptive(nodes, owner[rest], a[rest], b[rest], [maps[r] for r in rest], rtol)
        value[rest], error[rest], settled[rest], ok[rest] = v, e, s, o
        largest[rest] = np.maximum(largest[rest], big)
    error = error + T.MU_FLOOR**2 * largest  # nodes below MU_FLOOR evaluated there
    return value, error, settled & ok, integrals + nodes.integrals


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
