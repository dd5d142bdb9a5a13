"""Albedo of microfacet lobes integrated over the half vector, exact from rough lobes down to mirrors.

What it computes
----------------
E(V) = ∫ f(L, V)(N·L) dL for f = D(H) G2(L, V) F(V·H) / (4 N·L N·V) (:mod:`brdfnorm.models.microfacet`).
With the reflection map's Jacobian dω_L = 4 (V·H) dω_H (Walter et al. 2007 eq. 14),

    E(V) = ∫ G2 F (V·H)/(N·V N·H) · D(H)(N·H) dω_H,

and D(H)(N·H) dω_H is the probability measure of the slopes (x, y) = (α_x s cos φ, α_y s sin φ), with φ
uniform and s distributed by the standardized radial CDF u(s) (GGX s²/(1+s²), Beckmann 1 − e^{−s²}). In
these coordinates the weight is exactly the distribution, whatever α, and the integrand is
(H ∝ (x, y, 1), c = (V_x, V_y)/V_z):

    w = G2(L, V) F(V·H) (1 + c·x),    L = 2(V·H)H − V,    E = (1/2π) ∫₀^{2π} ∫ w du dφ.        (H1)

Where the horizon lies. N·L = V_z (1 + 2c·x − |x|²)/(1 + |x|²) > 0 is the disk |x − c| < 1/V_z in real
slopes, which contains x = 0; along each ray x = s d(φ), d = (α_x cos φ, α_y sin φ), it ends at

    s_h(φ) = (q + p)/|d|²,   p = c·d,  q = √(p² + |d|²)        (the positive root, cancellation-free),

so integrating s over [0, s_h(φ)] puts the horizon on the boundary of the domain, and N·L is evaluated as
V_z (s_h − s)(|d|² s + q − p)/(1 + s²|d|²), a product that keeps its relative accuracy at the horizon.

Radial coordinate. The integral runs over t with u = u(s(t)) (``Distribution.radial``): GGX t = atan s
(u = sin²t: no √u branch point at the pole, and the heavy tail ends at t → π/2 analytically in 1/s, i.e.
in the inverse real slope); Beckmann t = s (weight 2s e^{−s²}, truncated at s = 8 with the dropped mass
e⁻⁶⁴ bounded and added to the error). Near the horizon G2 has a boundary layer: Λ(L) ≈ α/(2 N·L) turns on
where N·L ≲ α, a band of width ~α² in t next to t_h for small α (it carries ~α³ of the albedo: 1e-9 at
α = 1e-3, more than the tolerance, yet far narrower than a quadrature panel). Each ray is therefore cut at
the point where the linearized N·L reaches 4 max(α_x, α_y),

    s_split = s_h / (1 + Δs/s_h),   Δs = 4α (1 + s_h²|d|²)/(2 q V_z)   (a smooth function of φ),

and the two pieces are mapped to v ∈ [0, 1] and [1, 2] of one rectangle (φ, v) ∈ [0, 2π] × [0, 2]: on each
piece the integrand is analytic, with its nearest singularity (Λ's branch point at N·L = ±iα) at a distance
comparable to the piece. The φ panels start at the zeros and extrema of p(φ) = c·d(φ), where s_h(φ) changes
fastest at grazing views (over a φ-width ~ V_z).

Cubature. First a global tensor rule per case and piece (:mod:`brdfnorm.engine.routes.halfvector_global`: periodic
trapezoid
in φ × Fejér in v, degree doubling with node reuse), which settles most views with half the evaluations; the
cases it does not settle (grazing views, μ ≲ 0.01) start afresh on the panels below.
Adaptive Gauss–Kronrod over the rectangles of all cases at once (no Python loop per case), by the engine's rectangle
driver (:func:`brdfnorm.engine.machinery.panels.adaptive_rectangles`): a tensor K15 ⊗ K15 rule per panel (225
nodes), its error the plain |KK − GK| + |KK − KG| of the embedded G7 rules (not QUADPACK's rescaling); panels are
bisected along their worse direction while their case misses max(atol, rtol·|E|). Before a case stops, meeting the
tolerance or out of budget, every panel not yet checked is re-integrated on its four quarters with Lobatto7 ⊗
Lobatto7 (new nodes, the edges among them) and the difference joins its error
(:mod:`brdfnorm.engine.machinery.confirmation`; taking the smaller of the two instead halves the work but was found
optimistic at μ ≲ 1e-6: kept as a sum). The tests check estimate ≥ true error against an independent reference on
every case they compute.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from ...errors import ArgumentError
from ...models.microfacet import Distribution, fresnel, roughness, shadowing_masking
from ...validate import DEFAULT_MAX_EVALUATIONS, DEFAULT_RTOL
from ..machinery.panels import PANELS_PER_CHUNK, Panels, RectangleIntegrand, adaptive_rectangles
from ..machinery.result import RouteResult
from ..machinery.slope_coordinates import slope_coordinates
from . import halfvector_global as global_rule

#: Roughness floor inside the integral (α = 0 is a mirror; 1e-150 differs from it by ~1e-300).
_ALPHA_FLOOR = 1e-150
#: The horizon piece spans N·L ∈ [0, LAYER·α] (linearized), where G2's boundary layer lives.
_LAYER = 4.0
_TWO_PI = 2.0 * np.pi



# -- the microfacet integrand (H1) -------------------------------------------------------------------------

@dataclass
class SlopeGeometry:
    """Per-case quantities of (H1): the fixed direction, roughness, Λ(V), Fresnel parameters."""

    distribution: Distribution
    shadowing: str
    V: np.ndarray  # (K, 3)
    ax: np.ndarray  # (K,)
    ay: np.ndarray
    lambda_v: np.ndarray
    fresnel_params: dict = field(default_factory=dict)  # per case (K, 3) or shared
    multiplicity: np.ndarray | None = None  # (K,) 2 where only half of a symmetric azimuth range is integrated


def slope_geometry(distribution: Distribution, fixed: np.ndarray, params: Mapping[str, object]) -> SlopeGeometry:
    K = fixed.shape[0]
    ax, ay = roughness(params)
    ax = np.maximum(np.broadcast_to(ax, (K,)), _ALPHA_FLOOR)
    ay = np.maximum(np.broadcast_to(ay, (K,)), _ALPHA_FLOOR)
    a2 = ((ax * fixed[:, 0]) ** 2 + (ay * fixed[:, 1]) ** 2) / fixed[:, 2] ** 2
    lambda_v = distribution.smith_lambda(a2)
    colours = {"fresnel": params["fresnel"]}
    for name in ("f0", "f90", "eta", "k"):
        value = np.asarray(params[name], dtype=float)
        colours[name] = value if value.ndim <= 1 else np.broadcast_to(value, (K, value.shape[-1]))  # (K, 3) or (K, 1)
    return SlopeGeometry(distribution, params["shadowing"], fixed, ax, ay, lambda_v, colours)


def _case_slice(params: dict, case: np.ndarray) -> dict:
    return {k: (v[case][:, None, None, :] if isinstance(v, np.ndarray) and v.ndim == 2 else v)
            for k, v in params.items()}


def _grading_width(g: SlopeGeometry) -> np.ndarray:
    """δ per case: the azimuthal width of the grazing feature next to the zeros of p(φ) (1 where none)."""
    Vz = g.V[:, 2]
    cx, cy = g.V[:, 0] / Vz, g.V[:, 1] / Vz
    # Azimuth grading (φ-map): the horizon radius changes fastest near the zeros of p(φ) = c·d(φ), where
    # y = p/|d| ∈ [−reach, reach], reach = |c| α_max/α_min, crosses the scales 1 (horizon at real slope ~1;
    # it matters while the tail mass ~α² does) and 1/(16α) (the horizon enters the distribution's bulk,
    # s ≲ 8). Both lie at azimuthal distance ~y/reach from the zero; φ = δ sinh(κξ) with δ half the finest
    # such distance spreads the distances δ … π/2 evenly over ξ ∈ [0, 1] (δ = 1: a mild map, no feature).
    a_min, a_max = np.minimum(g.ax, g.ay), np.maximum(g.ax, g.ay)
    reach = np.hypot(cx, cy) * a_max / a_min
    scale = np.where(a_max > 1e-6, np.minimum(1.0, 1.0 / (16.0 * a_min)), 1.0 / (16.0 * a_min))
    with np.errstate(divide="ignore", invalid="ignore"):
        delta = np.where(reach > scale, np.clip(0.5 * scale / reach, 1e-300, 1.0), 1.0)
    return delta


@dataclass(frozen=True)
class SlopeNodes:
    """The quantities of (H1) at a grid of nodes (R, n, n) that a weight function needs: the case index ``k``
    (R, 1, 1) into the geometry, slope radius ``s`` along x = s d(φ), d = (``dx``, ``dy``), ``one_sp`` = 1 + s c·d =
    (V·H)/(V_z H_z), ``n2`` = 1 + s²|d|² = 1/H_z², ``Lz`` = N·L (accurate at the horizon),
    ``weight_t`` = du/dt of the radial coordinate, ``azimuth`` = dφ/dξ · multiplicity / 2π."""

    k: np.ndarray
    case: np.ndarray
    s: np.ndarray
    dx: np.ndarray
    dy: np.ndarray
    one_sp: np.ndarray
    n2: np.ndarray
    Lz: np.ndarray
    weight_t: np.ndarray
    azimuth: np.ndarray


#: w of (H1) at the nodes, times ``weight_t`` and ``azimuth``: (R, n, n, C).
SlopeWeight = Callable[[SlopeNodes], np.ndarray]


def microfacet_weight(g: SlopeGeometry) -> SlopeWeight:
    """w = G2(L, V) F(V·H) (1 + c·x) of the microfacet lobe (H1)."""
    dist = g.distribution

    def weight_of(n: SlopeNodes) -> np.ndarray:
        k, s, Lz = n.k, n.s, n.Lz
        ax, ay = g.ax[k], g.ay[k]
        # a² = (α_x² L_x² + α_y² L_y²)/L_z² with |L| = 1: α_y²(1 − L_z²) + (α_x² − α_y²) L_x², whose second term
        # vanishes for an isotropic lobe (the tables' case), saving L_x, L_y. 1 − L_z² = (1 − L_z)(1 + L_z) loses
        # relative accuracy only where L_z → 1, where a² ~ α² eps is far below the tolerance.
        tangent2 = np.maximum((1.0 - Lz) * (1.0 + Lz), 0.0) * (ay * ay)
        if np.any(ax != ay):
            Lx = 2.0 * g.V[k, 2] * n.one_sp * s * n.dx / n.n2 - g.V[k, 0]
            tangent2 += (ax * ax - ay * ay) * Lx * Lx
        with np.errstate(divide="ignore", invalid="ignore"):
            lambda_l = dist.smith_lambda(tangent2 / (Lz * Lz))
        G2 = shadowing_masking(g.shadowing, lambda_l, g.lambda_v[k])
        weight = G2 * n.one_sp * n.weight_t * n.azimuth
        weight = np.where(Lz > 0, weight, 0.0)[..., None]  # only t = t_h itself, where G2 = 0 anyway
        if g.fresnel_params["fresnel"] == "none":
            return weight
        F = fresnel(_case_slice(g.fresnel_params, n.case), g.V[k, 2] * n.one_sp / np.sqrt(n.n2))  # F(V·H)
        return weight * F

    return weight_of


def slope_map(g: SlopeGeometry) -> dict[str, np.ndarray]:
    """Per case, the constants of the slope map of (H1) that :func:`slope_integrand` uses (and the compiled
    backend's kernel, :func:`brdfnorm.engine.compiled.slopes.shader_grid`)."""
    Vz = g.V[:, 2]
    cx, cy = g.V[:, 0] / Vz, g.V[:, 1] / Vz
    offset = np.arctan2(cy * g.ay, cx * g.ax) + np.pi / 2  # a zero of p(φ) = c·d(φ) = A cos(φ − offset + π/2)
    delta = _grading_width(g)
    return {"vz": Vz, "cos_offset": np.cos(offset), "sin_offset": np.sin(offset),
            "amplitude": np.hypot(cx * g.ax, cy * g.ay), "ax": g.ax, "ay": g.ay,
            "layer": _LAYER * np.maximum(g.ax, g.ay), "delta": delta, "kappa": np.arcsinh(0.5 * np.pi / delta),
            "multiplicity": g.multiplicity}


def slope_integrand(g: SlopeGeometry, weight_of: SlopeWeight, linear: bool = False) -> RectangleIntegrand:
    """The rectangle (φ, v) of (H1) with the weight ``weight_of``; ``linear``: φ is the azimuth from the offset
    itself (no φ-map), for the global rule (:mod:`brdfnorm.engine.routes.halfvector_global`), which clusters its own
    nodes."""
    Vz = g.V[:, 2]
    cx, cy = g.V[:, 0] / Vz, g.V[:, 1] / Vz
    offset = np.arctan2(cy * g.ay, cx * g.ax) + np.pi / 2  # a zero of p(φ) = c·d(φ) = A cos(φ − offset + π/2)
    amplitude = np.hypot(cx * g.ax, cy * g.ay)
    cos_offset, sin_offset = np.cos(offset), np.sin(offset)
    layer = _LAYER * np.maximum(g.ax, g.ay)
    dist = g.distribution
    coords = slope_coordinates(dist)
    delta = _grading_width(g)
    kappa = np.arcsinh(0.5 * np.pi / delta)
    log_horizon = linear and dist.name in global_rule.GRADED

    def integrand(case, phi, v, piece):
        # Slopes of ~1e150 (α → 0) square to inf where their weight is 0; np.where evaluates both branches.
        with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
            return evaluate(case, phi, v, piece)

    def evaluate(case, phi, v, piece):
        k = case[:, None, None]
        ax, ay, vz = g.ax[k], g.ay[k], Vz[k]
        zero = np.pi * np.round(phi / np.pi)  # the zero of p at the panel's end (panels never straddle one)
        # The azimuth is offset + zero + ε; ε, the distance from the zero of p, is kept apart so that p and the
        # direction keep their relative accuracy next to the zero (at grazing views |c| ~ 1/μ is huge).
        if linear:
            epsilon, phi_jacobian = phi - zero, 1.0
        else:
            stretch = kappa[k] * np.abs(phi - zero) / (0.5 * np.pi)
            epsilon = np.sign(phi - zero) * delta[k] * np.sinh(stretch)
            phi_jacobian = delta[k] * kappa[k] * np.cosh(stretch) / (0.5 * np.pi)
        parity = 1.0 - 2.0 * (np.round(zero / np.pi) % 2)  # cos(zero), sin(zero) = 0
        cos_e, sin_e = np.cos(epsilon), np.sin(epsilon)
        cos_a = parity * (cos_offset[k] * cos_e - sin_offset[k] * sin_e)
        sin_a = parity * (sin_offset[k] * cos_e + cos_offset[k] * sin_e)
        dx, dy = ax * cos_a, ay * sin_a  # (R, n, 1)
        d2 = dx * dx + dy * dy
        p = -amplitude[k] * parity * sin_e  # A cos(π/2 + zero + ε)
        q = np.sqrt(p * p + d2)
        q_plus_p = np.where(p > 0, q + p, d2 / (q - p))
        q_minus_p = np.where(p > 0, d2 / (q + p), q - p)
        s_h = q_plus_p / d2
        r_h2 = q_plus_p * q_plus_p / d2
        gap = layer[k] * (1.0 + r_h2) / (2.0 * q * vz)
        s_split = s_h / (1.0 + gap / s_h)
        s_middle = s_split / (1.0 + s_split)  # ≈ min(1, s_split), smooth in φ
        s_end, s_split, s_middle = coords.cap(s_h), coords.cap(s_split), coords.cap(s_middle)
        local = v - piece[:, None, None]  # position in the piece, [0, 1], (R, 1, n)
        # Pole piece [0, s_middle] in the pole coordinate, tail piece [s_middle, s_split] in the tail
        # coordinate, horizon piece [s_split, s_h] linear in s; each computed on its own panels only.
        def piece_nodes(kind, rows, at):
            if kind == 0:
                length = coords.pole_coordinate(s_middle[rows])
                radius, density = coords.pole(at * length)
            elif kind == 1:
                start = coords.tail_coordinate(s_middle[rows])
                length = coords.tail_coordinate(s_split[rows]) - start
                radius, density = coords.tail(start + at * length)
            elif log_horizon:  # ln s linear: a layer wider than the horizon radius spans decades (global rule)
                log_ratio = np.log(s_end[rows] / s_split[rows])
                radius = s_end[rows] * np.exp((at - 1.0) * log_ratio)
                length, density = radius * log_ratio, dist.slope_density(radius)
                to_end = -s_end[rows] * np.expm1((at - 1.0) * log_ratio)
            else:
                length = s_end[rows] - s_split[rows]
                radius = s_split[rows] + at * length
                density, to_end = dist.slope_density(radius), length * (1.0 - at)
            gap = s_h[rows] - radius if kind < 2 else (s_h[rows] - s_end[rows]) + to_end
            return radius, density * length, gap

        s, weight_t, gap_to_horizon = fill_pieces(piece, local, s_h.shape, piece_nodes)
        one_sp = 1.0 + s * p
        n2 = 1.0 + s * s * d2
        Lz = vz * gap_to_horizon * (d2 * s + q_minus_p) / n2
        return weight_of(SlopeNodes(k, case, s, dx, dy, one_sp, n2, Lz, weight_t,
                                    phi_jacobian * (g.multiplicity[k] / _TWO_PI)))

    return integrand


def fill_pieces(piece: np.ndarray, local: np.ndarray, shape: tuple[int, ...],
                piece_nodes: Callable[[int, np.ndarray, np.ndarray], tuple[np.ndarray, ...]]
                ) -> tuple[np.ndarray, ...]:
    """The radial nodes of panels that belong to different pieces (0 pole, 1 tail, 2 horizon layer), each piece
    computed on its own panels only: ``piece_nodes(kind, rows, at)`` gives three arrays for the panel rows ``rows``
    at their positions ``at`` ∈ [0, 1] within the piece; they are gathered into arrays of the broadcast shape of
    ``local`` (R, 1, n) and ``shape``. Shared by this module's integrand and the refraction's
    (:mod:`brdfnorm.engine.routes.dielectric`)."""
    shape = np.broadcast_shapes(local.shape, shape)
    out = tuple(np.empty(shape) for _ in range(3))
    for kind in range(3):
        rows = np.flatnonzero(piece == kind)
        if rows.size:
            for target, value in zip(out, piece_nodes(kind, rows, local[rows]), strict=True):
                target[rows] = value
    return out


def single_scattering_albedo(distribution: Distribution, fixed: np.ndarray, params: Mapping[str, object], *,
                             rtol: float = DEFAULT_RTOL, atol: float | np.ndarray = 0.0,
                             max_evaluations: int = DEFAULT_MAX_EVALUATIONS, use_global: bool = True,
                             compiled: bool = False) -> RouteResult:
    """E(V) of the single-scattering microfacet lobe for fixed directions (K, 3) and per-case parameters.

    Views below cos θ = :data:`GRAZING_MU` (9e-5) are integrated to min(rtol, :data:`GRAZING_RTOL`): there the
    estimates at looser tolerances were found optimistic (GGX against the 1-D route of
    :mod:`brdfnorm.engine.routes.azimuthal`, 150 random (μ ∈ [1e-6, 1e-2], α ∈ [1e-8, 1]) views: up to 5·10⁵ times the
    estimate at rtol 1e-3, μ = 1.5e-6, α = 0.84; 4.7 times at rtol 1e-5; 1.3e-7 ≤ μ: 0.056 off, estimated 1e-8,
    at rtol 1e-7), while at rtol 1e-10 every one of 300 views from μ = 1e-8 to 1e-4 was within its estimate.
    ``compiled``: the rectangle integrand as one compiled kernel (:mod:`brdfnorm.engine.compiled.slopes`)."""
    fixed = np.atleast_2d(np.asarray(fixed, dtype=float))
    # Per case (K, 1): both rules compare each case's estimate with max(atol, rtol·|E|) elementwise.
    rtol = np.where(fixed[:, 2] < GRAZING_MU, min(rtol, GRAZING_RTOL), rtol)[:, None]
    g = slope_geometry(distribution, fixed, params)
    rectangle = None
    if compiled:
        from ..compiled.slopes import microfacet_rectangle

        def rectangle(linear: bool) -> RectangleIntegrand:
            return microfacet_rectangle(g, linear, linear and distribution.name in global_rule.GRADED, slope_map(g))
    result = integrate_slopes(g, microfacet_weight(g), g.ax == g.ay, rtol=rtol, atol=atol,
                              max_evaluations=max_evaluations, use_global=use_global, rectangle=rectangle)
    # Beckmann's truncation: w = G2 F (1 + c·x) ≤ 1 + |c| α_max s (G2, F ≤ 1) over the dropped slope radii.
    mass, moment = slope_coordinates(distribution).truncated_moments()
    truncated = mass + moment * np.hypot(fixed[:, 0], fixed[:, 1]) / fixed[:, 2] * np.maximum(g.ax, g.ay)
    return RouteResult(result.value, result.error + truncated[:, None], result.evaluations, result.converged)


def integrate_slopes(g: SlopeGeometry, weight_of: SlopeWeight, symmetric: np.ndarray, *, rtol: float | np.ndarray,
                     atol: float | np.ndarray, max_evaluations: int, use_global: bool = True,
                     max_nodes: int = global_rule.MAX_NODES, chunk: int = PANELS_PER_CHUNK,
                     rectangle: Callable[[bool], RectangleIntegrand] | None = None) -> RouteResult:
    """∫∫ w du dφ/2π over the rectangle of (H1) for every case of ``g``: the global rule first (``max_nodes`` per
    radial piece), then the adaptive panels for the cases it does not settle. ``symmetric`` (K,): w is symmetric
    about the plane of N and V, so half the azimuth range, counted twice, is the whole integral (the azimuth map's
    zeros at φ = 0, π and its symmetry axes at φ = π/2, 3π/2). ``chunk``: panels per call of ``weight_of``;
    ``rectangle(linear)``, where given, is the rectangle integrand itself (the compiled backend's fused kernel) in
    place of :func:`slope_integrand` with ``weight_of``."""
    if rectangle is None:
        def rectangle(linear: bool) -> RectangleIntegrand:
            return slope_integrand(g, weight_of, linear=linear)

    K = g.V.shape[0]
    g.multiplicity = np.where(symmetric, 2.0, 1.0)
    full = np.linspace(0.0, _TWO_PI, 5)
    pieces = np.arange(4.0)
    cases, bounds = [], []
    for mask, edges_a in ((symmetric, full[1:4]), (~symmetric, full)):
        a0, b0 = np.meshgrid(edges_a[:-1], pieces[:-1], indexing="ij")
        a1, b1 = np.meshgrid(edges_a[1:], pieces[1:], indexing="ij")
        index = np.flatnonzero(mask)
        cases.append(np.repeat(index, a0.size))
        bounds.append([np.tile(x.ravel(), index.size) for x in (a0, a1, b0, b1)])
    lam = global_rule.clustering(g.V[:, 2])
    tried = np.arange(K) if use_global else np.arange(0)
    rule = global_rule.integrate_global(
        rectangle(True), K, tried, lam, symmetric, 1.0 / g.multiplicity, rtol=rtol,
        atol=atol, max_nodes=max_nodes, width=global_rule.grading_width(g.V[:, 2], g.distribution.name))
    value, error, evaluations, settled = rule.value, rule.error, rule.evaluations, rule.converged
    initial = Panels(np.concatenate(cases), *(np.concatenate([b[i] for b in bounds]) for i in range(4)))
    initial = initial.take(~settled[initial.case])
    if initial.case.size:
        panels = adaptive_rectangles(rectangle(False), initial, K, rtol=rtol, atol=atol,
                                     max_evaluations=max(max_evaluations - int(evaluations.max()), 1), chunk=chunk)
        shape = (K, max(value.shape[1], panels.value.shape[1]))  # 1 channel where no case ran on a side
        value, error = (np.broadcast_to(x, shape).copy() for x in (value, error))
        value[~settled] = np.broadcast_to(panels.value, shape)[~settled]
        error[~settled] = np.broadcast_to(panels.error, shape)[~settled]
        evaluations = evaluations + np.where(settled, 0, panels.evaluations)
        settled = settled | panels.converged
    return RouteResult(value, error, evaluations, settled)


# -- limits ---------------------------------------------------------------------------------------------------

#: Views below this cos θ are integrated to at most GRAZING_RTOL (see single_scattering_albedo): below the tables'
#: clamp μ = 1e-4 (where the honesty grids pass at every rtol), whatever rounding cos(arccos 1e-4) brings.
GRAZING_MU = 9e-5
GRAZING_RTOL = 1e-10
#: Below this cos θ the reference checks found the estimates optimistic (GGX, μ = 1e-11: 2e-9 off, 7e-11 claimed).
MU_MIN = 1e-8


def require_mu_min(cos_fixed: np.ndarray) -> None:
    """Refuse fixed directions closer to the horizon than :data:`MU_MIN`."""
    if np.any(cos_fixed < MU_MIN):
        raise ArgumentError(
            f"the microfacet methods need cos θ ≥ {MU_MIN:g} (θ ≤ {np.degrees(np.arccos(MU_MIN)):.7f}°): closer to "
            "the horizon float64 cannot resolve where it cuts the lobe (estimates would be optimistic)", where="theta")
