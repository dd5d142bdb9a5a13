"""Seed 002's hypergeometric form of the Blinn-Phong albedo (brdfnorm.engine.routes.series) against independent routes.

Routes: mpmath at 30 digits on seed 002's own one-dimensional form with its ₂F₁(n/4, n/4+½; 1; z) (not the
Legendre rewriting the module uses), mpmath's 2-D quadrature of Equation 1, seed 000's closed form at θ_o = 0,
the elementary values of the Legendre ratio, and brdfnorm's adaptive hemisphere quadrature.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
from helpers.seed_reference import seed_form

from brdfnorm.engine.routes.series import blinn_phong_albedo_series, legendre_ratio
from brdfnorm.errors import ArgumentError, ParameterError
from brdfnorm.models.closed_forms import blinn_phong_albedo_normal

EXPONENTS = [0.5, 1.0, 10.0, 512.0, 1e4]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("n", "degrees"),
    [
        (0.5, 85.9),
        (1.0, 89.9),
        (10.0, 60.0),
        (512.0, 30.0),
        (512.0, 89.9),
        # n = 10⁴ takes mpmath ~10 s a point; the pointwise ₂F₁ identity and the quadrature test cover it fast.
        pytest.param(1e4, 85.9, marks=pytest.mark.slow),
        pytest.param(1e4, 89.9, marks=pytest.mark.slow),
    ],
)
def test_matches_seed_form_at_30_digits(n, degrees):
    theta = np.radians(degrees)
    result = blinn_phong_albedo_series(n, theta)
    reference = float(seed_form(n, theta))
    assert result.converged
    assert abs(result.value / reference - 1.0) <= 1e-13
    assert result.error <= 1e-12 * result.value


@pytest.mark.slow
def test_matches_equation_1_by_2d_quadrature():
    # Equation 1 of seed 002 (before any ₂F₁), integrated in Δθ and φ_i by mpmath: no shared derivation.
    n, theta = 10.0, 1.2
    with mp.workdps(17):
        co, so = mp.cos(theta), mp.sin(theta)

        def f(d, p):
            ci, si = mp.cos(p), mp.sin(p)
            return ((co + ci) / mp.sqrt(2 * (so * si * mp.cos(d) + co * ci + 1))) ** n * ci * si

        reference = float(mp.quad(f, [0, mp.pi, 2 * mp.pi], [0, theta, mp.pi / 2]))
    assert abs(blinn_phong_albedo_series(n, theta).value / reference - 1.0) <= 1e-13


def test_normal_incidence_is_seed_000_closed_form():
    n = np.array(EXPONENTS + [0.0, 1e5])
    result = blinn_phong_albedo_series(n, 0.0)
    np.testing.assert_allclose(result.value, blinn_phong_albedo_normal(n), rtol=2e-15, atol=0)


def test_n_zero_is_lambertian_everywhere():
    theta = np.radians([0.0, 45.0, 89.9, 90.0])
    np.testing.assert_allclose(blinn_phong_albedo_series(0.0, theta).value, np.pi, rtol=1e-15)


@pytest.mark.parametrize("m", [0.005, 0.25, 0.5, 1.7, 5.0, 256.0, 5000.0, 50000.0])
@pytest.mark.parametrize("lam", [1 - 1e-9, 0.9, 0.1, 1e-4, 1e-8, 1e-12])
def test_legendre_ratio_is_the_hypergeometric_function(m, lam):
    with mp.workdps(30):
        reference = float(mp.mpf(lam) ** m * mp.hyp2f1(m, 0.5, 1, 1 - mp.mpf(lam)))
    xi = -0.5 * np.log(lam) if lam < 0.5 else np.arctanh((1 - lam) / (1 + lam))
    assert abs(legendre_ratio(m, xi) / reference - 1.0) <= 5e-15


def test_legendre_ratio_elementary_values():
    lam = np.array([1e-10, 1e-3, 0.3, 0.99, 1.0])
    xi = -0.5 * np.log(lam)
    np.testing.assert_allclose(legendre_ratio(0.0, xi), 1.0, rtol=0)
    np.testing.assert_allclose(legendre_ratio(1.0, xi), np.sqrt(lam), rtol=4e-15)
    # m = ½: the complete elliptic integral, λ^¼ P_{−½} = √λ / AGM(1, √λ).
    agm = np.array([float(mp.agm(1, mp.sqrt(x))) for x in lam])
    np.testing.assert_allclose(legendre_ratio(0.5, xi), np.sqrt(lam) / agm, rtol=4e-15)


@pytest.mark.parametrize(("n", "theta", "phi"), [(1.0, 0.4, 1.1), (512.0, 1.5, 1.49), (1e4, 1.567, 1.566)])
def test_inner_integral_is_seed_002_hypergeometric_form(n, theta, phi):
    """Step (S2)-(S3): 2π cos^n(δ/2) G_{n/2}(λ) equals seed 002's 2π 2^(−n/2) (…)^n ₂F₁(n/4, n/4+½; 1; z)."""
    with mp.workdps(40):
        co, so, ci, si = mp.cos(theta), mp.sin(theta), mp.cos(phi), mp.sin(phi)
        z = (so * si / (co * ci + 1)) ** 2
        seed = (
            2 ** (-mp.mpf(n) / 2)
            * ((co + ci) / mp.sqrt(co * ci + 1)) ** n
            * mp.hyp2f1(mp.mpf(n) / 4, mp.mpf(n) / 4 + mp.mpf(1) / 2, 1, z)
        )
        xi = mp.atanh(so * si / (1 + co * ci))
        ours = mp.cos((theta - phi) / 2) ** n * float(legendre_ratio(n / 2, float(xi)))
    assert abs(float(ours / seed) - 1.0) <= 1e-14


def test_agrees_with_adaptive_hemisphere_quadrature():
    from brdfnorm.engine.methods import albedo
    from brdfnorm.models import BlinnPhong

    for n in EXPONENTS:
        theta = np.radians([0.0, 40.0, 85.9, 89.9])
        # rtol 1e-12 is the finest that (N·H)^n at n = 1e4 can honour in float64 (its rounding is amplified n×).
        quad = albedo(BlinnPhong(n=n), theta, method="quadrature", rtol=1e-12)
        assert quad.converged.all()
        series = blinn_phong_albedo_series(n, theta).value
        np.testing.assert_allclose(series, quad.value[..., 0], rtol=1e-12, atol=0, err_msg=f"n={n}")


def test_broadcasting_matches_scalar_calls():
    n = np.array([[1.0], [100.0], [3000.0]])
    theta = np.radians([5.0, 50.0, 88.0])
    grid = blinn_phong_albedo_series(n, theta)
    assert grid.value.shape == grid.error.shape == grid.evaluations.shape == (3, 3)
    for i in range(3):
        for j in range(3):
            assert grid.value[i, j] == pytest.approx(blinn_phong_albedo_series(n[i, 0], theta[j]).value, rel=1e-14)


def test_large_exponents_are_graceful():
    result = blinn_phong_albedo_series(np.array([1e5, 3e5]), np.radians(89.9))
    assert np.all(result.converged) and np.all(np.isfinite(result.value)) and np.all(result.value > 0)
    normal = blinn_phong_albedo_series(1e5, 0.0).value
    assert normal == pytest.approx(blinn_phong_albedo_normal(1e5), rel=1e-14)


def test_albedo_decreases_toward_grazing_for_a_sharp_lobe():
    theta = np.radians(np.linspace(0.0, 89.9, 30))
    values = blinn_phong_albedo_series(100.0, theta).value
    assert np.all(np.diff(values) < 0)


@pytest.mark.parametrize(
    ("kwargs", "error"),
    [
        ({"n": -1.0, "theta": 0.1}, ParameterError),
        ({"n": np.nan, "theta": 0.1}, ParameterError),
        ({"n": 1.0, "theta": 1.6}, ArgumentError),
        ({"n": 1.0, "theta": -0.1}, ArgumentError),
        ({"n": 1.0, "theta": 0.1, "rtol": 0.0}, ArgumentError),
        ({"n": 1.0, "theta": 0.1, "atol": -1.0}, ArgumentError),
    ],
)
def test_bad_input_raises_project_errors(kwargs, error):
    with pytest.raises(error):
        blinn_phong_albedo_series(**kwargs)


def test_registered_as_albedo_method_series():
    from brdfnorm.engine import methods as albedo
    from brdfnorm.models import BlinnPhong, PhongModified

    # "auto" picks the series for Blinn-Phong (other methods may come before it in AUTO_ORDER for other lobes).
    assert "series" in albedo.METHODS
    assert albedo.resolve_method(BlinnPhong(n=10.0), "light", "auto").name == "series"
    assert albedo.resolve_method(BlinnPhong(n=10.0), "view", "auto").name == "series"
    theta = np.radians([0.0, 85.9])
    result = albedo.albedo(BlinnPhong(n=np.array([[1.0], [1e4]])), theta, method="series", rtol=1e-12)
    assert result.method == "series" and result.value.shape == (2, 2, 1)
    np.testing.assert_allclose(result.value[..., 0], blinn_phong_albedo_series([[1.0], [1e4]], theta).value, rtol=0)
    with pytest.raises(ArgumentError):
        albedo.albedo(PhongModified(n=10.0), 0.3, method="series")
