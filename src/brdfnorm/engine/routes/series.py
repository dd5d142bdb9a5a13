"""Seed 002's hypergeometric form of the Blinn-Phong albedo, made into a fast exact method.

The albedo of f = max(0, N·H)^n at view angle θ_o (it does not depend on the view azimuth) is

    E(θ_o) = ∫ (N·H)^n (N·L) dL,   H = (L + V)/‖L + V‖.

Seed 002 (/work/shared/seeds/002_*.txt, "Spherical Coordinates: Integrating Δθ") writes L in polar angle φ_i
and azimuth Δθ relative to V, uses ‖L + V‖ = √2·√(L·V + 1), and integrates Δθ in closed form:

    E(θ_o) = 2π·2^(−n/2) ∫₀^{π/2} ((c_o+c_i)/√(c_o c_i+1))^n c_i s_i ₂F₁(n/4, n/4+½; 1; z) dφ_i,      (S1)
    z = (s_o s_i/(c_o c_i + 1))²,  c = cos, s = sin.

Evaluated as written, (S1) fails for large n and grazing views: the power factor overflows (it is as large as
2^(n/2)) while ₂F₁ with c − a − b = ½ − n/2 blows up like (1 − z)^(½−n/2) as z → 1 — at the mirror direction
of a grazing view z = 1 − O(cos²θ_o) — and the product of the two is a 0·∞ in floating point. We rewrite it
so that every factor is bounded by one and computed without cancellation.

Derivation
----------
1. The inner integral of (S1) is K(φ_i) = ∫₀^{2π} (N·H)^n dΔθ with (N·H)² = (c_o+c_i)²/(2(B + C cos Δθ)),
   B = 1 + c_o c_i, C = s_o s_i. Its largest value, at the mirror side Δθ = π, is
   (c_o+c_i)²/(2(B − C)) = cos²(δ/2) with δ = θ_o − φ_i (write c_o + c_i and B − C = 1 + cos(θ_o+φ_i) as
   products of half-angle cosines). Factoring it out and setting t = π − Δθ,

       K = cos^n(δ/2) ∫₀^{2π} ((B − C)/(B − C cos t))^m dt,   m = n/2.                               (S2)

2. Laplace's first integral for the Legendre function (DLMF §14.12), P_ν(x) = (1/π)∫₀^π (x + √(x²−1) cos t)^ν
   dt with ν = −m (and P_{−m} = P_{m−1}, DLMF §14.9), evaluates (S2):

       K = 2π cos^n(δ/2) G_m(λ),   G_m(λ) = λ^(m/2) P_{m−1}((1+λ)/(2√λ)) = λ^m ₂F₁(m, ½; 1; 1 − λ),        (S3)
       λ = (B − C)/(B + C) = cos²((θ_o+φ_i)/2) / cos²((θ_o−φ_i)/2) ∈ (0, 1].

   The ₂F₁ in (S3) and seed 002's ₂F₁(m/2, m/2+½; 1; C²/B²) are the same function under the quadratic
   transformation of DLMF §15.8 (c = 2b with b = ½); the tests check (S3) against seed 002's form with
   mpmath.hyp2f1. With ρ = 1/√λ = x + √(x²−1) one has 0 < G_m ≤ 1: G is the mean of ((B−C)/(B−C cos t))^m.

3. G_m is evaluated through the Mehler–Dirichlet integral (DLMF §14.12), with x = cosh ξ, ξ = −½ ln λ:

       P_ν(cosh ξ) = (√2/π) ∫₀^ξ cosh((ν+½)τ) / √(cosh ξ − cosh τ) dτ.

   Substituting τ = ξ − s² (which removes the inverse square root at τ = ξ) and taking every exponential
   relative to its maximum,

       G_m = (√(2λ)/π) ∫₀^{√ξ} [e^{−(m−¾)s²} + e^{ξ/2 − (m−¼)(2ξ−s²)}] s / √((1 − e^{−(2ξ−s²)}) sinh(s²/2)) ds.   (S4)

   The integrand is analytic on the closed interval (its nearest singularities are at s = √(2ξ) and at the
   zeros of sinh(s²/2), a fixed distance away relative to the interval) and, for large m, a Gaussian of width
   1/√m, so the range is cut where e^{−(m−¾)s²} < e^{−45}, where the second term is below e^{−45} too.
   A 24-point Gauss–Legendre rule on (S4) gives G to ≤ 3e-15 relative for m ∈ [0, 5·10⁴], λ ∈ [10⁻¹², 1]
   (tests: against mpmath.hyp2f1 at 30 digits). The cost is independent of n.

4. The outer integral is

       E(θ_o) = 2π ∫₀^{π/2} cos^n((θ_o−φ)/2) G_{n/2}(λ(φ)) cos φ sin φ dφ,                            (S5)

   integrated by vectorized adaptive Gauss–Legendre (15 points on a panel against 15 points on each half,
   whose difference is the error estimate) on panels with breakpoints at the mirror peak φ = θ_o and at
   multiples of its width 2√2/√(n+1); outside |φ − θ_o| ≤ √(8·60/n) the factor cos^n is below e^{−60} and the
   range is cut. cos^n(δ/2) is computed as exp(n·log1p(−2 sin²(δ/4))): a power of a rounded cosine would
   carry n times its rounding error. λ and ξ come from cancellation-free forms: ξ = atanh(s_o s/(1 + c_o c))
   for small ξ, cos((θ_o+φ)/2) = sin((π/2 − θ_o + π/2 − φ)/2) near the grazing corner.

At θ_o = 0, λ = 1 and G = 1, and (S5) reduces to seed 000's Eq. 3, 8π(2^(−n/2)+n)/((n+2)(n+4)).
"""

from __future__ import annotations

import numpy as np
from scipy.special import roots_legendre

from ... import validate
from ...errors import ParameterError, ParameterTypeError
from ..machinery.interval import adaptive_gauss_legendre
from ..machinery.result import RouteResult

#: Gauss–Legendre order for G_m (S4) and for one outer panel (S5).
_INNER_ORDER = 24
#: Cut of the Gaussian e^{−(m−¾)s²} in (S4) and of cos^n(δ/2) in (S5), as exponents.
_INNER_CUT = 45.0
_OUTER_CUT = 60.0
#: Rounding in the estimate, relative to E: G_m by (S4) is good to 5e-15 (tests/engine/test_series.py checks it against
#: mpmath's 2F1 at 30 digits), and the sums of nodes and panels and the cos^n factor round a few ulps each.
#: Measured against mpmath at 25 digits (tests/engine/test_error_bounds.py): errors up to 1.7e-15 relative; at n = 270,
#: theta = 36 degrees an error of 8.3e-17 where the difference of the two rules alone said 1.2e-17.
_G_RTOL = 5e-15
_SUM_ULPS = 8.0
_EPS = np.finfo(float).eps
_HALF_PI = 0.5 * np.pi

_S_NODES, _S_WEIGHTS = roots_legendre(_INNER_ORDER)



def legendre_ratio(m: np.ndarray, xi: np.ndarray) -> np.ndarray:
    """G_m(λ) = λ^(m/2) P_{m−1}((1+λ)/(2√λ)) = λ^m ₂F₁(m, ½; 1; 1−λ) with λ = e^{−2ξ}, by (S4).

    ``m`` ≥ 0 and ``xi`` ≥ 0 broadcast together. G_m(1) = 1, G_0 = 1, G_1 = √λ, G_{½} = √λ/AGM(1, √λ).
    """
    m, xi = np.broadcast_arrays(np.asarray(m, dtype=float), np.asarray(xi, dtype=float))
    decay = m - 0.75
    with np.errstate(divide="ignore"):
        cut = np.where(decay > 0, _INNER_CUT / np.where(decay > 0, decay, 1.0), np.inf)
    top = np.sqrt(np.minimum(xi, cut))[..., None]
    s = 0.5 * top * (_S_NODES + 1.0)
    s2 = s * s
    mm, xx = m[..., None], xi[..., None]
    rest = 2.0 * xx - s2  # > 0: s² ≤ ξ
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        terms = np.exp(-decay[..., None] * s2) + np.exp(0.5 * xx - (mm - 0.25) * rest)
        kernel = s / np.sqrt(-np.expm1(-rest) * np.sinh(0.5 * s2))
        integral = 0.5 * top[..., 0] * np.sum(_S_WEIGHTS * terms * kernel, axis=-1)
    value = np.sqrt(2.0) * np.exp(-xi) / np.pi * integral
    # Near λ = 1 (a view within ~1e-9 rad of the normal) G = 1 − mξ + O((mξ)²): (S4)'s kernel underflows there
    # (ξ < 1e-154 gave G = inf), and the first-order term is exact to float64 once mξ < 1e-9.
    near_one = xi * np.maximum(m, 1.0) < 1e-9
    value = np.where(near_one, 1.0 - m * xi, value)
    # ξ = 0 is λ = 1, where the interval is empty and G = 1 exactly; m = 0 is G = 1 for every λ.
    return np.where((xi <= 0.0) | (m == 0.0), 1.0, value)


def _integrand(n: np.ndarray, theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(S5) without its 2π: cos^n((θ−φ)/2) G_{n/2}(λ) cos φ sin φ, all arguments broadcast."""
    delta = theta - phi
    half_cos = np.cos(0.5 * delta)
    power = np.exp(n * np.log1p(-2.0 * np.sin(0.25 * delta) ** 2))
    # cos((θ+φ)/2) without the cancellation of cos near π/2 at grazing view and light.
    sum_cos = np.sin(0.5 * ((_HALF_PI - theta) + (_HALF_PI - phi)))
    q = np.sin(theta) * np.sin(phi) / (1.0 + np.cos(theta) * np.cos(phi))  # C/B = tanh ξ
    with np.errstate(divide="ignore"):
        xi = np.where(q < 0.5, np.arctanh(np.minimum(q, 0.5)), np.log(half_cos / sum_cos))
    return power * legendre_ratio(0.5 * n, xi) * np.cos(phi) * np.sin(phi)


def _initial_panels(n: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Breakpoints at the peak φ = θ and at ±1, 3, 8 widths from it, inside the range where cos^n matters."""
    width = 2.0 * np.sqrt(2.0) / np.sqrt(n + 1.0)
    reach = np.sqrt(8.0 * _OUTER_CUT / np.maximum(n, 1e-300))
    lo = np.maximum(0.0, theta - reach)
    hi = np.minimum(_HALF_PI, theta + reach)
    offsets = np.array([-8.0, -3.0, -1.0, 0.0, 1.0, 3.0, 8.0])
    points = np.clip(theta[:, None] + width[:, None] * offsets, lo[:, None], hi[:, None])
    points = np.sort(np.concatenate([lo[:, None], points, hi[:, None]], axis=1), axis=1)
    a, b = points[:, :-1].ravel(), points[:, 1:].ravel()
    case = np.repeat(np.arange(n.size), points.shape[1] - 1)
    keep = b > a
    return a[keep], b[keep], case[keep]


def _check(n: object, theta: object, rtol: object, atol: object) -> tuple[np.ndarray, np.ndarray]:
    """The exponents (finite, ≥ 0), view angles in [0, π/2] and tolerances (:mod:`brdfnorm.validate`)."""
    n_arr = validate.real_array(n, "n", error=ParameterError, type_error=ParameterTypeError)
    if np.any(n_arr < 0):
        raise ParameterError("n must be a finite number ≥ 0", where="n")
    validate.tolerances(rtol, atol, floor=0.0)
    return n_arr, validate.polar_angles(theta, horizon=True)


def blinn_phong_albedo_series(n, theta, *, rtol: float = 1e-12, atol: float = 0.0) -> RouteResult:
    """Albedo ∫ max(0,N·H)^n (N·L) dL of Blinn-Phong at view angle ``theta`` (radians) by seed 002's form.

    ``n`` and ``theta`` broadcast together; a case is done when its error estimate is at most
    max(rtol·|E|, atol). The error estimate is an upper bound in practice: the difference of a 15-point rule on
    a panel and on its halves (the finer of which is kept), plus the rounding of G_m and of the sums. The result's
    arrays have the broadcast shape of (n, θ); ``evaluations`` counts outer nodes (each one Legendre-function
    evaluation of 24 terms).
    """
    n_arr, theta_arr = _check(n, theta, rtol, atol)
    shape = np.broadcast_shapes(n_arr.shape, theta_arr.shape)
    nc = np.broadcast_to(n_arr, shape).ravel()
    tc = np.broadcast_to(theta_arr, shape).ravel()

    a, b, case = _initial_panels(nc, tc)

    def integrand(index: np.ndarray, phi: np.ndarray) -> np.ndarray:
        return _integrand(nc[index, None], tc[index, None], phi)

    result = adaptive_gauss_legendre(integrand, a, b, case, nc.size, rtol=rtol, atol=atol / (2.0 * np.pi))
    value, error = result.value, result.error
    scale = 2.0 * np.pi
    # The quadrature's estimate sees only the truncation; the rounding of G (where it is not exactly 1: theta > 0
    # and n > 0) and of the sums is added, so the estimate bounds the error to the last bits.
    rounding = np.abs(value) * (_SUM_ULPS * _EPS + np.where((tc > 0) & (nc > 0), _G_RTOL, 0.0))
    return RouteResult(
        value=(scale * value).reshape(shape),
        error=(scale * (error + rounding)).reshape(shape),
        evaluations=result.evaluations.reshape(shape),
        converged=result.converged.reshape(shape),
    )


def albedo_method(problem, *, rtol: float, atol: float = 0.0, **_: object):
    """``brdfnorm.engine.methods`` method adapter: a :class:`brdfnorm.engine.methods.Problem` batch for ``blinn-phong``.

    The lobe is reciprocal, so the light and view integrals coincide and both are (S5) at the fixed direction's
    polar angle. Returns value and error (K, 1).
    """
    fixed = np.asarray(problem.fixed, dtype=float)
    count = fixed.shape[0]
    theta = np.arctan2(np.hypot(fixed[:, 0], fixed[:, 1]), fixed[:, 2])
    n = np.asarray(problem.case_params(np.arange(count))["n"], dtype=float)
    n = n.reshape(-1) if n.size == count else np.broadcast_to(n.reshape(-1)[:1], (count,))
    result = blinn_phong_albedo_series(n, theta, rtol=rtol, atol=atol)
    return result.with_(value=result.value[:, None], error=result.error[:, None])
