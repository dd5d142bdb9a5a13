"""The rough dielectrics' ``refraction_shadowing`` (issue 29): the refraction's G2 as Heitz's B(1 + Λ_V, 1 + Λ_L)
(``correlated-beta``; what ``auto`` gives with height-correlated shadowing), the reflection's 1/(1 + Λ_V + Λ_L)
(``reflection-form``, Blender Cycles' glass) or G1·G1 (``separable``, OpenPBR/Mitsuba). R and T by brdfnorm's
dielectric route against nested scipy quadrature over the facet normal (tests/helpers/dielectric_reference.py), which
shares no code with it."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.dielectric_reference import albedo_part

import brdfnorm as bn

VARIANTS = ("correlated-beta", "reflection-form", "separable")


@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize(("name", "mu", "alpha", "eta"), [("ggx", 0.5, 0.3, 1.5), ("beckmann", 0.3, 0.6, 1 / 1.5)])
def test_parts_against_the_facet_reference(variant, name, mu, alpha, eta):
    m = bn.load(f"{name}-dielectric", alpha=alpha, eta=eta, refraction_shadowing=variant)
    r = bn.albedo(m, np.arccos(mu), rtol=1e-9)
    assert r.converged.all()
    for part, value in (("R", r.reflected[0]), ("T", r.transmitted[0])):
        reference = albedo_part(name, mu, alpha, eta, part, refraction=variant)
        assert abs(value - reference) <= r.error[0] + 1e-13 * max(abs(reference), 1e-3), (part, value, reference)


def test_auto_is_todays_refraction_and_separable_shadowing_is_g1_g1():
    """``auto`` with height-correlated shadowing is the Beta form; ``shadowing=separable`` already gives G1·G1 for
    refraction (``refraction_shadowing=separable`` with height-correlated reflection differs only in R)."""
    L = np.array([[0.3, -0.2, -0.93]])
    L /= np.linalg.norm(L)
    V = np.array([[-0.5, 0.1, 0.86]])
    V /= np.linalg.norm(V)
    m = bn.load("ggx-dielectric", alpha=0.4)
    assert m.eval(L, V)[0, 0] == m.with_params(refraction_shadowing="correlated-beta").eval(L, V)[0, 0]
    sep = m.with_params(shadowing="separable").eval(L, V)[0, 0]
    assert sep == pytest.approx(m.with_params(refraction_shadowing="separable").eval(L, V)[0, 0], rel=1e-14)
    assert sep != m.eval(L, V)[0, 0]


def test_grazing_rough_transmission_differs_between_the_forms():
    """At a grazing view through a rough interface the refraction's G2 matters: T with the reflection's form
    against Heitz's Beta form, both by the reference: 0.728 against 0.0506 at μ = 0.05, α = 1, η = 1.5 (B(1 + a,
    1 + b) ≤ 1/(1 + a + b): the Beta form shadows more)."""
    mu, alpha, eta = 0.05, 1.0, 1.5
    beta = albedo_part("ggx", mu, alpha, eta, "T", refraction="correlated-beta")
    reflection = albedo_part("ggx", mu, alpha, eta, "T", refraction="reflection-form")
    assert reflection == pytest.approx(0.7278, abs=1e-3) and beta == pytest.approx(0.05056, abs=1e-4)


@pytest.mark.slow
@pytest.mark.parametrize("variant", ("reflection-form", "separable"))
def test_average_albedo_route_follows_the_variant(variant):
    """E_avg = 2∫ (R + T) μ dμ by the glass tables' route (brdfnorm.engine.routes.dielectric_average) against
    Gauss-Legendre over μ of the facet reference's R + T (η = 1.5 from outside: no total internal reflection, E(μ)
    smooth in μ)."""
    from brdfnorm.engine.routes.dielectric_average import average_albedo

    m = bn.load("ggx-dielectric")
    alpha, eta = 0.5, 1.5
    route = average_albedo(m.distribution, alpha, eta, "height-correlated", variant, rtol=1e-9)
    x, w = np.polynomial.legendre.leggauss(24)
    mu = (x + 1) / 2
    e = [sum(albedo_part("ggx", float(u), alpha, eta, part, refraction=variant) for part in "RT") for u in mu]
    reference = float(np.sum(w * np.array(e) * mu))  # 2 ∫₀¹ E μ dμ with dμ = dx/2
    assert route.converged[0] and abs(route.value[0] - reference) < 1e-7 + route.error[0]
    default = average_albedo(m.distribution, alpha, eta, "height-correlated", rtol=1e-9)
    assert abs(default.value[0] - route.value[0]) > 1e-3  # the variant is not today's
