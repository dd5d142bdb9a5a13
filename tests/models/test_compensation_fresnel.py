"""Energy compensation of ggx/beckmann with a Fresnel: ``ms=kulla-conty`` (Kulla & Conty 2017's F_avg, E_avg term)
and ``ms=turquin`` (Turquin 2019). Independent routes: F_avg against scipy quad of 2∫F μ dμ; the white furnace of
the compensated lobe by method "quadrature" (the hemisphere cubature of f·cos, which assumes nothing about the
result); the albedo methods' closed-form compensation against that quadrature for coloured F0 and conductors."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

import brdfnorm as bn
from brdfnorm.check import check
from brdfnorm.models.microfacet import fresnel, fresnel_average

THETA = np.radians([0.0, 45.0, 80.0])


@pytest.mark.parametrize("params", [
    {"fresnel": "schlick", "f0": (0.04, 0.5, 1.0)},
    {"fresnel": "schlick", "f0": (0.9, 0.6, 0.2), "f90": (0.95, 0.9, 0.5)},
    {"fresnel": "dielectric", "eta": (1.5, 1 / 1.5, 1.0001)},
    {"fresnel": "conductor", "eta": (0.2, 0.9, 1.1), "k": (3.9, 2.4, 2.2)},
])
def test_fresnel_average_against_scipy_quad(params):
    model = bn.load("ggx", **params)
    ours = fresnel_average(model.params)
    for channel in range(3):
        def weighted(mu, c=channel):
            return 2 * mu * fresnel(model.params, np.array(mu))[c]
        points = [np.sqrt(1 - params["eta"][channel] ** 2)] if params["fresnel"] == "dielectric" \
            and params["eta"][channel] < 1 else None
        reference, _ = integrate.quad(weighted, 0, 1, points=points, epsabs=0, epsrel=1e-13, limit=200)
        assert ours[channel] == pytest.approx(reference, rel=1e-12, abs=1e-15)
    if params["fresnel"] == "schlick" and "f90" not in params:
        np.testing.assert_allclose(ours, np.array(params["f0"]) + (1 - np.array(params["f0"])) / 21, rtol=1e-15)


@pytest.mark.parametrize(("name", "alpha"), [("ggx", 0.6), pytest.param("ggx", 0.15, marks=pytest.mark.slow),
                                             pytest.param("ggx", 1.0, marks=pytest.mark.slow),
                                             pytest.param("beckmann", 0.5, marks=pytest.mark.slow)])
def test_white_furnace_of_kulla_conty_by_quadrature_of_the_compensated_lobe(name, alpha):
    # Exact E and E_avg (ms_table=0); method "quadrature" integrates f_ss + f_ms over the hemisphere.
    model = bn.load(name, alpha=alpha, ms="kulla-conty", ms_table=0)
    result = bn.albedo(model, THETA, rtol=1e-9, method="quadrature")
    assert result.method == "quadrature"
    assert np.max(np.abs(result.value - 1.0)) <= 1e-9
    closed = bn.albedo(model, THETA, rtol=1e-10)  # the albedo method's closed form for ∫ f_ms cos
    assert np.all(np.abs(closed.value - 1.0) <= closed.error + 1e-12)


def test_turquin_white_furnace_by_quadrature():
    model = bn.load("ggx", alpha=0.7, ms="turquin", ms_table=0)
    result = bn.albedo(model, THETA, rtol=1e-9, method="quadrature")
    assert np.max(np.abs(result.value - 1.0)) <= 1e-9


@pytest.mark.parametrize("params", [
    {"ms": "kulla-conty", "fresnel": "schlick", "f0": (1.0, 0.5, 0.1)},
    pytest.param({"ms": "kulla-conty", "fresnel": "conductor", "eta": (0.2, 0.9, 1.1), "k": (3.9, 2.4, 2.2)},
                 marks=pytest.mark.slow),
    {"ms": "turquin", "fresnel": "schlick", "f0": 0.5},
])
def test_compensated_albedo_method_agrees_with_quadrature(params):
    model = bn.load("ggx", alpha=0.6, ms_table=0, **params)
    fast = bn.albedo(model, THETA, rtol=1e-10)
    assert fast.method == "microfacet"
    generic = bn.albedo(model, THETA, rtol=1e-8, method="quadrature")
    assert np.all(np.abs(fast.value - generic.value) <= fast.error + generic.error)
    assert np.max(np.abs(fast.value - generic.value)) <= 1e-8


def test_kulla_conty_colour_term_for_a_constant_fresnel():
    # F ≡ c (Schlick with f90 = f0 = c): single scattering is c·E(μ), and Kulla & Conty's term adds
    # (1 − E(μ)) c² E_avg/(1 − c(1 − E_avg)); E and E_avg from the white lobe's own albedo methods.
    c, alpha = np.array([0.3, 0.7, 0.95]), 0.8
    model = bn.load("ggx", alpha=alpha, ms="kulla-conty", ms_table=0, fresnel="schlick", f0=tuple(c), f90=tuple(c))
    white = bn.albedo(bn.load("ggx", alpha=alpha), THETA, rtol=1e-12).value[:, 0]
    from brdfnorm.engine.routes.microfacet import GGXDistribution, average_albedo

    e_avg = float(average_albedo(GGXDistribution(), "height-correlated", alpha, rtol=1e-12)[0][0])
    expected = c * white[:, None] + (1 - white[:, None]) * c * c * e_avg / (1 - c * (1 - e_avg))
    np.testing.assert_allclose(bn.albedo(model, THETA, rtol=1e-11).value, expected, rtol=1e-9)
    # Metals keep their saturation: the compensation scales each channel by F_ms/F_avg = F_avg E_avg/(1 − F_avg(1 −
    # E_avg)) < 1 — the darker channel gains relatively less.
    gain = bn.albedo(model, THETA, rtol=1e-11).value / (c * white[:, None])
    assert np.all(np.diff(gain, axis=1) > 0)


def test_check_reports_turquins_energy_and_asymmetry_at_f0_half():
    report = check(bn.load("ggx", ms="turquin", fresnel="schlick", f0=0.5), checks=("energy", "reciprocity"), budget=10)
    energy = report.results["energy"]
    assert energy.status == "pass" and 0.9 < energy.value < 1.0
    assert report.results["reciprocity"].status == "fail"  # Turquin's factor depends on the view only
    described = report.coverage["parameters"]
    assert any(d.startswith("ms_table") and "held" in d for d in described)  # a table size is not searched
    assert any(d.startswith("alpha ∈ [1e-12, 1]") for d in described)  # the tables' range


def test_turquin_over_the_view_goes_to_quadrature():
    # Turquin's factor depends on V: the lobe is not reciprocal, so the microfacet methods (which integrate at the
    # fixed direction as if it were) must not answer the albedo over the view.
    model = bn.load("ggx", alpha=0.5, ms="turquin", ms_table=0, fresnel="schlick", f0=0.5)
    over_view = bn.albedo(model, np.radians(60.0), over="view", rtol=1e-8)
    over_light = bn.albedo(model, np.radians(60.0), rtol=1e-8)
    assert over_view.method == "quadrature" and over_light.method == "microfacet"
    assert abs(over_view.value[0] - over_light.value[0]) > 1e-4
