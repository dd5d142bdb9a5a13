"""Albedo of rough dielectrics (:mod:`brdfnorm.models.dielectric`): reflection plus refraction, over the
microfacet normal with the slope distribution as the measure, exact from rough interfaces down to mirrors.

Reflection is the microfacet BRDF with the exact dielectric Fresnel, integrated by
:func:`brdfnorm.halfvector.single_scattering_albedo`. Refraction follows the same route (Walter et al. 2007,
§5.3: sampling the facet normal m with density D(m)(N·m), the refracted direction's weight is
|V·m| G2 (1 − F)/(|N·V| |N·m|), the same form as the reflected one with F → 1 − F), so in the energy form

    E_T(V) = (1/2π) ∫₀^{2π} ∫ G2(L, V) (1 − F(V·m)) (1 + c·x) du dφ,    L = refract(V, m, η),        (T1)

in the slope coordinates of :mod:`brdfnorm.halfvector` (m ∝ (x, y, 1), x = s d(φ), c = V_xy/V_z, u(s) the
distribution's radial CDF), with G2 the refraction shadowing (Heitz's B(1 + Λ_V, 1 + Λ_L) when
height-correlated).

Where refraction exists along a ray. With β the facet's polar angle (tan β = s|d|), V·m = A cos(β − β₀)
(A = √(V_z² + (V·d̂)²)): refraction needs V·m > c* (c* = √(1 − η²) for η < 1, the critical cosine, else 0),
an interval of β in closed form; within it the refracted L must also point below the surface (L_z < 0), whose
ends are found by bisection to float64's resolution. The ray's piece [s_a, s_b] is then integrated in three
parts as the reflection is (pole coordinate, tail coordinate, and a last part next to s_b where G2's boundary
layer at L_z → 0 lives), with quadratic grading at both ends: 1 − F vanishes like a square root at the
critical angle, and the grading makes that analytic. Where refraction reaches the horizontal facet (s_b = ∞),
the heavy GGX tail is cut at s = 1e16 and the dropped share bounded in the error.
"""

from __future__ import annotations

import numpy as np

from .halfvector import CubatureResult, _Panels, adaptive_rectangles, single_scattering_albedo
from .models.dielectric import MicrofacetDielectric, refraction_shadowing
from .models.microfacet import Distribution, fresnel_dielectric

_TWO_PI = 2.0 * np.pi
#: Slope radius at which a ray that refracts up to the horizontal facet is cut (its dropped share is bounded).
_S_CAP = 1e16
#: Samples of L_z along a ray's β-interval before its sign changes are located by bisection.
_SAMPLES = 17
_BISECTIONS = 60
#: The last part of a ray spans the band where Λ(L) turns on: |L_z| ≲ LAYER·α.
_LAYER = 4.0


def _ray(V, alpha, eta, angle):
    """Per ray (broadcast arrays): the direction d, and the β-interval [b_lo, b_hi] where refraction exists
    and L points below the surface."""
    dx, dy = alpha * np.cos(angle), alpha * np.sin(angle)
    vx, vy, vz = V
    w = vx * np.cos(angle) + vy * np.sin(angle)  # V·d̂
    amplitude = np.hypot(vz, w)
    beta0 = np.arctan2(w, vz)
    critical = np.sqrt(np.maximum(1.0 - eta * eta, 0.0))
    half = np.arccos(np.clip(critical / amplitude, -1.0, 1.0))
    lo = np.clip(beta0 - half, 0.0, np.pi / 2)
    hi = np.clip(beta0 + half, 0.0, np.pi / 2)
    empty = critical >= amplitude

    def below(beta):  # L_z < 0 for the facet at polar angle β on this ray (β may carry one more axis)
        extra = (...,) + (None,) * (np.ndim(beta) - np.ndim(angle))
        args = (vx, vy, vz, eta, np.cos(angle), np.sin(angle))
        return _refracted_z(*(np.broadcast_to(q, np.shape(angle))[extra] for q in args), beta) < 0

    # Sample L_z < 0 on [lo, hi]; the interval runs from the first to the last sample below the surface,
    # its ends located between neighbouring samples by bisection.
    grid = lo[..., None] + (hi - lo)[..., None] * np.linspace(0.0, 1.0, _SAMPLES)
    inside = below(grid) & (hi > lo)[..., None]
    first = np.argmax(inside, axis=-1)
    last = _SAMPLES - 1 - np.argmax(inside[..., ::-1], axis=-1)
    none = ~np.any(inside, axis=-1) | empty
    take = np.take_along_axis
    b_lo = take(grid, first[..., None], -1)[..., 0]
    b_hi = take(grid, last[..., None], -1)[..., 0]
    # Bisect towards the outside neighbour where the end is not the interval's own end.
    out_lo = take(grid, np.maximum(first - 1, 0)[..., None], -1)[..., 0]
    out_hi = take(grid, np.minimum(last + 1, _SAMPLES - 1)[..., None], -1)[..., 0]
    refine_lo, refine_hi = first > 0, last < _SAMPLES - 1
    a, b = out_lo.copy(), b_lo.copy()
    c, d = b_hi.copy(), out_hi.copy()
    for _ in range(_BISECTIONS):
        mid = 0.5 * (a + b)
        ok = below(mid)
        a, b = np.where(ok, a, mid), np.where(ok, mid, b)
        mid = 0.5 * (c + d)
        ok = below(mid)
        c, d = np.where(ok, mid, c), np.where(ok, d, mid)
    b_lo = np.where(refine_lo, b, b_lo)
    b_hi = np.where(refine_hi, c, b_hi)
    return dx, dy, np.where(none, 0.0, b_lo), np.where(none, 0.0, b_hi), none


def _refracted_z(vx, vy, vz, eta, cos_a, sin_a, beta):
    """L_z of V refracted through the facet (sin β cos a, sin β sin a, cos β)."""
    sb, cb = np.sin(beta), np.cos(beta)
    cos_i = (vx * cos_a + vy * sin_a) * sb + vz * cb
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    return -vz / eta + cb * (cos_i / eta - cos_t)


def _transmission_integrand(distribution: Distribution, shadowing: str, V: np.ndarray, alpha: np.ndarray,
                            eta: np.ndarray):
    lam = distribution.smith_lambda
    lambda_v = lam(alpha**2 * (V[:, 0] ** 2 + V[:, 1] ** 2) / V[:, 2] ** 2)

    def integrand(case, phi, v, piece):
        k = case[:, None, None]
        a, e = alpha[k], eta[k]
        vx, vy, vz = V[k, 0], V[k, 1], V[k, 2]
        # Ray quantities per (panel, azimuth node), then broadcast over the radial nodes.
        ray = _ray((vx[..., 0], vy[..., 0], vz[..., 0]), a[..., 0], e[..., 0], phi[..., 0])
        dx, dy, b_lo, b_hi, none = (q[..., None] for q in ray)
        d = a  # |d| for an isotropic distribution
        s_lo = np.tan(b_lo) / d
        s_hi = np.where(b_hi >= np.pi / 2, _S_CAP, np.minimum(np.tan(b_hi) / d, _S_CAP))
        # The last part: the band next to s_hi where |L_z| < LAYER·α (linearized through the slope of L_z).
        step = 1e-6 * (s_hi - s_lo)
        z_end = _refracted_z(vx, vy, vz, e, np.cos(phi), np.sin(phi), np.arctan((s_hi - step) * d))
        slope = np.maximum(np.abs(z_end) / np.maximum(step, 1e-300), 1e-300)
        s_split = np.clip(s_hi - _LAYER * a / slope, s_lo, s_hi)
        s_middle = np.clip(s_split / (1.0 + s_split), s_lo, s_split)
        # Beckmann's truncation (its dropped mass is bounded below); GGX has none.
        s_lo, s_middle, s_split, s_hi = (distribution.cap(q) for q in (s_lo, s_middle, s_split, s_hi))
        local = v - piece[:, None, None]
        # Grading: quadratic towards s_lo in the first part (1 − F ~ √ at the critical angle) and towards s_hi
        # in the last part (the boundary layer and the square root alike).
        first_map, first_jac = local * local, 2.0 * local
        last_map, last_jac = 1.0 - (1.0 - local) ** 2, 2.0 * (1.0 - local)
        t_lo, t_mid = distribution.pole_coordinate(s_lo), distribution.pole_coordinate(s_middle)
        s_pole, density_pole = distribution.pole(t_lo + first_map * (t_mid - t_lo))
        t_start, t_stop = distribution.tail_coordinate(s_middle), distribution.tail_coordinate(s_split)
        s_tail, density_tail = distribution.tail(t_start + local * (t_stop - t_start))
        s_near = s_split + last_map * (s_hi - s_split)
        pole, tail = (piece == 0)[:, None, None], (piece == 1)[:, None, None]
        s = np.where(pole, s_pole, np.where(tail, s_tail, s_near))
        density = np.where(pole, density_pole, np.where(tail, density_tail, distribution.slope_density(s_near)))
        length = np.where(pole, (t_mid - t_lo) * first_jac, np.where(tail, t_stop - t_start,
                                                                       (s_hi - s_split) * last_jac))
        x, y = s * dx, s * dy
        n = np.sqrt(1.0 + x * x + y * y)
        one_sp = 1.0 + (vx * x + vy * y) / vz
        cos_i = vz * one_sp / n
        sin2_t = (1.0 - cos_i * cos_i) / (e * e)
        cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
        scale = (cos_i / e - cos_t) / n
        Lx, Ly, Lz = -vx / e + scale * x, -vy / e + scale * y, -vz / e + scale
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            lambda_l = lam(a * a * (Lx * Lx + Ly * Ly) / (Lz * Lz))
            G2 = refraction_shadowing(shadowing, lambda_l, lambda_v[k])
            F = fresnel_dielectric(np.clip(cos_i, 0.0, 1.0), e)
            weight = G2 * (1.0 - F) * one_sp * density * length / _TWO_PI
        valid = (Lz < 0) & (cos_i > 0) & (sin2_t < 1.0) & ~none & np.isfinite(weight)
        return np.where(valid, weight, 0.0)[..., None]

    return integrand


def transmitted_albedo(distribution: Distribution, fixed: np.ndarray, alpha, eta, shadowing: str, *,
                       rtol: float = 1e-10, atol: float = 0.0, max_evaluations: int = 20_000_000) -> CubatureResult:
    """E_T(V) by (T1) for fixed directions (K, 3) (upper hemisphere) and per-case α, η."""
    fixed = np.atleast_2d(np.asarray(fixed, dtype=float))
    K = fixed.shape[0]
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), (K,)).copy()
    eta = np.broadcast_to(np.asarray(eta, dtype=float), (K,)).copy()
    edges_a = np.linspace(0.0, _TWO_PI, 9)
    edges_b = np.array([0.0, 1.0, 2.0, 3.0])
    a0, b0 = np.meshgrid(edges_a[:-1], edges_b[:-1], indexing="ij")
    a1, b1 = np.meshgrid(edges_a[1:], edges_b[1:], indexing="ij")
    n = a0.size
    initial = _Panels(np.repeat(np.arange(K), n), np.tile(a0.ravel(), K), np.tile(a1.ravel(), K),
                      np.tile(b0.ravel(), K), np.tile(b1.ravel(), K))
    result = adaptive_rectangles(_transmission_integrand(distribution, shadowing, fixed, alpha, eta), initial, K,
                                 rtol=rtol, atol=atol, max_evaluations=max_evaluations)
    # Dropped: rays cut at s = 1e16 (GGX's tail beyond carries ≤ 1/S² + 2|p|/S of weight), Beckmann's cap.
    p = alpha * np.hypot(fixed[:, 0], fixed[:, 1]) / fixed[:, 2]
    dropped = 1.0 / _S_CAP**2 + 2.0 * p / _S_CAP + distribution.truncated_mass() * 3.0 / fixed[:, 2] ** 2
    return CubatureResult(result.value, result.error + dropped[:, None], result.evaluations, result.converged)


def albedo_method(problem, *, rtol: float, atol: float = 0.0, max_evaluations: int = 20_000_000, **_: object):
    """``brdfnorm.albedo`` method ``"dielectric"``: reflection by the half-vector BRDF integral with the exact
    dielectric Fresnel, refraction by (T1); each part to ``rtol`` of the total."""
    model: MicrofacetDielectric = problem.model
    K = problem.fixed.shape[0]
    params = problem.case_params(np.arange(K))
    alpha = np.broadcast_to(np.asarray(params["alpha"], dtype=float), (K,))
    eta = np.broadcast_to(np.asarray(params["eta"], dtype=float), (K,))
    reflection_params = {"alpha": alpha, "alpha_x": 0.0, "alpha_y": 0.0, "shadowing": params["shadowing"],
                         "fresnel": "dielectric", "f0": 0.0, "f90": 1.0, "eta": eta[:, None], "k": 0.0}
    # Both parts are ≤ the total, so each at rtol of itself meets rtol of the sum.
    reflected = single_scattering_albedo(model.distribution, problem.fixed, reflection_params, rtol=rtol,
                                         atol=atol / 2, max_evaluations=max_evaluations // 2)
    transmitted = transmitted_albedo(model.distribution, problem.fixed, alpha, eta, params["shadowing"], rtol=rtol,
                                     atol=atol / 2, max_evaluations=max_evaluations // 2)
    r, t = reflected.value[:, :1], transmitted.value
    return (r + t, reflected.error[:, :1] + transmitted.error, reflected.evaluations + transmitted.evaluations,
            reflected.converged & transmitted.converged, None, {"reflected": r, "transmitted": t})
