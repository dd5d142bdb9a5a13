"""The openpbr material and its composition rules (brdfnorm.materials): the white furnace of a coat over a white
Lambert base, the symmetric rule's loss, the metalness mix against the F0 blend — each by the term-by-term route,
the generic cubature of the whole BRDF, and a closed form from independently computed lobe albedos."""

import numpy as np
import pytest
from scipy import integrate

import brdfnorm as bn
from brdfnorm.engine.routes.microfacet import average_albedo
from brdfnorm.errors import ParameterError
from brdfnorm.materials.albedo import CACHE, build_curve
from brdfnorm.materials.components import Microfacet, Sheen
from brdfnorm.models.fresnel import Fresnel
from brdfnorm.models.microfacet import GGXDistribution

THETA = np.radians([0.0, 20.0, 45.0, 70.0, 85.0, 89.9])
WHITE_COAT = dict(base_color=(1, 1, 1), specular_weight=0.0, coat_weight=1.0, coat_roughness=0.5,
                  coat_fresnel="none")


def test_white_lambert_under_view_side_coat_is_one():
    m = bn.load("openpbr", **WHITE_COAT)
    terms = bn.albedo(m, THETA)
    assert terms.method == "material"
    whole = bn.albedo(m, THETA, method="quadrature", rtol=1e-11)
    assert np.all(np.abs(terms.value - 1.0) <= 1e-9)
    assert np.all(np.abs(whole.value - 1.0) <= 1e-9)  # the composed BRDF integrated as one lobe
    assert np.all(np.abs(whole.value - 1.0) <= whole.error + 1e-15)


@pytest.mark.slow
def test_white_furnace_by_scipy_at_one_view():
    m = bn.load("openpbr", **WHITE_COAT)
    V = np.array([np.sin(1.0), 0.0, np.cos(1.0)])

    def f(theta, phi):
        L = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
        return float(m.eval(L, V)[0]) * np.cos(theta) * np.sin(theta)

    value, _ = integrate.dblquad(f, 0.0, 2 * np.pi, 0.0, np.pi / 2, epsabs=1e-11, epsrel=1e-11)
    assert value == pytest.approx(1.0, abs=1e-8)


def test_symmetric_rule_loses_exactly_its_predicted_energy():
    m = bn.load("openpbr", **WHITE_COAT, layering="symmetric")
    terms = bn.albedo(m, THETA)
    whole = bn.albedo(m, THETA, method="quadrature", rtol=1e-11)
    # Lambert ρ = 1 under (1 − E(μi))(1 − E(μo)): E = E_c(μo) + (1 − E_c(μo))(1 − E_avg), E_avg by the engine's
    # own 2∫Eμdμ (not the material's curve).
    coat = bn.load("ggx", alpha=0.25)
    e_c = bn.albedo(coat, THETA).value[:, 0]
    e_avg = average_albedo(GGXDistribution(), "height-correlated", 0.25, rtol=1e-12)[0][0]
    expected = e_c + (1 - e_c) * (1 - e_avg)
    assert np.all(np.abs(terms.value[:, 0] - expected) <= 1e-10)
    assert np.all(np.abs(whole.value[:, 0] - expected) <= 1e-9)
    assert np.all(np.abs(terms.value[:, 0] - expected) <= terms.error[:, 0] + 1e-12)
    assert terms.value.min() < 0.88  # a loss of ~12.7% near 80°


def test_reciprocal_rule_conserves_over_lambert():
    m = bn.load("openpbr", **WHITE_COAT, layering="reciprocal")
    terms = bn.albedo(m, THETA[:4])
    whole = bn.albedo(m, THETA[:4], method="quadrature", rtol=1e-11)
    assert np.all(np.abs(terms.value - 1.0) <= 1e-9)
    assert np.all(np.abs(whole.value - 1.0) <= 1e-9)


@pytest.mark.parametrize("metalness", [0.0, 0.25, 0.5, 0.75, 1.0])
def test_metalness_mix_against_f0_blend(metalness):
    common = dict(base_color=(1, 1, 1), dielectric_fresnel="schlick", metal_fresnel="schlick",
                  specular_roughness=0.5, base_metalness=metalness)
    theta = np.radians([0.0, 60.0])
    mixed = bn.albedo(bn.load("openpbr", **common), theta)
    blended = bn.albedo(bn.load("openpbr", base_mix="f0-blend", **common), theta)
    # Schlick's albedo is linear in F0, so the blend's loss is exactly (1 − M) M ρ (E_metal − E_dielectric).
    e_d = bn.albedo(bn.load("ggx", alpha=0.25, fresnel="schlick", f0=0.04), theta).value[:, 0]
    e_m = bn.albedo(bn.load("ggx", alpha=0.25, fresnel="schlick", f0=1.0), theta).value[:, 0]
    loss = (1 - metalness) * metalness * (e_m - e_d)
    assert np.all(np.abs(mixed.value[:, 0] - blended.value[:, 0] - loss) <= 1e-11)
    whole = bn.albedo(bn.load("openpbr", base_mix="f0-blend", **common), theta, method="quadrature")
    assert np.all(np.abs(whole.value - blended.value) <= 1e-9)


def test_defaults_agree_between_routes_and_sweeps_bind():
    m = bn.load("openpbr")
    theta = np.radians([0.0, 50.0])
    terms = bn.albedo(m, theta)
    whole = bn.albedo(m, theta, method="quadrature")
    assert np.all(np.abs(terms.value - whole.value) <= 1e-9)
    swept = bn.albedo(m.with_params(base_metalness=np.array([0.0, 1.0])[:, None]), theta)
    assert np.allclose(swept.value[0], terms.value, atol=1e-14)
    metal = bn.albedo(bn.load("openpbr", base_metalness=1.0), theta)
    assert np.allclose(swept.value[1], metal.value, atol=1e-14)


TABLE = dict(WHITE_COAT, coat_roughness=0.43, layering="symmetric", albedo_source="table", albedo_table=8)


def test_table_source_is_read_bilinearly():
    theta = np.radians([10.0, 75.0])
    terms = bn.albedo(bn.load("openpbr", **TABLE), theta).value[:, 0]
    # The engine's 8 × 8 table rebuilt here: E of the ggx lobe at the nodes (μ = 0 row at 1e-4), bilinear in
    # (μ, roughness); the symmetric rule over white Lambert is E_c(μo) + (1 − E_t(μo)) 2∫(1 − E_t)μ dμ, the coat's
    # own lobe integrated exactly and the table only in the factors (the furnace residual is E_c − E_t).
    nodes = np.linspace(0.0, 1.0, 8)
    grid = np.array([bn.albedo(bn.load("ggx", alpha=max(r * r, 1e-12)), np.arccos(np.maximum(nodes, 1e-4)))
                     .value[:, 0] for r in nodes]).T  # [μ, roughness]
    j = np.searchsorted(nodes, 0.43) - 1
    t = (0.43 - nodes[j]) / (nodes[j + 1] - nodes[j])
    column = (1 - t) * grid[:, j] + t * grid[:, j + 1]

    def table(mu):
        return np.interp(mu, nodes, column)

    loss = 1.0 - integrate.quad(lambda mu: 2 * mu * table(mu), 0.0, 1.0, points=nodes[1:-1], epsabs=1e-14)[0]
    e = table(np.cos(theta))
    e_c = bn.albedo(bn.load("ggx", alpha=0.43**2), theta).value[:, 0]
    assert np.all(np.abs(terms - (e_c + (1 - e) * loss)) <= 1e-10)
    exact = bn.albedo(bn.load("openpbr", **dict(TABLE, albedo_source="exact")), theta).value[:, 0]
    assert 1e-6 < np.abs(terms - exact).max() < 0.05  # the 8 × 8 table's interpolation error, visible


@pytest.mark.slow
def test_table_source_by_the_whole_cubature():
    theta = np.radians([10.0, 75.0])
    m = bn.load("openpbr", **TABLE)
    whole = bn.albedo(m, theta, method="quadrature", rtol=1e-9)
    assert np.all(np.abs(bn.albedo(m, theta).value - whole.value) <= 1e-8)


@pytest.mark.parametrize("component", [
    Microfacet("coat", roughness=0.5),
    pytest.param(Microfacet("coat", roughness=0.3, fresnel=Fresnel("schlick", f0=0.04)), marks=pytest.mark.slow)])
def test_albedo_curve_error_is_honest(component):
    curve = build_curve(component)
    mu = np.random.default_rng(3).uniform(1e-6, 1.0, 64)
    exact, _ = component.albedo(mu)
    assert np.abs(curve(mu) - exact).max() <= curve.error
    assert curve.error < 1e-10


@pytest.mark.slow
def test_sheen_curve():
    curve = CACHE.curve(Sheen("fuzz", roughness=0.6))
    mu = np.array([0.2, 0.7])
    assert np.abs(curve(mu) - Sheen("fuzz", roughness=0.6).albedo(mu)[0]).max() <= curve.error


def test_bad_parameters():
    with pytest.raises(ParameterError, match="fuzz_roughness"):
        bn.load("openpbr", fuzz_weight=1.0, fuzz_roughness=0.01, fuzz_lobe="charlie")
    with pytest.raises(ParameterError, match="layering"):
        bn.load("openpbr", layering="sideways")


def test_metal_multiple_scattering_with_exact_f_avg():
    theta = np.radians([0.0, 60.0, 88.0])
    white = bn.load("openpbr", base_metalness=1, base_color=1, specular_roughness=0.6, metal_ms="kulla-conty")
    assert np.all(np.abs(bn.albedo(white, theta).value - 1.0) <= 1e-10)  # OpenPBR's white-metal furnace
    assert np.all(np.abs(bn.albedo(white, theta, method="quadrature").value - 1.0) <= 1e-9)
    tinted = dict(base_metalness=1, base_color=1, specular_color=0.7, specular_roughness=0.6)
    single = bn.albedo(bn.load("openpbr", **tinted), theta).value[:, 0]
    multiple = bn.albedo(bn.load("openpbr", metal_ms="kulla-conty", **tinted), theta).value[:, 0]
    # ∫ f_ms (N·L) dL = F_ms (1 − E(μo)) with F_avg of F82-tint in closed form and E_avg by the engine
    e = bn.albedo(bn.load("ggx", alpha=0.36), theta).value[:, 0]
    e_avg = average_albedo(GGXDistribution(), "height-correlated", 0.36, rtol=1e-12)[0][0]
    f_avg = Fresnel("f82-tint", f0=1.0, tint=0.7).average()[0]
    f_ms = f_avg**2 * e_avg / (1 - f_avg * (1 - e_avg))
    assert np.all(np.abs(multiple - single - f_ms * (1 - e)) <= 1e-10)


def test_symmetric_coat_over_a_metal_by_both_routes():
    # The metal under light-side factors goes through the term route's cubature branch; the whole BRDF's cubature
    # is the second route.
    m = bn.load("openpbr", base_metalness=1, base_color=1, specular_roughness=0.5, coat_weight=1.0,
                coat_roughness=0.3, coat_fresnel="none", layering="symmetric")
    theta = np.radians([0.0, 65.0])
    terms = bn.albedo(m, theta)
    whole = bn.albedo(m, theta, method="quadrature", rtol=1e-10)
    assert np.all(np.abs(terms.value - whole.value) <= terms.error + whole.error + 1e-12)
    view = bn.albedo(m.with_params(layering="view"), theta).value
    assert np.all(view - terms.value > 0.005)  # the symmetric rule loses against the view rule here too
