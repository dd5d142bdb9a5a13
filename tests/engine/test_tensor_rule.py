"""The global tensor rule (brdfnorm.engine.machinery.tensor_rule) in front of the adaptive panels: its pieces against
exact
values, and a randomized honesty probe of the whole engine against independent references (issue 13)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.paths import EXAMPLES, FIXTURES
from helpers.references import ggx_albedo_reference, half_vector_gauss_legendre, phong_like_reference

import brdfnorm as bn
from brdfnorm.engine.machinery.hemisphere_global import integrate_global
from brdfnorm.engine.machinery.tensor_rule import LAMBDA_MIN, START_LEVELS, beta_map, fejer, radial_width_scale
from brdfnorm.engine.routes import hemisphere as engine
from brdfnorm.engine.routes.hemisphere import integrate_hemisphere

NAIVE_GGX = FIXTURES / "ggx_naive.brdf"


@pytest.mark.parametrize("level", [2, 4, 7])
def test_fejer_rule_is_nested_and_exact_for_polynomials(level):
    nodes, weights = fejer(level)
    # Fejér's second rule with N − 1 nodes integrates polynomials of degree N − 2 exactly.
    for degree in range(2**level - 1):
        assert abs(weights @ nodes**degree - 1.0 / (degree + 1)) < 1e-14
    coarse = fejer(level - 1)[0]
    np.testing.assert_array_equal(nodes[1::2], coarse)


@pytest.mark.parametrize("lam", [0.1, 0.4, 1.0])
def test_beta_map_is_a_periodic_bijection_with_its_derivative(lam):
    t = np.linspace(0.0, 2 * np.pi, 2001)
    beta, derivative = beta_map(t, lam)
    assert np.all(np.diff(beta) > 0)
    assert abs(beta[0]) < 1e-15 and abs(beta[-1] - 2 * np.pi) < 1e-14
    h = 1e-6
    numeric = (beta_map(t + h, lam)[0] - beta_map(t - h, lam)[0]) / (2 * h)
    np.testing.assert_allclose(derivative, numeric, rtol=1e-7)
    # Clustered at β = π: the derivative there is λ.
    assert abs(beta_map(np.array([np.pi]), lam)[1][0] - lam) < 1e-15


@pytest.mark.parametrize("lam", [LAMBDA_MIN, 0.6, 1.0])
def test_radial_width_follows_an_ellipse_of_axis_ratio_lambda(lam):
    # The map's nodes t and the widths at them: the point (width cos β, width sin β) lies on the ellipse
    # x² + (y/λ)² = 1 (axes 1 along β = 0, π and λ along β = ±π/2), whose parametrization by t is the map itself.
    t = np.linspace(0.0, 2 * np.pi, 101)
    beta, derivative = beta_map(t, lam)
    width = radial_width_scale(derivative, lam)
    np.testing.assert_allclose((width * np.cos(beta)) ** 2 + (width * np.sin(beta) / lam) ** 2, 1.0, rtol=1e-13)


@pytest.mark.slow
def test_global_rule_alone_is_honest_at_grazing_views(rng, monkeypatch, lobe_aligned_only):
    # Beyond θ_o ≈ 75° the β map's clustering is held at LAMBDA_MIN and the elliptic radial width is narrowest:
    # every case the global rule settles (not the panels after it) must carry an estimate ≥ its true error.
    settled = []

    def spy(*args, **kwargs):
        result = integrate_global(*args, **kwargs)
        settled.append(result)
        return result

    monkeypatch.setattr(engine, "integrate_global", spy)
    checked = 0
    for rtol in RTOLS:
        theta = np.radians(np.concatenate([rng.uniform(75.0, 85.0, 16), rng.uniform(85.0, 89.95, 32)]))
        n = np.exp(rng.uniform(np.log(5.0), np.log(1e4), theta.size))
        model = bn.load("blinn-phong").with_params(n=n)
        reference = bn.albedo(model, theta, method="series", rtol=1e-13)
        settled.clear()
        _quiet(model, theta, rtol=rtol)
        (result,) = settled
        picked = result.converged
        true_error = np.abs(result.value[picked, 0] - reference.value[picked, 0])
        allowance = reference.error[picked, 0] + 4e-15 * reference.value[picked, 0]
        assert np.all(result.error[picked, 0] + allowance >= true_error), (rtol, np.flatnonzero(picked))
        checked += picked.sum()
    assert checked >= len(RTOLS) * 48 // 3  # the check has substance: many grazing cases settle in the rule


def test_smooth_cases_settle_in_the_global_rule_with_few_evaluations():
    # A polynomial over the hemisphere, ∫ z² dω = 2π/3, about poles at several heights (a broad "lobe").
    poles = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.999, 0.0, 0.0447]])
    poles /= np.linalg.norm(poles, axis=1, keepdims=True)
    result = integrate_hemisphere(lambda w, k: w[:, 2:3] ** 2, poles, np.full(3, 1.0), np.full(3, np.pi),
                                  rtol=1e-12)
    np.testing.assert_allclose(result.value[:, 0], 2 * np.pi / 3, rtol=1e-13)
    assert result.converged.all()
    # Probe (576) plus a handful of doublings from the 8 × 15 start, where the panels needed 20 000 and more.
    assert result.evaluations.max() < 10_000
    assert np.all(result.error[:, 0] >= np.abs(result.value[:, 0] - 2 * np.pi / 3))


def test_unsettled_and_nonfinite_cases_go_to_the_panels():
    from brdfnorm.engine.machinery.rounding import noise_bound
    from brdfnorm.engine.routes.hemisphere import lobe_frame

    def integrand(w, k):
        # Case 0: smooth. Case 1: NaN on half the hemisphere (the panels raise or zero it, never the rule).
        return np.where((k[:, None] == 1) & (w[:, 0:1] > 0), np.nan, w[:, 2:3])

    frame = lobe_frame(np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]))
    result = integrate_global(integrand, frame, np.full(2, 0.5), np.full(2, np.pi), np.arange(2), np.zeros((2, 1)),
                              rtol=1e-10, atol=0.0, noise_bound=noise_bound)
    assert result.converged.tolist() == [True, False]
    assert abs(result.value[0, 0] - np.pi) < 1e-10 * np.pi
    assert result.evaluations[1] == 2 ** START_LEVELS[0] * (2 ** START_LEVELS[1] - 1)


def test_pre_asymptotic_plateau_is_covered():
    # Found by the randomized probe: Fejér's rule with 15 and 31 radial nodes, both 4e-7 off, 2.4e-7 apart; the
    # plain deviation of the embedded rule (3.1e-9 absolute) was 1.5 times below the true error (4.8e-9).
    model = bn.load("blinn-phong", n=805.2)
    theta = np.radians(50.40)
    exact = bn.albedo(model, theta, method="series", rtol=1e-13).value[0]
    result = bn.albedo(model, theta, method="quadrature", rtol=1e-6)
    assert result.error[0] >= abs(result.value[0] - exact)


def _quiet(model, theta, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bn.albedo(model, theta, method="quadrature", **kwargs)


def _record(ratios: list, value, error, reference, allowance, label):
    true_error = np.abs(value - reference)
    assert np.all(error + allowance >= true_error), (label, np.flatnonzero(error + allowance < true_error))
    ratios.append(float(np.max(true_error / np.maximum(error, 1e-300))))


RTOLS = [1e-6, 1e-8, 1e-9, 1e-10, 1e-11]


def _angles(rng, count: int) -> np.ndarray:
    """Polar angles, a third of them grazing (85° … 89.9°)."""
    grazing = rng.uniform(85.0, 89.9, count // 3)
    return np.radians(np.concatenate([rng.uniform(0.0, 85.0, count - grazing.size), grazing]))


@pytest.mark.slow
def test_randomized_honesty_probe(rng):
    """Estimate ≥ true error on ~250 random cases of the whole engine (global rule, then panels) against
    independent references: seed 002's series (Blinn-Phong), a 1-D route by scipy quad (Phong, modified Phong),
    Gauss–Legendre in the half-vector CDF (GGX written as shaders write it)."""
    ratios: list[float] = []
    for rtol in RTOLS:
        theta = _angles(rng, 72)
        n = np.exp(rng.uniform(0.0, np.log(1e4), theta.size))
        model = bn.load("blinn-phong").with_params(n=n)
        reference = bn.albedo(model, theta, method="series", rtol=1e-13)
        result = _quiet(model, theta, rtol=rtol)
        _record(ratios, result.value[:, 0], result.error[:, 0], reference.value[:, 0],
                reference.error[:, 0] + 4e-15 * reference.value[:, 0], ("blinn-phong", rtol))
        for name in ("phong", "modified-phong"):
            theta = _angles(rng, 6)
            n = np.exp(rng.uniform(0.0, np.log(1e4), theta.size))
            result = _quiet(bn.load(name).with_params(n=n), theta, rtol=rtol)
            original = name == "phong"
            exact = np.array([phong_like_reference(a, b, original=original) for a, b in zip(n, theta, strict=True)])
            _record(ratios, result.value[:, 0], result.error[:, 0], exact, 1e-13 * exact, (name, rtol))
        if rtol >= 1e-9:  # the reference's own accuracy (~1e-12) bounds what can be checked
            mu = np.concatenate([rng.uniform(0.05, 1.0, 3), rng.uniform(0.0017, 0.05, 2)])
            alpha = np.exp(rng.uniform(np.log(0.02), 0.0, mu.size))
            result = _quiet(bn.load(str(NAIVE_GGX)).with_params(alpha=alpha), np.arccos(mu), rtol=rtol)
            exact = np.array([ggx_albedo_reference(a, m) for a, m in zip(alpha, mu, strict=True)])
            _record(ratios, result.value[:, 0], result.error[:, 0], exact, 1e-12 * exact, ("naive ggx", rtol))
    assert len(ratios) == 3 * len(RTOLS) + 3
    print(f"worst true error / estimate: {max(ratios):.3g}")


@pytest.mark.parametrize("budget", [1, 100, 1000])
def test_tiny_budgets_end_unconverged_with_a_reason(budget):
    # A quarter of the budget below the rule's first grid: the global rule is skipped, the panels say "budget".
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(bn.load("blinn-phong", n=50), 0.5, method="quadrature", max_evaluations=budget)
    assert not result.converged[()] and result.reason[()] == "budget"
    exact = bn.albedo(bn.load("blinn-phong", n=50), 0.5, method="series", rtol=1e-13).value[0]
    assert result.error[0] >= abs(result.value[0] - exact)


def test_heavy_tails_get_the_cubic_horizon_grading_and_settle_in_the_global_rule():
    # examples/ggx.brdf at roughness 0.107 (α = 0.0114), θ_o = 60°: with the quadratic grading the u estimate fell
    # only algebraically (Smith G1's boundary layer at the horizon) and the case went to the panels (55 248
    # evaluations); with the cubic grading, and β alone doubled once u is within the whole tolerance, the global
    # rule settles it. The value is checked against the built-in GGX (Schlick F, separable Smith) by the
    # half-vector cubature, a different route.
    theta = np.radians(60.0)
    model = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=0.107)
    result = bn.albedo(model, theta, method="quadrature", rtol=1e-9)
    assert result.evaluations[()] < 20_000
    reference = bn.albedo(bn.load("ggx", alpha=0.107**2, shadowing="separable", fresnel="schlick", f0=0.04,
                                  f90=1.0), theta, method="microfacet", rtol=1e-12)
    assert abs(result.value[0] - reference.value[0]) <= result.error[0] + reference.error[0]


@pytest.mark.parametrize("theta_deg", [29.5, 29.77482180521632, 30.99])
def test_a_stall_before_a_sudden_agreement_is_not_settled(theta_deg):
    # examples/oren_nayar.brdf (max(s, 0) and the switch at θ_L = θ_V: kinks the grid crosses obliquely) at
    # rtol 1e-6: the global rule's value moved 3.4e-5, 2.7e-5, then 4.6e-9 (29.77°) while every level stayed 3e-7
    # off, and it settled with an estimate 0.71–0.74 of the error; _stalled now keeps such a case going. The
    # reference reduces the azimuth in closed form (∫ max(cos Δφ, 0) dφ = 2) and integrates θ_L by scipy quad.
    from scipy.integrate import quad

    theta = np.radians(theta_deg)
    sigma2, rho = 0.25, 0.8
    A, B = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33), 0.45 * sigma2 / (sigma2 + 0.09)

    def polar(t):
        return 2.0 * np.sin(t) ** 2 * np.cos(t) / max(np.cos(t), np.cos(theta))

    polar_integral = quad(polar, 0.0, theta, epsrel=1e-13)[0] + quad(polar, theta, np.pi / 2, epsrel=1e-13)[0]
    exact = rho / np.pi * (A * np.pi + B * np.sin(theta) * polar_integral)
    model = bn.load(str(EXAMPLES / "oren_nayar.brdf"))
    result = _quiet(model, theta, rtol=1e-6)
    assert result.error[0] >= abs(result.value[0] - exact)


def test_an_unresolved_azimuthal_wedge_does_not_settle_in_the_global_rule():
    # Ashikhmin-Shirley with n_u = 1407, n_v = 2.3 is a wedge ~1/25 rad wide about its peak in the lobe-aligned
    # azimuth β. At rtol 1e-5 the rule settled it at 128 × 255 nodes, the 64- and 128-azimuth rules agreeing to
    # 4.5e-7 on a value 1.1e-6 off (0.7 of the error); the Fourier tail of the β profile (tensor_rule._azimuthal_tail)
    # keeps it from settling there. Reference: composite Gauss-Legendre over the half vector, at two orders that
    # must agree.
    params = dict(nu=1407.321199972626, nv=2.306811896628435, Rs=0.03160002608104069, Rd=0.13596547178173649)
    model = bn.load(str(EXAMPLES / "ashikhmin_shirley.brdf"), **params)
    theta, phi = 1.0418883384140385, 3.860220958354151
    V = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    coarse, reference = (half_vector_gauss_legendre(model, V, n, 16) for n in (24, 32))
    assert abs(coarse - reference) < 1e-7  # the failure being guarded against was 1.1e-6 off
    for rtol in (1e-4, 1e-5):
        result = bn.albedo(model, theta, phi=phi, rtol=rtol, method="quadrature")
        assert abs(result.value.ravel()[0] - reference) <= result.error.ravel()[0], rtol
