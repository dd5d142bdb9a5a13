"""The hemisphere integrator's coordinates, and a global tensor rule with degree doubling on them.

Coordinates (shared with the adaptive panels of :mod:`brdfnorm.engine.routes.hemisphere`, which explains them):
lobe-aligned
polar angles (α, β) about the lobe's peak P, the horizon α_h(β) as the boundary, and the width-adapted radial map
α = w tan(v·A(β)), v = 1 − (1 − u)^p (p = 2, or 3 for heavy tails), on the rectangle (β, u) ∈ [0, 2π) × [0, 1].

The global rule
---------------
On that rectangle the integrand is periodic and, away from float64's limit, analytic in β, and smooth in u. So
before any panel is cut, each case is integrated by one tensor rule over the whole rectangle:

* in β, the periodic trapezoid rule on the smooth periodic map tan(β − π) = λ tan(t − π) (a Möbius map of the
  circle: dβ/dt = λ/(cos²y + λ² sin²y), y = t − π, so nodes 1/λ times denser at β = π and at β = 0
  (dβ/dt = λ at both), 1/λ times sparser at β = ±π/2),
  with λ = c_P + 2w² (P = the peak, w = the lobe's width), at least 2.4 w, clipped to [0.25, 1]
  (:func:`clustering`). β = π points from the peak down to the nearest horizon: for a peak c_P above the
  horizon the lobe's tail is cut there, at α_h ≈ c_P/|cos β|, and the cut profile varies fastest in β there.
  (Measured on Blinn-Phong n = 512 at rtol 1e-9 over
  θ_o = 0…89°, global rule and panels together: 11 700 evaluations per albedo with this map, 19 600 with
  uniform β; nodes clustered at β = ±π/2, where the horizon turns, mixtures of both clusters, and compositions
  were all worse. Broad lobes — GGX at roughness 1 — do best with uniform nodes, hence the 2w².) The floor
  0.25 matters at grazing views only (c_P < 0.25, θ_o > 75°): there stronger clustering starves β ≈ ±π/2, where
  the cut lobe's edges lie (Blinn-Phong n = 512 at 86°, 64 azimuths: error 9e-9 at λ = 0.1, 3e-12 at 0.15,
  9e-16 at 0.3, 1e-5 at 1; a broader lobe's edges lie further out, hence at least 2.4 w). Heavy-tailed lobes
  (GGX), detected on the start grid, restart with the floor 0.6 and the cubic horizon grading
  (:func:`_heavy_tailed`);
* the radial map's width follows an ellipse of axis ratio λ: w(β) = w √(cos²y + λ² sin²y) = w √(λ / (dβ/dt)),
  w along β = 0, π, λw along β = ±π/2 — with the β map, elliptic coordinates about the peak. A half-vector lobe
  seen from V is such an ellipse: a tilt δ of H moves L by 2δ in the plane of incidence and by 2 c_P δ across it
  (L = 2(V·H)H − V), so at grazing views the lobe is a thin sliver along β = 0, π, and a radial map of one width
  put its profile at β ≈ ±π/2 into the first few nodes (Blinn-Phong n = 512 at 86°, 63 radial nodes: error
  1.7e-9 with one width, 1.6e-11 with the ellipse);
  The trapezoid rule converges geometrically for periodic analytic integrands (Trefethen & Weideman, "The
  exponentially convergent trapezoidal rule", SIAM Review 56, 2014), and its node sets are nested when M doubles;
* in u, Fejér's second rule (the interior Clenshaw-Curtis nodes, nested when N doubles; Waldvogel, "Fast
  construction of the Fejér and Clenshaw-Curtis quadrature rules", BIT 46, 2006). No node lies on the horizon
  (u = 1) or the pole (u = 0), where a BRDF may divide by zero.

The error estimate of the M × N rule is built from the deviations of the embedded coarser rules, which cost no
evaluation (every other node, every fourth node): along each direction d₁ + min(d₂, 9 d₁), with d₁ = |Q − Q(½)| and
d₂ = |Q(½) − Q(¼)| (:func:`sums`), plus the rounding floor and the integrand's float64 noise bound
(:mod:`brdfnorm.engine.machinery.rounding`). d₁ is the error of the *coarser* rule; the reported Q(M, N), with twice
the nodes, is
far more accurate once convergence is geometric (its error is roughly the square of d₁, relative). The factor 10
covers pre-asymptotic plateaus, where two rules agree better than either is accurate (a randomized probe found
Blinn-Phong n = 805 at θ_o = 50°, rtol 1e-6, 1.5 times outside the plain d₁). Where convergence along a direction
is shown to be geometric, :mod:`brdfnorm.engine.machinery.grid_estimate` replaces that estimate by one of the
reported grid itself, extrapolated from d₁, d₂ and d₃ = |Q(¼) − Q(⅛)|. The direction(s) whose estimate
exceeds half the tolerance (the larger one where neither does) are doubled — only one where the other is within
the whole tolerance alone — and a case whose value stalled over its last two doublings is not settled
(:func:`_stalled`), nor any case on the start azimuths, nor on 16 azimuths after a sudden agreement
(:mod:`brdfnorm.engine.machinery.global_driver`, step 2). A case goes to the adaptive panels of
:mod:`brdfnorm.engine.routes.hemisphere` when it would need more than :data:`MAX_NODES` nodes — predicted early, from
the last
doubling's reduction, assuming each doubling squares it (geometric convergence), or from the radial level its
lobe's neck needs at a grazing view (:func:`neck_u`: no case settles before its coarsest embedded rule has a node
inside the neck) — when its integrand is not finite
at a node, or when its rounding noise is a visible share of its tolerance. The panels are thus paid for only where
needed: narrow lobes near the horizon (Blinn-Phong n = 512 beyond θ_o ≈ 84°), kinks at a support edge, float64's
limit.

Structure
---------
The levels loop is :mod:`brdfnorm.engine.machinery.global_driver`'s, shared by every coordinate system of the rule;
each is a :class:`GlobalGrid` (its methods say what a coordinate system adds to the plain rule). The lobe-aligned
coordinates above are :class:`LobeAlignedGrid` (the hemisphere route calls it through
:mod:`brdfnorm.engine.machinery.hemisphere_global`); the half-vector rectangle is
:class:`brdfnorm.engine.routes.halfvector_global.HalfVectorGrid`.
"""

from __future__ import annotations

from functools import cache

import numpy as np

from . import grid_estimate

_EPS = np.finfo(float).eps

#: Starting levels: M = 2^3 azimuths × N − 1 = 2^4 − 1 radial nodes (120 evaluations).
START_LEVELS = (3, 4)
START_NODES = 2 ** START_LEVELS[0] * (2 ** START_LEVELS[1] - 1)
#: A case needing more nodes than this goes to the adaptive panels.
MAX_NODES = 65_536
#: Azimuths at most: 2^MAX_LEVEL_B.
MAX_LEVEL_B = 10
#: Nodes per integrand call: arrays of this size stay in cache (measured 52 against 79 ns per node for 32 768
#: against 731 520 nodes per call, Blinn-Phong map and lobe together).
CHUNK_NODES = 32_768
#: Grid values held at once (all cases of a batch at their largest grids): 64 MiB per channel.
BATCH_NODES = 2**23
#: The β map's strongest clustering (:func:`clustering`).
LAMBDA_MIN = 0.25
#: The β map's clustering at least this many widths of the lobe (:func:`clustering`).
WIDTH_CLUSTERING = 2.4
#: The floor for heavy-tailed lobes (:func:`_heavy_tailed`).
LAMBDA_MIN_HEAVY_TAIL = 0.6
#: The horizon grading's exponent for heavy-tailed lobes (:func:`_heavy_tailed`, :func:`map_grid`).
HEAVY_TAIL_GRADING = 3
#: A lobe is heavy-tailed when this share of its |integrand| on the start grid lies at u ≥ 1/2.
HEAVY_TAIL_SHARE = 0.15
#: The plain deviation's margin (:func:`sums`).
SAFETY = 9.0
#: A level-to-level change of the value larger than this share of the one before is a stall
#: (:func:`_stalled`).
STALL = 0.5
#: Rounding floor per node sum, as QUADPACK's on |K − G|.
FLOOR = 50.0 * _EPS


def neck_u(frame, widths, supports, width_scale=1.0, grading=2) -> np.ndarray:
    """Per case, the u below which the radial map (:func:`map_grid`) at β = ±π/2, with the width ``widths`` ×
    ``width_scale`` and horizon grading exponent ``grading``, covers the lobe's *neck*: the radius c_P·w about a
    peak c_P above the horizon.

    Why: a half-vector lobe is an ellipse about its peak only while c_P ≫ w. A tilt δ of H moves L by 2(V·H)δ
    across the plane of incidence (L = 2(V·H)H − V), and at grazing views V·H runs from ≈ c_P at the peak to
    ≈ w at the lobe's far end, so the lobe is a fan: a wedge about β = 0 whose half-width in β is about
    w/2 + c_P·w/α (α the angle from the peak), which covers every azimuth within α ≲ c_P·w of the peak. The
    radial map spends its nodes on the scale w; at u ≲ c_P/3 every node of a rule with too few radial nodes
    misses the neck, and the embedded rules agree on the miss (Beckmann α = 0.0176 at μ = 1.26e-4: panels
    β ∈ [π/8, π/4] × u ∈ [0, 1/4] gave 1e-27 against 4.4e-7; the albedo settled 1.3e-6 off with an estimate
    of 5.4e-10, the global rule's Fejér nodes as blind at μ ≲ 1e-6 for GGX). The rules below put nodes inside
    it: the global rule by a minimum radial level (:func:`_neck_levels`; without it, broad Beckmann lobes at
    μ ≈ 1e-6…1e-4 settled up to 4.6 times outside their estimates on a random sweep), the panels by initial
    edges graded towards the pole (:func:`brdfnorm.engine.machinery.grazing_panels.starting_panels`)."""
    P = frame[0]
    pz = np.maximum(P[:, 2], 0.0)
    w = widths * width_scale
    alpha_max = np.minimum(np.pi / 2, supports)
    A = np.arctan(alpha_max / w)
    v = np.clip(np.arctan(pz * widths / w) / A, 0.0, 1.0)
    # u = 1 − (1 − v)^(1/p), accurate for tiny v.
    return -np.expm1(np.log1p(-np.minimum(v, 1.0 - _EPS)) / grading)


def _neck_levels(u_neck: np.ndarray) -> np.ndarray:
    """The smallest radial level whose coarsest embedded rule (two levels down, :func:`sums`) has its first node
    (1 − cos(π/2^l))/2 = sin²(π/2^(l+1)) at or below ``u_neck``: only then do the rules whose deviations make the
    estimate see the neck (:func:`neck_u`)."""
    with np.errstate(divide="ignore"):
        inner = np.ceil(np.log2(np.pi / np.arcsin(np.sqrt(np.clip(u_neck, 0.0, 1.0))))) - 1.0
    return np.clip(np.nan_to_num(inner, posinf=99.0) + 2.0, START_LEVELS[1], 99).astype(int)


def map_grid(case, beta, u, weight, frame, widths, supports, width_scale=1.0, grading=None):
    """Directions (R, nβ, nu, 3) and Jacobians sin α dα/du · ``weight`` (R, nβ, nu) on the grid β (R, nβ) × u
    (R or 1, nu) for the cases ``case`` (R,); ``weight`` (R, 1 or nβ) carries the rule's scale factors,
    ``width_scale`` (scalar or R, nβ) multiplies the lobe's width per azimuth, and ``grading`` (R,), 2 (the
    default) or 3, is the exponent p of the horizon grading v = 1 − (1 − u)^p.

    This is the integrator's hot path: the transcendental functions run on (R, nβ, nu) arrays once each, and
    the directions are assembled component by component in place.
    """
    P, T, B = frame
    cos_b, sin_b = np.cos(beta), np.sin(beta)
    pz = P[case, 2][:, None]
    s = np.sqrt(np.maximum(1.0 - pz * pz, 0.0))
    alpha_max = np.minimum(np.arctan2(pz, -s * cos_b), supports[case][:, None])  # (R, nβ)
    w = widths[case][:, None] * width_scale
    # v = 1 − (1 − u)^p clusters nodes at the horizon end (dv/du → 0 there), where boundary layers live
    # (Smith G, Fresnel); then the Cauchy map α = w tan(v·A), A = atan(α_max/w), for the lobe.
    one_minus_u = 1.0 - u
    squared = one_minus_u * one_minus_u
    cubic = None if grading is None else (np.asarray(grading) == 3)[:, None]
    v = 1.0 - (squared if cubic is None else np.where(cubic, squared * one_minus_u, squared))
    A = np.arctan(alpha_max / w)[:, :, None]  # (R, nβ, 1)
    t = v[:, None, :] * A  # (R, nβ, nu), becomes tan(vA)
    np.tan(t, out=t)
    # sin α and cos α from h = tan(α/2), one transcendental instead of two: 2h/(1 + h²), (1 − h²)/(1 + h²).
    h = t * (0.5 * w[:, :, None])
    np.tan(h, out=h)
    h2 = h * h
    scale = 1.0 + h2
    np.reciprocal(scale, out=scale)
    sin_a = h
    sin_a *= 2.0 * scale
    cos_a = np.subtract(1.0, h2, out=h2)
    cos_a *= scale
    # dα/du = wA(1 + t²)·dv/du.
    jacobian = t
    np.multiply(t, t, out=jacobian)
    jacobian += 1.0
    jacobian *= A * (w * weight)[:, :, None]
    # dv/du = p(1 − u)^(p − 1).
    jacobian *= (2.0 * one_minus_u if cubic is None else np.where(cubic, 3.0 * squared, 2.0 * one_minus_u))[:, None, :]
    jacobian *= sin_a
    omega = np.empty(sin_a.shape + (3,))
    for i in range(3):
        radial = cos_b * T[case, i][:, None] + sin_b * B[case, i][:, None]  # (R, nβ)
        np.multiply(sin_a, radial[:, :, None], out=omega[..., i])
        omega[..., i] += cos_a * P[case, i][:, None, None]
    return omega, jacobian


@cache
def fejer(level: int) -> tuple[np.ndarray, np.ndarray]:
    """Fejér's second rule on [0, 1] with N = 2^level: the N − 1 nodes (1 − cos(kπ/N))/2 and their weights."""
    N = 2**level
    theta = np.arange(1, N) * np.pi / N
    odd = 2 * np.arange(1, N // 2 + 1) - 1
    weights = 2.0 / N * np.sin(theta) * (np.sin(np.outer(theta, odd)) / odd).sum(axis=1)
    return (1.0 - np.cos(theta)) / 2.0, weights


def beta_map(t: np.ndarray, lam: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """β(t) and dβ/dt of the periodic map with tan((β − π)/1) = λ tan(t − π): nodes 1/λ times denser at β = π
    (the horizon nearest the lobe) and at β = 0 (dβ/dt = λ at both), 1/λ times sparser at β = ±π/2 (module
    docstring)."""
    y = t - np.pi
    sin_y, cos_y = np.sin(y), np.cos(y)
    beta = t + (np.arctan2(lam * sin_y, cos_y) - np.arctan2(sin_y, cos_y))
    return beta, lam / (cos_y * cos_y + lam * lam * sin_y * sin_y)


def clustering(frame, widths) -> np.ndarray:
    """λ per case: c_P + 2w², the height of the lobe's peak above the horizon (where the cut tail varies fast in
    β) plus a term that turns the clustering off for broad lobes (w ≳ 0.6), whose integrand varies slowly
    everywhere and is best served by uniform nodes; at least :data:`WIDTH_CLUSTERING` × w (which binds where the
    peak is low against the lobe's width: grazing views), and between :data:`LAMBDA_MIN` and 1.

    The floor in widths: the cut lobe's edges at β ≈ ±π/2 lie about a width from the peak, so a clustering much
    stronger than the width starves them. Measured on Blinn-Phong at rtol 1e-9, θ_o = 70…89°: n = 512 (w = 0.125)
    does best at λ ≈ 0.3 (module docstring), n = 100 (w = 0.28) at λ ≈ 0.6–0.7, where the floor 0.25 cost it
    20 250 evaluations per albedo over those views and 2.4 w costs 13 760 (mean over θ_o = 0…89°: 10 261 → 8 818;
    the worst true error 0.05 of its estimate)."""
    pz = frame[0][:, 2]
    return np.clip(np.maximum(pz + 2.0 * widths**2, WIDTH_CLUSTERING * widths), LAMBDA_MIN, 1.0)


def radial_width_scale(dbeta: np.ndarray, lam: np.ndarray) -> np.ndarray:
    """The radial map's width factor √(cos²y + λ² sin²y) = √(λ / (dβ/dt)) at the map's nodes: with it, (t, r) are
    elliptic coordinates x = r cos y, y' = λ r sin y about the peak, the lobe's width 1 along β = 0, π and λ
    along β = ±π/2 (module docstring)."""
    return np.sqrt(lam / dbeta)


class GlobalGrid:
    """The coordinates a global tensor rule runs on, for the one driver of
    :mod:`brdfnorm.engine.machinery.global_driver` (which passes its groups of units (case, piece) at the same
    levels). Override :meth:`evaluate` and :meth:`estimate` (and the others where the coordinates need more than
    the plain rule)."""

    #: Radial pieces per case, sharing the case's tolerance in equal parts; a case fails as a whole.
    pieces = 1
    #: Whether one direction may be doubled alone where the other is within the whole tolerance on its own.
    lone = False
    #: Whether, where both directions would be doubled, β is doubled and u checked on half the azimuths
    #: (:func:`brdfnorm.engine.machinery.global_driver._refine_half`).
    half_azimuth = False

    def evaluate(self, case: np.ndarray, piece: np.ndarray, index: np.ndarray, M: int, u: np.ndarray) -> np.ndarray:
        """Weighted integrand values (n, len(index), len(u), C) at the azimuth parameters t = 2π·index/M and the
        radial nodes u ∈ (0, 1) of the units (case, piece)."""
        raise NotImplementedError

    def count(self, case: np.ndarray, index: np.ndarray, M: int) -> np.ndarray | int:
        """Azimuths :meth:`evaluate` spends per unit for ``index`` (each of them at every radial node)."""
        return index.size

    def batch_nodes(self, max_nodes: int) -> int:
        """Grid values one case may hold at most (for the batches of :data:`BATCH_NODES`)."""
        return self.pieces * max_nodes

    def start(self, group) -> np.ndarray | None:
        """Called once the start grid is in: the units to evaluate again (the grid changed their map), or None."""
        return None

    def sums(self, F: np.ndarray, level_u: int):
        """Q, the deviations along β and u, and the |F| integral (:func:`sums` or its compiled pass)."""
        return sums(F, level_u)

    def estimate(self, group, F, q, e_b, e_u, magnitude):
        """(e_b, e_u, floor, noise, estimate): the deviations along β and u as the grid reads them (any extra
        term, any extrapolation to the reported grid), the rounding floor, the float64 noise bound (both taken off
        the tolerance the deviations share) and the estimate."""
        raise NotImplementedError

    def short(self, group) -> np.ndarray:
        """Units whose radial level is below the least they need before they may settle."""
        return np.zeros(group.case.size, dtype=bool)

    def min_level_u(self, group) -> np.ndarray | int:
        """The least radial level each unit needs (0: none)."""
        return 0

    def may_settle(self, group, q: np.ndarray) -> np.ndarray | bool:
        """Units that may settle at this level if within their tolerance (the grid may record ``q`` here)."""
        return True

    def may_predict(self, group) -> np.ndarray | bool:
        """Units the doubling prediction may give up."""
        return True


class LobeAlignedGrid(GlobalGrid):
    """The rectangle (β, u) of the lobe-aligned coordinates about each case's peak (``frame``), with the lobe's
    width and support per case; ``noise_amplitude`` and ``noise_bound`` give the integrand's float64 noise,
    ``azimuthal_tail`` (K,) marks the lobes that are not rotation-invariant."""

    lone = True
    half_azimuth = True

    def __init__(self, integrand, frame, widths, supports, noise_amplitude, noise_bound, max_nodes_per_call: int,
                 azimuthal_tail: np.ndarray | None):
        K = frame[0].shape[0]
        self.integrand, self.frame, self.widths, self.supports = integrand, frame, widths, supports
        self.noise_amplitude, self.noise_bound = noise_amplitude, noise_bound
        self.max_nodes_per_call = max_nodes_per_call
        self.azimuthal_tail = np.zeros(K, dtype=bool) if azimuthal_tail is None else azimuthal_tail
        #: Per case the β map's λ and the horizon grading's exponent (:func:`map_grid`), updated by :meth:`start`.
        self.lam, self.grading = clustering(frame, widths), np.full(K, 2)
        self._min_level_u = np.zeros(K, dtype=int)

    def evaluate(self, case, piece, index, M, u):
        t = index * (2 * np.pi / M)
        parts = []
        chunk = max(1, min(self.max_nodes_per_call, CHUNK_NODES) // (t.size * u.size))
        for start in range(0, case.size, chunk):
            k = case[start:start + chunk]
            beta, dbeta = beta_map(t[None, :], self.lam[k][:, None])
            omega, jacobian = map_grid(k, beta, u[None, :], dbeta, self.frame, self.widths, self.supports,
                                       radial_width_scale(dbeta, self.lam[k][:, None]), self.grading[k])
            index_k = np.broadcast_to(k[:, None, None], jacobian.shape)
            with np.errstate(all="ignore"):
                values = np.asarray(self.integrand(omega.reshape(-1, 3), index_k.ravel()), dtype=float)
                parts.append(values.reshape(jacobian.shape + (-1,)) * jacobian[..., None])
        return np.concatenate(parts)

    def sums(self, F, level_u):
        # (one compiled pass where the integrand is compiled: numpy's strided matmuls cost more than it)
        return (compiled_sums if hasattr(self.integrand, "kernels") else sums)(F, level_u)

    def batch_nodes(self, max_nodes):
        return max(max_nodes, START_NODES)

    def start(self, group) -> np.ndarray:
        # Heavy tails (GGX) want weaker clustering than the floor and a stronger horizon grading: start those cases
        # again on that map.
        # (Not where the integrand is not finite: the panels take those.)
        cases = group.case
        weaker = _heavy_tailed(group.grid, group.level_u) & np.isfinite(group.grid).all(axis=(1, 2, 3))
        if weaker.any():
            self.lam[cases[weaker]] = np.maximum(self.lam[cases[weaker]], LAMBDA_MIN_HEAVY_TAIL)
            self.grading[cases[weaker]] = HEAVY_TAIL_GRADING
        # The radial level each case needs before it may settle (neck_u), on its final map.
        self._min_level_u[cases] = _neck_levels(neck_u(self.frame, self.widths, self.supports, self.lam,
                                                       self.grading)[cases])
        return weaker

    def estimate(self, group, F, q, e_b, e_u, magnitude):
        noise = self.noise_bound(self.noise_amplitude[group.case], magnitude)
        floor = FLOOR * magnitude
        # The reported grid's own error where its convergence is shown to be geometric (grid_estimate).
        e_b, e_u = grid_estimate.own_error(F, [fejer(group.level_u - k)[1] for k in range(4)], e_b, e_u, magnitude,
                                           floor + noise, self.frame[0][group.case, 2], self.widths[group.case],
                                           self.grading[group.case] == HEAVY_TAIL_GRADING, d=group.deviations)
        if self.azimuthal_tail[group.case].any():
            tail = np.where(self.azimuthal_tail[group.case][:, None], _azimuthal_tail(F, group.level_u), 0.0)
            e_b = np.maximum(e_b, tail)
        estimate = e_b + e_u + floor + noise
        return e_b, e_u, floor, noise, estimate

    def admit(self, cases: np.ndarray, max_nodes: int) -> np.ndarray:
        """The ``cases`` worth trying: not those whose neck (:func:`neck_u`) no grid within ``max_nodes`` reaches,
        even on the start map (the panels take them untried)."""
        return cases[_fits(_neck_levels(neck_u(self.frame, self.widths, self.supports, self.lam,
                                                self.grading)[cases]), max_nodes)]

    def min_level_u(self, group):
        return self._min_level_u[group.case]

    def short(self, group):
        return group.level_u < self._min_level_u[group.case]

    def may_settle(self, group, q):
        earlier = np.full((q.shape[0], 3, q.shape[1]), np.nan) if group.earlier is None else group.earlier
        stalled = _stalled(q, earlier)
        group.earlier = np.concatenate([q[:, None], earlier[:, :2]], axis=1)
        return ~stalled


def _heavy_tailed(grid: np.ndarray, level_u: int) -> np.ndarray:
    """Whether a case's lobe is heavy-tailed: more than :data:`HEAVY_TAIL_SHARE` of the |integrand| on its start
    grid at u ≥ 1/2, i.e. beyond the width w of the radial map (GGX at roughness 0.3: 0.28–0.44 at every view;
    Blinn-Phong n = 512: 0.04–0.06). Such lobes are integrated with fewer nodes on a weaker β clustering, the
    floor :data:`LAMBDA_MIN_HEAVY_TAIL` (examples/ggx.brdf, 90 views, rtol 1e-6: 11 710 evaluations per albedo with
    the floor 0.25, 10 900 with 0.45, 9 500 with 0.6, 11 100 with 1; 0.65 took 8 400 but one view's true error
    reached 0.59 of its estimate, against ≤ 0.005 at 0.45, 0.6 and 0.8); Gaussian-like lobes need the stronger
    floor (Blinn-Phong n = 512 at 70–79°, rtol 1e-9: 14 400 at 0.25, 18 900 at 0.45).

    They also get the cubic horizon grading v = 1 − (1 − u)³ (:data:`HEAVY_TAIL_GRADING`): a GGX tail reaches the
    horizon, where Smith's G1 = 2c/(c + √(α² + (1 − α²)c²)) turns on within c ≈ α of it (branch points at
    c = ±iα/√(1 − α²)), a boundary layer the quadratic grading resolves only algebraically in u (examples/ggx.brdf,
    roughness 0.107, θ_o = 60°, rtol 1e-9: the u estimate fell 1e-2, 1e-4, 2e-6, 4e-8 over four doublings, and the
    case went to the panels, 55 248 evaluations; cubic: 2e-2, 4e-5, 2e-7, 6e-10, settled at 16 952 with β doubled
    once more). Gaussian-like lobes have no such layer and lose by it (Blinn-Phong n = 512, 90 views, rtol 1e-9:
    9 464 evaluations per albedo with p = 2, 14 600 with p = 3), hence only for heavy tails."""
    u, w = fejer(level_u)
    with np.errstate(invalid="ignore"):
        radial = np.abs(np.nan_to_num(grid, nan=0.0, posinf=0.0, neginf=0.0)).sum(axis=(1, 3)) * w  # (n, N − 1)
        total = radial.sum(axis=1)
        return radial[:, u >= 0.5].sum(axis=1) > HEAVY_TAIL_SHARE * total


def _fits(level_u: np.ndarray, max_nodes: int) -> np.ndarray:
    """Whether a grid of the start's azimuths and radial level ``level_u`` fits in ``max_nodes``."""
    return 2 ** START_LEVELS[0] * (2.0 ** np.minimum(level_u, 60) - 1) <= max_nodes


def _stalled(q: np.ndarray, earlier: np.ndarray) -> np.ndarray:
    """Whether a case's value Q (n, C) stalled over its last two doublings: a level-to-level change more than
    :data:`STALL` times the change before it (``earlier`` holds Q₋₁, Q₋₂, Q₋₃, NaN before the start). The
    estimate d₁ + min(d₂, 9 d₁) assumes the rule converges from one level to the next; a stall, or a change that
    grows, around a sudden agreement is the mark of a kink the grid crosses obliquely (examples/oren_nayar.brdf,
    rtol 1e-6: at θ_o = 29.77° the value moved 3.4e-5, 2.7e-5, then 4.6e-9 over three doublings, every level
    3e-7 off, the estimate 0.74 of the error; at 29.5°, 3.5e-5, 2.7e-5, 3.1e-8, then 6.7e-8, 0.71). Such a case
    is not settled at this level: it doubles on, or goes to the panels. Among 489 random Blinn-Phong, Phong and
    GGX cases that the rule settles (rtol 1e-6…1e-11), one had stalled, a pre-asymptotic plateau, 2.9e-10 off
    at rtol 1e-6: it pays one more doubling."""
    values = np.concatenate([q[:, None], earlier], axis=1)
    with np.errstate(invalid="ignore"):
        change = np.abs(np.diff(values, axis=1))  # newest first
        return np.any((change[:, 0] > STALL * change[:, 1]) | (change[:, 1] > STALL * change[:, 2]), axis=1)


def doublings(ratio: np.ndarray, last: np.ndarray) -> np.ndarray:
    """Doublings still needed along a direction for its estimate to fall from ``ratio`` (× its share of the
    tolerance) to 1, if each doubling squares the last one's reduction r = ``ratio / last`` (geometric
    convergence, err ∝ ρ^M): after k more, ratio·r^(2^(k+1) − 2). 0 where already within or before any doubling
    (nothing to extrapolate from); 99 where the estimate did not shrink."""
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        reduction = np.where(np.isfinite(last) & (last > 0), ratio / last, 0.0)
        exponent = np.log(np.maximum(ratio, 1.0)) / -np.log(np.clip(reduction, 1e-300, 1.0))
        needed = np.ceil(np.log2(exponent + 2.0)) - 1.0
    needed = np.where(ratio <= 1.0, 0.0, np.where(reduction >= 1.0, 99.0, needed))
    return np.clip(np.nan_to_num(needed, nan=0.0), 0.0, 99.0).astype(int)


def normalized(error: np.ndarray, share: np.ndarray) -> np.ndarray:
    """error / share, with 0/0 = 0 and x/0 = inf (a zero tolerance accepts only a zero error)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(share > 0, error / share, np.where(error > 0, np.inf, 0.0))


def sums(F: np.ndarray, level_u: int):
    """Q(M, N), the error estimates along β and along u, and the |F| integral, per case and channel.

    Along each direction the estimate is d₁ + min(d₂, 9 d₁), with d₁ = |Q − Q(½)| and d₂ = |Q(½) − Q(¼)| the
    deviations of the embedded rules with half and a quarter of the nodes (all on the grid already): ten times
    the plain deviation, unless the coarser pair agreed better still. The margin covers pre-asymptotic plateaus,
    where Q(½) and Q agree better than either is accurate (Blinn-Phong n = 805 at θ_o = 50°: Fejér with 15 and 31
    radial nodes both 4e-7 off, 2.4e-7 apart; 63 nodes are 7.5e-12 off).
    """
    M = F.shape[1]
    w = fejer(level_u)[1]
    by_channel = F.transpose(0, 1, 3, 2)  # (n, M, C, N − 1): matmul over the radial nodes
    over_u = by_channel @ w
    q = over_u.sum(axis=1) * (2 * np.pi / M)
    q_b = over_u[:, ::2].sum(axis=1) * (4 * np.pi / M)
    q_bb = over_u[:, ::4].sum(axis=1) * (8 * np.pi / M)
    q_u = (by_channel[..., 1::2] @ fejer(level_u - 1)[1]).sum(axis=1) * (2 * np.pi / M)
    q_uu = (by_channel[..., 3::4] @ fejer(level_u - 2)[1]).sum(axis=1) * (2 * np.pi / M)
    magnitude = (np.abs(by_channel) @ w).sum(axis=1) * (2 * np.pi / M)
    return q, _margin(np.abs(q - q_b), np.abs(q_b - q_bb)), _margin(np.abs(q - q_u), np.abs(q_u - q_uu)), magnitude


def compiled_sums(F: np.ndarray, level_u: int):
    """:func:`sums` by one compiled pass (:mod:`brdfnorm.engine.compiled.rules`), for the compiled backend."""
    from ..compiled.rules import tensor_sums

    M = F.shape[1]
    q, q_b, q_bb, q_u, q_uu, magnitude = tensor_sums(F, fejer(level_u)[1], fejer(level_u - 1)[1],
                                                     fejer(level_u - 2)[1])
    step = 2 * np.pi / M
    q, q_u, q_uu, magnitude = q * step, q_u * step, q_uu * step, magnitude * step
    q_b, q_bb = q_b * (2 * step), q_bb * (4 * step)
    return q, _margin(np.abs(q - q_b), np.abs(q_b - q_bb)), _margin(np.abs(q - q_u), np.abs(q_u - q_uu)), magnitude


def _azimuthal_tail(F: np.ndarray, level_u: int) -> np.ndarray:
    """10 × 2π × the largest Fourier coefficient of the β-profile ∫F du in the top quarter of the frequencies the
    grid carries (|k| ∈ [3M/8, M/2]), per case and channel: what the M-point trapezoid rule's error would be if
    the coefficients stopped decaying there. It stays large while a feature narrower than the azimuth spacing is
    unresolved, where two nested levels can agree on the same wrong value: an anisotropic lobe is such a wedge
    about its peak (Ashikhmin-Shirley at n_u = 1407, n_v = 2.3: ~1/25 rad; θ_o = 59.7°, rtol 1e-5, it settled at
    128 × 255 nodes 1.1e-6 off with an estimate of 7.9e-7; this tail was 7.7e-5 there). Only for such lobes: a
    round one's profile can carry large mid-band coefficients while its integral is exact (∫ z² about a pole at
    87.4° went from 4 760 evaluations to 83 380 with it)."""
    M = F.shape[1]
    profile = F.transpose(0, 1, 3, 2) @ fejer(level_u)[1]  # (n, M, C)
    coefficients = np.abs(np.fft.rfft(profile, axis=1)) * (2 * np.pi / M)
    return 10.0 * coefficients[:, 3 * M // 8:].max(axis=1)


def _margin(deviation: np.ndarray, coarser: np.ndarray) -> np.ndarray:
    return deviation + np.minimum(coarser, SAFETY * deviation)
