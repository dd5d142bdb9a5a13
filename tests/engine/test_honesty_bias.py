"""The float64 bias of a lobe's cosine (brdfnorm.engine.machinery.rounding.cosine_bias): the fixed direction and the
lobe frame are vectors whose norms are off by up to half an ulp, the same for every node, so (R·V)^n is off by
n·(δ_V + δ_P) relative over the whole lobe, which no fourth difference of the rounding probe sees."""

from __future__ import annotations

import warnings
from fractions import Fraction

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.machinery.rounding import cosine_bias, norm_error
from brdfnorm.engine.routes.hemisphere import lobe_frame

BACKENDS = pytest.mark.parametrize("backend", ["numpy", "compiled"])
EPS = np.finfo(float).eps


@BACKENDS
def test_modified_phong_estimate_covers_the_bias_of_cos_n(backend):
    # n = 7 006 at 3.9…4.3°, rtol 1e-10: the errors (up to 1.0 ε/w² relative, w² = 2/(n + 1), ~7e-16 on 8.9e-4)
    # were up to 1.34× outside estimates built on the probe's noise (0.36–0.41 ε/w²); the lobe is 0 in float64
    # long before it meets the horizon, so the closed form of the whole cosine lobe is exact.
    n, theta = 7006.0, np.radians(np.linspace(3.9, 4.3, 41))
    model = bn.load("modified-phong").with_params(n=np.full(theta.size, n))
    exact = 2 * np.pi * np.cos(theta) / (n + 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(model, theta, method="quadrature", backend=backend, rtol=1e-10)
    error = np.abs(result.value[:, 0] - exact)
    assert result.converged.all()
    assert np.all(error <= result.error[:, 0]), (error / result.error[:, 0]).max()
    # The bias is there to be covered: several views are off by more than 0.5 ε/w².
    assert np.sum(error / exact > 0.5 * EPS * (n + 1) / 2) >= 5


def test_norm_error_is_exact():
    rng = np.random.default_rng(7)
    v = rng.normal(size=(200, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    v[0] = [0.0, 0.0, 1.0]
    exact = np.array([float((sum(Fraction(float(c)) ** 2 for c in row) - 1) / 2) for row in v])
    np.testing.assert_allclose(norm_error(v), exact, rtol=1e-6, atol=1e-40)
    assert norm_error(v[0]) == 0.0
    assert np.abs(exact).max() > EPS / 8  # rounded unit vectors do miss 1 by fractions of an ulp


def _one_case(n: float, fixed: np.ndarray):
    frame = lobe_frame(np.array([[-fixed[0], -fixed[1], fixed[2]]]))
    width = np.array([np.sqrt(2 / (n + 1))])
    return frame, width, np.array([np.pi / 2])


def _phong(F):
    def integrand(omega, case):
        mirrored = omega * np.array([-1.0, -1.0, 1.0])
        return np.maximum(np.einsum("mi,mi->m", mirrored, F[case]), 0.0)[:, None] ** 1e4
    return integrand


def _half_vector(F):
    def integrand(omega, case):
        h = omega + F[case]
        return (h[:, 2] / np.linalg.norm(h, axis=1))[:, None] ** 1e4
    return integrand


@pytest.mark.parametrize("lobe", [_phong, _half_vector])
def test_the_bias_is_the_lobe_exponent_in_the_norms_times_their_errors(lobe):
    # (R·V)^n is off by n(δ_V + δ_P); (N·H)^n, H normalized, by nothing of the norms whatever its ω-width.
    theta = np.radians(30.0)
    F = np.array([[np.sin(theta), 0.0, np.cos(theta)]])
    frame, width, support = _one_case(1e4, F[0])
    predicted = 1e4 * abs(norm_error(frame[0])[0] + norm_error(F)[0])
    assert predicted > 0.1 * 1e4 * EPS / 2  # this view's vectors are rounded
    bias, probed = cosine_bias(lambda factor: lobe(F * factor[:, None]), frame, F, width, support,
                               np.array([[1e-20]]), np.array([[1.0]]))
    assert probed.tolist() == [True]
    if lobe is _phong:
        assert bias[0, 0] == pytest.approx(predicted, rel=1e-2, abs=1e-3 * 1e4 * EPS)
    else:
        assert bias[0, 0] < 1e-3 * predicted


def test_exact_inputs_are_not_probed():
    # At normal incidence V = (0, 0, 1) and the frame are exact: nothing to charge, nothing evaluated.
    F = np.array([[0.0, 0.0, 1.0]])
    frame, width, support = _one_case(1e4, F[0])
    bias, probed = cosine_bias(lambda factor: _phong(F * factor[:, None]), frame, F, width, support,
                               np.array([[1e-20]]), np.array([[1.0]]))
    assert probed.tolist() == [False]
    assert bias.tolist() == [[0.0]]
