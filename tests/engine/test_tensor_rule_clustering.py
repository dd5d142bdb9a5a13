"""The lobe-aligned global rule's β clustering at least WIDTH_CLUSTERING lobe widths
(brdfnorm.engine.machinery.tensor_rule.clustering): the map it gives, and honest estimates where it acts (grazing
views of lobes of width ~0.1…0.6 rad, Blinn-Phong n ≈ 15…700) against seed 002's series; and a sweep of lobes at
the tolerances the randomized probe of test_tensor_rule.py leaves out."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.paths import FIXTURES
from helpers.references import ggx_albedo_reference, phong_like_reference

import brdfnorm as bn
from brdfnorm.engine.machinery.tensor_rule import LAMBDA_MIN, WIDTH_CLUSTERING, clustering

NAIVE_GGX = FIXTURES / "ggx_naive.brdf"


def _frame(pz: np.ndarray) -> tuple[np.ndarray, ...]:
    P = np.stack([np.sqrt(1.0 - pz**2), np.zeros_like(pz), pz], axis=1)
    return P, None, None


def test_clustering_is_held_at_a_multiple_of_the_width_near_the_horizon():
    pz = np.array([0.02, 0.02, 0.02, 0.9, 0.02])
    widths = np.array([0.28, 0.125, 0.05, 0.28, 0.85])
    lam = clustering(_frame(pz), widths)
    np.testing.assert_allclose(lam[:2], WIDTH_CLUSTERING * widths[:2])  # the width's floor
    assert lam[2] == LAMBDA_MIN  # a narrow lobe: the old floor
    np.testing.assert_allclose(lam[3], min(1.0, 0.9 + 2 * 0.28**2))  # a high peak: c_P + 2w²
    assert lam[4] == 1.0  # a broad lobe: uniform azimuths


def test_estimates_bound_the_error_where_the_width_floor_acts(rng):
    n = np.exp(rng.uniform(np.log(15.0), np.log(700.0), 12))
    theta = np.radians(rng.uniform(70.0, 89.9, n.size))
    model = bn.load("blinn-phong").with_params(n=n)
    reference = bn.albedo(model, theta, method="series", rtol=1e-13)
    worst = 0.0
    for rtol in (1e-5, 1e-9, 1e-11):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = bn.albedo(model, theta, method="quadrature", rtol=rtol)
        error = np.abs(result.value[:, 0] - reference.value[:, 0])
        allowance = reference.error[:, 0] + 4e-15 * reference.value[:, 0]
        assert np.all(error <= result.error[:, 0] + allowance), (rtol, n, np.degrees(theta))
        worst = max(worst, float(np.max(error / (result.error[:, 0] + allowance))))
        if rtol == 1e-5:  # the check can fail: at a loose tolerance the errors are visible
            assert np.max(error) > 1e3 * np.max(allowance)
    assert worst > 1e-4


@pytest.mark.slow
def test_estimates_bound_the_error_on_a_sweep_of_lobes_at_loose_and_middle_tolerances(rng):
    """The tolerances the randomized probe of test_tensor_rule.py leaves out (rtol 1e-4, 1e-7): Blinn-Phong n = 1…1e4
    against seed 002's series, Phong by a 1-D route (scipy quad), a GGX shader as shaders write it (Gauss–Legendre in
    the half-vector CDF), θ_o up to 89.9°."""
    worst = 0.0
    for rtol in (1e-4, 1e-7):
        theta = np.radians(np.concatenate([rng.uniform(0.0, 85.0, 24), rng.uniform(85.0, 89.9, 12)]))
        n = np.exp(rng.uniform(0.0, np.log(1e4), theta.size))
        model = bn.load("blinn-phong").with_params(n=n)
        reference = bn.albedo(model, theta, method="series", rtol=1e-13)
        worst = max(worst, _check(model, theta, rtol, reference.value[:, 0],
                                  reference.error[:, 0] + 4e-15 * reference.value[:, 0]))
        theta = np.radians(rng.uniform(0.0, 89.9, 4))
        n = np.exp(rng.uniform(0.0, np.log(1e4), theta.size))
        exact = np.array([phong_like_reference(a, b, original=True) for a, b in zip(n, theta, strict=True)])
        worst = max(worst, _check(bn.load("phong").with_params(n=n), theta, rtol, exact, 1e-13 * exact))
        mu = np.concatenate([rng.uniform(0.05, 1.0, 2), rng.uniform(0.0017, 0.05, 1)])
        alpha = np.exp(rng.uniform(np.log(0.02), 0.0, mu.size))
        exact = np.array([ggx_albedo_reference(a, m) for a, m in zip(alpha, mu, strict=True)])
        worst = max(worst, _check(bn.load(str(NAIVE_GGX)).with_params(alpha=alpha), np.arccos(mu), rtol, exact,
                                  1e-12 * exact))
    assert worst > 1e-3  # the check has substance: some errors are a visible share of their estimates


def _check(model, theta, rtol, reference, allowance) -> float:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(model, theta, method="quadrature", rtol=rtol)
    error = np.abs(result.value[:, 0] - reference)
    assert np.all(error <= result.error[:, 0] + allowance), (model.name, rtol, np.flatnonzero(
        error > result.error[:, 0] + allowance))
    return float(np.max(error / (result.error[:, 0] + allowance)))
