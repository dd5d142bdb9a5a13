"""A case with several separated peaks integrated as one sub-case per peak, by a smooth partition of unity.

What it computes
----------------
A case whose integrand g has peaks P_1 (the main one) … P_m, of widths w_1 … w_m
(:func:`brdfnorm.engine.machinery.lobe_search.search_lobes`), is integrated as m sub-cases, sub-case i integrating
g·ψ_i over the hemisphere with

    ψ_i(ω) = k_i(ω) / Σ_j k_j(ω),   k_j(ω) = (w_j² + |ω − P_j|²)^(−p),   p = :data:`EXPONENT`,

computed as ψ_i = 1 / Σ_j ((w_i² + |ω − P_i|²) / (w_j² + |ω − P_j|²))^p, which neither overflows nor divides 0
by 0, and |ω − P|² summed from the component differences (2 − 2ω·P would lose the small angles of a narrow core).
Σ_i ψ_i = 1, so the sub-cases' integrals add up to the albedo whatever peaks were found: a spurious peak costs
evaluations, never correctness. Each ψ_i is smooth, ≈ 1 on its own core and ≈ (w_j/d_ij)^(2p) on the core of peak
j at distance d_ij, so each sub-case is single-peaked about its own pole P_i with its own width w_i — what the
lobe-aligned coordinates of :mod:`brdfnorm.engine.routes.hemisphere` are built for, where a narrow second lobe
35° from the main peak fell between all their nodes (docs/numerics.md).

:func:`fold` adds the sub-cases' values, error estimates and evaluations back into their cases; a case is converged
where all its sub-cases are, its reason the first non-empty one, its share of the hemisphere where the integrand
was not finite the largest of its sub-cases' (each sees the whole of it: ψ multiplies a NaN into a NaN).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .lobe_search import Peaks
from .result import RouteResult

#: The exponent p of the partition's kernels: the cores of the other peaks are damped to (w/d)^(2p) and the
#: partition turns over within ~d/p of the boundary between two peaks at distance d, smooth on the scale of the
#: lobe-aligned panels.
EXPONENT = 8


@dataclass(frozen=True)
class SubCases:
    """S sub-cases of k cases: the ``owner`` case of each (S,, an index into the k), its lobe (``poles`` (S, 3),
    ``widths``, ``supports`` (S,)), and the partition: every peak of its owner (``centres`` (S, m, 3), ``sizes``
    (S, m), padded with infinite widths, which weigh nothing) and which of them is its own (``own`` (S,))."""

    owner: np.ndarray
    poles: np.ndarray
    widths: np.ndarray
    supports: np.ndarray
    centres: np.ndarray
    sizes: np.ndarray
    own: np.ndarray

    def weight(self, omega: np.ndarray, sub: np.ndarray) -> np.ndarray:
        """ψ of sub-case ``sub`` (M,) at ``omega`` (M, 3): (M,)."""
        centres, sizes = self.centres[sub], self.sizes[sub]
        mine = np.arange(sub.size)
        own = sizes[mine, self.own[sub]]**2 + ((omega - centres[mine, self.own[sub]])**2).sum(axis=-1)
        total = np.zeros(sub.size)
        with np.errstate(over="ignore"):
            for j in range(centres.shape[1]):
                # (a padded peak: own / inf = 0; an overflow: ψ = 0, as it is to float64's precision)
                total += (own / (sizes[:, j]**2 + ((omega - centres[:, j])**2).sum(axis=-1)))**EXPONENT
        return 1.0 / total

    def wrap(self, integrand):
        """g·ψ of each sub-case, from ``integrand(omega, sub)``, g of the sub-cases' owners (a batch whose case i is
        sub-case i's owner)."""
        def weighted(omega: np.ndarray, sub: np.ndarray) -> np.ndarray:
            values = np.asarray(integrand(omega, sub), dtype=float)
            return values * self.weight(omega, sub)[:, None]

        return weighted


def expand(poles: np.ndarray, widths: np.ndarray, supports: np.ndarray, peaks: Peaks,
           cases: np.ndarray) -> SubCases:
    """The sub-cases of the cases ``cases`` (indices into ``poles``, ``widths``, ``supports``, the main peaks, and
    into ``peaks.case``): per case its main peak first, then its separated peaks; ``owner`` indexes ``cases``."""
    position = np.full(poles.shape[0], -1, dtype=np.intp)
    position[cases] = np.arange(cases.size)
    extra = position[peaks.case] >= 0
    owner_extra = position[peaks.case[extra]]
    owner = np.concatenate([np.arange(cases.size), owner_extra])
    order = np.argsort(owner, kind="stable")  # each case's sub-cases together, the main one first
    owner = owner[order]
    sub_poles = np.concatenate([poles[cases], peaks.direction[extra]])[order]
    sub_widths = np.concatenate([widths[cases], peaks.width[extra]])[order]
    sub_supports = np.concatenate([supports[cases], np.full(owner_extra.size, np.pi)])[order]
    rank = np.arange(owner.size) - np.searchsorted(owner, owner)
    m = int(rank.max()) + 1
    centres = np.zeros((cases.size, m, 3))
    sizes = np.full((cases.size, m), np.inf)
    centres[owner, rank] = sub_poles
    sizes[owner, rank] = sub_widths
    return SubCases(owner, sub_poles, sub_widths, sub_supports, centres[owner], sizes[owner], rank)


def fold(result: RouteResult, sub: SubCases, cases: int) -> RouteResult:
    """The sub-cases' ``result`` added back into their ``cases`` owners (the module's docstring says how)."""
    value = np.zeros((cases,) + result.value.shape[1:])
    error = np.zeros_like(value)
    np.add.at(value, sub.owner, result.value)
    np.add.at(error, sub.owner, result.error)
    evaluations = np.bincount(sub.owner, weights=result.evaluations, minlength=cases).astype(np.int64)
    converged = np.bincount(sub.owner, weights=~np.asarray(result.converged), minlength=cases) == 0
    reason = np.full(cases, "", dtype=object)
    for s, why in enumerate(result.reasons()):
        if why and not reason[sub.owner[s]]:
            reason[sub.owner[s]] = why
    nonfinite = np.zeros(cases)
    np.maximum.at(nonfinite, sub.owner, np.asarray(result.extras.get("nonfinite_fraction", np.zeros(sub.owner.size))))
    return RouteResult(value, error, evaluations, converged, reason.astype(str), {"nonfinite_fraction": nonfinite})
