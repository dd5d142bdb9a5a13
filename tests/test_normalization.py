"""Normalization conventions: normal, max (with argmax) and per view, and sweeps."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.references import phong_like_reference

import brdfnorm as bn
from brdfnorm.errors import ArgumentError, ParameterError
from brdfnorm.models import closed_forms
from brdfnorm.models.base import Model, normal_lobe


def test_normal_factor_sweep_matches_closed_form():
    values = np.geomspace(1, 1e4, 9)
    result = bn.normalize(bn.load("blinn-phong"), at="normal", sweep={"n": values}, rtol=1e-12)
    assert result.factor.shape == (9, 1, 1)
    np.testing.assert_allclose(result.factor[:, 0, 0], 1 / closed_forms.blinn_phong_albedo_normal(values),
                               rtol=1e-10)
    np.testing.assert_array_equal(result.values, values)


@pytest.mark.slow
@pytest.mark.parametrize("model", ["phong", "blinn-phong"])
def test_max_is_at_normal_incidence_for_the_seed_lobes(model):
    values = np.array([0.5, 5.0, 50.0, 500.0])
    result = bn.normalize(bn.load(model), at="max", sweep={"n": values}, rtol=1e-11)
    normal = bn.normalize(bn.load(model), at="normal", sweep={"n": values}, rtol=1e-11)
    np.testing.assert_allclose(result.albedo, normal.albedo, rtol=1e-10)
    np.testing.assert_array_equal(result.theta, 0.0)


class TiltedDiffuse(Model):
    """A test lobe whose albedo 1 + 0.5 sin θ cos(φ − 1) peaks off-normal and off-axis (anisotropic)."""

    name = "tilted"
    isotropic = False

    def evaluate(self, L, V, params):
        return ((1 + 0.5 * (V[..., 0] * np.cos(1.0) + V[..., 1] * np.sin(1.0))) / np.pi)[..., None]

    def lobe(self, fixed, params, over):
        return normal_lobe(fixed)


@pytest.mark.slow
def test_max_search_finds_an_off_normal_anisotropic_maximum():
    result = bn.normalize(TiltedDiffuse(), at="max", rtol=1e-12)
    assert abs(result.phi[0, 0] - 1.0) < 1e-4
    assert abs(result.theta[0, 0] - np.radians(89.9)) < 1e-9
    np.testing.assert_allclose(result.albedo[0, 0, 0], 1 + 0.5 * np.sin(np.radians(89.9)), rtol=1e-11)


def test_view_convention_gives_one_factor_per_direction():
    theta = np.radians([0.0, 45.0, 80.0])
    result = bn.normalize(bn.load("modified-phong", n=20.0), at="view", theta=theta, rtol=1e-11)
    assert result.factor.shape == (1, 3, 1)
    for j, t in enumerate(theta):
        reference = phong_like_reference(20.0, t, original=False)
        assert abs(result.factor[0, j, 0] * reference - 1) < 1e-9


def test_bad_arguments_are_refused():
    with pytest.raises(ArgumentError):
        bn.normalize(bn.load("blinn-phong"), at="middle")
    with pytest.raises(ArgumentError):
        bn.normalize(bn.load("blinn-phong"), at="view")
    with pytest.raises(ArgumentError):
        bn.normalize(bn.load("blinn-phong"), sweep={"n": []})
    with pytest.raises(ParameterError):
        bn.normalize(bn.load("blinn-phong"), sweep={"n": [-1.0, 2.0]})
    with pytest.raises(ParameterError):
        bn.normalize(bn.load("blinn-phong"), sweep={"m": [1.0]})
    with pytest.raises(ArgumentError):
        bn.albedo(bn.load("blinn-phong"), np.radians(90.0))
    with pytest.raises(ArgumentError):
        bn.albedo(bn.load("blinn-phong"), 0.0, rtol=0.0)
    with pytest.raises(ArgumentError):
        bn.albedo(bn.load("blinn-phong", n=3), 0.5, method="closed-form")
    with pytest.raises(ArgumentError):
        bn.albedo(bn.load("blinn-phong-gaussian"), 0.0, method="closed-form")
    with pytest.raises(ArgumentError):
        bn.albedo(bn.load("blinn-phong"), 0.0, method="simpson")
