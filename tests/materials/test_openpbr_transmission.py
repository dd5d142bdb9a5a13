"""OpenPBR's translucent base (specification *Base Substrate* → *Translucent base*, and the mixture model's
f_dielectric-base = lerp(f^R + (1 − E_R) f_diffuse, f^R + f^T, T)) through brdfnorm's rough dielectric lobe.

Independent routes: the ``ggx-dielectric`` lobe's own albedo (the dielectric route, reflected and transmitted
apart), the generic adaptive cubature of the composed material over both hemispheres, and the furnace identity
R + T = 1 of a smooth, white, non-absorbing interface.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.errors import ParameterError

THETA = np.radians([0.0, 40.0, 70.0, 85.0])


def _dielectric(r: float, eta: float = 1.5):
    return bn.albedo(bn.load("ggx-dielectric", alpha=max(r * r, 1e-12), eta=eta), THETA, rtol=1e-12)


@pytest.mark.parametrize("r", [0.0, 0.2, 0.6])
def test_full_transmission_is_the_dielectric_lobe(r):
    """transmission_weight 1: R, T and R + T are the ggx-dielectric's (R through the material's own GGX lobe with
    the exact Fresnel, by the half-vector route — a different route from the dielectric one)."""
    material = bn.albedo(bn.load("openpbr", transmission_weight=1.0, specular_roughness=r), THETA)
    lobe = _dielectric(r)
    assert material.method == "material"
    assert np.abs(material.reflected - lobe.reflected).max() <= 1e-12
    assert np.abs(material.transmitted - lobe.transmitted).max() <= 1e-12
    assert np.abs(material.value - lobe.value).max() <= 1e-12
    assert np.all(np.abs(material.value - lobe.value) <= material.error + lobe.error)


def test_white_furnace_smooth_and_rough():
    """A white, non-absorbing interface: R + T = 1 when smooth; when rough, 1 less the lobe's single-scattering
    loss, which is the ggx-dielectric's own (reported, not hidden)."""
    smooth = bn.albedo(bn.load("openpbr", transmission_weight=1.0, specular_roughness=0.0), THETA)
    assert np.abs(smooth.value - 1.0).max() <= 1e-12
    rough = bn.albedo(bn.load("openpbr", transmission_weight=1.0, specular_roughness=0.6), THETA)
    loss = 1.0 - rough.value[:, 0]
    assert np.all(loss > 1e-3)  # single scattering loses energy at roughness 0.6
    assert np.abs(loss - (1.0 - _dielectric(0.6).value[:, 0])).max() <= 1e-12


@pytest.mark.slow
def test_by_the_generic_cubature_of_both_hemispheres():
    """The composed BSDF integrated as a whole by the generic cubature (upper and lower hemispheres apart): measured
    4.2e-10 (transmitted) and 5.6e-17 (reflected) from the material route, within the cubature's estimate."""
    model = bn.load("openpbr", transmission_weight=0.7, specular_roughness=0.5, base_color=(0.9, 0.5, 0.1))
    theta = np.radians([20.0, 60.0])
    material = bn.albedo(model, theta)
    with warnings.catch_warnings():  # the cubature's estimate (~1e-7) stays above rtol near the refraction's edge
        warnings.simplefilter("ignore", UserWarning)
        whole = bn.albedo(model, theta, method="quadrature", rtol=1e-7, backend="numpy")
    assert np.all(np.abs(whole.value - material.value) <= whole.error + material.error)
    assert np.abs(whole.transmitted - material.transmitted).max() <= 1e-8
    assert np.abs(whole.reflected - material.reflected).max() <= 1e-8


def test_partial_transmission_and_tint():
    """T = 0.5 over a diffuse ρ: E = E_R + (1 − T)(1 − E_R)ρ + T·T_d·c, with transmission_color c tinting the
    refraction at transmission_depth 0 only (a deeper medium absorbs inside, beyond the surface's albedo)."""
    rho, c, w, r = np.array([0.9, 0.5, 0.1]), np.array([1.0, 0.6, 0.2]), 0.5, 0.3
    lobe = _dielectric(r)
    R, T = lobe.reflected, lobe.transmitted
    tinted = bn.albedo(bn.load("openpbr", transmission_weight=w, specular_roughness=r, base_color=rho,
                               transmission_color=c), THETA)
    assert np.abs(tinted.value - (R + (1 - w) * (1 - R) * rho + w * T * c)).max() <= 1e-12
    assert np.abs(tinted.transmitted - w * T * c).max() <= 1e-12
    deep = bn.albedo(bn.load("openpbr", transmission_weight=w, specular_roughness=r, base_color=rho,
                             transmission_color=c, transmission_depth=0.1), THETA)
    assert np.abs(deep.transmitted - w * T).max() <= 1e-12


@pytest.mark.parametrize("layering", ["view", pytest.param("symmetric", marks=pytest.mark.slow),
                                      pytest.param("reciprocal", marks=pytest.mark.slow)])
def test_coat_over_transmission_crosses_once(layering):
    """Under a coat (C = 1, colour T_c) the transmitted light crosses the coat once, on the view's side, whatever
    the rule: T_coated(μ) = T_c (1 − E_coat(μ)) T_d(μ), E_coat the coat's reflection (ggx-dielectric's reflected
    share at the coat's IOR and roughness)."""
    tc = np.array([0.9, 0.8, 0.7])
    model = bn.load("openpbr", transmission_weight=1.0, specular_roughness=0.4, coat_weight=1.0,
                    coat_roughness=0.3, coat_ior=1.6, coat_color=tc, layering=layering)
    coated = bn.albedo(model, THETA)
    e_coat = _dielectric(0.3, 1.6).reflected
    # the coat's adjustments: the base's IOR ratio is lerp(1.5, 1.6/1.5, 1) and its roughness (0.4⁴ + 2·0.3⁴)^¼
    under = _dielectric((0.4**4 + 2 * 0.3**4) ** 0.25, 1.6 / 1.5).transmitted
    assert np.abs(coated.transmitted - tc * (1 - e_coat) * under).max() <= 1e-11


def test_refusals():
    with pytest.raises(ParameterError, match="thin-walled"):
        bn.load("openpbr", transmission_weight=0.5, geometry_thin_walled=True)
    with pytest.raises(ParameterError, match="base_mix"):
        bn.load("openpbr", transmission_weight=0.5, base_mix="f0-blend")
    with pytest.raises(ParameterError, match="index-matched"):
        bn.load("openpbr", transmission_weight=0.5, specular_weight=0.0)
    assert not bn.load("openpbr").transmits and bn.load("openpbr", transmission_weight=0.1).transmits
    bn.load("openpbr", geometry_thin_walled=True)  # without transmission the reflection is the same


def test_lut_writes_the_reflected_and_transmitted_tables():
    from brdfnorm import lut

    model = bn.load("openpbr", transmission_weight=1.0)
    mu = np.array([0.2, 1.0])
    tables = lut.compute(model, {"mu": mu, "specular_roughness": np.array([0.2, 0.6])}, rtol=1e-10, average=False)
    for j, r in enumerate((0.2, 0.6)):
        lobe = bn.albedo(bn.load("ggx-dielectric", alpha=r * r, eta=1.5), np.arccos(mu), rtol=1e-12)
        assert np.abs(np.asarray(tables["E_T"])[:, j] - lobe.transmitted[:, 0]).max() <= 1e-12
        assert np.abs(np.asarray(tables["E_R"])[:, j] - lobe.reflected[:, 0]).max() <= 1e-12


def test_reference_carries_reflected_and_transmitted():
    from brdfnorm.materials.reference import reference

    doc = reference(bn.load("openpbr", transmission_weight=1.0, specular_roughness=0.0), {"specular_ior": [1.5]},
                    np.array([0.5, 1.0]))
    point = doc["points"][0]
    assert np.abs(np.asarray(point["E_R"]) + np.asarray(point["E_T"]) - np.asarray(point["E"])).max() <= 1e-15
    assert abs(point["max_residual"]) <= 1e-12  # the smooth white interface: R + T = 1


def test_white_furnace_of_a_coated_translucent_base():
    """The specification's *White furnace testing* list: a translucent base (white transmission_color) under a
    white coat. Smooth interfaces: E = 1 (the darkening's E_b counts the transmitted share, so Δ = 1)."""
    model = bn.load("openpbr", transmission_weight=1.0, specular_roughness=0.0, coat_weight=1.0, coat_roughness=0.0)
    result = bn.albedo(model, THETA)
    assert np.abs(result.value - 1.0).max() <= 1e-12
    assert result.transmitted[0, 0] > 0.9  # most of it goes through, head-on
