"""The generic engine's half-vector route (brdfnorm.engine.routes.halfvector_generic): where it is taken, that its
estimates
cover its errors against routes that share none of its code, and where it must not be taken."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.paths import EXAMPLES
from helpers.references import half_vector_gauss_legendre

import brdfnorm as bn
from brdfnorm.engine.routes import halfvector_generic
from brdfnorm.engine.routes.quadrature import rotation_invariant


@pytest.mark.parametrize("roughness", [0.05, 0.3, 1.0])
def test_ggx_brdf_agrees_with_the_one_dimensional_integral(kept, roughness):
    # examples/ggx.brdf with f0 = 1 is GGX with separable Smith shadowing and F = 1, whose albedo brdfnorm also
    # computes as a 1-D integral over the light's elevation (brdfnorm.engine.routes.azimuthal: no code in common). The
    # narrow
    # lobes take the route as heavy-tailed lobes at the mirror direction, roughness 1 (α = 1) as a broad one.
    model = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=roughness, f0=1.0)
    reference_model = bn.load("ggx", alpha=roughness**2, shadowing="separable")
    theta = np.radians([0.0, 20.0, 45.0, 70.0, 85.0, 89.0])
    result = bn.albedo(model, theta, rtol=1e-9)
    reference = bn.albedo(reference_model, theta, rtol=1e-12)
    assert reference.method == "azimuthal"
    assert kept[0].all()
    error = np.abs(result.value[:, 0] - reference.value[:, 0])
    assert np.all(error <= result.error[:, 0] + reference.error[:, 0]), error / result.error[:, 0]
    assert np.all(result.error[:, 0] <= 1e-9 * result.value[:, 0])


@pytest.mark.parametrize("rtol", [1e-5, 1e-7, 1e-9, 1e-11])
def test_estimates_cover_the_one_dimensional_integral_on_random_views(kept, rtol):
    # Random roughness (α = 2.5e-3 … 0.25) and views (μ ≥ 1e-3, through the azimuth too) of examples/ggx.brdf,
    # F = 1, against brdfnorm.engine.routes.azimuthal.
    rng = np.random.default_rng(int(-np.log10(rtol)))
    roughness = np.exp(rng.uniform(np.log(0.05), np.log(0.5), 30))
    theta = np.arccos(np.exp(rng.uniform(np.log(1e-3), 0.0, 30)))
    phi = rng.uniform(0.0, 2 * np.pi, 30)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(bn.load(str(EXAMPLES / "ggx.brdf"), roughness=roughness, f0=1.0), theta, phi=phi,
                           rtol=rtol)
    reference = bn.albedo(bn.load("ggx", alpha=roughness**2, shadowing="separable"), theta, rtol=1e-12)
    assert kept[0].sum() >= 10  # the route is what this test exercises (at 1e-11 the shader's noise sends cases on)
    error = np.abs(result.value[:, 0] - reference.value.ravel())
    assert np.all(error <= result.error[:, 0] + reference.error.ravel()), (error / result.error[:, 0]).max()


def test_gaussian_lobes_are_left_to_the_lobe_aligned_routes(kept):
    # Blinn-Phong costs both routes about the same evaluations (n = 512, 90 views, rtol 1e-9: 8 700 against
    # 8 784), each three times cheaper in the lobe-aligned coordinates; its tail is e^(−57) at s = 8 in H.
    bn.albedo(bn.load("blinn-phong", n=512.0), np.radians([0.0, 45.0, 85.0]), rtol=1e-9, method="quadrature")
    assert not kept[0].any()


def test_anisotropic_lobe_is_left_to_the_lobe_aligned_routes(kept):
    # Ashikhmin-Shirley with n_u = 1.6, n_v = 5112 is an ellipse in H thinner than the route's azimuths where it is
    # long: taken, it was 1.37 times its estimate off at rtol 1e-9 (the honesty sweep of examples/*.brdf).
    params = dict(nu=1.6146753089889108, nv=5112.32214346958, Rs=0.22769689173059135, Rd=0.7440986880783406)
    model = bn.load(str(EXAMPLES / "ashikhmin_shirley.brdf"), **params)
    theta, phi = np.arccos(0.6514), 1.0
    result = bn.albedo(model, theta, phi=phi, rtol=1e-9)
    assert not kept[0].any()

    def brdf(L, V, case):
        return model.evaluate(L, V, model.params)

    assert not rotation_invariant(brdf, np.arange(1), 1e-9).any()
    isotropic = bn.load(str(EXAMPLES / "ashikhmin_shirley.brdf"), **{**params, "nv": params["nu"]})
    assert rotation_invariant(
        lambda L, V, case: isotropic.evaluate(L, V, isotropic.params), np.arange(1), 1e-9).all()
    assert result.converged.all()


def test_mirror_symmetry_is_measured_not_assumed():
    fixed = np.array([[np.sin(1.0), 0.0, np.cos(1.0)]])
    alpha = np.array([0.2])

    def symmetric(omega, case):
        return (omega[:, 2] * (1.0 + omega[:, 0]))[:, None]

    def lopsided(omega, case):
        return (omega[:, 2] * (1.0 + 0.01 * omega[:, 1]))[:, None]

    assert halfvector_generic.mirror_symmetric(symmetric, fixed, alpha, np.arange(1), 1e-9).all()
    assert not halfvector_generic.mirror_symmetric(lopsided, fixed, alpha, np.arange(1), 1e-9).any()
    # A lopsided lobe integrated over the full azimuth range: the exact integral of cos·(1 + 0.01 ω_y) is π.
    result = halfvector_generic.route(
        fixed, np.ones(1, dtype=bool), lopsided, fixed * [-1, -1, 1], np.array([0.2]), np.arange(1),
        np.zeros((1, 1)), rtol=1e-10, atol=0.0, max_evaluations=10**6)
    assert result.converged.all()
    assert abs(result.value[0, 0] - np.pi) <= result.error[0, 0] <= 1e-10 * np.pi


def test_where_it_is_not_tried():
    poles = np.array([[0.0, 0.0, 1.0], [-0.5, 0.0, np.sqrt(0.75)], [-0.6, 0.0, 0.8]])
    fixed = np.array([[0.0, 0.0, 1.0], [-0.5, 0.0, np.sqrt(0.75)], [np.sqrt(1 - 2.5e-9), 0.0, 5e-5]])
    eligible, _, _ = halfvector_generic.specular(fixed, poles, np.array([0.1, 0.1, 0.1]))
    # centred on the mirror direction; a retro-reflective peak (H far from N); too close to the horizon
    assert eligible.tolist() == [True, False, False]
    # a broad lobe is taken wherever its peak lies
    assert halfvector_generic.specular(fixed[1:2], poles[1:2], np.array([0.8]))[0].all()

    def lobe(power_law):
        def integrand(omega, case):  # a lobe about the mirror of F = N, of width 0.1 in the half vector
            c = np.clip(omega[:, 2], 0.0, 1.0)  # cos 2θ_H
            t2 = (1.0 - c) / (1.0 + c) / 0.01  # tan²θ_H / α²
            return (1.0 / (1.0 + t2) ** 2 if power_law else np.exp(-t2))[:, None] * c[:, None]
        return integrand

    one = np.arange(1)
    assert halfvector_generic.heavy_tailed(lobe(True), fixed[:1], np.array([0.1]), one).all()
    assert not halfvector_generic.heavy_tailed(lobe(False), fixed[:1], np.array([0.1]), one).any()


def test_nonfinite_values_are_not_kept():
    fixed = np.array([[0.0, 0.0, 1.0]])

    def broken(omega, case):
        return np.where(omega[:, 2:3] > 0.5, np.nan, 1.0)

    result = halfvector_generic.route(
        fixed, np.ones(1, dtype=bool), broken, fixed, np.array([1.0]), np.arange(1), np.zeros((1, 1)),
        rtol=1e-8, atol=0.0, max_evaluations=10**6)
    assert not result.converged.any() and result.evaluations[0] > 0


def test_isotropy_is_tested_at_each_cases_parameters(kept):
    # One sweep, two parameter sets: α_x = α_y (isotropic, taken) and α_x ≠ α_y (left to the other routes).
    model = bn.load(str(EXAMPLES / "anisotropic_ggx.brdf"), alpha_x=np.array([0.1, 0.1]), alpha_y=np.array([0.1, 0.4]))
    bn.albedo(model, np.array([0.5, 0.5]), rtol=1e-8)
    assert kept[0].tolist() == [True, False]


def test_a_spike_over_a_broad_base_at_a_grazing_view(kept):
    # examples/layered_series.brdf: a clear coat's (N·H)^200 spike, 0.02 of it, over a broad base. At θ_o = 88.3°
    # the lobe-aligned route, locked on the base, returns 0.07210339 at every rtol down to 1e-12 (scipy's dblquad:
    # 0.07218625); this route, where the spike sits at the pole, takes the broad lobe.
    params = dict(rho=0.07442320106603, f0=0.00175376368894451, eta=1.8327178493802307, coat=0.020029664416776803)
    model = bn.load(str(EXAMPLES / "layered_series.brdf"), **params)
    theta, phi = 1.541435886344325, 3.5700576008157974
    V = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
    coarse, reference = (half_vector_gauss_legendre(model, V, n, 16) for n in (24, 32))
    assert abs(coarse - reference) < 1e-10
    for rtol in (1e-5, 1e-9):
        result = bn.albedo(model, theta, phi=phi, rtol=rtol)
        assert abs(result.value.ravel()[0] - reference) <= result.error.ravel()[0]
    assert all(k.all() for k in kept)
