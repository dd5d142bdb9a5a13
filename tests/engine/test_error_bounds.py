"""Every printed error estimate bounds the true error, the rounding of the float64 result included (issue 43).

The true albedo comes from mpmath at 25 digits, evaluated at the same float64 parameters and angles: seed 000's
closed form 8π(2^(−n/2) + n)/((n+2)(n+4)) for Blinn-Phong at normal incidence, 2π/(n+1) and 2π/(n+2) for Phong's
two readings, π for Lambert, and seed 002's one-dimensional ₂F₁ form (S1) away from it — a route that shares
nothing with the series method's Legendre rewriting nor with the hemisphere quadrature. The routes checked are
the three a user meets first: ``series`` (Blinn-Phong's default), ``closed-form`` and ``quadrature``.

The fixed cases are those the issue found: ``normalize blinn-phong --sweep n=1:1e4:9:log --at max`` printed at
n = 10^1.5 an estimate of 3.3e-22 for an error of 2.3e-16, and at n = 100 2.2e-17 for 2.6e-17.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
from helpers.seed_reference import seed_form
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import brdfnorm
from brdfnorm.engine.methods import FINAL_ROUNDING_ULPS, with_final_rounding
from brdfnorm.models.blinn_phong import BlinnPhong
from brdfnorm.models.lambert import Lambert
from brdfnorm.models.phong import PhongModified, PhongOriginal

DPS = 25


def blinn_phong_normal(n: float) -> mp.mpf:
    """Seed 000's Eq. 3 at the float64 n, exactly."""
    with mp.workdps(DPS):
        n = mp.mpf(n)
        return 8 * mp.pi * (2 ** (-n / 2) + n) / ((n + 2) * (n + 4))


def assert_bounds(result, reference: mp.mpf, what: str) -> None:
    """``result``: an albedo result, or a (value, error) pair."""
    value, error = (result.value, result.error) if hasattr(result, "value") else result
    value, error = float(np.ravel(value)[0]), float(np.ravel(error)[0])
    with mp.workdps(DPS):
        true_error = abs(mp.mpf(value) - reference)
    shown = mp.nstr(reference, 20)
    assert true_error <= error, f"{what}: |{value!r} - {shown}| = {float(true_error):.3g} > {error:.3g}"
    assert error >= FINAL_ROUNDING_ULPS * np.spacing(abs(value)), what


@pytest.mark.parametrize("n", [10**1.5, 100.0])
def test_issue_cases_at_max(n):
    # `normalize blinn-phong --sweep n=1:1e4:9:log --at max`: the maximum is at normal incidence.
    result = brdfnorm.normalize(BlinnPhong(), at="max", sweep={"n": [n]})
    theta = float(result.theta.ravel()[0])
    reference = blinn_phong_normal(n) if theta == 0.0 else seed_form(n, theta, dps=DPS)
    assert_bounds((result.albedo, result.error), reference, f"normalize at max, n={n!r}, theta={theta!r}")


def test_issue_sweep_every_row():
    n = np.logspace(0, 4, 9)
    result = brdfnorm.normalize(BlinnPhong(), at="normal", sweep={"n": n})
    for k, value in enumerate(n):
        assert_bounds((result.albedo[k], result.error[k]), blinn_phong_normal(float(value)), f"sweep row n={value!r}")


@pytest.mark.parametrize("n", [0.5, 10**1.5, 100.0, 5000.0])
@pytest.mark.parametrize("method", ["series", "closed-form"])
def test_blinn_phong_normal_incidence(method, n):
    assert_bounds(brdfnorm.albedo(BlinnPhong(n=n), 0.0, method=method), blinn_phong_normal(n), f"{method} n={n!r}")


@pytest.mark.parametrize("n", [0.0, 1.0, 37.3, 1e6])
def test_phong_closed_forms(n):
    with mp.workdps(DPS):
        light, view = 2 * mp.pi / (mp.mpf(n) + 1), 2 * mp.pi / (mp.mpf(n) + 2)
    assert_bounds(brdfnorm.albedo(PhongOriginal(n=n), 0.0, method="closed-form"), light, f"phong n={n!r}")
    assert_bounds(brdfnorm.albedo(PhongOriginal(n=n), 0.0, method="closed-form", over="view"), view, "phong view")
    assert_bounds(brdfnorm.albedo(PhongModified(n=n), 0.0, method="closed-form"), view, f"modified-phong n={n!r}")


@pytest.mark.parametrize("reflectance", [1.0, 0.3, 0.7071067811865476])
@pytest.mark.parametrize("method", ["closed-form", "quadrature"])
def test_lambert(method, reflectance):
    # E = reflectance exactly, at every view (the float64 reflectance is the exact reference).
    result = brdfnorm.albedo(Lambert(reflectance=reflectance), np.radians(40.0), method=method)
    assert_bounds(result, mp.mpf(reflectance), f"lambert {method} reflectance={reflectance!r}")


VIEWS = st.floats(0.0, np.radians(85.0))
EXPONENTS = st.floats(0.0, 2.0).map(lambda e: 10.0**e)  # n in [1, 100]: mpmath's ₂F₁ quadrature stays fast


def test_series_at_views_within_float64_of_the_normal():
    # found by the property test below: at theta = 3.9e-157 the Legendre kernel underflowed and E was inf
    for theta in (3.922492407662235e-157, 1e-300, 1e-12):
        assert_bounds(brdfnorm.albedo(BlinnPhong(n=1.0), theta, method="series"), seed_form(1.0, theta, dps=DPS),
                      f"series theta={theta!r}")


@settings(max_examples=12, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(n=EXPONENTS, theta=VIEWS)
def test_series_bounds_its_error(n, theta):
    assert_bounds(brdfnorm.albedo(BlinnPhong(n=n), theta, method="series"), seed_form(n, theta, dps=DPS),
                  f"series n={n!r} theta={theta!r}")


@settings(max_examples=6, deadline=None, derandomize=True, suppress_health_check=[HealthCheck.too_slow])
@given(n=EXPONENTS, theta=VIEWS, phi=st.floats(0.0, 2 * np.pi))
def test_quadrature_bounds_its_error(n, theta, phi):
    result = brdfnorm.albedo(BlinnPhong(n=n), theta, phi, method="quadrature", rtol=1e-12)
    assert_bounds(result, seed_form(n, theta, dps=DPS), f"quadrature n={n!r} theta={theta!r} phi={phi!r}")


def test_floor_is_units_in_the_last_place():
    value = np.array([[0.6635577962346356], [0.0], [np.nan], [1e300]])
    error = np.array([[3.3e-22], [0.0], [np.nan], [np.inf]])
    floored = with_final_rounding(value, error)
    assert floored[0, 0] == FINAL_ROUNDING_ULPS * np.spacing(0.6635577962346356)
    assert floored[1, 0] == FINAL_ROUNDING_ULPS * np.spacing(0.0)
    assert np.isnan(floored[2, 0]) and floored[3, 0] == np.inf
    # an estimate above the floor is kept as it is
    assert with_final_rounding(np.array([1.0]), np.array([1e-10]))[0] == 1e-10
