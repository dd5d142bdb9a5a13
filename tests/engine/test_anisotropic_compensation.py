"""Compensation of anisotropic lobes with their own E(μ, φ) and E_avg (issue #45, item 2): the white furnace by
quadrature of the compensated lobe (the generic hemisphere engine, which knows nothing of the closed form), the
albedo method's closed form against it, and the geometric-mean lookup's furnace for contrast."""

from __future__ import annotations

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.routes import anisotropic as kernel
from brdfnorm.errors import ParameterError

LOBE = {"alpha_x": 1.0, "alpha_y": 0.1}
VIEWS = (np.radians([0.0, 40.0, 70.0]), np.radians([0.0, 30.0, 90.0]))


def interpolation_error(model, theta, phi):
    """|E as the compensation's table reads it − E exact| at the views, with the exact value's estimate."""
    table = model.anisotropic_table(model.params)
    exact, error, _, _ = kernel.albedo(model.distribution.name, "height-correlated", np.cos(theta), 1.0, 0.1, phi,
                                       rtol=1e-10)
    return np.abs(table.albedo(np.cos(theta), phi) - exact) + error


@pytest.mark.parametrize("ms", [pytest.param("kulla-conty", marks=pytest.mark.slow), "turquin"])
def test_white_furnace_by_quadrature_of_the_compensated_lobe(ms):
    model = bn.load("ggx", ms=ms, ms_table=16, **LOBE)
    theta, phi = VIEWS
    result = bn.albedo(model, theta, phi, rtol=1e-7, method="quadrature")
    assert result.method == "quadrature" and result.converged.all()
    furnace = result.value[:, 0]
    # Kulla & Conty: E(V) + (1 − E_table(V)); Turquin: E(V)/E_table(V) — 1 up to the table's interpolation error.
    read = model.anisotropic_table(model.params).albedo(np.cos(theta), phi)
    bound = interpolation_error(model, theta, phi) / (1.0 if ms == "kulla-conty" else read) + result.error[:, 0]
    assert np.all(np.abs(furnace - 1.0) <= bound + 1e-6), (furnace, bound)
    assert np.max(np.abs(furnace - 1.0)) < 0.01
    fast = bn.albedo(model, theta, phi, rtol=1e-9)  # the albedo method's closed form for the compensation
    assert fast.method == "microfacet"
    assert np.all(np.abs(fast.value - result.value) <= fast.error + result.error)


@pytest.mark.slow
def test_exact_tables_give_one():
    model = bn.load("beckmann", ms="kulla-conty", ms_table=0, alpha_x=0.6, alpha_y=0.2)
    result = bn.albedo(model, np.radians([10.0, 60.0]), np.radians([20.0, 75.0]), rtol=1e-9)
    assert np.all(np.abs(result.value - 1.0) <= result.error + 1e-9)


def test_geometric_mean_compensation_falls_short_where_this_one_does_not():
    # The isotropic compensation at √(α_x α_y) = 0.316 (what engines do) against this lobe's own: normal view.
    iso = bn.load("ggx", ms="kulla-conty", ms_table=0, alpha=np.sqrt(0.1))
    iso_table = iso._table(iso.params)
    single = bn.albedo(bn.load("ggx", **LOBE), 0.0, rtol=1e-10).value.ravel()[0]
    engines = single + 1.0 - float(iso_table.albedo(np.array(1.0), np.array(np.sqrt(0.1))))  # E + (1 − E_iso)
    assert abs(engines - 0.6657) < 1e-3
    own = bn.albedo(bn.load("ggx", ms="kulla-conty", ms_table=16, **LOBE), 0.0, rtol=1e-9).value.ravel()[0]
    assert abs(own - 1.0) < 1e-3


@pytest.mark.slow
def test_colour_term_with_fresnel_agrees_with_quadrature():
    model = bn.load("ggx", ms="kulla-conty", ms_table=12, fresnel="schlick", f0=(1.0, 0.5, 0.1), alpha_x=0.5,
                    alpha_y=0.15)
    fast = bn.albedo(model, np.radians(35.0), np.radians(50.0), rtol=1e-9)
    generic = bn.albedo(model, np.radians(35.0), np.radians(50.0), rtol=1e-7, method="quadrature")
    assert np.all(np.abs(fast.value - generic.value) <= fast.error + generic.error)


def test_refusals():
    with pytest.raises(ParameterError, match="aspect"):
        bn.load("ggx", ms="kulla-conty", alpha_x=1.0, alpha_y=1e-3)
    with pytest.raises(ParameterError, match="one lobe"):
        bn.load("ggx", ms="kulla-conty", alpha_x=[1.0, 0.5], alpha_y=0.2)
