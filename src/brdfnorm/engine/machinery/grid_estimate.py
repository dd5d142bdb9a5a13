"""The error of the global tensor rule's *reported* grid, extrapolated where its convergence is shown to be
geometric (issue 39, item 5: evaluations per generic albedo).

The plain estimate of :func:`brdfnorm.engine.machinery.tensor_rule.sums` along a direction, d₁ + min(d₂, 9 d₁)
with d₁ = |Q − Q(½)|, d₂ = |Q(½) − Q(¼)|, is the error of the embedded rule with *half* the nodes. Once the rule
converges geometrically (the periodic trapezoid rule on an analytic integrand, Trefethen & Weideman, SIAM Review
56, 2014; Fejér's rule likewise, its error ~ ρ⁻ᴺ) each doubling squares the reduction, and the reported Q(M, N) is
far more accurate than that: Blinn-Phong n = 100 at θ_o = 30°, rtol 1e-9, the 32 × 63 grid is 3e-15 off while its
plain estimate is 8e-7, so the rule doubled both directions once more (×4 in nodes) for nothing.

Here, per direction, with also d₃ = |Q(¼) − Q(⅛)| (every eighth node, on the grid too), the last fall r = d₁/d₂
and the one before it, r₋ = d₂/d₃, the estimate is

    :data:`SAFETY` · d₁ · r^p,   p = :data:`POWER_B` along β, :data:`POWER_U` along u,

never above the plain estimate nor below the estimate's rounding terms, and only where

* *converging*: both falls are at least :data:`CONVERGING`-fold (the ``.brdf`` table's E_avg rule,
  :func:`brdfnorm.lut.table.rule_error`, whose power 0.75 is also the one along u here);
* *geometric*: r₋²/:data:`ACCELERATION` ≤ r ≤ :data:`GEOMETRIC`·r₋². A fall much steeper than the square of the
  one before is not convergence but a coincidence or a pre-asymptotic phase, which ends (Blinn-Phong n = 268 at
  34°, rtol 1e-11: u fell 16-fold, then 38 000-fold, 146 times steeper than the square; extrapolated, 4.6 times
  outside the estimate); a steady ratio (r ≈ r₋) is algebraic convergence, whose ratio drifts (Blinn-Phong
  n = 6 667 at 85.0°, rtol 1e-5: u fell 105-, 125-, then only 14-fold; 1.34 times outside);
* the coarsest embedded rule has at least :data:`COARSEST_B` azimuths / :data:`COARSEST_U` radial nodes (a
  1-node rule says nothing: examples/beckmann.brdf, α = 0.24 at 2.4°, rtol 1e-3, settled on its start grid 2.4
  times outside before the geometric band above was added, which refuses it too);
* the lobe's peak lies at least :data:`HORIZON` widths above the horizon (c_P ≥ w): the horizon's cut, a
  feature the lobe-aligned coordinates do not follow, adds a slowly converging part under the fast bulk
  (beckmann.brdf, α = 0.10 at 85.5°, rtol 1e-5: u fell 31-, 146-, then only 6-fold, 2.1 times outside);
* the lobe is not heavy-tailed (:func:`brdfnorm.engine.machinery.tensor_rule._heavy_tailed`, GGX-like): its Smith
  boundary layer at the horizon makes plateaus that three differences cannot tell from convergence
  (examples/ggx.brdf, roughness 0.418 at 11.9°, rtol 1e-9: u fell 255-, then 96 000-fold — squaring — yet the 15-
  and 31-node rules were both 2.5e-9 off; 1 373 times outside);
* d₁ is above :data:`RESOLVED` units of rounding of the |integrand| integral (differences of rounding noise are
  not convergence).

The margins: were the next fall as steep as the last, the true error would be r·d₁, and the estimate is
S·r^(p−1) times that — at least 4 (u) and 8 (β) for r ≤ 1/16, more as r falls; under geometric convergence
(error r²·d₁) far more. It fails only where the next fall is slower than the last by more than that margin,
which the guards above are there to exclude. Power 1 (a margin of 2) failed along both directions: Phong n = 79
at 40.9°, rtol 1e-11, u squaring exactly (r = 7.6e-5 after 1.05e-2), then the next fall only 3.4e-4, 1.007 times
outside; beckmann.brdf α = 0.33 at 73.5° (before the horizon guard), β falling 1e-2, then 1e-4 — squaring — then
only 270-fold, 19 times outside. Measured mean evaluations and honesty ratios per variant are in
docs/performance.md ("Where the evaluations of a generic albedo go", fourth session); the cases of the geometric
band, the horizon and the heavy tails are tests in tests/engine/test_grid_estimate.py that fail with their guard
off. (Berntsen and Espelid 1991, "Error estimation in automatic quadrature routines", decide by such ratios whether
a rule is in its asymptotic range.)

The same band read the other way guards the plain estimate of every global grid (:func:`sudden`): at 16 azimuths,
the first level a unit may settle, a fall steeper than :data:`ACCELERATION` times the square of the one before
keeps the coarser difference d₂ in the estimate.
"""

from __future__ import annotations

import numpy as np

#: Both of the last two differences along a direction must have fallen at least this many times.
CONVERGING = 16.0
#: The last fall may be at most this many times steeper than the square of the fall before it (geometric
#: convergence squares it; a steeper one is pre-asymptotic or a coincidence) ...
ACCELERATION = 2.0
#: ... and at most this many times shallower: a steady ratio (r ≈ r₋) is algebraic convergence, not geometric.
GEOMETRIC = 8.0
#: The extrapolation's power of the last fall along β and along u (below 1: a margin against a slower next
#: fall, which grows as the fall steepens).
POWER_B = 0.5
POWER_U = 0.75
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
                 power: float) -> np.ndarray:
    """The estimate (module docstring) from one direction's differences ``d`` (3, n, C) and its plain estimate
    ``plain`` (n, C): the extrapolation with ``power`` where the direction converges geometrically, else ``plain``;
    ``magnitude`` (n, C) is the integral of |integrand|, ``rounding`` (n, C) the rounding terms of the whole
    estimate (the extrapolation never goes below them, nor above ``plain``)."""
    d1, d2, d3 = d
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        fall, before = d1 / d2, d2 / d3
        converging = (d1 * CONVERGING <= d2) & (d2 * CONVERGING <= d3)
        squared = before * before
        geometric = (fall * ACCELERATION >= squared) & (fall <= GEOMETRIC * squared)
        estimate = SAFETY * d1 * fall**power
    use = converging & geometric & np.isfinite(estimate) & (d1 > RESOLVED * _EPS * magnitude)
    return np.where(use, np.minimum(np.maximum(estimate, rounding), plain), plain)


def own_error(F: np.ndarray, weights: list[np.ndarray], e_b: np.ndarray, e_u: np.ndarray, magnitude: np.ndarray,
              rounding: np.ndarray, height: np.ndarray, width: np.ndarray, heavy: np.ndarray,
              d: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The β and u estimates of the reported grid ``F`` (n, M, N − 1, C), ``weights`` as in :func:`deviations`, from
    the plain ones ``e_b``, ``e_u`` and the |integrand| integral ``magnitude`` (n, C) of
    :func:`brdfnorm.engine.machinery.tensor_rule.sums`; ``rounding`` (n, C): the estimate's rounding floor and noise
    bound; ``height``, ``width`` (n,): the lobe's peak height c_P above the horizon and its width w; ``heavy`` (n,):
    whether the lobe is heavy-tailed (:func:`brdfnorm.engine.machinery.tensor_rule._heavy_tailed`); ``d``: the
    grid's :func:`deviations` where the caller has them."""
    clear = ((height >= HORIZON * width) & ~heavy)[:, None]
    along_b, along_u = F.shape[1] >= 8 * COARSEST_B, weights[3].size >= COARSEST_U
    if not (clear.any() and (along_b or along_u)):
        return e_b, e_u
    d_b, d_u = deviations(F, weights) if d is None else d
    if along_b:
        e_b = np.where(clear, extrapolated(d_b, e_b, magnitude, rounding, POWER_B), e_b)
    if along_u:
        e_u = np.where(clear, extrapolated(d_u, e_u, magnitude, rounding, POWER_U), e_u)
    return e_b, e_u


def sudden(F: np.ndarray, weights: list[np.ndarray], e_b: np.ndarray, e_u: np.ndarray,
           magnitude: np.ndarray, d: tuple | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The β estimate ``e_b`` (n, C) of a grid ``F`` (n, M, N − 1, C) at the first level where a unit may settle
    (M = 16: the global driver never settles one on the 8 start azimuths), raised to d₁ + d₂ where the last fall
    d₂/d₁ is more than :data:`ACCELERATION` times steeper than the square of the fall before it, d₃/d₂
    (``weights`` as in :func:`deviations`); ``e_u`` and other levels as they are.

    Why: the plain estimate d₁ + min(d₂, 9 d₁) trusts that the next difference is at most nine times the last. A
    sudden agreement of the 16- and 8-azimuth rules after a large difference of the 8- and 4-azimuth ones —
    steeper than geometric convergence allows — is no such evidence: a kink or a feature narrower than the
    nodes' spacing can fall between both rules' nodes, and the next level moves again (examples/oren_nayar.brdf,
    σ = 0.871 at θ_o = 29.67°, rtol 1e-3: the half-vector rectangle's horizon piece fell 2.7e5-fold from 8 to 16
    azimuths, 2 070 times the square of the fall before, d₁ = 3.5e-8, then moved 1.8e-4 at 32; the albedo settled
    3.9 times outside its estimate). The estimate then keeps the coarser pair's difference d₂, which sends the
    unit on to 32 azimuths, where d₃ is no longer a 2-azimuth rule's and the stall check of
    :func:`brdfnorm.engine.machinery.tensor_rule._stalled` and the band of :func:`extrapolated` see three levels.
    Only there: at every level (and along u) the same test took Blinn-Phong n = 100 at rtol 1e-9 from 6 989 to
    14 822 (22 501) evaluations per albedo, its β falls up to 955 times steeper than the square before
    convergence; at M = 16 only, 7 012. Differences at rounding level (:data:`RESOLVED`) are not falls. ``d``: the
    grid's :func:`deviations` where the caller has them."""
    if F.shape[1] != 16:
        return e_b, e_u
    d1, d2, d3 = (deviations(F, weights) if d is None else d)[0]
    resolved = RESOLVED * _EPS * magnitude
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        # (a fall to below the rounding counts as one to the rounding: 0 against 1e-17 decided it by the rounding
        # of the backend, Blinn-Phong n = 100 at 1°, rtol 1e-9)
        steep = d2 * d2 * d2 > ACCELERATION * np.maximum(d1, resolved) * d3 * d3  # d₂/d₁ > ACCELERATION · (d₃/d₂)²
    steep &= np.maximum(d1, d2) > resolved
    return np.where(steep, np.maximum(e_b, d1 + d2), e_b), e_u
