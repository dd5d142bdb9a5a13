"""The ``charlie`` sheen lobe (Estevez & Kulla 2017) against independent routes: the distribution's normalization
by scipy quad, the albedo by scipy's dblquad of the BRDF (a second integration method), the paper's Λ fit written
out again here, and ``examples/charlie.brdf`` (the same lobe in GLSL) to 1e-9 in albedo."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.paths import EXAMPLES
from helpers.references import dblquad_albedo
from scipy import integrate

import brdfnorm as bn
from brdfnorm.brdffile import random_hemisphere
from brdfnorm.check import check
from brdfnorm.errors import ParameterError
from brdfnorm.models.charlie import charlie_distribution, charlie_lambda


@pytest.mark.parametrize("alpha", [0.002, 0.01, 0.1, 0.35, 0.7, 1.0])
def test_distribution_is_normalized_for_every_alpha(alpha):
    # ∫ D(H) cos θ_H dω_H = 2π ∫₀^{π/2} D(θ) cos θ sin θ dθ = 1 (the paper's eq. 2), by adaptive quadrature; the
    # lobe of small α sits at θ_H = π/2, hence the breakpoints there.
    value, _ = integrate.quad(lambda t: 2 * np.pi * charlie_distribution(np.cos(t), alpha) * np.cos(t) * np.sin(t),
                              0.0, np.pi / 2, points=[np.pi / 2 - 3 * np.sqrt(alpha), np.pi / 2 - np.sqrt(alpha)],
                              epsabs=0.0, epsrel=1e-13, limit=400)
    assert value == pytest.approx(1.0, abs=1e-11)


def test_lambda_is_the_papers_fit():
    # Written out again from the paper's table: L(x) = a/(1 + b x^c) + d x + e, interpolated by (1 − α)².
    def fit(x, alpha):
        t = (1 - alpha) ** 2
        p = [t * q0 + (1 - t) * q1 for q0, q1 in zip((25.3245, 3.32435, 0.16801, -1.27393, -4.85967),
                                                      (21.5473, 3.82987, 0.19823, -1.97760, -4.32054), strict=True)]
        return p[0] / (1 + p[1] * x ** p[2]) + p[3] * x + p[4]

    for alpha in (0.05, 0.4, 1.0):
        for mu in (0.01, 0.3, 0.49, 0.5, 0.8, 1.0):
            expected = np.exp(fit(mu, alpha)) if mu < 0.5 else np.exp(2 * fit(0.5, alpha) - fit(1 - mu, alpha))
            assert charlie_lambda(np.array(mu), alpha) == pytest.approx(expected, rel=1e-14)
    # Λ grows towards grazing and is continuous at μ = 1/2 (the paper's two branches meet there).
    lam = charlie_lambda(np.array([0.5 - 1e-12, 0.5]), 0.3)
    assert lam[0] == pytest.approx(lam[1], rel=1e-9)
    assert np.all(np.diff(charlie_lambda(np.linspace(0.01, 1, 50), 0.3)) < 0)


SLOW = pytest.mark.slow


@pytest.mark.parametrize(("params", "theta"), [pytest.param({"roughness": 0.6}, 0.0, marks=SLOW),
                                               pytest.param({"roughness": 0.8}, 1.0, marks=SLOW),
                                               ({"roughness": 1.0, "shadowing": "neubelt"}, 0.7),
                                               pytest.param({"alpha": 0.3, "terminator": 1}, 1.2, marks=SLOW)])
def test_albedo_agrees_with_scipy_dblquad(params, theta):
    model = bn.load("charlie", **params)
    ours = bn.albedo(model, theta, rtol=1e-11)
    reference = dblquad_albedo(model, np.cos(theta), even=True)  # the sheen lobe is even in φ_L
    assert abs(ours.value[0] - reference) <= 1e-8
    assert ours.error[0] <= 1e-9


def test_roughness_is_alpha_squared_and_color_scales_channels():
    L = random_hemisphere(np.random.default_rng(3), 64)
    V = random_hemisphere(np.random.default_rng(4), 64)
    by_roughness = bn.load("charlie", roughness=0.6, color=(1.0, 0.5, 0.25)).eval(L, V)
    by_alpha = bn.load("charlie", alpha=0.36).eval(L, V)
    np.testing.assert_allclose(by_roughness, by_alpha[:, :1] * np.array([1.0, 0.5, 0.25]), rtol=1e-14)
    with pytest.raises(ParameterError):
        bn.load("charlie", roughness=0.01)  # α = 1e-4 < 1e-3


def _file_and_builtin(**params):
    shadowing = params.pop("shadowing", "kulla")
    builtin = bn.load("charlie", shadowing=shadowing, **params)
    file = bn.load(EXAMPLES / "charlie.brdf", neubelt=int(shadowing == "neubelt"),
                   **{("sheenColor" if k == "color" else k): v for k, v in params.items()})
    return file, builtin


@pytest.mark.parametrize("params", [{}, {"roughness": 0.25, "color": (0.9, 0.4, 0.1)}, {"shadowing": "neubelt"},
                                    {"roughness": 0.8, "terminator": 1}])
def test_example_file_albedo_equals_the_builtin(params):
    file, builtin = _file_and_builtin(**dict(params))
    theta = np.radians([0.0, 35.0, 70.0, 85.0])
    ours, theirs = bn.albedo(builtin, theta, rtol=1e-10), bn.albedo(file, theta, rtol=1e-10)
    assert np.max(np.abs(ours.value - theirs.value)) <= 1e-9
    L = random_hemisphere(np.random.default_rng(5), 500)
    V = random_hemisphere(np.random.default_rng(6), 500)
    np.testing.assert_allclose(file.eval(L, V), builtin.eval(L, V), rtol=1e-11, atol=1e-300)


def test_check_finds_the_grazing_gain_and_the_softened_terminator_asymmetry():
    # At low roughness the sheen lobe reflects more than it receives at grazing views (why renderers clamp the
    # roughness); the terminator softening makes the lobe non-reciprocal.
    energy = check(bn.load("charlie", roughness=0.1), fixed="all", checks=("energy",), budget=10).results["energy"]
    assert energy.status == "fail" and energy.value - energy.error > 1.5 and energy.theta_deg > 85
    report = check(bn.load("charlie", terminator=1), fixed="all", checks=("reciprocity",), budget=10)
    assert report.results["reciprocity"].status == "fail"
    report = check(bn.load("charlie"), fixed="all", checks=("reciprocity",), budget=10)
    assert report.results["reciprocity"].status == "pass"


def test_cli_albedo(run_cli):
    code, out, err = run_cli("albedo", "charlie", "-p", "roughness=0.5", "-p", "shadowing=neubelt",
                             "--theta", "0", "--json")
    assert code == 0, err
    assert '"albedo"' in out
