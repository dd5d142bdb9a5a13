"""The rough diffuse lobes — ``oren-nayar`` (1994), ``fon`` and ``eon`` (Portsmouth, Kutz & Hill 2025), ``burley``
(Disney 2012) — against independent routes: FON's closed-form albedo and average against brdfnorm's quadrature and
scipy, the Lambert limit at zero roughness, EON's white furnace by quadrature of the lobe (not its formula), the
example ``.brdf`` files of the same lobes to 1e-9, and ``check``'s energy verdicts (Burley's gain, the cost of
EON's fitted albedo)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.paths import EXAMPLES
from scipy import integrate

import brdfnorm as bn
from brdfnorm.brdffile import random_hemisphere
from brdfnorm.check import check
from brdfnorm.models.fon import fon_albedo_approx, fon_albedo_exact, fon_average_approx, fon_average_exact

THETA = np.radians([0.0, 25.0, 50.0, 75.0, 89.0])


@pytest.mark.parametrize("roughness", [0.1, 0.5, 1.0])
def test_fon_albedo_closed_form_against_quadrature(roughness):
    model = bn.load("fon", roughness=roughness, reflectance=0.8)
    numeric = bn.albedo(model, THETA, rtol=1e-11)
    closed = 0.8 * fon_albedo_exact(np.cos(THETA), roughness)
    assert np.max(np.abs(numeric.value[:, 0] - closed)) <= 1e-10
    assert np.all(np.abs(numeric.value[:, 0] - closed) <= numeric.error[:, 0] + 1e-14)
    assert np.max(np.abs(bn.albedo(model, THETA, method="closed-form").value[:, 0] - closed)) <= 1e-15


def test_fon_average_and_fitted_average_against_scipy():
    for r in (0.2, 1.0):
        exact, _ = integrate.quad(lambda mu, r=r: 2 * mu * fon_albedo_exact(mu, r), 0, 1, epsabs=0, epsrel=1e-13)
        fitted, _ = integrate.quad(lambda mu, r=r: 2 * mu * fon_albedo_approx(mu, r), 0, 1, epsabs=0, epsrel=1e-13)
        assert fon_average_exact(r) == pytest.approx(exact, rel=1e-12)
        assert fon_average_approx(r) == pytest.approx(fitted, rel=1e-12)


@pytest.mark.parametrize("name", ["oren-nayar", "fon", "eon"])
def test_lambert_limit_at_zero_roughness(name):
    model = bn.load(name, **({"sigma": 0.0} if name == "oren-nayar" else {"roughness": 0.0}))
    L = random_hemisphere(np.random.default_rng(1), 200)
    V = random_hemisphere(np.random.default_rng(2), 200)
    np.testing.assert_allclose(model.eval(L, V)[:, 0], 1 / np.pi, rtol=1e-15)
    assert np.max(np.abs(bn.albedo(model, THETA, rtol=1e-12).value - 1.0)) <= 1e-11


@pytest.mark.parametrize("roughness", [0.05, 0.5, 1.0])
def test_eon_white_furnace_by_quadrature_of_the_lobe(roughness):
    # Method "quadrature" integrates f·cos over the hemisphere: the 1 is not assumed anywhere.
    result = bn.albedo(bn.load("eon", roughness=roughness), THETA, rtol=1e-11, method="quadrature")
    assert np.max(np.abs(result.value - 1.0)) <= 1e-10


@pytest.mark.parametrize("params", [{"roughness": 0.7, "reflectance": 0.3}, {"roughness": 1.0, "fon_albedo": "approx"},
                                    {"roughness": 0.4, "reflectance": 0.9, "fon_albedo": "approx"}])
def test_eon_closed_form_albedo_against_quadrature(params):
    model = bn.load("eon", **params)
    numeric = bn.albedo(model, THETA, rtol=1e-11).value
    closed = bn.albedo(model, THETA, method="closed-form").value
    assert np.max(np.abs(numeric - closed)) <= 1e-10


@pytest.mark.slow
def test_eon_fitted_albedo_excess_by_closed_form_and_by_check():
    # The white albedo with the fitted E_F, in closed form on a dense grid (the formula is checked against
    # quadrature above), and check's search of the lobe by quadrature: the same maximum excess, > 0.
    mu, r = np.meshgrid(np.linspace(1e-3, 1.0, 1000), np.linspace(0.0, 1.0, 101), indexing="ij")
    model = bn.load("eon", roughness=r.ravel(), fon_albedo="approx")
    grid = model.closed_form_albedo(np.stack([np.sqrt(1 - mu.ravel() ** 2), 0 * mu.ravel(), mu.ravel()], -1),
                                    model.params, "light")[:, 0]
    worst = int(np.argmax(grid))
    assert 1e-4 < grid[worst] - 1 < 2e-4
    energy = check(bn.load("eon", fon_albedo="approx"), checks=("energy",), budget=8).results["energy"]
    assert energy.status == "fail"
    assert abs(energy.value - grid[worst]) <= 2e-6
    assert abs(energy.params["roughness"] - r.ravel()[worst]) <= 0.05
    exact = check(bn.load("eon"), checks=("energy",), budget=8).results["energy"]
    assert exact.status == "pass" and abs(exact.value - 1.0) <= 1e-8


def test_check_finds_burleys_gain_at_grazing_and_high_roughness():
    energy = check(bn.load("burley"), checks=("energy",), budget=8).results["energy"]
    assert energy.status == "fail"
    assert energy.params["roughness"] == 1.0 and energy.theta_deg >= 89.0
    # The independent value at (r = 1, 89.9°): scipy's dblquad of the BRDF.
    model = bn.load("burley", roughness=1.0)
    theta = np.radians(energy.theta_deg)
    V = np.array([np.sin(theta), 0.0, np.cos(theta)])

    def g(t, p):
        L = np.array([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)])
        return model.eval(L, V)[0] * L[2] * np.sin(t)

    reference = 2 * integrate.dblquad(g, 0, np.pi, 0, np.pi / 2, epsabs=1e-11, epsrel=1e-10)[0]
    assert abs(energy.value - reference) <= 1e-8 and reference > 1.5


PAIRS = [
    pytest.param("eon.brdf", {"roughness": 0.7, "rho": 0.8}, "eon", {"roughness": 0.7, "reflectance": 0.8},
                 marks=pytest.mark.slow),
    pytest.param("eon.brdf", {"roughness": 1.0, "exact": 0}, "eon", {"roughness": 1.0, "fon_albedo": "approx"},
                 marks=pytest.mark.slow),
    pytest.param("eon.brdf", {"roughness": 0.4, "multiscatter": 0}, "fon", {"roughness": 0.4}, marks=pytest.mark.slow),
    pytest.param("oren_nayar.brdf", {"sigma": 0.3, "rho": 1.0}, "oren-nayar", {"sigma": 0.3}, marks=pytest.mark.slow),
    ("disney_diffuse.brdf", {"roughness": 0.9, "baseColor": (1.0, 1.0, 1.0)}, "burley", {"roughness": 0.9}),
]


@pytest.mark.parametrize(("file", "file_params", "name", "params"), PAIRS)
def test_example_files_albedo_equals_the_builtins(file, file_params, name, params):
    ours = bn.albedo(bn.load(name, **params), THETA, rtol=1e-10).value[:, 0]
    theirs = bn.albedo(bn.load(EXAMPLES / file, **file_params), THETA, rtol=1e-10).value[:, 0]
    assert np.max(np.abs(ours - theirs)) <= 1e-9


@pytest.mark.parametrize(("file", "file_params", "name", "params"), [p.values if hasattr(p, "values") else p
                                                                      for p in PAIRS])
def test_example_files_equal_the_builtins_pointwise(file, file_params, name, params):
    L = random_hemisphere(np.random.default_rng(7), 2000)
    V = random_hemisphere(np.random.default_rng(8), 2000)
    ours = bn.load(name, **params).eval(L, V)[:, 0]
    theirs = bn.load(EXAMPLES / file, **file_params).eval(L, V)[:, 0]
    np.testing.assert_allclose(theirs, ours, rtol=1e-12)


def test_engine_error_estimate_on_fons_kinks():
    # f has kinks where max(N·L, N·V) switches (θ_L = θ_V) and where s = L·V − N·L N·V changes sign; the closed form
    # is exact (scipy's dblquad agrees to 3e-14 there). An error estimate must never be below the true error. The kink
    # θ_L = θ_V lay 0.0008 inside a panel's edge, beyond all its Gauss-Kronrod nodes (error 5.8e-7, estimate 3.3e-11):
    # brdfnorm.engine.machinery.kinks.
    mu = np.linspace(0.001, 1.0, 60)[35]
    result = bn.albedo(bn.load("fon", roughness=1.0), np.arccos(mu), rtol=1e-10)
    assert abs(result.value[0] - fon_albedo_exact(mu, 1.0)) <= result.error[0]
