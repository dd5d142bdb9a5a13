"""engine/machinery/slope_coordinates: the half-vector routes' radial coordinates over each slope distribution
(moved out of models/microfacet.Distribution, issue 40 item 5), checked against the distributions' own du/ds."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

from brdfnorm.engine.machinery.slope_coordinates import (
    BeckmannCoordinates,
    GGXCoordinates,
    SlopeCoordinates,
    slope_coordinates,
)
from brdfnorm.models.microfacet import BeckmannDistribution, Distribution, GGXDistribution

COORDINATE_NAMES = ("pole", "tail", "pole_coordinate", "tail_coordinate", "cap", "truncated_moments", "CAP")


def test_the_distribution_holds_physics_only():
    for cls in (Distribution, GGXDistribution, BeckmannDistribution):
        assert not [name for name in COORDINATE_NAMES if hasattr(cls, name)], cls
    assert type(slope_coordinates(GGXDistribution())) is GGXCoordinates
    assert type(slope_coordinates(BeckmannDistribution())) is BeckmannCoordinates

    class Other(Distribution):
        name = "other"

    assert type(slope_coordinates(Other())) is SlopeCoordinates


@pytest.mark.parametrize("distribution", [GGXDistribution(), BeckmannDistribution()], ids=lambda d: d.name)
def test_each_piece_maps_t_to_s_with_du_dt_equal_to_the_slope_density_times_ds_dt(distribution):
    coords = slope_coordinates(distribution)
    s = np.array([1e-6, 0.01, 0.3, 0.9, 2.0, 7.5])
    for forward, inverse in ((coords.pole, coords.pole_coordinate), (coords.tail, coords.tail_coordinate)):
        t = inverse(s)
        radius, du_dt = forward(t)
        np.testing.assert_allclose(radius, s, rtol=1e-13)
        h = 1e-6 * np.maximum(t, 1e-3)
        ds_dt = (forward(t + h)[0] - forward(t - h)[0]) / (2 * h)  # central difference: an independent route
        np.testing.assert_allclose(du_dt, distribution.slope_density(s) * ds_dt, rtol=1e-7)


def test_beckmanns_truncated_moments_bound_the_dropped_mass_and_moment():
    distribution = BeckmannDistribution()
    coords = slope_coordinates(distribution)
    mass, moment = coords.truncated_moments()
    cap = coords.CAP
    exact_mass = integrate.quad(distribution.slope_density, cap, np.inf, epsabs=0, epsrel=1e-12)[0]
    exact_moment = integrate.quad(lambda s: s * distribution.slope_density(s), cap, np.inf, epsabs=0,
                                  epsrel=1e-12)[0]
    assert exact_mass == pytest.approx(mass, rel=1e-10)
    assert exact_moment <= moment < 1.2 * exact_moment
    assert coords.cap(np.array([1.0, 9.0])).tolist() == [1.0, cap]
    assert slope_coordinates(GGXDistribution()).truncated_moments() == (0.0, 0.0)
    assert slope_coordinates(GGXDistribution()).CAP is None
