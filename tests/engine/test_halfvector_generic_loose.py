"""The generic engine's half-vector route below μ = 1e-4 at loose tolerances
(brdfnorm.engine.routes.halfvector_generic.MU_MIN_LOOSE, LOOSE: E_avg's grazing nodes): taken there, and its estimates
cover its errors against the one-dimensional integral of brdfnorm.engine.routes.azimuthal (no code in common)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.honesty import assert_generic_ggx_covers_azimuthal

from brdfnorm.engine.routes import halfvector_generic


@pytest.mark.parametrize("rtol", [2.5e-6, 1e-4])
def test_estimates_cover_the_one_dimensional_integral_below_mu_min_narrow(kept, rtol):
    # examples/ggx.brdf, F = 1 (GGX with separable Smith shadowing), random roughness 0.05…0.6 and views
    # log-uniform in μ ∈ [1e-6, 1e-4] through the azimuth; E_avg's three grazing nodes first.
    rng = np.random.default_rng(int(-np.log10(rtol)) + 61)
    roughness = np.exp(rng.uniform(np.log(0.05), np.log(0.6), 12))
    mu = np.exp(rng.uniform(np.log(1e-6), np.log(1e-4), 12))
    mu[:3] = (1 - np.cos(np.pi / np.array([16, 32, 64]))) ** 2 / 4 * np.array([1, 1, 81])  # x_1 of 16, 32; ≈ x_3 of 64
    phi = rng.uniform(0.0, 2 * np.pi, 12)
    assert_generic_ggx_covers_azimuthal(roughness, np.arccos(mu), phi, rtol)
    assert kept[0].sum() >= 6  # the route is what this test exercises


def test_only_loose_tolerances_go_below_mu_min_narrow():
    # A narrow lobe at μ = 1e-5: taken where loose, not otherwise; a broad one never below MU_MIN_NARROW.
    fixed = np.array([[np.sqrt(1 - 1e-10), 0.0, 1e-5]] * 2)
    poles = np.array([[-fixed[0, 0], 0.0, 1e-5], [-0.9, 0.0, np.sqrt(0.19)]])
    widths = np.array([0.1, 0.9])
    assert halfvector_generic.specular(fixed, poles, widths, loose=True)[0].tolist() == [True, False]
    assert halfvector_generic.specular(fixed, poles, widths)[0].tolist() == [False, False]
