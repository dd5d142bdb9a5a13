"""OpenPBR's coat adjustments (specification *Coat*): the IOR ratio under the coat, the roughening of the base and
the darkening, each against an independent route — the same material with the adjusted value given by hand
(``coat_adjustments = "none"``), and for the darkening the interfaced Lambertian's exact albedo (Elias 2001,
d'Eon 2021) with its internal reflectance integrated here by scipy from a Fresnel written here.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy import integrate

import brdfnorm as bn
from brdfnorm.materials import openpbr

THETA = np.radians([0.0, 40.0, 70.0, 85.0])


def _fresnel(mu: float, eta: float) -> float:
    """Unpolarized dielectric Fresnel, light from the side of index 1 into index eta (eta < 1: from inside)."""
    sin2 = (1.0 - mu * mu) / (eta * eta)
    if sin2 >= 1.0:
        return 1.0
    ct = np.sqrt(1.0 - sin2)
    rs = (mu - eta * ct) / (mu + eta * ct)
    rp = (eta * mu - ct) / (eta * mu + ct)
    return 0.5 * (rs * rs + rp * rp)


def _albedo(**params) -> np.ndarray:
    return bn.albedo(bn.load("openpbr", **params), THETA, rtol=1e-12).value


def test_roughening_is_the_specification_formula():
    r_b, r_c, c = 0.3, 0.45, 0.6
    adjusted = r_b + c * (min(1.0, r_b**4 + 2 * r_c**4) ** 0.25 - r_b)
    common = dict(base_metalness=1.0, base_color=(0.9, 0.6, 0.3), coat_weight=c, coat_roughness=r_c,
                  coat_darkening=0.0)
    spec = _albedo(**common, specular_roughness=r_b)
    by_hand = _albedo(**common, specular_roughness=adjusted, coat_adjustments="none")
    unadjusted = _albedo(**common, specular_roughness=r_b, coat_adjustments="none")
    assert np.abs(spec - by_hand).max() <= 1e-13
    assert np.abs(spec - unadjusted).max() > 1e-3
    assert openpbr.coat_roughened(dict(specular_roughness=0.9, coat_roughness=1.0, coat_weight=1.0,
                                       coat_adjustments="spec")) == 1.0  # min(1, ·) caps it


@pytest.mark.parametrize("coat_ior, adjustments, ratio", [
    (1.4, "spec", 1.5 / 1.4), (1.6, "spec", 1.6 / 1.5), (1.6, "spec-no-tir-fix", 1.5 / 1.6)])
def test_specular_ior_ratio_under_the_coat(coat_ior, adjustments, ratio):
    c = 0.7
    eta_s = 1.5 + c * (ratio - 1.5)  # eq. [specular_ior_ratio], n_a = 1
    common = dict(base_color=(0.2, 0.4, 0.6), specular_roughness=0.35, coat_weight=c, coat_roughness=0.0,
                  coat_ior=coat_ior, coat_darkening=0.0)
    spec = _albedo(**common, specular_ior=1.5, coat_adjustments=adjustments)
    by_hand = _albedo(**common, specular_ior=eta_s, coat_adjustments="none")
    assert np.abs(spec - by_hand).max() <= 1e-13


@pytest.mark.parametrize("rho, eta, delta", [(0.8, 1.5, 1.0), (0.3, 1.6, 1.0), (0.8, 1.5, 0.4)])
def test_darkening_is_the_interfaced_lambertian(rho, eta, delta):
    """A Lambert base under a smooth clear coat (no base specular: r_b = 1, K = K_r): the view rule with the
    darkening gives E = F + ρ(1 − F) lerp(1, Δ, δ), Δ = (1 − K_r)/(1 − ρ K_r), and at δ = 1 that is the exact albedo
    of the interfaced Lambertian, K_r its internal diffuse reflectance 2∫F_inside(μ)μ dμ."""
    critical = np.sqrt(1 - 1 / eta**2)  # total internal reflection below it: F = 1
    k_r = critical**2 + 2 * integrate.quad(lambda m: _fresnel(m, 1.0 / eta) * m, critical, 1.0, epsabs=1e-15,
                                           epsrel=1e-14)[0]
    dark = (1 - k_r) / (1 - rho * k_r)
    mu = np.cos(THETA)
    F = np.array([_fresnel(m, eta) for m in mu])
    expected = F + rho * (1 - F) * (1 + delta * (dark - 1))
    E = _albedo(base_color=(rho,) * 3, specular_weight=0.0, coat_weight=1.0, coat_roughness=0.0, coat_ior=eta,
                coat_darkening=delta)
    assert np.abs(E[:, 0] - expected).max() <= 1e-12  # measured 3.3e-16
    # the specification's K_r = 1 − (1 − E_F(η))/η² is the same internal reflectance
    e_f = 2 * integrate.quad(lambda m: _fresnel(m, eta) * m, 0.0, 1.0, epsabs=1e-15, epsrel=1e-14)[0]
    assert abs(1 - (1 - e_f) / eta**2 - k_r) <= 1e-12


def test_no_darkening_keeps_the_undarkened_albedo():
    """δ = 0: the coated base's albedo at normal incidence is lerp(F0, 1, E_b) (eq. [undarkened_coat_albedo])."""
    rho, eta = 0.5, 1.5
    E = _albedo(base_color=(rho,) * 3, specular_weight=0.0, coat_weight=1.0, coat_roughness=0.0, coat_ior=eta,
                coat_darkening=0.0)
    f0 = ((eta - 1) / (eta + 1)) ** 2
    assert abs(E[0, 0] - (f0 + rho * (1 - f0))) <= 1e-9


def test_darkening_uses_the_base_albedo_at_normal_incidence():
    """E_b of a metal base is its own albedo at normal incidence (here by the generic quadrature of the uncoated
    metal); a white base is not darkened (Δ = 1)."""
    p = {par.name: par.default for par in openpbr.PARAMETERS}
    p.update(base_metalness=1.0, base_color=(0.9, 0.6, 0.3), coat_weight=1.0, coat_roughness=0.0)
    terms = openpbr.build(p)
    factor = next(t for term in terms for t in term.view if t.label == "coat-darkening")
    uncoated = bn.albedo(bn.load("openpbr", base_metalness=1.0, base_color=(0.9, 0.6, 0.3)), 0.0,
                         method="quadrature", rtol=1e-11, backend="numpy").value
    assert np.abs(np.asarray(factor.base_albedo) - uncoated).max() <= 1e-9
    assert factor.base_roughness == pytest.approx(0.3)  # r_b = r_m = specular_roughness for a metal
    white = dict(base_color=(1, 1, 1), specular_weight=0.0, coat_weight=1.0, coat_roughness=0.0)
    assert np.abs(_albedo(**white) - _albedo(**white, coat_darkening=0.0)).max() <= 1e-15


def test_darkening_keeps_the_reciprocal_rules_reciprocal():
    """Under the symmetric rule the darkening's K_s is its average E_F (a constant factor): f(L, V) = f(V, L); under
    the view rule K_s = F(μ_o) makes it view-dependent (the view rule is not reciprocal anyway)."""
    rng = np.random.default_rng(3)
    L, V = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    L[:, 2], V[:, 2] = np.abs(L[:, 2]), np.abs(V[:, 2])
    L, V = L / np.linalg.norm(L, axis=1, keepdims=True), V / np.linalg.norm(V, axis=1, keepdims=True)
    common = dict(base_color=(0.6, 0.4, 0.2), specular_weight=0.0, coat_weight=1.0, coat_roughness=0.3)
    model = bn.load("openpbr", layering="symmetric", **common)
    forward, backward = model.eval(L, V), model.eval(V, L)
    assert np.abs(forward - backward).max() <= 1e-12 * np.abs(forward).max()
    undarkened = bn.load("openpbr", layering="symmetric", coat_darkening=0.0, **common).eval(L, V)
    assert np.all(forward < undarkened)  # and it does darken
