"""The hemisphere integrator against closed forms and independent 1-D routes, and its error honesty."""

from __future__ import annotations

from pathlib import Path

import mpmath
import numpy as np
import pytest
from conftest import nquad_albedo, phong_like_reference

import brdfnorm as bn
from brdfnorm import closed_forms
from brdfnorm.integrate import fibonacci_hemisphere, integrate_hemisphere, lobe_frame

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"

EXPONENTS = [0.0, 1.0, 3.5, 100.0, 512.0, 1e4]


@pytest.mark.parametrize("n", EXPONENTS)
@pytest.mark.parametrize(
    ("model", "over", "closed"),
    [
        ("phong", "light", closed_forms.phong_original_albedo_normal),
        ("phong", "view", closed_forms.phong_modified_albedo_normal),
        ("modified-phong", "light", closed_forms.phong_modified_albedo_normal),
        ("modified-phong", "view", closed_forms.phong_modified_albedo_normal),
        ("blinn-phong", "light", closed_forms.blinn_phong_albedo_normal),
        ("blinn-phong", "view", closed_forms.blinn_phong_albedo_normal),
    ],
)
def test_quadrature_matches_closed_forms_at_normal_incidence(model, over, closed, n):
    result = bn.albedo(bn.load(model, n=n), 0.0, over=over, method="quadrature", rtol=1e-12)
    exact = float(closed(n))
    assert result.converged.all()
    assert abs(result.value[0] / exact - 1) <= 1e-10
    assert result.error[0] >= abs(result.value[0] - exact) - 1e-16 * exact


def test_lambert_is_its_reflectance_everywhere():
    result = bn.albedo(bn.load("lambert", reflectance=0.7), np.radians([0, 30, 60, 89.9]), rtol=1e-12)
    np.testing.assert_allclose(result.value[:, 0], 0.7, rtol=1e-12)


@pytest.mark.parametrize("n", [0.5, 3.5, 100.0, 1e4])
@pytest.mark.parametrize("theta_deg", [20.0, 60.0, 85.0, 89.9])
@pytest.mark.parametrize("model", ["phong", "modified-phong"])
def test_view_dependent_phong_against_one_dimensional_route(model, n, theta_deg):
    theta = np.radians(theta_deg)
    reference = phong_like_reference(n, theta, original=(model == "phong"))
    result = bn.albedo(bn.load(model, n=n), theta, method="quadrature", rtol=1e-11)
    assert abs(result.value[0] / reference - 1) <= 1e-9


def _blinn_phong_mpmath(n: float, theta: float) -> mpmath.mpf:
    """Seed 002's 1-D form with the Δθ integral in closed form (₂F₁), by mpmath at 30 digits."""
    mpmath.mp.dps = 30
    n = mpmath.mpf(n)
    co, so = mpmath.cos(theta), mpmath.sin(theta)

    def integrand(phi):
        ci, si = mpmath.cos(phi), mpmath.sin(phi)
        z = (so * si / (co * ci + 1)) ** 2
        return ((co + ci) / mpmath.sqrt(co * ci + 1)) ** n * ci * si * mpmath.hyp2f1(n / 4, n / 4 + 0.5, 1, z)

    width = 2 * mpmath.sqrt(2 / (n + 1))
    points = sorted({mpmath.mpf(0), mpmath.pi / 2, mpmath.mpf(theta)} |
                    {p for p in (theta - 3 * width, theta + 3 * width) if 0 < p < mpmath.pi / 2})
    return 2 * mpmath.pi * 2 ** (-n / 2) * mpmath.quad(integrand, points)


@pytest.mark.parametrize(("n", "theta_deg"), [(1.0, 45.0), (10.0, 70.0), (100.0, 30.0), (512.0, 80.0)])
def test_view_dependent_blinn_phong_against_mpmath_hypergeometric_form(n, theta_deg):
    theta = np.radians(theta_deg)
    reference = float(_blinn_phong_mpmath(n, theta))
    result = bn.albedo(bn.load("blinn-phong", n=n), theta, method="quadrature", rtol=1e-12)
    assert abs(result.value[0] / reference - 1) <= 1e-10


def test_seed_002_grazing_case_where_dblquad_fails():
    # Issue 2: dblquad(epsrel=1e-9) returns 1.30674e-5 here; the true value is 1.3068174212e-5.
    result = bn.albedo(bn.load("blinn-phong", n=1e4), 1.5, method="quadrature", rtol=1e-12)
    assert abs(result.value[0] / 1.3068174212e-5 - 1) < 1e-9
    assert abs(result.value[0] / 1.30674e-5 - 1) > 1e-5


def test_blinn_phong_gaussian_against_a_second_parametrization():
    model = bn.load("blinn-phong-gaussian", n=10.0)
    theta_o = np.radians(40.0)
    value = nquad_albedo(model, theta_o, [theta_o], epsabs=1e-13, limit=200)
    result = bn.albedo(model, theta_o, method="quadrature", rtol=1e-12)
    assert abs(result.value[0] / value - 1) <= 1e-9


def test_error_estimates_are_honest_on_random_cases(rng):
    """≥ 50 random (model, n, θ_o, rtol) cases: the error estimate is never below the true error."""
    cases = 0
    for _ in range(60):
        model = rng.choice(["phong", "modified-phong"])
        n = float(np.exp(rng.uniform(np.log(0.2), np.log(1e4))))
        theta = float(np.radians(rng.uniform(0.0, 89.5)))
        rtol = float(rng.choice([1e-3, 1e-5, 1e-7, 1e-9]))
        reference = phong_like_reference(n, theta, original=(model == "phong"))
        result = bn.albedo(bn.load(model, n=n), theta, method="quadrature", rtol=rtol)
        true_error = abs(result.value[0] - reference)
        assert result.error[0] + 1e-13 * reference >= true_error, (model, n, theta, rtol)
        assert true_error <= max(rtol * reference, 1e-13 * reference), (model, n, theta, rtol)
        cases += 1
    assert cases >= 50


def test_vectorized_over_views_and_parameters_matches_single_calls():
    model = bn.load("blinn-phong").with_params(n=np.array([[2.0], [300.0]]))
    theta = np.radians([0.0, 50.0, 88.0])
    batch = bn.albedo(model, theta[None, :], rtol=1e-11)
    assert batch.value.shape == (2, 3, 1)
    for i, n in enumerate([2.0, 300.0]):
        for j, t in enumerate(theta):
            single = bn.albedo(bn.load("blinn-phong", n=n), t, rtol=1e-11)
            assert abs(batch.value[i, j, 0] / single.value[0] - 1) < 1e-10


def test_integrator_on_a_known_polynomial_with_an_off_normal_pole():
    # ∫ z² dω over the hemisphere = 2π/3, whatever pole the coordinates use.
    poles = fibonacci_hemisphere(7)
    result = integrate_hemisphere(lambda w, k: w[:, 2:3] ** 2, poles, np.full(7, 0.3), np.full(7, np.pi),
                                  rtol=1e-13)
    np.testing.assert_allclose(result.value[:, 0], 2 * np.pi / 3, rtol=1e-12)


def test_lobe_frame_is_orthonormal_and_points_towards_the_normal():
    P, T, B = lobe_frame(np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.1, -0.7, 0.01]]))
    for a, b in ((P, T), (P, B), (T, B)):
        np.testing.assert_allclose(np.einsum("ki,ki->k", a, b), 0.0, atol=1e-15)
    assert (T[1:, 2] > 0).all()


def test_nonfinite_values_raise_with_the_offending_pair_or_are_zeroed_with_a_warning():
    from brdfnorm.errors import EvaluationError
    from brdfnorm.models.base import Model, normal_lobe

    class HalfNaN(Model):
        name = "half-nan"

        def evaluate(self, L, V, params):
            return np.where(L[..., 0:1] > 0, np.nan, 1.0 / np.pi)

        def lobe(self, fixed, params, over):
            return normal_lobe(fixed)

    with pytest.raises(EvaluationError, match=r"L=\(.*\), V=\(0, 0, 1\)"):
        bn.albedo(HalfNaN(), 0.0)
    with pytest.warns(UserWarning, match="non-finite"):
        result = bn.albedo(HalfNaN(), 0.0, nonfinite="zero", rtol=1e-9)
    assert abs(result.value[0] - 0.5) < 1e-9
    assert abs(result.nonfinite_fraction - 0.5) < 1e-9


def test_lobe_is_estimated_when_the_model_gives_no_hint():
    from brdfnorm.models.base import Model
    from brdfnorm.models.phong import _cosine_lobe

    class HintlessModifiedPhong(Model):
        name = "hintless"

        def evaluate(self, L, V, params):
            return _cosine_lobe(L, V, 2000.0)[..., None]

    theta = np.radians(70.0)
    result = bn.albedo(HintlessModifiedPhong(), theta, rtol=1e-10)
    reference = phong_like_reference(2000.0, theta, original=False)
    assert abs(result.value[0] / reference - 1) < 1e-9


# scipy.integrate.nquad in spherical coordinates about N (φ breakpoint at the mirror azimuth, θ breakpoints at
# the mirror angle), epsrel 1e-12: the GGX example at roughness 0.05, θ_o = 20°.
GGX_20_DEGREES = 0.04000054102038473


@pytest.mark.parametrize("rtol", [1e-5, 1e-7, 1e-9])
def test_error_estimate_covers_the_smith_horizon_layer(rtol):
    # Smith G1 rises within α = 0.0025 of the horizon: a layer that must not fall between all the nodes.
    ggx = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=0.05)
    result = bn.albedo(ggx, np.radians(20.0), rtol=rtol)
    assert result.error[0] >= abs(result.value[0] - GGX_20_DEGREES)


@pytest.mark.slow
def test_ggx_reference_by_nquad():
    ggx = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=0.05)
    theta_o = np.radians(20.0)
    value = nquad_albedo(ggx, theta_o, [theta_o - 0.01, theta_o, theta_o + 0.01])
    assert abs(value / GGX_20_DEGREES - 1) < 1e-12


@pytest.mark.parametrize("rtol", [1e-4, 1e-6, 1e-9])
@pytest.mark.parametrize("n", [512.0, 1e4])
def test_error_estimate_covers_the_grazing_sliver(n, rtol):
    # At θ_o = 89.9° the Blinn-Phong lobe is a sliver 2c/(s√n) wide sideways; seed 002's series is exact.
    model = bn.load("blinn-phong", n=n)
    exact = bn.albedo(model, np.radians(89.9), method="series", rtol=1e-13).value[0]
    result = bn.albedo(model, np.radians(89.9), method="quadrature", rtol=rtol)
    assert result.error[0] >= abs(result.value[0] - exact)
    assert abs(result.value[0] - exact) <= rtol * exact
