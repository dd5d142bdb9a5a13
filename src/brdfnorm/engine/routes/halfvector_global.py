"""A global tensor rule for the half-vector albedo (H1) of :mod:`brdfnorm.engine.routes.halfvector`, tried before its
panels.

On the rectangle (φ, v) of (H1) each radial piece v ∈ [j, j + 1] (pole, tail, horizon layer) carries an integrand
that is periodic and analytic in the azimuth φ and smooth in v. So each (case, piece) is first integrated by one
tensor rule over the whole piece, as :mod:`brdfnorm.engine.machinery.tensor_rule` does for the hemisphere engine,
by the same driver (:mod:`brdfnorm.engine.machinery.global_driver`, this rectangle being its
:class:`HalfVectorGrid`): the periodic trapezoid rule in φ (geometric convergence, Trefethen & Weideman, SIAM
Review 56, 2014) × Fejér's second rule in v, both nested under doubling, error along each direction
d₁ + min(d₂, 9 d₁) from the embedded coarser rules (:func:`brdfnorm.engine.machinery.tensor_rule.sums`), plus the
rounding floor.

Azimuth nodes. At grazing views the horizon radius s_h(φ) varies over an azimuthal width ~V_z next to the zeros
of p(φ) = c·d(φ), which lie at φ = 0, π from the offset of :func:`brdfnorm.engine.routes.halfvector.slope_integrand`
(called with ``linear=True``: φ is the azimuth from that offset, no φ-map of its own). The trapezoid runs on t
with tensor_rule's periodic Möbius map :func:`brdfnorm.engine.machinery.tensor_rule.beta_map`, tan φ = λ tan t: nodes
1/λ times
denser at both zeros, λ = clip(1.2 √V_z, 0.05, 1). (Measured, GGX at α = 0.03, 0.2, 0.7, azimuths for a deviation
below 1e-11 on every piece, over λ ∈ {1, 0.7, 0.5, 0.3, 0.2, 0.1, 0.05}: the best λ was 1 at μ = 0.6, 0.5–0.7 at
0.3, 0.3–0.5 at 0.1, 0.3 at 0.04, 0.2 at 0.01, 0.1 at 0.002; 1.2 √μ follows it. At μ = 0.04 that is 256
azimuths against 1024 uniform ones; below μ ≈ 2e-3 even the best λ needs > 1024, and the panels, whose sinh map
follows any width, take the case.)

Grazing views of a heavy-tailed lobe (GGX, :data:`GRADED`). Two things defeated the rule there: the horizon's
azimuthal features next to the zeros of p are ~μ wide, with structure out to O(1), and the horizon layer's width, ∝
α/V_z, exceeds the horizon radius s_h, so the horizon piece [s_split, s_h] spans decades of s (s_split = s_h²/(s_h
+ gap)) over which the slope density falls as a power: linear in s, Fejér's rule needed > 1000 radial nodes (μ ≲
3e-3) or never converged (μ ≲ 3e-4). So for these lobes the horizon piece runs linear in ln s at every view (see
``slope_integrand``; linear in s where its ends are close; analytic in a wide strip for a power-law tail, not
for Beckmann's e^{−s²}, where the sweep of ``tests/engine/test_halfvector_global.py`` found estimates 10³× too small,
hence GGX only), and below μ = :data:`GRADED_BELOW` the azimuth takes a periodic analogue of the panels' sinh
grading: tan φ = δ sinh(κ sin t)/cos t, δ = μ, κ = arsinh(1/δ) — dφ/dt = δκ at the zeros, distances δ … 1 spread
log-evenly over sin t, period π and the mirror symmetry kept (κ → 0 with δκ = λ is the Möbius map). The map
converges pre-asymptotically (the doubling prediction of tensor_rule reads its first levels as hopeless), so for
graded cases the prediction may stop a case only from :data:`GRADED_PREDICTS` azimuth levels on. Measured (GGX,
panels off, rtol 2.5e-10): μ = 1e-2 … 1e-4 settle in 20 000–28 000 evaluations where they needed 40 000–580 000 (or
failed), and the 32×32 table's E_avg needs 0.60× the evaluations (34.9 M → 20.9 M). The graded map up to μ = 0.2
saved another 15 % (17.7 M), but at μ = 0.05 its results were so much better than asked (3e-12 at rtol 1e-3) that
the honesty tests' can-it-fail guards no longer held, so it starts at 0.04, below which the Möbius map needed
more than 32 768 nodes a piece.

An isotropic lobe is even about the plane of N and V (φ = ±π/2 here), and the map is symmetric about it too
(φ(π − t) = π − φ(t)): the mirror nodes t ↔ π − t share one evaluation.

A piece whose estimate misses its third of the case's tolerance is doubled along the direction(s) that need it;
cases needing more than :data:`MAX_NODES` per piece (predicted from the last doubling, as tensor_rule does), or
with a non-finite value, go to the adaptive panels, which start afresh (their evaluations are added).
"""

from __future__ import annotations

import numpy as np

from ..machinery import global_driver
from ..machinery.result import RouteResult
from ..machinery.tensor_rule import FLOOR, GlobalGrid, beta_map, compiled_sums, sums

#: Radial pieces of (H1): pole, tail, horizon layer.
PIECES = 3
#: Nodes per piece at most before a case goes to the panels (their K15⊗K15 start costs 3·16·225 = 10 800).
MAX_NODES = 32_768
#: The Möbius map's strongest clustering (μ ≲ 2e-3; GGX takes the graded map below GRADED_BELOW instead).
LAMBDA_MIN = 0.05
#: Views below this μ take the graded azimuth map (δ = μ) instead of the Möbius map.
GRADED_BELOW = 0.04
#: Azimuth levels the graded map runs before the doubling prediction may give up (without this, GGX views at
#: μ ≤ 3e-4 were given up at 32 azimuths; with it they settle within 2^MAX_LEVEL_B).
GRADED_PREDICTS = 6
#: Distributions whose grazing views take the graded map, their horizon piece linear in ln s (power-law tails;
#: module docstring).
GRADED = ("ggx",)
#: Nodes per integrand call (arrays that stay in cache).
CHUNK_NODES = 16_384


def clustering(cos_view: np.ndarray) -> np.ndarray:
    """λ of the azimuth map: 1.2 √μ between 0.05 and 1 (μ = cos θ of the fixed direction; module docstring)."""
    return np.clip(1.2 * np.sqrt(cos_view), LAMBDA_MIN, 1.0)


def grading_width(cos_view: np.ndarray, distribution: str) -> np.ndarray:
    """δ of the graded azimuth map: μ below :data:`GRADED_BELOW` for the :data:`GRADED` distributions, else 0
    (the Möbius map; module docstring)."""
    return np.where((cos_view < GRADED_BELOW) & (distribution in GRADED), cos_view, 0.0)


def azimuth_map(t: np.ndarray, lam: np.ndarray, width: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """φ(t) and dφ/dt: tensor_rule's periodic Möbius map, tan φ = λ tan t (nodes 1/λ times denser at φ = 0, π),
    or where ``width`` δ > 0 the graded map tan φ = δ sinh(κ sin t)/cos t, κ = arsinh(1/δ)."""
    phi, dphi = beta_map(t, lam)
    if width is None or not np.any(width > 0):
        return phi, dphi
    delta = np.where(width > 0, width, 1.0)
    kappa = np.arcsinh(1.0 / delta)
    turns = np.round(t / np.pi)  # t − turns·π ∈ [−π/2, π/2], where cos ≥ 0 keeps atan2 on its principal branch
    sin_t, cos_t = np.sin(t - turns * np.pi), np.cos(t - turns * np.pi)
    y = delta * np.sinh(kappa * sin_t)
    graded = np.arctan2(y, cos_t) + turns * np.pi
    graded_dphi = (cos_t * cos_t * delta * kappa * np.cosh(kappa * sin_t) + y * sin_t) / (cos_t * cos_t + y * y)
    return np.where(width > 0, graded, phi), np.where(width > 0, graded_dphi, dphi)


class HalfVectorGrid(GlobalGrid):
    """The rectangle (φ, v) of (H1) for the one driver (:mod:`brdfnorm.engine.machinery.global_driver`): three
    radial pieces per case sharing its tolerance, the azimuth map per case (λ, and the graded map's δ =
    ``width``), mirror-symmetric azimuths sharing one evaluation where ``symmetric``; ``scale`` (K,) turns the
    integrand's weight into one over the full azimuth range."""

    pieces = PIECES

    def __init__(self, integrand, lam, width, symmetric, scale):
        self.integrand, self.lam, self.width, self.symmetric, self.scale = integrand, lam, width, symmetric, scale

    def evaluate(self, case, piece, index, M, u):
        """Weighted values (n, len(index), len(u), C) at t = 2π·index/M and v = piece + u (sharing mirror nodes)."""
        out = None
        fresh = getattr(self.integrand, "compiled", False)
        for mirrored in (False, True):
            rows = np.flatnonzero(self.symmetric[case] == mirrored)
            if not rows.size:
                continue
            canonical = index
            if mirrored:  # t ↔ π − t: keep t ∈ [−π/2, π/2]
                i = index % M
                canonical = np.where((i <= M // 4) | (i >= 3 * M // 4), i, (M // 2 - i) % M)
            unique, back = np.unique(canonical, return_inverse=True)
            phi, dphi = azimuth_map(unique[None, :] * (2 * np.pi / M), self.lam[case[rows]][:, None],
                                    self.width[case[rows]][:, None])
            chunk = max(1, CHUNK_NODES // (unique.size * u.size))
            for start in range(0, rows.size, chunk):
                r = rows[start:start + chunk]
                k = case[r]
                values = self.integrand(k, phi[start:start + chunk, :, None], (piece[r][:, None] + u)[:, None, :],
                                        piece[r])
                factor = dphi[start:start + chunk, :, None, None] * self.scale[k][:, None, None, None]
                if fresh:  # (a compiled integrand's output is its own: scaled in place, and kept where it is all)
                    values *= factor
                    if not mirrored and r.size == case.size:
                        out = values
                        continue
                else:
                    values = values * factor
                if out is None:
                    out = np.empty((case.size, index.size, u.size, values.shape[-1]))
                out[r] = values[:, back] if mirrored else values  # (index is sorted: back is the identity)
        return out

    def count(self, case, index, M):
        """Azimuths evaluated per unit for ``index``: the distinct mirror classes where symmetric."""
        i = index % M
        canonical = np.where((i <= M // 4) | (i >= 3 * M // 4), i, (M // 2 - i) % M)
        return np.where(self.symmetric[case], np.unique(canonical).size, index.size)

    def sums(self, F, level_u):
        # (one compiled pass where the integrand is compiled: numpy's strided matmuls cost more than it)
        return (compiled_sums if getattr(self.integrand, "compiled", False) else sums)(F, level_u)

    def estimate(self, group, F, q, e_b, e_u, magnitude):
        floor = FLOOR * magnitude
        estimate = e_b + e_u + floor
        return e_b, e_u, floor, 0.0, estimate

    def may_predict(self, group):
        # The graded map converges pre-asymptotically: no prediction before GRADED_PREDICTS azimuth levels.
        return (group.level_b >= GRADED_PREDICTS) | (self.width[group.case] == 0)


def integrate_global(integrand, K: int, cases: np.ndarray, lam: np.ndarray, symmetric: np.ndarray,
                     scale: np.ndarray, *, rtol: float | np.ndarray, atol: float | np.ndarray,
                     max_nodes: int = MAX_NODES, width: np.ndarray | None = None):
    """The global rule for ``cases`` as a :class:`RouteResult` (value and error (K, C), evaluations and converged
    (K,): ``converged`` marks the cases it settled; the others go to the panels); ``scale`` (K,) turns the
    integrand's weight into one over the full azimuth range. A compiled microfacet integrand (its ``fused``
    arguments) runs the whole rule in one kernel (:mod:`brdfnorm.engine.compiled.global_rule`)."""
    atol = np.broadcast_to(np.asarray(atol, dtype=float).reshape(-1), (K,))
    width = np.zeros(K) if width is None else width
    lobe = getattr(integrand, "fused", None)
    # (one tolerance per case, and the route's node cap, which the fused kernel's tables cover)
    if lobe is not None and np.size(rtol) in (1, K) and max_nodes <= MAX_NODES:
        from ..compiled.global_rule import integrate  # (the compiled backend's: Numba imported only there)

        per_case = np.broadcast_to(np.asarray(rtol, dtype=float).reshape(-1), (K,))
        return RouteResult(*integrate(cases, np.broadcast_to(lam, (K,)), width, symmetric,
                                      np.broadcast_to(scale, (K,)), per_case, atol, max_nodes, GRADED_PREDICTS, lobe))
    return global_driver.integrate_global(HalfVectorGrid(integrand, lam, width, symmetric, scale), K, cases,
                                          rtol=rtol, atol=atol, max_nodes=max_nodes)
