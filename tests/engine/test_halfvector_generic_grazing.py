"""The generic engine's half-vector route at grazing views of narrow heavy-tailed lobes
(brdfnorm.engine.routes.halfvector_generic.MU_MIN_NARROW, μ ∈ [1e-4, 1e-3]): taken there, and its estimates cover its
errors against the one-dimensional integral of brdfnorm.engine.routes.azimuthal (no code in common)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.honesty import assert_generic_ggx_covers_azimuthal
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.engine.routes import halfvector_generic


@pytest.mark.parametrize("rtol", [1e-6, 1e-9, 1e-10])
def test_estimates_cover_the_one_dimensional_integral_at_grazing_views(kept, rtol):
    # examples/ggx.brdf, F = 1 (GGX with separable Smith shadowing), random roughness 0.05…0.6 (α ≤ 0.36: narrow
    # lobes) and views log-uniform in μ ∈ [1e-4, 1e-3] through the azimuth, μ = 1e-4 itself (the tables' clamp) first.
    rng = np.random.default_rng(int(-np.log10(rtol)) + 39)
    roughness = np.exp(rng.uniform(np.log(0.05), np.log(0.6), 16))
    mu = np.exp(rng.uniform(np.log(1e-4), np.log(1e-3), 16))
    mu[0] = 1e-4
    phi = rng.uniform(0.0, 2 * np.pi, 16)
    assert_generic_ggx_covers_azimuthal(roughness, np.arccos(mu), phi, rtol)
    assert kept[0].sum() >= 8  # the route is what this test exercises (above MU_MIN it declined every case)


def test_a_sheen_lobe_at_grazing_views(kept, monkeypatch):
    # examples/charlie.brdf: a broad lobe peaked near the horizon, taken below MU_MIN; against the lobe-aligned
    # routes alone at rtol 1e-12 (the half-vector route switched off: no code of it in the reference).
    model = bn.load(str(EXAMPLES / "charlie.brdf"))
    theta = np.arccos(np.geomspace(1e-4, 9e-4, 6))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(model, theta, rtol=1e-9, method="quadrature")
    assert kept[0].all()

    monkeypatch.setattr(halfvector_generic, "MU_MIN", 2.0)  # no view is eligible: the route is off
    monkeypatch.setattr(halfvector_generic, "MU_MIN_NARROW", 2.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reference = bn.albedo(model, theta, rtol=1e-12, method="quadrature")
    error = np.abs(result.value - reference.value)
    assert np.all(error <= result.error + reference.error), (error / result.error).max()
    assert np.all(result.evaluations < reference.evaluations)


def test_which_lobes_are_taken_below_mu_min():
    # At μ = 1e-4: a narrow lobe centred on the mirror direction of F is tried, a broad one peaked near N (a diffuse
    # lobe, cheap for the lobe-aligned panels) is not, a broad one peaked near the horizon is; nothing below
    # MU_MIN_NARROW; above MU_MIN a broad lobe is taken wherever its peak lies.
    grazing = [np.sqrt(1 - 1e-8), 0.0, 1e-4]
    fixed = np.array([grazing, grazing, grazing, [np.sqrt(1 - 2.5e-9), 0.0, 5e-5]])
    poles = np.array([[-grazing[0], 0.0, 1e-4], [0.0, 0.0, 1.0], [-0.9, 0.0, np.sqrt(0.19)], [-1.0, 0.0, 5e-5]])
    eligible, _, broad = halfvector_generic.specular(fixed, poles, np.array([0.1, 0.9, 0.9, 0.1]))
    assert eligible.tolist() == [True, False, True, False]
    assert broad.tolist() == [False, True, True, False]
    assert halfvector_generic.specular(np.array([[0.0, np.sqrt(1 - 4e-6), 2e-3]]), poles[1:2], np.array([0.9]))[0].all()


def test_a_lobe_whose_rounding_noise_is_near_the_tolerance(kept):
    # examples/ggx.brdf at roughness 0.05 (α = 0.0025): the shader's float64 noise bound is ~6e-11 of the albedo,
    # above rtol/16 at rtol 1e-10, so the global rule of the lobe-aligned coordinates is not tried; the half-vector
    # route is (noise below rtol/halfvector_generic.HOPEFUL: it adds the bound to its estimate before keeping a
    # case). Against the 1-D integral of brdfnorm.engine.routes.azimuthal.
    mu = np.array([0.03, 0.1, 0.2, 0.5, 0.9])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(bn.load(str(EXAMPLES / "ggx.brdf"), roughness=0.05, f0=1.0), np.arccos(mu), rtol=1e-10)
    reference = bn.albedo(bn.load("ggx", alpha=0.0025, shadowing="separable"), np.arccos(mu), rtol=1e-13)
    assert kept[0].sum() >= 3
    error = np.abs(result.value[:, 0] - reference.value.ravel())
    assert np.all(error <= result.error[:, 0] + reference.error.ravel()), (error / result.error[:, 0]).max()
    assert result.converged.all()
