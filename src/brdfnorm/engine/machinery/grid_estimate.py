"""The error of the global tensor rule's *reported* grid, extrapolated where convergence is shown to be geometric
(issue 39, item 5: evaluations per generic albedo).

The plain estimate of :func:`brdfnorm.engine.machinery.tensor_rule.sums` along a direction, d₁ + min(d₂, 9 d₁)
with d₁ = |Q − Q(½)|, d₂ = |Q(½) − Q(¼)|, is the error of the embedded rule with *half* the nodes. Once the rule
converges geometrically (the periodic trapezoid rule on an analytic integrand, Trefethen & Weideman, SIAM Review
56, 2014; Fejér's rule likewise, its error ~ ρ⁻ᴺ) each doubling squares the reduction, and the reported Q(M, N) is
far more accurate than that: Blinn-Phong n = 100 at θ_o = 30°, rtol 1e-9, the 32 × 63 grid is 3e-15 off while its
plain estimate is 8e-7, so the rule doubled both directions once more (×4 in nodes) for nothing.

Here, per direction, with also d₃ = |Q(¼) − Q(⅛)| (every eighth node, on the grid too):

    converging:  d₁ ≤ d₂ / :data:`CONVERGING` and d₂ ≤ d₃ / :data:`CONVERGING`,
    steady:      d₁ ≥ (d₂/d₃)^:data:`ACCELERATION` · d₂,
    estimate:    :data:`SAFETY` · d₁ · (d₁/d₂)^:data:`POWER`   where both hold, never above the plain one.

With a steady per-doubling reduction r the true error of Q is r·d₁ and the estimate S·r^P·d₁ is S·r^(P−1) times
larger; under geometric convergence the reduction squares at each doubling (e(Q) ≈ r²·d₁), which only widens the
margin. This is the Clenshaw–Curtis rule of the ``.brdf`` table's E_avg (:func:`brdfnorm.lut.table.rule_error`:
power 0.75, both differences falling 16-fold, true errors ≤ 0.18 of the estimates on 90 lobes) with one more
guard, *steady*: a pre-asymptotic plateau — two rules that agree better than either is accurate — shows up as a
last fall d₁/d₂ far steeper than the square of the fall before it (d₂/d₃), since the coincidence, not the rule,
made d₁ small. Geometric convergence has d₁/d₂ ≈ (d₂/d₃)²; a fall steeper than (d₂/d₃)^ACCELERATION keeps the
plain estimate (Berntsen and Espelid 1991, "Error estimation in automatic quadrature routines", decide by such
ratios whether a rule is in its asymptotic range). The numbers that chose the constants, and the cases each guard
is needed for, are in docs/performance.md ("Where the evaluations of a generic albedo go", fourth session) and
tests/engine/test_grid_estimate.py.
"""

from __future__ import annotations

import numpy as np

#: Both of the last two differences along a direction must have fallen at least this many times.
CONVERGING = 16.0
#: The last fall may be at most this many times steeper than the square of the fall before it (geometric
#: convergence squares it; a steeper one is pre-asymptotic or a coincidence).
ACCELERATION = 2.0
#: The extrapolation's power of the last fall along β and along u (below 1: a margin against a slower next
#: fall, which grows as the fall steepens).
POWER_B = 0.5
POWER_U = 0.75
#: Along u, where the last fall is at most the one before to this power (the squaring of geometric convergence
#: seen, not only a steady ratio), the power :data:`POWER_SQUARING`.
SQUARING = 2.0
POWER_SQUARING = 1.0
#: The extrapolation's factor.
SAFETY = 2.0
#: The coarsest embedded rule (every eighth node) must have at least this many azimuths, radial nodes.
COARSEST_B = 4
COARSEST_U = 3
#: Only lobes whose peak lies at least this many widths above the horizon (c_P ≥ HORIZON · w) are extrapolated.
HORIZON = 1.0
#: Differences below this many units of rounding of the |integrand| integral are noise, not convergence.
RESOLVED = 1000.0

_EPS = np.finfo(float).eps


def deviations(F: np.ndarray, weights: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """(d_β, d_u), each (3, n, C): the differences |Q − Q(½)|, |Q(½) − Q(¼)|, |Q(¼) − Q(⅛)| of the embedded rules
    along β (every 2nd, 4th, 8th azimuth) and along u (every 2nd, 4th, 8th radial node) of the weighted grid ``F``
    (n, M, N − 1, C), as in :func:`brdfnorm.engine.machinery.tensor_rule.sums`; ``weights``: the radial rule's
    weights for the N − 1 nodes and for every 2nd, 4th and 8th of them (Fejér's rule at the grid's level and
    one, two, three below)."""
    M = F.shape[1]
    by_channel = F.transpose(0, 1, 3, 2)  # (n, M, C, N − 1)
    over_u = by_channel @ weights[0]
    along_b = [over_u[:, ::step].sum(axis=1) * (2 * np.pi * step / M) for step in (1, 2, 4, 8)]
    along_u = [along_b[0]] + [(by_channel[..., 2**k - 1::2**k] @ weights[k]).sum(axis=1) * (2 * np.pi / M)
                              for k in (1, 2, 3)]
    return tuple(np.abs(np.diff(np.stack(q), axis=0)) for q in (along_b, along_u))


def extrapolated(d: np.ndarray, plain: np.ndarray, magnitude: np.ndarray, rounding: np.ndarray,
                 power: float, squaring_power: float | None = None) -> np.ndarray:
    """The estimate (module docstring) from one direction's differences ``d`` (3, n, C) and its plain estimate
    ``plain`` (n, C): the extrapolation with ``power`` where the direction converges steadily, else ``plain``;
    ``magnitude`` (n, C) is the integral of |integrand|, ``rounding`` (n, C) the rounding terms of the whole
    estimate (the extrapolation never goes below them, nor above ``plain``)."""
    d1, d2, d3 = d
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        fall, before = d1 / d2, d2 / d3
        converging = (d1 * CONVERGING <= d2) & (d2 * CONVERGING <= d3)
        steady = fall * ACCELERATION >= before * before
        if squaring_power is not None:
            power = np.where(fall <= before**SQUARING, squaring_power, power)
        estimate = SAFETY * d1 * fall**power
    use = converging & steady & np.isfinite(estimate) & (d1 > RESOLVED * _EPS * magnitude)
    return np.where(use, np.minimum(np.maximum(estimate, rounding), plain), plain)


def own_error(F: np.ndarray, weights: list[np.ndarray], e_b: np.ndarray, e_u: np.ndarray, magnitude: np.ndarray,
              rounding: np.ndarray, height: np.ndarray, width: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The β and u estimates of the reported grid ``F`` (n, M, N − 1, C), ``weights`` as in :func:`deviations`, from
    the plain ones ``e_b``, ``e_u`` and the |integrand| integral ``magnitude`` (n, C) of
    :func:`brdfnorm.engine.machinery.tensor_rule.sums`; ``rounding`` (n, C): the estimate's rounding floor and noise
    bound."""
    d_b, d_u = deviations(F, weights)
    clear = (height >= HORIZON * width)[:, None]
    rounding = np.where(clear, rounding, np.inf)  # a lobe cut by the horizon keeps the plain estimates
    if F.shape[1] >= 8 * COARSEST_B:
        e_b = extrapolated(d_b, e_b, magnitude, rounding, POWER_B)
    if weights[3].size >= COARSEST_U:
        e_u = extrapolated(d_u, e_u, magnitude, rounding, POWER_U, POWER_SQUARING)
    return e_b, e_u
