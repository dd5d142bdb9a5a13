"""A case with several separated peaks integrated as one sub-case per peak, by a smooth partition of unity.

What it computes
----------------
A case whose integrand g has peaks P_1 (the main one) … P_m (:func:`brdfnorm.engine.machinery.lobe_search.
search_lobes`) is integrated as m sub-cases: sub-case j ≥ 2 integrates g·χ_j over the cap of radius R_j about P_j,
sub-case 1 integrates g·(1 − Σ_j χ_j) over the hemisphere, with

    χ_j(ω) = ½ erfc((α_j − :data:`MIDDLE` R_j)/(:data:`SPREAD` R_j)) for α_j < R_j, else 0,   α_j = ∠(ω, P_j),

R_j :data:`REACH` of the distance from P_j to the main peak and at most half that to the nearest other
separated peak: an analytic step (the global rule's estimates assume
geometric convergence, which a C^∞ bump step e^(−1/t) does not give: 3 times the estimate at rtol 1e-10) cut where
it is 1e-17. The caps do not overlap and contain no other peak, so the χ_j and 1 − Σ χ_j are a partition of unity
and the sub-cases' integrals add up to the albedo whatever peaks were found: a spurious peak costs evaluations,
never correctness. Each sub-case is single-peaked about its own pole: sub-case j sees its lobe whole well inside
R_j and the step, a function of α_j alone, end at its cap's edge (its domain's ``support``: the lobe-aligned
coordinates of :mod:`brdfnorm.engine.routes.hemisphere` put it on their boundary); sub-case 1 sees its lobe with
holes where the others were, their edges a fifth of the holes' radii wide. Nothing of a lobe leaks into another's
sub-case (a rational partition, k_j = (w_j² + |ω − P_j|²)^−p, left copies of each lobe damped by (w/d)^(2p) in
every other sub-case, and its turnover, ~d/p wide, broke the honesty of broad lobes: Blinn-Phong n = 43 with a
second lobe 0.72 rad away, 2.5 times its estimate at rtol 1e-6).

:func:`fold` adds the sub-cases' values, error estimates (times :data:`MARGIN`) and evaluations back into their
cases; a case is converged
where all its sub-cases are, its reason the first non-empty one, its share of the hemisphere where the integrand
was not finite the largest of its sub-cases'.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import special

from .directions import angle_between
from .lobe_search import Peaks
from .result import RouteResult

#: The sub-cases' summed error estimate is charged this many times over (and their tolerance is this much tighter,
#: so that the case still converges): the steps are features the rules' estimates were not validated on, and the
#: global rule's extrapolated estimate of a broad lobe with a hole fell short of its true error (Blinn-Phong
#: n = 91 with a second lobe m = 349 at 2.2 rad, θ_o = 52.8°, rtol 1e-8: 1.26e-12 for 1.50e-12, ratio 1.18).
MARGIN = 4.0
#: A cap reaches this share of the way to its case's main peak: the wider the cap, the gentler the edges of the hole
#: it leaves in the main peak's sub-case (half the way: Blinn-Phong n = 101 at θ_o = 73°, width 0.19, a second lobe
#: 0.34 rad away, 7 times the estimate at rtol 1e-6).
REACH = 0.9
#: Where each cap's step is ½, and its scale σ, as shares of its radius R: χ = ½ erfc((α − MIDDLE·R)/(SPREAD·R)),
#: 1 − 1e-37 at its pole, 1e-17 (then 0) at its edge.
MIDDLE = 0.6
SPREAD = 0.4 / 6


@dataclass(frozen=True)
class SubCases:
    """S sub-cases of k cases: the ``owner`` case of each (S,, an index into the k), its lobe (``poles`` (S, 3),
    ``widths``, ``supports`` (S,): a cap's radius R for a separated peak), and the partition: the separated peaks of
    its owner (``centres`` (S, m, 3), ``radii`` (S, m), padded with radius 0, which weighs nothing) and which of them
    is its own (``own`` (S,), −1 for the main peak's sub-case)."""

    owner: np.ndarray
    poles: np.ndarray
    widths: np.ndarray
    supports: np.ndarray
    centres: np.ndarray
    radii: np.ndarray
    own: np.ndarray

    def weight(self, omega: np.ndarray, sub: np.ndarray) -> np.ndarray:
        """The partition's weight of sub-case ``sub`` (M,) at ``omega`` (M, 3): (M,)."""
        centres, radii, own = self.centres[sub], self.radii[sub], self.own[sub]
        steps = np.stack([_step(omega, centres[:, j], radii[:, j]) for j in range(centres.shape[1])], axis=1)
        mine = np.take_along_axis(steps, np.maximum(own, 0)[:, None], axis=1)[:, 0]
        return np.where(own < 0, 1.0 - steps.sum(axis=1), mine)

    def wrap(self, integrand):
        """g times the weight of each sub-case, from ``integrand(omega, sub)``, g of the sub-cases' owners (a batch
        whose case i is sub-case i's owner)."""
        def weighted(omega: np.ndarray, sub: np.ndarray) -> np.ndarray:
            values = np.asarray(integrand(omega, sub), dtype=float)
            return values * self.weight(omega, sub)[:, None]

        return weighted


def _step(omega: np.ndarray, centre: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """χ of caps of ``radius`` (M,) about ``centre`` (M, 3) at ``omega`` (M, 3) (0 where the radius is 0)."""
    angle = angle_between(omega, centre)
    with np.errstate(divide="ignore", invalid="ignore"):
        scaled = (angle - MIDDLE * radius) / (SPREAD * radius)
    return np.where((radius > 0) & (angle < radius), 0.5 * special.erfc(np.nan_to_num(scaled, nan=np.inf)), 0.0)


def expand(poles: np.ndarray, widths: np.ndarray, supports: np.ndarray, peaks: Peaks,
           cases: np.ndarray) -> SubCases:
    """The sub-cases of the cases ``cases`` (indices into ``poles``, ``widths``, ``supports``, the main peaks, and
    into ``peaks.case``): per case its main peak first, then its separated peaks; ``owner`` indexes ``cases``."""
    position = np.full(poles.shape[0], -1, dtype=np.intp)
    position[cases] = np.arange(cases.size)
    extra = np.flatnonzero(position[peaks.case] >= 0)
    owner_extra = position[peaks.case[extra]]
    order = np.argsort(owner_extra, kind="stable")
    extra, owner_extra = extra[order], owner_extra[order]
    rank = np.arange(extra.size) - np.searchsorted(owner_extra, owner_extra)
    m = int(rank.max()) + 1 if extra.size else 0
    centres = np.zeros((cases.size, m, 3))
    radii = np.zeros((cases.size, m))
    centres[owner_extra, rank] = peaks.direction[extra]
    # Each cap's radius: REACH of the distance to its case's main peak (whose core then sees χ < 1e-17), and half
    # the distance to the nearest other separated peak (whose cap it then does not overlap).
    every = np.concatenate([poles[cases][:, None], centres], axis=1)
    present = np.concatenate([np.ones((cases.size, 1), dtype=bool), np.zeros((cases.size, m), dtype=bool)], axis=1)
    present[owner_extra, 1 + rank] = True
    mine = every[owner_extra, 1 + rank]
    apart = angle_between(mine[:, None], every[owner_extra])
    apart = np.where(present[owner_extra], apart, np.inf)
    apart[np.arange(extra.size), 1 + rank] = np.inf
    apart[:, 0] *= 2.0 * REACH
    radii[owner_extra, rank] = np.minimum(apart.min(axis=1) / 2.0, np.pi)
    owner = np.concatenate([np.arange(cases.size), owner_extra])
    own = np.concatenate([np.full(cases.size, -1), rank])
    return SubCases(owner, np.concatenate([poles[cases], peaks.direction[extra]]),
                    np.concatenate([widths[cases], peaks.width[extra]]),
                    np.concatenate([supports[cases], radii[owner_extra, rank]]), centres[owner], radii[owner], own)


def fold(result: RouteResult, sub: SubCases, cases: int) -> RouteResult:
    """The sub-cases' ``result`` added back into their ``cases`` owners (the module's docstring says how)."""
    value = np.zeros((cases,) + result.value.shape[1:])
    error = np.zeros_like(value)
    np.add.at(value, sub.owner, result.value)
    np.add.at(error, sub.owner, MARGIN * result.error)
    evaluations = np.bincount(sub.owner, weights=result.evaluations, minlength=cases).astype(np.int64)
    converged = np.bincount(sub.owner, weights=~np.asarray(result.converged), minlength=cases) == 0
    reason = np.full(cases, "", dtype=object)
    for s, why in enumerate(result.reasons()):
        if why and not reason[sub.owner[s]]:
            reason[sub.owner[s]] = why
    nonfinite = np.zeros(cases)
    np.maximum.at(nonfinite, sub.owner, np.asarray(result.extras.get("nonfinite_fraction", np.zeros(sub.owner.size))))
    return RouteResult(value, error, evaluations, converged, reason.astype(str), {"nonfinite_fraction": nonfinite})
