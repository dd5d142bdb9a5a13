"""Albedo of isotropic GGX and Beckmann lobes with F = 1 as a one-dimensional integral: the azimuth in closed form.

What it computes
----------------
E(V) = ∫ f(L, V)(N·L) dL for f = D(H) G2(L, V) / (4 N·L N·V) — the single-scattering lobe of
:mod:`brdfnorm.models.microfacet` with ``fresnel=none`` — for isotropic GGX (Walter et al. 2007, eq. 33):
D(H) = α² / (π (1 + (α² − 1) cos²θ_H)²), and isotropic Beckmann (eq. 25): D(H) = e^{−tan²θ_H/α²}/(π α²
cos⁴θ_H). The same integral as :mod:`brdfnorm.engine.routes.halfvector`, by another route; the tests compare the two,
and
both with the reference of ``tests/helpers/microfacet_reference.py``.

The reduction (GGX)
-------------------
For an isotropic lobe G2 depends on L through θ_L only (Λ(L) is a function of tan θ_L), so with L at polar
angles (θ_L, φ) and V at (θ_V, 0)

    E(V) = 1/(4 cos θ_V) ∫₀^{π/2} G2(θ_L, θ_V) [∫₀^{2π} D(H) dφ] sin θ_L dθ_L,                    (A1)

and the inner integral is elementary. With H ∝ L + V, cos²θ_H = m²/w, m = cos θ_L + cos θ_V, w = |L + V|² =
a + b cos φ (a = 2 + 2 cos θ_L cos θ_V, b = 2 sin θ_L sin θ_V), D = (α²/π)(w/(c + b cos φ))² with
c = a − g, g = (1 − α²) m², and ∫₀^{2π} dφ/(c + b cos φ)^k = 2π/√(c² − b²), 2πc/(c² − b²)^{3/2} (k = 1, 2):

    ∫₀^{2π} D dφ = 2α² [1 + 2g/√P + g²c/P^{3/2}],    P = (c − b)(c + b).

Both factors of P are sums of squares — no cancellation anywhere:

    c − b = m² (d² + α²),   d = tan((θ_L − θ_V)/2),        c + b = (sin θ_L + sin θ_V)² + α² m²

(c − b = (sin θ_L − sin θ_V)² + α² m², and sin θ_L − sin θ_V = m d). So the lobe is a peak of width α in d at
the mirror direction θ_L = θ_V, with tails ∝ α²/|d|³ that matter over every scale of d out to O(1). The
substitution d = α sinh t follows both: with r = √(d² + α²) = α cosh t and dθ_L = 2r dt/(1 + d²),

    E = 1/cos θ_V ∫ G2 sin θ_L/(1 + d²) · [α²r + 2α²(1 − α²) m/√Q + (1 − α²)² m c/(cosh²t Q^{3/2})] dt,

Q = c + b, over t from −asinh(tan(θ_V/2)/α) (θ_L = 0) to asinh(tan((π/2 − θ_V)/2)/α) (the horizon). For α > 1 (g < 0)
the bracket cancels (E ~ 1/α², relative errors of 2e-11 at α = 30–70 were measured), so there it is taken from
the completed square 1 + 2g/√P + g²c/P^{3/2} = (ca − b²)²/(c P^{3/2}) + b²/(c(c + √P)), where
ca − b² = (a − b)(a + b) − g·a is a sum of positive terms (a − b = m²(1 + d²), a + b = (sin θ_L + sin θ_V)² + m²).
The peak
is the bounded last term, ~1/cosh²t, and the tails are smooth in t ~ ln|d| (a map that compresses them, such as
d = α tan ψ, piles the tail's α²|d| into a layer at the ends of the range that the rule cannot see). At α = 1
the bracket is r and the integrand G2 sin θ_L dθ_L/(2 dt), so at θ_V = 0 (G2 = 2μ/(1 + μ),
height-correlated) E = ∫₀¹ μ/(1 + μ) dμ = 1 − ln 2; as α → 0 the last term's integral tends to 2 and E → G2(V, V).

Beckmann
--------
With tan²θ_H = (w − m²)/m² and 1/cos⁴θ_H = w²/m⁴ the azimuthal integral is a von Mises moment: shifting
φ by π and writing a − b cos φ = (a − b) + b(1 − cos φ),

    ∫₀^{2π} D dφ = (2/(α² m⁴)) e^{−(a − b − m²)/(α² m²)} [(a − b)² J₀ + 2(a − b) b J₁ + b² J₂],
    J_k(κ) = (1/2π) ∫₀^{2π} (1 − cos φ)^k e^{−κ(1 − cos φ)} dφ,   κ = b/(α² m²),

and a − b = m²(1 + d²) (2 + 2 cos(θ_L + θ_V) over (cos θ_L + cos θ_V)²), so the exponent is −d²/α²: a Gaussian
of width α in d at the mirror direction, with no heavy tail. With d = α s and dθ_L = 2α ds/(1 + d²), (A1) is

    E = 1/cos θ_V ∫ G2 sin θ_L/(1 + d²) · e^{−s²} (1/α)[(1 + d²)² J₀ + 2(b/m²)(1 + d²) J₁ + (b/m²)² J₂] ds.

Every term is positive. J₀ = e^{−κ}I₀(κ), J₁ = e^{−κ}(I₀ − I₁)(κ), J₂ = 2J₁ − e^{−κ}I₁(κ)/κ, but those
differences cancel catastrophically for large κ (κ ~ 1/α² at the peak, 1e16 at α = 1e-8): :func:`cosine_moments`
takes J_k from its integral instead. As an Euler integral (1 − cos φ = 2x) it is a Kummer function, and by
Kummer's transformation (DLMF 13.2.39) one with positive terms,

    J_k = (2^k Γ(k + ½)/(√π Γ(k + 1))) e^{−2κ} ₁F₁(½; k + 1; 2κ)                      (scipy.special.hyp1f1),

used for κ < :data:`KAPPA_SWITCH`; above it, the large-argument expansion of the same function (DLMF 13.7.2;
Watson's lemma on the Euler integral, whose other end contributes O(e^{−2κ}) < e^{−50} here),

    κ^k J_k = (Γ(k + ½)/π) √y Σ_n (k + ½)_n (½)_n/n! yⁿ,   y = 1/(2κ),

a series of positive terms falling by a factor ≤ (n + k + ½) y ≤ 0.77 up to n = :data:`_ASYMPTOTIC_TERMS`, so the
dropped rest is a few times its first omitted term: < 1e-17 at κ ≥ 25 (J₁'s expansion is that of I₀ − I₁, first
coefficient ½). There the bracket is taken as (1/α)·κ^k J_k = (m/√(2b))·(…), with y = α²m²/(2b): no κ is
formed, so α down to the tables' floor 1e-150 does not overflow it. The Gaussian needs no grading: panels of
:data:`S_STEP` out to |s| = :data:`S_REACH` (e^{−S_REACH²} < 2e-28; the rest of the integrand is bounded
relative to E by ~1/μ_V, see the tests' reach check), and G2's horizon layer gets the same panels as for GGX.

Angles are carried both as θ and as elevations π/2 − θ (θ_L = θ_V + 2 atan d, e_L = e_V − 2 atan d), sin θ
from the one and cos θ from the other, so that both keep their relative accuracy (at a normal view the peak
lies at θ_L ~ α: sin θ_L from π/2 − e_L was 1e-11 off there at α = 6e-6). G2's boundary layer at the horizon
(Λ(L) turns on where α tan θ_L ~ 1, a band of width ~α in θ_L, ~α/d in t, for both distributions) gets panels of its
own; the rest is :func:`brdfnorm.engine.machinery.interval.adaptive_gauss_legendre` (15-point Gauss–Legendre panels
bisected while their case misses its tolerance; a panel's error is the difference between the rule on it and on its
halves, the error of the coarser value, while the finer one is kept).
"""

from __future__ import annotations

from fractions import Fraction
from math import gamma, pi

import numpy as np
from scipy.special import hyp1f1

from ...models.microfacet import Distribution, MicrofacetModel, shadowing_masking
from ...validate import DEFAULT_MAX_EVALUATIONS
from ..machinery.interval import adaptive_gauss_legendre
from ..machinery.result import RouteResult
from .halfvector import single_scattering_albedo

_HALF_PI = 0.5 * np.pi
#: Rounding of the sum of positive node values, relative (as the half-vector rules' floor).
ROUNDING_FLOOR = 50.0 * np.finfo(float).eps
#: GGX: initial panel width in t, out to |t| = T_REACH (beyond it the lobe's tail is below 1e-20 of E).
T_STEP = 2.0
T_REACH = 24.0
#: Beckmann: initial panel width in s = d/α, out to |s| = S_REACH (the Gaussian e^{−s²} < 2e-28 beyond).
S_STEP = 4.0
S_REACH = 8.0
#: Horizon grading: breakpoints at e_L = scale·4^j (G2's boundary layer, see :func:`_panels`).
_GRADES = 4.0 ** np.arange(-2, 40)
#: Distributions with a closed-form azimuthal integral here.
DISTRIBUTIONS = ("ggx", "beckmann")
#: Roughness floor: 1 − E = O(α²), so α = 1e-60 is a mirror to float64 (E differs by ~1e-120), while q^{3/2} ~ α³
#: of a normal view still stays far above float64's underflow (at 1e-150 it was 0: a division by zero).
ALPHA_FLOOR = 1e-60
#: Beckmann's von Mises moments J_k: Kummer's series below this κ, the asymptotic expansion from it on.
KAPPA_SWITCH = 25.0
_ASYMPTOTIC_TERMS = 36


def _asymptotic_coefficients(k: int) -> np.ndarray:
    """Γ(k + ½)/π · (k + ½)_n (½)_n/n!, n < :data:`_ASYMPTOTIC_TERMS`, lowest first: κ^k J_k/√y as a series in y
    (the Pochhammer ratios exact, in rationals)."""
    term, coefficients = Fraction(1), []
    for n in range(_ASYMPTOTIC_TERMS):
        coefficients.append(float(term) * gamma(k + 0.5) / pi)
        term *= (Fraction(2 * k + 1, 2) + n) * (Fraction(1, 2) + n) / (n + 1)
    return np.array(coefficients)


_ASYMPTOTIC = [_asymptotic_coefficients(k) for k in range(3)]
#: J_k = _KUMMER[k] e^{−2κ} ₁F₁(½; k + 1; 2κ): 2^k Γ(k + ½)/(√π k!).
_KUMMER = (1.0, 1.0, 1.5)


def applies(model, over) -> bool:
    """Whether method ``"azimuthal"`` computes the albedo of ``model``: GGX or Beckmann, isotropic, F = 1 (either
    reading of the albedo: the lobe is reciprocal)."""
    return (isinstance(model, MicrofacetModel) and model.distribution.name in DISTRIBUTIONS and model.isotropic
            and model.params["fresnel"] == "none")


def white_albedo(distribution: Distribution, shadowing: str, fixed: np.ndarray, alpha: np.ndarray, *, rtol: float,
                 atol: float | np.ndarray = 0.0, max_evaluations: int = DEFAULT_MAX_EVALUATIONS) -> RouteResult:
    """E(V) of the isotropic single-scattering lobe with F = 1 at fixed directions (K, 3) and roughness (K,):
    by this module's 1-D integral where it has the distribution, else by the half-vector cubature (H1), which
    also takes any case the 1-D route does not settle (none is known). ``atol`` scalar or (K,)."""
    K = fixed.shape[0]
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float).ravel(), (K,))
    atol = np.broadcast_to(np.asarray(atol, dtype=float).ravel(), (K,))
    params = {"alpha": alpha, "alpha_x": 0.0, "alpha_y": 0.0, "shadowing": shadowing, "fresnel": "none",
              "f0": 0.0, "f90": 1.0, "eta": 1.0, "k": 0.0}
    if distribution.name not in DISTRIBUTIONS:
        return single_scattering_albedo(distribution, fixed, params, rtol=rtol, atol=atol[:, None],
                                        max_evaluations=max_evaluations)
    value, error, evaluations, converged = albedo(distribution, shadowing, fixed[:, 2],
                                                  np.maximum(alpha, ALPHA_FLOOR), rtol=rtol, atol=atol)
    value, error = value[:, None], error[:, None]
    if not converged.all():
        rest = np.flatnonzero(~converged)
        again = single_scattering_albedo(distribution, fixed[rest], {**params, "alpha": alpha[rest]}, rtol=rtol,
                                         atol=atol[rest, None], max_evaluations=max_evaluations)
        value[rest], error[rest], converged[rest] = again.value, again.error, again.converged
        evaluations[rest] += again.evaluations
    return RouteResult(value, error, evaluations, converged)


def cosine_moments(kappa) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(J₀, J₁, J₂) at κ ≥ 0 (any shape): J_k(κ) = (1/2π) ∫₀^{2π} (1 − cos φ)^k e^{−κ(1 − cos φ)} dφ, so
    J₀ = e^{−κ}I₀(κ), J₁ = e^{−κ}(I₀(κ) − I₁(κ)), J₂ = 2J₁ − e^{−κ}I₁(κ)/κ, each to its relative accuracy (the
    differences are never formed)."""
    kappa = np.asarray(kappa, dtype=float)
    moments = np.zeros((3,) + kappa.shape)
    small = kappa < KAPPA_SWITCH
    moments[:, small] = _kummer_moments(kappa[small])
    large = ~small & np.isfinite(kappa)
    y = 0.5 / kappa[large]
    moments[:, large] = np.sqrt(y) * _scaled_asymptotic(y) / kappa[large] ** np.arange(3)[:, None]
    return moments[0], moments[1], moments[2]


def _kummer_moments(kappa: np.ndarray) -> np.ndarray:
    """J_k(κ), k = 0, 1, 2 (rows), for κ < :data:`KAPPA_SWITCH`: Kummer's series, all terms positive."""
    z = 2.0 * kappa
    return np.array([c * np.exp(-z) * hyp1f1(0.5, k + 1.0, z) for k, c in enumerate(_KUMMER)])


def _scaled_asymptotic(y: np.ndarray) -> np.ndarray:
    """κ^k J_k(κ)/√y, k = 0, 1, 2 (rows), at y = 1/(2κ) ≤ 1/(2 :data:`KAPPA_SWITCH`)."""
    return np.array([np.polynomial.polynomial.polyval(y, c) for c in _ASYMPTOTIC])


def albedo(distribution, shadowing: str, cos_view: np.ndarray, alpha: np.ndarray, *, rtol: float,
           atol: float | np.ndarray = 0.0):
    """(value (K,), error (K,), evaluations (K,), converged (K,)) of E at cos θ_V = ``cos_view`` (K,) in (0, 1]
    and roughness ``alpha`` (K,) > 0; ``atol`` scalar or (K,)."""
    route = _ROUTES[distribution.name]
    mu = np.asarray(cos_view, dtype=float)
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), mu.shape)
    K = mu.size
    sin_v = np.sqrt((1.0 - mu) * (1.0 + mu))
    # θ and the elevation π/2 − θ, each from its own arctan: sin θ_L is taken from θ_L (relative accuracy at
    # the pole, where the peak of a normal view lies) and cos θ_L from e_L (at the horizon).
    theta_v, e_v = np.arctan2(sin_v, mu), np.arctan2(mu, sin_v)
    lambda_v = distribution.smith_lambda(alpha * alpha * (1.0 - mu) * (1.0 + mu) / (mu * mu))
    a, b, case = _panels(route, e_v, theta_v, alpha, np.minimum(alpha, alpha / (1.0 + 2.0 * lambda_v)))

    def integrand(k: np.ndarray, t: np.ndarray) -> np.ndarray:
        al = alpha[k][:, None]
        d = route.d(al, t)
        turn = 2.0 * np.arctan(d)
        cos_l, sin_l = np.sin(e_v[k][:, None] - turn), np.sin(theta_v[k][:, None] + turn)
        m = cos_l + mu[k][:, None]
        kernel = route.kernel(al, t, d, sin_l, sin_v[k][:, None], m)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            lambda_l = distribution.smith_lambda(al * al * (sin_l / cos_l) ** 2)
        g2 = np.where(cos_l > 0.0, shadowing_masking(shadowing, lambda_l, lambda_v[k][:, None]), 0.0)
        return g2 * sin_l / (1.0 + d * d) * kernel

    scale = 1.0 / mu
    atol_scaled = np.broadcast_to(np.asarray(atol, dtype=float), (K,)) / scale
    result = adaptive_gauss_legendre(integrand, a, b, case, K, rtol=rtol, atol=atol_scaled)
    value, error, evaluations, converged = result.value, result.error, result.evaluations, result.converged
    # The integrand is positive, so its rounding (a few ulps a node, summed over the nodes) is bounded by
    # ROUNDING_FLOOR · E, which the panel differences cannot see.
    error = error + ROUNDING_FLOOR * np.abs(value)
    converged &= error <= np.maximum(rtol * np.abs(value), atol_scaled)
    return value * scale, error * scale, evaluations, converged


class _GGXRoute:
    """d = α sinh t; the kernel is the bracket of the GGX section of the module docstring (its tail beyond
    |t| = T_REACH keeps a panel of its own: nothing is cut)."""

    step, reach, cut = T_STEP, T_REACH, np.inf

    @staticmethod
    def d(alpha: np.ndarray, t: np.ndarray) -> np.ndarray:
        return alpha * np.sinh(t)

    @staticmethod
    def t(alpha: np.ndarray, d: np.ndarray) -> np.ndarray:
        return np.arcsinh(d / alpha)

    @staticmethod
    def kernel(alpha, t, d, sin_l, sin_v, m):
        al2 = alpha * alpha
        cosh = np.cosh(t)
        r = alpha * cosh
        q = (sin_l + sin_v) ** 2 + al2 * m * m
        root_q = np.sqrt(q)
        c = 0.5 * (m * m * r * r + q)
        g = 1.0 - al2
        bracket = al2 * (r + 2.0 * g * m / root_q) + g * g * m * c / (cosh * cosh * q * root_q)
        if np.any(alpha > 1.0):  # g < 0: the sum above cancels; the completed square below does not
            # w = a_w + b_w cos φ with a_w − b_w = m²(1 + d²), a_w + b_w = (sin θ_L + sin θ_V)² + m².
            a_minus_b, a_plus_b = m * m * (1.0 + d * d), (sin_l + sin_v) ** 2 + m * m
            a_w, b_w = 0.5 * (a_plus_b + a_minus_b), 2.0 * sin_l * sin_v
            root_p = m * r * root_q
            square = (a_minus_b * a_plus_b - g * m * m * a_w) ** 2  # (c·a_w − b_w²)², c = a_w − g m²
            completed = al2 * r * (square / (c * root_p**3) + b_w * b_w / (c * (c + root_p)))
            bracket = np.where(alpha > 1.0, completed, bracket)
        return bracket


class _BeckmannRoute:
    """d = α s; the kernel is e^{−s²} times the bracket of the Beckmann section of the module docstring, cut at
    |s| = S_REACH."""

    step, reach, cut = S_STEP, S_REACH, S_REACH

    @staticmethod
    def d(alpha: np.ndarray, s: np.ndarray) -> np.ndarray:
        return alpha * s

    @staticmethod
    def t(alpha: np.ndarray, d: np.ndarray) -> np.ndarray:
        return d / alpha

    @staticmethod
    def kernel(alpha, s, d, sin_l, sin_v, m):
        alpha, d, m = (np.broadcast_to(x, s.shape) for x in (alpha, d, m))
        b = 2.0 * sin_l * sin_v
        one_d2 = 1.0 + d * d
        a2m2 = (alpha * m) ** 2
        large = (b > 0.0) & (b >= KAPPA_SWITCH * a2m2)  # α²m² may underflow: then b ≥ 0 decides alone
        bracket = np.empty(s.shape)
        # κ ≥ KAPPA_SWITCH: (1/α) κ^k J_k = (√y/α)·(κ^k J_k/√y) = (m/√(2b))·(…), y = α²m²/(2b).
        al, dd, y = alpha[large], one_d2[large], 0.5 * a2m2[large] / b[large]
        j0, j1, j2 = _scaled_asymptotic(y)
        bracket[large] = m[large] / np.sqrt(2.0 * b[large]) * (dd * dd * j0 + 2.0 * al * al * dd * j1
                                                               + al ** 4 * j2)
        # κ < KAPPA_SWITCH: (1/α)[(1 + d²)² J₀ + 2(b/m²)(1 + d²) J₁ + (b/m²)² J₂].
        small = ~large
        ratio, dd = b[small] / (m[small] * m[small]), one_d2[small]
        j0, j1, j2 = _kummer_moments(ratio / (alpha[small] * alpha[small]))
        bracket[small] = (dd * dd * j0 + 2.0 * ratio * dd * j1 + ratio * ratio * j2) / alpha[small]
        return np.exp(-s * s) * bracket


_ROUTES = {"ggx": _GGXRoute, "beckmann": _BeckmannRoute}


def _panels(route, e_v: np.ndarray, theta_v: np.ndarray, alpha: np.ndarray, scale: np.ndarray):
    """Initial panels in the route's variable t per case, each within reach of the rule's geometric
    convergence: t = 0 (the peak) and steps of ``route.step`` out to |t| = ``route.reach`` (GGX: the integrand
    is analytic in a strip |Im t| < π/2, where cosh t vanishes: a 15-point panel of width 2 then converges like
    3.4^-30; Beckmann: e^{−s²} is entire), and towards the horizon, on both sides of the peak, panels graded
    geometrically in the elevation e_L (by 4 from a 16th of ``scale``), G2's singularities being at distance
    ~``scale`` from e_L = 0: Λ(L)'s branch points at e_L = ±i atanh α (GGX; Beckmann's Λ has a pole at e_L = 0),
    and for height-correlated G2 the pole of 1/(1 + Λ(L) + Λ(V)) at e_L ≈ −α/(2(1 + Λ(V))) (Λ(L) ≈ α/(2 e_L)),
    ~μ_V away at grazing views; for α > 1 also from the pole θ_L = 0, where Λ(L)'s branch points lie at
    θ_L = ±i atanh(1/α) then (GGX; Beckmann's Λ turns on at θ_L ~ 1/α there, e^{−cot²θ_L/α²} growing off the
    real axis). A panel whose distance to them is 4 times its own width converges like 3^-30, where one wide
    panel agreed with its halves before either was accurate (3e-6 off, estimated 8e-7, at μ_V = 1.4e-6,
    α = 0.85, before the pole's scale was added)."""
    to_t = lambda elevation_gap: route.t(alpha[:, None], np.tan(0.5 * elevation_gap))  # noqa: E731
    start = np.maximum(-to_t(theta_v[:, None]), -route.cut)
    end = np.minimum(to_t(e_v[:, None]), route.cut)  # e_L = 0: the horizon, or the route's cut
    steps = route.step * np.arange(-route.reach // route.step, route.reach // route.step + 1)[None, :]
    graded = to_t(e_v[:, None] - np.minimum(scale[:, None] * _GRADES[None, :], _HALF_PI))
    # For α > 1 Λ(L)'s branch points move to the pole: tan θ_L = ±i/α, θ_L = ±i atanh(1/α).
    pole_scale = np.full(alpha.shape, np.inf)
    pole_scale[alpha > 1.0] = np.arctanh(1.0 / alpha[alpha > 1.0])
    graded_pole = to_t(np.minimum(pole_scale[:, None] * _GRADES[None, :], _HALF_PI) - theta_v[:, None])
    points = np.concatenate([start, steps + 0 * start, graded, graded_pole, end], axis=1)
    points = np.clip(points, start, end)
    points = np.sort(points, axis=1)
    a, b = points[:, :-1].ravel(), points[:, 1:].ravel()
    case = np.repeat(np.arange(e_v.size), points.shape[1] - 1)
    keep = b > a
    return a[keep], b[keep], case[keep]
