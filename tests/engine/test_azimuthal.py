"""Method "azimuthal" (brdfnorm.engine.routes.azimuthal): isotropic GGX and Beckmann with F = 1 as a 1-D integral, the
azimuth
in closed form.

Checked against routes that share nothing with it but the lobe: the closed form 1 − ln 2 (GGX, α = 1, μ = 1), the
half-vector cubature (``method="microfacet"``, rtol 1e-13, a 2-D integral over the half vector), the fixed-order
Gauss–Legendre reference of tests/helpers/microfacet_reference.py, and mpmath (the mirror limit; Beckmann's von Mises
moments from ``besseli``, its normal view). Its estimates are ~1e-14 (its initial panels already resolve the
lobe), so "true error ≤ estimate + the reference's own" is a strict check: a wrong angle at the pole (sin θ_L
taken as cos(π/2 − θ_L)) failed it by 10× at α = 6e-6, one wide tail panel by 12×, G2's pole at grazing views
(e_L ≈ −μ) by 4×, and for α > 1 the cancelling bracket and Λ's branch points next to the pole by 2–4× — all
found by the sweep below before they were fixed.
"""

from __future__ import annotations

import warnings

import mpmath
import numpy as np
import pytest
from helpers.microfacet_reference import reference_albedo

import brdfnorm as bn
from brdfnorm.engine.routes import azimuthal
from brdfnorm.errors import ArgumentError
from brdfnorm.models.microfacet import BeckmannDistribution, GGXDistribution

MUS = np.array([1e-6, 1e-4, 2e-3, 0.04, 0.3, 0.75, 1.0])
ALPHAS = np.array([1e-8, 1e-4, 0.01, 0.07, 0.35, 1.0])
SHADOWINGS = ("height-correlated", "separable")


@pytest.mark.parametrize("shadowing", SHADOWINGS)
def test_alpha_one_at_normal_incidence_is_one_minus_ln2(shadowing):
    result = bn.albedo(bn.load("ggx", alpha=1.0, shadowing=shadowing), 0.0, rtol=1e-12)
    true_error = abs(result.value[0] - (1.0 - np.log(2.0)))
    assert result.method == "azimuthal" and result.converged.all()
    assert true_error <= 1e-15 and result.error[0] >= true_error


def test_auto_picks_it_only_for_isotropic_ggx_and_beckmann_without_fresnel():
    for name in azimuthal.DISTRIBUTIONS:
        assert bn.albedo(bn.load(name, alpha=0.3), 0.5).method == "azimuthal"
        assert bn.albedo(bn.load(name, alpha=0.3, ms="kulla-conty", ms_table=16), 0.5).method == "azimuthal"
        for model in (bn.load(name, alpha=0.3, fresnel="schlick", f0=0.04), bn.load(name, alpha_x=0.3, alpha_y=0.1)):
            assert bn.albedo(model, 0.5).method == "microfacet"
            with pytest.raises(ArgumentError, match="does not apply"):
                bn.albedo(model, 0.5, method="azimuthal")


def test_beckmann_cosine_moments_against_mpmath_bessel_functions():
    # J₁ = e^{−κ}(I₀ − I₁) and J₂ = 2J₁ − e^{−κ}I₁/κ cancel catastrophically for large κ; mpmath forms those
    # differences with enough digits (30 + 2 log₁₀ κ) that they keep 25. Both branches, and the switch between.
    kappa = np.concatenate([[0.0], np.geomspace(1e-3, 1e20, 120),
                            azimuthal.KAPPA_SWITCH * np.array([1 - 1e-9, 1.0, 1 + 1e-9])])
    ours = np.array(azimuthal.cosine_moments(kappa))
    for i, k in enumerate(kappa):
        with mpmath.workdps(30 + 2 * int(np.log10(max(k, 1.0)))):
            x = mpmath.mpf(k)
            j0, i1 = mpmath.exp(-x) * mpmath.besseli(0, x), mpmath.exp(-x) * mpmath.besseli(1, x)
            j1 = j0 - i1
            exact = (j0, j1, 2 * j1 - i1 / x if k > 0 else mpmath.mpf(1.5))
            for n in range(3):
                assert abs(ours[n, i] - exact[n]) <= 2e-15 * exact[n], (n, k, ours[n, i], exact[n])
    assert azimuthal.cosine_moments(np.inf) == (0.0, 0.0, 0.0)


def _beckmann_normal_view(alpha: float) -> float:
    """E(N) of Beckmann by mpmath (30 digits) over θ_L: at V = N, θ_H = θ_L/2 for every azimuth and Λ(V) = 0, so
    E = (π/2) ∫₀^{π/2} D(θ_L/2) sin θ_L/(1 + Λ(L)) dθ_L for both shadowings — no von Mises moment involved."""
    with mpmath.workdps(30):
        a = mpmath.mpf(alpha)

        def integrand(theta):
            t = mpmath.tan(theta / 2)
            density = mpmath.exp(-(t / a) ** 2) / (mpmath.pi * a * a * mpmath.cos(theta / 2) ** 4)
            b = 1 / (a * mpmath.tan(theta))
            lam = (mpmath.erf(b) - 1) / 2 + mpmath.exp(-b * b) / (2 * b * mpmath.sqrt(mpmath.pi))
            return density * mpmath.sin(theta) / (1 + lam)

        points = [0] + [min(2 * mpmath.atan(a * s), mpmath.pi / 2) for s in (0.5, 1, 2, 4, 8)] + [mpmath.pi / 2]
        return float(mpmath.pi / 2 * mpmath.quad(integrand, sorted(set(points))))


@pytest.mark.parametrize("alpha", [1e-3, 0.05, 0.4, 1.0, 3.0])
def test_beckmann_normal_view_against_mpmath(alpha):
    result = bn.albedo(bn.load("beckmann", alpha=alpha), 0.0, rtol=1e-12)
    true_error = abs(result.value[0] - _beckmann_normal_view(alpha))
    assert result.method == "azimuthal" and result.converged.all()
    assert true_error <= result.error[0] and true_error <= 1e-14


@pytest.mark.slow
@pytest.mark.parametrize("name", azimuthal.DISTRIBUTIONS)
@pytest.mark.parametrize("shadowing", SHADOWINGS)
def test_agrees_with_the_half_vector_cubature_and_gauss_legendre(name, shadowing):
    theta = np.arccos(MUS)[None, :]
    model = bn.load(name, alpha=ALPHAS[:, None], shadowing=shadowing)
    ours = bn.albedo(model, theta, rtol=1e-10)
    cubature = bn.albedo(model, theta, rtol=1e-13, method="microfacet")
    assert ours.method == "azimuthal" and ours.converged.all()
    value, estimate = ours.value[..., 0], ours.error[..., 0]
    true_error = np.abs(value - cubature.value[..., 0])
    assert np.all(true_error <= estimate + cubature.error[..., 0]), np.max(true_error / estimate)
    assert np.all(estimate <= 1e-10 * value)
    assert np.all(true_error <= 1e-13 * value)  # the issue asks 1e-10
    # The reference at the μ = cos θ asked for (θ = arccos μ in float64 is 1e-12 relative off μ at grazing).
    for i, alpha in enumerate(ALPHAS):
        for j, mu in enumerate(np.cos(np.arccos(MUS[1:])), start=1):  # its bisection stops at μ = 1e-4
            fine = reference_albedo(name, mu, alpha, shadowing, order=20)
            own = abs(fine - reference_albedo(name, mu, alpha, shadowing, order=14))
            assert abs(value[i, j] - fine) <= estimate[i, j] + own + 1e-15, (mu, alpha)


@pytest.mark.slow
@pytest.mark.parametrize("name", azimuthal.DISTRIBUTIONS)
@pytest.mark.parametrize("rtol", [1e-3, 1e-6, 1e-10])
def test_estimates_bound_the_error_on_random_views_and_roughnesses(name, rtol):
    rng = np.random.default_rng(11)
    n = 160
    mu = np.exp(rng.uniform(np.log(1e-6), 0.0, n))
    alpha = np.exp(rng.uniform(np.log(1e-8), np.log(100.0), n))  # the parameter's range: α > 1 too
    mu[:10], alpha[10:20] = 1.0, 1.0
    for shadowing in SHADOWINGS:
        model = bn.load(name, alpha=alpha, shadowing=shadowing)
        ours = bn.albedo(model, np.arccos(mu), rtol=rtol)
        reference = bn.albedo(model, np.arccos(mu), rtol=1e-13, method="microfacet")
        true_error = np.abs(ours.value - reference.value)[:, 0]
        bound = (ours.error + reference.error)[:, 0]
        worst = np.argmax(true_error / bound)
        assert np.all(true_error <= bound), (mu[worst], alpha[worst], true_error[worst], ours.error[worst])
        assert ours.converged.all() and np.all(ours.error[:, 0] <= rtol * ours.value[:, 0])
        # A handful of panels per albedo: far fewer evaluations than the half-vector cubature's.
        assert ours.evaluations.mean() < 0.25 * reference.evaluations.mean()


def test_rounding_floor_is_in_the_estimate():
    # Positive node values sum with a relative rounding of a few ulps: an estimate below ~1e-15·E would claim
    # more than float64 gives (the panel differences alone are 0 for a smooth lobe at α = 1).
    result = bn.albedo(bn.load("ggx", alpha=1.0), np.arccos([0.5, 1.0]), rtol=1e-12)
    assert np.all(result.error[:, 0] >= 1e-14 * result.value[:, 0])


def test_beckmann_rougher_than_one_agrees_with_the_half_vector_cubature():
    # α > 1 (allowed up to 100): the range in s = d/α shrinks below one panel and κ stays small.
    theta = np.arccos([1e-6, 1e-3, 0.1, 0.5, 1.0])[None, :]
    model = bn.load("beckmann", alpha=np.array([1.5, 10.0, 100.0])[:, None])
    ours = bn.albedo(model, theta, rtol=1e-13)
    cubature = bn.albedo(model, theta, rtol=1e-13, method="microfacet")
    true_error = np.abs(ours.value - cubature.value)
    assert ours.method == "azimuthal" and ours.converged.all()
    assert np.all(true_error <= ours.error + cubature.error) and np.all(true_error <= 1e-13 * ours.value)


def test_beckmann_tail_beyond_the_reach_is_negligible(monkeypatch):
    # The Gaussian e^{−s²} is cut at |s| = S_REACH: integrate what is cut (to |s| = 3·S_REACH, e^{−576} beyond)
    # with the module's own integrand, on random views and roughnesses, relative to E.
    rng = np.random.default_rng(5)
    mu, alpha = np.exp(rng.uniform(np.log(1e-6), 0.0, 400)), np.exp(rng.uniform(np.log(1e-8), np.log(3.0), 400))
    distribution = BeckmannDistribution()
    albedo = azimuthal.albedo(distribution, "height-correlated", mu, alpha, rtol=1e-12)[0]
    reach = azimuthal.S_REACH

    def tail_panels(route, e_v, theta_v, alpha, scale):
        start, end = -route.t(alpha, np.tan(0.5 * theta_v)), route.t(alpha, np.tan(0.5 * e_v))
        a = np.concatenate([np.maximum(start, -3 * reach), np.maximum(start, reach)])
        b = np.concatenate([np.minimum(end, -reach), np.minimum(end, 3 * reach)])
        case = np.tile(np.arange(e_v.size), 2)
        return a[b > a], b[b > a], case[b > a]

    monkeypatch.setattr(azimuthal, "_panels", tail_panels)
    tail = azimuthal.albedo(distribution, "height-correlated", mu, alpha, rtol=1e-3)[0]
    assert np.any(tail > 0.0)  # some cases reach past the cut
    assert np.all(tail <= 1e-25 * albedo)


@pytest.mark.parametrize("name", azimuthal.DISTRIBUTIONS)
def test_no_floating_point_warnings_over_the_parameter_range(name):
    # α = 0 (the mirror: GGX's q^{3/2} ~ α³ underflowed at a normal view), α = 1 (g = 0), just above it (the
    # pole's branch points at distance atanh(1/α) → ∞), α = 100, μ = 1e-8.
    alpha = np.array([1e-12, 1e-8, 0.5, 1.0, 1.0 + 1e-12, 2.0, 100.0])[:, None]
    views = np.arccos([1e-8, 1e-4, 0.5, 1.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        result = bn.albedo(bn.load(name, alpha=alpha), views[None, :], rtol=1e-10)
        # The Kulla-Conty tables' α = 0 column (the model's own α stops at 1e-12): the 1-D route at α = 0.
        distribution = {"ggx": GGXDistribution, "beckmann": BeckmannDistribution}[name]()
        mirror = azimuthal.white_albedo(distribution, "height-correlated",
                                        bn.engine.methods._directions(views, 0.0 * views), np.zeros(4), rtol=1e-10)
    assert result.method == "azimuthal" and result.converged.all() and np.all(np.isfinite(result.value))
    assert mirror.converged.all() and np.all(np.abs(mirror.value[:, 0] - 1.0) <= 1e-15)  # a mirror keeps it all
