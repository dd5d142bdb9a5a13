"""Albedo of isotropic GGX lobes with F = 1 as a one-dimensional integral: the azimuth in closed form.

What it computes
----------------
E(V) = ∫ f(L, V)(N·L) dL for f = D(H) G2(L, V) / (4 N·L N·V) — the single-scattering lobe of
:mod:`brdfnorm.models.microfacet` with ``fresnel=none`` — for isotropic GGX (Walter et al. 2007, eq. 33):
D(H) = α² / (π (1 + (α² − 1) cos²θ_H)²). The same integral as :mod:`brdfnorm.halfvector`, by another route;
the tests compare the two, and both with the reference of ``tests/microfacet_reference.py``.

The reduction
-------------
For an isotropic lobe G2 depends on L through θ_L only (Λ(L) is a function of tan θ_L), so with L at polar
angles (θ_L, φ) and V at (θ_V, 0)

    E(V) = 1/(4 cos θ_V) ∫₀^{π/2} G2(θ_L, θ_V) [∫₀^{2π} D(H) dφ] sin θ_L dθ_L,

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

Angles are carried both as θ and as elevations π/2 − θ (θ_L = θ_V + 2 atan d, e_L = e_V − 2 atan d), sin θ
from the one and cos θ from the other, so that both keep their relative accuracy (at a normal view the peak
lies at θ_L ~ α: sin θ_L from π/2 − e_L was 1e-11 off there at α = 6e-6). G2's boundary layer at the horizon
(Λ(L) turns on where α tan θ_L ~ 1, a band of width ~α in θ_L, ~α/d in t) gets panels of its own; the rest is
:func:`brdfnorm.series.adaptive_gauss_legendre` (15-point Gauss–Legendre panels bisected while their case
misses its tolerance; a panel's error is the difference between the rule on it and on its halves, the error of
the coarser value, while the finer one is kept).
"""

from __future__ import annotations

import numpy as np

from .halfvector import CubatureResult, single_scattering_albedo
from .models.microfacet import Distribution, MicrofacetModel, shadowing_masking
from .series import adaptive_gauss_legendre

_HALF_PI = 0.5 * np.pi
#: Rounding of the sum of positive node values, relative (as the half-vector rules' floor).
ROUNDING_FLOOR = 50.0 * np.finfo(float).eps
#: Initial panel width in t, out to |t| = T_REACH (beyond it the lobe's tail is below 1e-20 of E).
T_STEP = 2.0
T_REACH = 24.0
#: Horizon grading: breakpoints at e_L = scale·4^j (G2's boundary layer, see :func:`_panels`).
_GRADES = 4.0 ** np.arange(-2, 40)
#: Distributions with a closed-form azimuthal integral here.
DISTRIBUTIONS = ("ggx",)
#: Roughness floor: 1 − E = O(α²), so α = 1e-60 is a mirror to float64 (E differs by ~1e-120), while q^{3/2} ~ α³
#: of a normal view still stays far above float64's underflow (at 1e-150 it was 0: a division by zero).
ALPHA_FLOOR = 1e-60


def applies(model, over) -> bool:
    """Whether method ``"azimuthal"`` computes the albedo of ``model``: GGX, isotropic, F = 1 (either reading
    of the albedo: the lobe is reciprocal)."""
    return (isinstance(model, MicrofacetModel) and model.distribution.name in DISTRIBUTIONS and model.isotropic
            and model.params["fresnel"] == "none")


def white_albedo(distribution: Distribution, shadowing: str, fixed: np.ndarray, alpha: np.ndarray, *, rtol: float,
                 atol: float | np.ndarray = 0.0, max_evaluations: int = 20_000_000) -> CubatureResult:
    """E(V) of the isotropic single-scattering lobe with F = 1 at fixed directions (K, 3) and roughness (K,):
    by this module's 1-D integral where it has the distribution (its 1-D integral), else by (H1); a case the
    1-D route does not settle (none is known) goes to (H1) too. ``atol`` scalar or (K,)."""
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
    return CubatureResult(value, error, evaluations, converged)


def albedo(distribution, shadowing: str, cos_view: np.ndarray, alpha: np.ndarray, *, rtol: float,
           atol: float | np.ndarray = 0.0):
    """(value (K,), error (K,), evaluations (K,), converged (K,)) of E at cos θ_V = ``cos_view`` (K,) in (0, 1]
    and roughness ``alpha`` (K,) > 0; ``atol`` scalar or (K,)."""
    mu = np.asarray(cos_view, dtype=float)
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), mu.shape)
    K = mu.size
    sin_v = np.sqrt((1.0 - mu) * (1.0 + mu))
    # θ and the elevation π/2 − θ, each from its own arctan: sin θ_L is taken from θ_L (relative accuracy at
    # the pole, where the peak of a normal view lies) and cos θ_L from e_L (at the horizon).
    theta_v, e_v = np.arctan2(sin_v, mu), np.arctan2(mu, sin_v)
    lambda_v = distribution.smith_lambda(alpha * alpha * (1.0 - mu) * (1.0 + mu) / (mu * mu))
    a2 = alpha * alpha
    a, b, case = _panels(e_v, theta_v, alpha, np.minimum(alpha, alpha / (1.0 + 2.0 * lambda_v)))

    def integrand(k: np.ndarray, t: np.ndarray) -> np.ndarray:
        al, al2 = alpha[k][:, None], a2[k][:, None]
        cosh = np.cosh(t)
        d = al * np.sinh(t)
        turn = 2.0 * np.arctan(d)
        cos_l, sin_l = np.sin(e_v[k][:, None] - turn), np.sin(theta_v[k][:, None] + turn)
        m = cos_l + mu[k][:, None]
        r = al * cosh
        q = (sin_l + sin_v[k][:, None]) ** 2 + al2 * m * m
        root_q = np.sqrt(q)
        c = 0.5 * (m * m * r * r + q)
        g = 1.0 - al2
        bracket = al2 * (r + 2.0 * g * m / root_q) + g * g * m * c / (cosh * cosh * q * root_q)
        if np.any(al > 1.0):  # g < 0: the sum above cancels; the completed square below does not
            # w = a_w + b_w cos φ with a_w − b_w = m²(1 + d²), a_w + b_w = (sin θ_L + sin θ_V)² + m².
            a_minus_b, a_plus_b = m * m * (1.0 + d * d), (sin_l + sin_v[k][:, None]) ** 2 + m * m
            a_w, b_w = 0.5 * (a_plus_b + a_minus_b), 2.0 * sin_l * sin_v[k][:, None]
            root_p = m * r * root_q
            square = (a_minus_b * a_plus_b - g * m * m * a_w) ** 2  # (c·a_w − b_w²)², c = a_w − g m²
            completed = al2 * r * (square / (c * root_p**3) + b_w * b_w / (c * (c + root_p)))
            bracket = np.where(al > 1.0, completed, bracket)
        with np.errstate(divide="ignore", over="ignore", invalid="ignore"):
            lambda_l = distribution.smith_lambda(al2 * (sin_l / cos_l) ** 2)
        g2 = np.where(cos_l > 0.0, shadowing_masking(shadowing, lambda_l, lambda_v[k][:, None]), 0.0)
        return g2 * sin_l / (1.0 + d * d) * bracket

    scale = 1.0 / mu
    atol_scaled = np.broadcast_to(np.asarray(atol, dtype=float), (K,)) / scale
    value, error, evaluations, converged = adaptive_gauss_legendre(integrand, a, b, case, K, rtol=rtol,
                                                                   atol=atol_scaled)
    # The integrand is positive, so its rounding (a few ulps a node, summed over the nodes) is bounded by
    # ROUNDING_FLOOR · E, which the panel differences cannot see.
    error = error + ROUNDING_FLOOR * np.abs(value)
    converged &= error <= np.maximum(rtol * np.abs(value), atol_scaled)
    return value * scale, error * scale, evaluations, converged


def _panels(e_v: np.ndarray, theta_v: np.ndarray, alpha: np.ndarray, scale: np.ndarray):
    """Initial panels in t per case, each within reach of the rule's geometric convergence: t = 0 (the peak)
    and steps of :data:`T_STEP` out to |t| = :data:`T_REACH` (the integrand is analytic in a strip |Im t| <
    π/2, where cosh t vanishes: a 15-point panel of width 2 then converges like 3.4^-30), and towards the
    horizon, on both sides of the peak, panels graded geometrically in the elevation e_L (by 4 from a 16th of
    ``scale``), G2's singularities being at distance ~``scale`` from e_L = 0: Λ(L)'s branch points at
    e_L = ±i atanh α, and for height-correlated G2 the pole of 1/(1 + Λ(L) + Λ(V)) at e_L ≈ −α/(2(1 + Λ(V)))
    (Λ(L) ≈ α/(2 e_L)), ~μ_V away at grazing views; for α > 1 also from the pole θ_L = 0, where Λ(L)'s branch
    points lie at θ_L = ±i atanh(1/α) then. A panel whose distance to them is 4 times its own width
    converges like 3^-30, where one wide panel agreed with its halves before either was accurate (3e-6 off,
    estimated 8e-7, at μ_V = 1.4e-6, α = 0.85, before the pole's scale was added)."""
    to_t = lambda elevation_gap: np.arcsinh(np.tan(0.5 * elevation_gap) / alpha[:, None])  # noqa: E731
    start = -to_t(theta_v[:, None])
    end = to_t(e_v[:, None])  # e_L = 0: the horizon
    steps = T_STEP * np.arange(-T_REACH // T_STEP, T_REACH // T_STEP + 1)[None, :]
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
