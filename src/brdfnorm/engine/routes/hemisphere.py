"""Adaptive hemisphere quadrature with honest error estimates, vectorized over many integrals at once.

What it computes
----------------
For K cases (a fixed direction and parameter values each) it integrates g_k(ω) over the upper hemisphere
H = {ω : ω_z > 0}, where g is the cosine-weighted BRDF f(L, V)(N·L) with the other direction fixed — the
directional albedo of seed 002, E(V) = ∫_H f(L, V)(N·L) dL.

Why this design
---------------
Specular lobes are peaked (width ~ 2/√n rad for Blinn-Phong, 0.02 rad at n = 1e4) and, at grazing views,
clipped by the horizon right next to their peak. Generic 2-D quadrature in (θ, φ) about N sees a narrow bump
cut by a coordinate line that does not follow it; ``dblquad`` then returns wrong digits with no warning
(seed 002's integral at n = 1e4, θ_o = 1.5 rad). Here, three changes of variables make the integrand smooth
and the domain a rectangle, after which adaptive Gauss-Kronrod cubature converges geometrically:

1. **Lobe-aligned polar coordinates.** Around the lobe's peak direction P (a hint from the model, or found by
   sampling) write ω = cos α P + sin α (cos β T + sin β B), dω = sin α dα dβ, with T the unit vector towards N
   in the plane of N and P and B = P × T. A radially symmetric lobe becomes a function of α alone.
2. **Horizon as a coordinate line.** With s = √(1 − P_z²), ω_z = P_z cos α + s cos β sin α vanishes at
   α_h(β) = atan2(P_z, −s cos β) ∈ (0, π). Integrating α over [0, α_max(β)] with
   α_max = min(α_h, support) puts the horizon (and a declared support edge, e.g. R·V = 0 for Phong) on the
   boundary of the domain instead of through its interior, so no kink is ever straddled.
3. **Width-adapted radial map.** α = w tan(v·A(β)), A = atan(α_max/w) — a Cauchy-quantile map that spends
   most of the range on the lobe core |α| ≲ 3w whatever the width w (the model's hint), so the same few panels
   resolve n = 1 and n = 1e4 and heavy tails (GGX) as well as Gaussian ones — composed with
   v = 1 − (1 − u)², u ∈ [0, 1], which grades the nodes towards the horizon, where the map alone would
   leave boundary layers (Smith G within α of the horizon, Fresnel) between all nodes.

On the rectangle (β, u) ∈ [0, 2π] × [0, 1] each case is first integrated by one global tensor rule with degree
doubling (:mod:`brdfnorm.engine.machinery.tensor_rule`: periodic trapezoid in β × Fejér in u), which settles smooth
lobes at low
and middle angles in a few thousand evaluations. The cases it does not settle — and those whose rounding noise
matters — are integrated by adaptive panels (starting from a grid cut further at two scales of a grazing peak's
height above the horizon, where no node of the plain grid looks: :mod:`brdfnorm.engine.machinery.grazing_panels`): a
tensor-product
Gauss-Kronrod rule (QUADPACK's G7/K15 pair, 225 nodes per panel) gives the estimate (K15 ⊗ K15) and two embedded
lower-order estimates (G7 in β or in u); their differences are the panel's error estimate in each direction.
This is the plain |K − G| estimate of the *lower*-order rule, not QUADPACK's heuristic rescaling: it bounds the
error of the reported K15 ⊗ K15 value with a wide margin, which is what "honest" means here (the tests check
estimate ≥ true error on random cases). Both embedded rules can still agree on a feature that lies between all
their nodes (the sliver a Blinn-Phong lobe becomes at grazing views, 2 cos θ_o/√n wide sideways). So before a
case stops — meeting its tolerance or not — each of its panels is recomputed as two halves on new nodes that include
its edges and corners (Lobatto ⊗ G7 along β and along u, Lobatto ⊗ Lobatto along u: docs/kinks.md) and the
differences join the panel's error. Panels
are bisected along their worse direction, largest errors first, until the summed estimate is below max(atol,
rtol·|E|) for every case and channel, or the evaluation budget runs out (then ``converged`` is False and the
estimate still says how far off the value may be).

At float64's limit the integrand itself is noise: a lobe written with a cosine near 1 (cos^n, (N·H)^n,
1 − (N·H)²) sees that cosine only to within ε, which at n = 1e16 or GGX α = 1e-8 is a staircase as wide as
the lobe. Before the first round :func:`rounding_noise` measures each case's noise by fourth differences
along rays from the peak (in full where it can matter, :func:`surveyed_noise`), and :func:`noise_bound` adds it
(times the |g|-integral) to the estimate. A case whose noise exceeds its tolerance stops once its quadrature
error is below the noise ("rounding-limited");
one whose estimate no longer halves when its evaluations double stops too ("stalled"); either way
``converged`` is False and ``reason`` says why. The bias no difference sees — of a lobe's cosine from the rounded
norms of the fixed direction and of the lobe frame (:func:`cosine_bias`) — is a floor on that noise, charged once
the estimates are known (a case it takes past its tolerance is "rounding-limited").

Every round evaluates all panels of all unconverged cases in one vectorized call to the integrand; there is
no Python loop per node or per case. ``scipy.integrate.cubature`` implements the same idea for a single
integrand; it cannot share rounds across thousands of integrals or use lobe-aligned coordinates, which is
where the speed comes from (see benchmarks/).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from typing import Literal

import numpy as np

from ...validate import DEFAULT_MAX_EVALUATIONS, DEFAULT_RTOL
from ..compiled import drivers as native
from ..machinery.confirmation import (
    CHECK_EVALUATIONS,
    SPLIT_EVALUATIONS,
    STALL_EVALUATIONS,
    check_with_corners,
    confirm_before_stop,
    stopping,
)
from ..machinery.directions import cross, norm
from ..machinery.grazing_panels import starting_panels
from ..machinery.hemisphere_global import integrate_global
from ..machinery.kinks import algebraic_floor, refinement_change
from ..machinery.kronrod import GAUSS, KRONROD, NODES
from ..machinery.panels import Panels, kronrod_estimate
from ..machinery.result import RouteResult
from ..machinery.rounding import BIAS_EVALUATIONS, cosine_bias, noise_bound, surveyed_noise
from ..machinery.tensor_rule import START_NODES, map_grid, neck_u, normalized

NonFinitePolicy = Literal["raise", "zero"]

#: Nodes per case the global tensor rule may spend before a case goes to the adaptive panels.
GLOBAL_NODES = 65_536
#: Integrand signature: (ω (M, 3), case index (M,)) -> (M, C) values of f·(N·ω).
Integrand = Callable[[np.ndarray, np.ndarray], np.ndarray]
#: (integrand, poles, widths, cases, noise amplitude, rtol=, atol=, max_evaluations=) -> RouteResult (``converged``:
#: the cases it keeps): a route tried before the others (``integrate_hemisphere``'s first_route).
FirstRoute = Callable[..., RouteResult]


class NonFiniteIntegrand(ArithmeticError):
    """The integrand returned NaN or ±Inf at ``direction`` for ``case`` (with nonfinite="raise")."""

    def __init__(self, case: int, direction: np.ndarray, value: np.ndarray) -> None:
        super().__init__(f"non-finite integrand for case {case} at {direction}")
        self.case = case
        self.direction = direction
        self.value = value


def lobe_frame(poles: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orthonormal (P, T, B) with T pointing from P towards N in their common plane, B = P × T."""
    P = np.array(poles, dtype=float, copy=True)
    # The pole must lie strictly above the horizon for α_h(β) to be positive everywhere.
    P[:, 2] = np.maximum(P[:, 2], 1e-9)
    P /= norm(P)[:, None]  # (directions' norm and cross product: numpy's bits, without their generic overhead)
    up = np.zeros_like(P)
    up[:, 2] = 1.0
    T = up - P[:, 2:3] * P
    length = norm(T)[:, None]
    at_pole = length[:, 0] < 1e-12
    T = np.where(at_pole[:, None], np.array([1.0, 0.0, 0.0]), T / np.where(at_pole[:, None], 1.0, length))
    B = np.stack(cross(P, T), axis=-1)
    return P, T, B


def _map_nodes(panels: Panels, frame, widths, supports, nodes: np.ndarray = NODES, nodes_u: np.ndarray | None = None):
    """Directions (R, n, m, 3) and Jacobians (R, n, m) at the tensor ``nodes`` (β) ⊗ ``nodes_u`` (u; or ``nodes``)."""
    beta_half = (panels.a1 - panels.a0) / 2
    u_half = (panels.b1 - panels.b0) / 2
    beta = ((panels.a0 + panels.a1) / 2)[:, None] + beta_half[:, None] * nodes  # (R, n)
    u = ((panels.b0 + panels.b1) / 2)[:, None] + u_half[:, None] * (nodes if nodes_u is None else nodes_u)
    return map_grid(panels.case, beta, u, (beta_half * u_half)[:, None], frame, widths, supports)


def integrate_hemisphere(
    integrand: Integrand,
    poles: np.ndarray,
    widths: np.ndarray,
    supports: np.ndarray,
    *,
    rtol: float = DEFAULT_RTOL,
    atol: float = 0.0,
    max_evaluations: int = DEFAULT_MAX_EVALUATIONS,
    nonfinite: NonFinitePolicy = "raise",
    initial_panels: tuple[int, int] = (4, 2),
    max_nodes_per_call: int = 1_500_000,
    first_route: FirstRoute | None = None,
    anisotropic: np.ndarray | None = None,
    epsilon: float | None = None,
    fixed: np.ndarray | None = None,
    rescaled: Callable[[np.ndarray], Integrand] | None = None,
) -> RouteResult:
    """Integrate ``integrand`` over the upper hemisphere for every case, adaptively.

    Parameters
    ----------
    integrand
        ``integrand(omega, case)`` with ω of shape (M, 3) and the case index (M,) of each node; returns (M, C).
    poles, widths, supports
        Per case (K, 3), (K,), (K,): the lobe hint (:class:`brdfnorm.models.Lobe`).
    rtol, atol
        Stop when the summed error estimate ≤ max(atol, rtol·|value|) for every channel.
    max_evaluations
        Budget per case; a case that exhausts it is returned with ``converged=False``.
    nonfinite
        "raise": raise :class:`NonFiniteIntegrand` at the first NaN/Inf; "zero": count them as 0 and report
        the share of solid angle affected.
    first_route
        Tried before the global rule on the cases whose rounding noise is far below the tolerance (the
        half-vector route of :mod:`brdfnorm.engine.routes.halfvector_generic`); the cases it keeps are final.
    anisotropic
        Per case (K,), True where the lobe is not rotation-invariant about N: the global rule's azimuth estimate
        then also bounds the Fourier tail (:func:`brdfnorm.engine.machinery.tensor_rule._azimuthal_tail`).
    epsilon
        The unit roundoff of the integrand's evaluation where it is coarser than float64's (a model's ``epsilon``,
        2⁻²⁴ for float32): the rounding-noise bound is charged at least that (:func:`rounding_noise`).
    fixed, rescaled
        Each case's fixed direction (K, 3), and ``rescaled(factor)``: the integrand with it scaled by ``factor``
        (K,). Given both, the bias of the lobe's cosine from the inputs' rounded norms joins the noise amplitude
        (:func:`brdfnorm.engine.machinery.rounding.cosine_bias`).
    """
    poles = np.atleast_2d(np.asarray(poles, dtype=float))
    K = poles.shape[0]
    widths = np.broadcast_to(np.clip(np.asarray(widths, dtype=float), 1e-12, 4.0), (K,)).copy()
    supports = np.broadcast_to(np.clip(np.asarray(supports, dtype=float), 1e-6, np.pi), (K,)).copy()
    frame = lobe_frame(poles)

    nb, nu = initial_panels
    edges_b = np.linspace(0.0, 2.0 * np.pi, nb + 1)
    edges_u = np.linspace(0.0, 1.0, nu + 1)

    value = np.zeros((K, 0))
    error = np.zeros((K, 0))
    bad_total = np.zeros(K)
    evaluations = np.zeros(K, dtype=np.int64)
    converged = np.zeros(K, dtype=bool)
    reason = np.full(K, "", dtype=object)
    nodes_per_panel = NODES.size**2
    noise_amplitude, probed = surveyed_noise(integrand, frame, widths, supports, rtol, max_nodes_per_call, epsilon,
                                             anisotropic)
    evaluations += probed
    # The global tensor rule first (brdfnorm.engine.machinery.tensor_rule), for every case whose rounding noise is far
    # below its tolerance; the adaptive panels below take the cases it does not settle.
    # (Not at all where a quarter of the budget would not cover its first grid.)
    global_nodes = min(GLOBAL_NODES, max_evaluations // 4)
    quiet = np.flatnonzero((rtol == 0) | np.all(noise_bound(noise_amplitude, 1.0) < rtol / 16, axis=-1))
    first = None
    if first_route is not None and rtol > 0:
        # (every case: the first route chooses by the noise itself, halfvector_generic.HOPEFUL)
        first = first_route(integrand, poles, widths, np.arange(K), noise_amplitude, rtol=rtol, atol=atol,
                            max_evaluations=max_evaluations // 4)
        evaluations += first.evaluations
        quiet = quiet[~first.converged[quiet]]
    tried = integrate_global(integrand, frame, widths, supports, quiet if global_nodes >= START_NODES else quiet[:0],
                             noise_amplitude, rtol=rtol, atol=atol, noise_bound=noise_bound, max_nodes=global_nodes,
                             max_nodes_per_call=max_nodes_per_call, azimuthal_tail=anisotropic)
    evaluations += tried.evaluations
    routes = [tried] + ([first] if first else [])
    remaining = np.flatnonzero(~np.any([route.converged for route in routes], axis=0))
    panels = Panels(*starting_panels(remaining, edges_b, edges_u, neck_u(frame, widths, supports)[remaining],
                                      frame[0][remaining, 2], widths[remaining], supports[remaining]))
    history = []  # total error estimate per case and round (for the stall check)
    confirmations = np.zeros(K, dtype=np.int64)  # evaluations spent on confirming panels (not on refining them)
    since = np.zeros(K, dtype=np.int64)  # refining evaluations when a confirmation last raised the case's estimate
    # The stall check's budget grows with the initial panels: a graded start (starting_panels) holds up to a few
    # hundred of them, and its first rounds are pre-asymptotic (GGX α = 0.0038 at μ = 2.3e-4, rtol 1e-9, 72 initial
    # panels: estimates 0.73, 0.85, 0.39 at 71 000 evaluations, stopped as stalled, where 8 panels had converged).
    stall_after = np.full(K, STALL_EVALUATIONS)
    stall_after[remaining] = np.maximum(
        STALL_EVALUATIONS, STALL_EVALUATIONS * np.bincount(panels.case, minlength=K)[remaining] // (nb * nu))
    pool = None  # evaluated panels of unfinished cases
    fresh = panels  # panels still to evaluate
    parent_value = parent_error = None  # values and |K − G| of the panels whose halves ``fresh`` holds

    while fresh.case.size:
        _evaluate(fresh, integrand, frame, widths, supports, nonfinite, max_nodes_per_call)
        np.add.at(evaluations, fresh.case, nodes_per_panel)
        fresh.checked = np.zeros(fresh.case.size, dtype=bool)
        fresh.floor = np.zeros_like(fresh.value)
        if parent_value is None:
            fresh.change = np.zeros_like(fresh.value)
        else:
            # What one more level of refinement changed: a check that both embedded rules can pass together
            # when a feature falls between all their nodes.
            half = parent_value.shape[0]
            change = refinement_change(parent_value, fresh.value[:half], fresh.value[half:]) / 2
            fresh.change = np.concatenate([change, change])
            fresh.floor = algebraic_floor(parent_error, fresh.err_a + fresh.err_b)
        pool = fresh if pool is None else Panels.join(pool, fresh)
        if value.shape[1] != pool.value.shape[1]:
            value = np.zeros((K, pool.value.shape[1]))
            error = np.zeros_like(value)
            noise_amplitude = np.broadcast_to(noise_amplitude, value.shape).copy()

        # Totals per unfinished case over all its panels; the rounding-noise bound joins the error.
        total_value = np.zeros_like(value)
        magnitude = np.zeros_like(value)
        np.add.at(total_value, pool.case, pool.value)
        np.add.at(magnitude, pool.case, pool.magnitude)
        noise = noise_bound(noise_amplitude, magnitude)
        tolerance = np.maximum(atol, rtol * np.abs(total_value))
        present = np.zeros(K, dtype=bool)
        present[pool.case] = True
        panel_error, quadrature_error, within = _case_errors(pool, present, noise, tolerance)
        # Before a case may stop, within tolerance or not (budget, stall, rounding), each of its panels not yet
        # confirmed is recomputed as halves on new nodes, among them its edges and corners (_check_by_halves), and
        # the difference joins its error (brdfnorm.engine.machinery.confirmation).
        unchecked = np.bincount(pool.case[~pool.checked], minlength=K)
        estimate = np.where(present, (quadrature_error + noise).max(axis=1), np.nan)
        ending = stopping(history + [(evaluations - confirmations, estimate)], present & ~within, noise,
                          quadrature_error, tolerance, evaluations, confirmations, since, unchecked, stall_after,
                          max_evaluations)
        ends = np.any(ending[:3], axis=0)
        before = quadrature_error.max(axis=1)
        confirm = partial(_confirm, noise_amplitude=noise_amplitude, integrand=integrand, frame=frame, widths=widths,
                          supports=supports, max_nodes_per_call=max_nodes_per_call)
        confirming = confirm_before_stop(pool, within, ends, confirm, evaluations, CHECK_EVALUATIONS)
        if confirming.any():
            np.add.at(confirmations, pool.case[confirming], CHECK_EVALUATIONS)
            unchecked = np.bincount(pool.case[~pool.checked], minlength=K)
            panel_error, quadrature_error, within = _case_errors(pool, present, noise, tolerance)
            # What a confirmation found was in no earlier estimate: the stall check of a case that goes on compares
            # from here on.
            raised = present & ~ends & (quadrature_error.max(axis=1) > before)
            since[raised] = (evaluations - confirmations)[raised]
        # (Every panel of a case still within tolerance, or stopping, has now been confirmed.)
        case_ok = within
        converged |= case_ok
        history.append((evaluations - confirmations, np.where(present, (quadrature_error + noise).max(axis=1), np.nan)))
        # A case confirmed to stop stops (with what its confirmation found), unless it now meets its tolerance.
        going_on = stopping(history, present & ~case_ok & ~ends, noise, quadrature_error, tolerance, evaluations,
                            confirmations, since, unchecked, stall_after, max_evaluations)
        stop, stalled, out_of_budget, rounding_limited = (
            (first & ~case_ok) | then for first, then in zip(ending, going_on, strict=True))
        reason[out_of_budget] = "budget"
        reason[stalled] = "stalled"
        reason[rounding_limited & (stop | stalled | out_of_budget)] = "rounding-limited"
        active = present & ~(case_ok | stop | stalled | out_of_budget)

        # Within an active case, split the panels carrying the largest errors, normalized by what the
        # quadrature may still spend (the tolerance less the noise bound, or the noise bound where that exceeds
        # the tolerance): all but the smallest ones whose errors together stay under half of it.
        target = np.where(noise < tolerance, tolerance - noise, noise)
        share = normalized(panel_error, target[pool.case]).max(axis=1)
        order = np.lexsort((share, pool.case))
        sorted_case = pool.case[order]
        cumulative = np.cumsum(share[order])
        case_start = np.searchsorted(sorted_case, sorted_case, side="left")
        before_case = np.where(case_start > 0, cumulative[np.maximum(case_start - 1, 0)], 0.0)
        split = np.zeros(pool.case.size, dtype=bool)
        # (no more of them than the budget can evaluate and confirm: the largest first)
        affordable = (max_evaluations - evaluations - unchecked * CHECK_EVALUATIONS) // SPLIT_EVALUATIONS
        from_top = np.searchsorted(sorted_case, sorted_case, side="right") - 1 - np.arange(sorted_case.size)
        split[order] = (cumulative - before_case > 0.5) & active[sorted_case] & (from_top < affordable[sorted_case])
        # Panels too thin to split further stay as they are (their error stays in the estimate).
        split &= np.minimum(pool.a1 - pool.a0, (pool.b1 - pool.b0) * 2 * np.pi) > 1e-12

        finished = ~active[pool.case]
        done = present & ~active
        np.add.at(value, pool.case[finished], pool.value[finished])
        np.add.at(error, pool.case[finished], panel_error[finished])
        np.add.at(bad_total, pool.case[finished], pool.bad[finished])
        error[done] += noise[done]
        parents = pool.take(split)
        pool = pool.take(~split & ~finished)
        fresh = parents.halves(parents.err_a.max(axis=1) >= parents.err_b.max(axis=1))
        parent_value, parent_error = parents.value, parents.err_a + parents.err_b
        if not fresh.case.size and pool.case.size:
            # Active cases whose every panel is too thin to split: finish them unconverged.
            left = np.zeros(K, dtype=bool)
            left[pool.case] = True
            reason[left] = np.where(rounding_limited[left], "rounding-limited", "stalled")
            np.add.at(value, pool.case, pool.value)
            np.add.at(error, pool.case, pool.error())
            np.add.at(bad_total, pool.case, pool.bad)
            error[left] += noise[left]

    if value.shape[1] == 0:
        value = np.zeros((K, max(route.value.shape[1] for route in routes)))
        error = np.zeros_like(value)
    for route in routes:
        value[route.converged], error[route.converged] = route.value[route.converged], route.error[route.converged]
        converged |= route.converged
    reason[converged] = ""
    if fixed is not None and rescaled is not None:
        # The bias of the lobe's cosine, charged once the estimates are known, as a floor on the noise amplitude
        # they hold (noise_bound takes no credit for averaging: its margin is what covers a bias, and the probe's
        # noise, independent from node to node, mostly averages out), |value| standing for the |g|-integral of a
        # lobe ≥ 0; a case it takes past its tolerance is rounding-limited.
        bias, probed = cosine_bias(rescaled, frame, fixed, widths, supports, error, np.abs(value))
        evaluations[probed] += BIAS_EVALUATIONS
        error = error + noise_bound(np.maximum(bias - noise_amplitude, 0.0), np.abs(value))
        over = converged & np.any(error > np.maximum(atol, rtol * np.abs(value)), axis=1)
        converged &= ~over
        reason[over] = "rounding-limited"
    return RouteResult(value, error, evaluations, converged, reason.astype(str),
                       {"nonfinite_fraction": bad_total / (2.0 * np.pi)})


def _case_errors(pool: Panels, present: np.ndarray, noise: np.ndarray, tolerance: np.ndarray):
    """Panel errors (R, C), their sums per case (K, C), and which present cases meet the tolerance with the
    rounding-noise bound added."""
    panel_error = pool.error()
    summed = np.zeros_like(noise)
    np.add.at(summed, pool.case, panel_error)
    return panel_error, summed, present & np.all(normalized(summed + noise, tolerance) <= 1.0, axis=1)


def _node_values(panels: Panels, integrand, frame, widths, supports, nodes: np.ndarray, max_nodes_per_call: int,
                 nodes_u: np.ndarray | None = None):
    """For bounded chunks of ``panels``: (chunk, directions, Jacobians, integrand values (R, n, m, C))."""
    chunk = max(1, max_nodes_per_call // (nodes.size * (nodes.size if nodes_u is None else nodes_u.size)))
    for start in range(0, panels.case.size, chunk):
        part = panels.take(slice(start, start + chunk))
        omega, jacobian = _map_nodes(part, frame, widths, supports, nodes, nodes_u)
        case_of_node = np.broadcast_to(part.case[:, None, None], jacobian.shape)
        values = np.asarray(integrand(omega.reshape(-1, 3), case_of_node.ravel()), dtype=float)
        yield part, omega, jacobian, values.reshape(jacobian.shape + (-1,))


def _confirm(pool: Panels, confirming: np.ndarray, *, noise_amplitude, integrand, frame, widths, supports,
             max_nodes_per_call) -> None:
    """The confirmation of the panels ``pool[confirming]`` (brdfnorm.engine.machinery.confirmation): halved along β
    and along u in turn, each change joins that direction's error (the panel is split where the check found it
    wanting), less the panel's rounding-noise bound (charged to the case apart); the corner check joins β's."""
    checked = pool.take(confirming)
    own_noise = 2.0 * noise_bound(noise_amplitude[checked.case], checked.magnitude)
    for along_beta, err in ((True, pool.err_a), (False, pool.err_b)):
        change, corner = _check_by_halves(checked, along_beta, integrand, frame, widths, supports, max_nodes_per_call)
        err[confirming] = np.maximum(err[confirming], change - own_noise)
        if corner is not None:
            pool.err_a[confirming] = np.maximum(pool.err_a[confirming], corner - own_noise)


def _check_by_halves(panels: Panels, along_beta: bool, integrand, frame, widths, supports,
                     max_nodes_per_call) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`brdfnorm.engine.machinery.confirmation.check_with_corners` of each panel, split along β or u, with this
    route's node map (or, under the compiled backend, one fused kernel: map, shader, Jacobian and sums): the change
    and, with the halves along u, their corner check (else None)."""
    def sums(halves: Panels, nodes: tuple, weights: tuple) -> np.ndarray:
        if hasattr(integrand, "kernels"):
            return native.hemisphere_sums(integrand, halves.case, halves.a0, halves.a1, halves.b0, halves.b1, frame,
                                          widths, supports, *nodes, *weights)
        parts = []
        with np.errstate(all="ignore"):
            for _, _, jacobian, values in _node_values(halves, integrand, frame, widths, supports, nodes[0],
                                                       max_nodes_per_call, nodes[1]):
                values = np.where(np.isfinite(values), values, 0.0)
                parts.append(np.einsum("rbuc,rbu,b,u->rc", values, jacobian, *weights))
        return np.concatenate(parts)

    return check_with_corners(panels, along_beta, sums)


def _evaluate(panels: Panels, integrand, frame, widths, supports, nonfinite, max_nodes_per_call) -> None:
    """Fill in the estimates of ``panels``, calling the integrand on bounded chunks of nodes (or, under the compiled
    backend, one fused kernel over all panels)."""
    if hasattr(integrand, "kernels"):
        value, err_a, err_b, magnitude, bad, first_bad = native.hemisphere_panels(
            integrand, panels.case, panels.a0, panels.a1, panels.b0, panels.b1, frame, widths, supports, NODES,
            KRONROD, GAUSS)
        if nonfinite == "raise" and np.any(first_bad >= 0):
            r = int(np.argmax(first_bad >= 0))
            b, u = divmod(int(first_bad[r]), NODES.size)
            omega, _ = _map_nodes(panels.take(slice(r, r + 1)), frame, widths, supports)
            raise NonFiniteIntegrand(int(panels.case[r]), omega[0, b, u],
                                     integrand(omega[0, b, u][None], panels.case[r:r + 1])[0])
        panels.value, panels.err_a, panels.err_b, panels.magnitude, panels.bad = value, err_a, err_b, magnitude, bad
        return
    parts = []
    for part, omega, jacobian, values in _node_values(panels, integrand, frame, widths, supports, NODES,
                                                      max_nodes_per_call):
        finite = np.isfinite(values).all(axis=-1)
        bad = np.zeros(part.case.size)
        if not finite.all():
            if nonfinite == "raise":
                r, b, u = np.argwhere(~finite)[0]
                raise NonFiniteIntegrand(int(part.case[r]), omega[r, b, u], values[r, b, u])
            values = np.where(finite[..., None], values, 0.0)
            bad = np.einsum("rbu,b,u->r", jacobian * ~finite, KRONROD, KRONROD)
        parts.append((*kronrod_estimate(values * jacobian[..., None]), bad))
    panels.value, panels.err_a, panels.err_b, panels.magnitude, panels.bad = (
        np.concatenate(p) for p in zip(*parts, strict=True))

