"""Certified microfacet albedo at any view (brdfnorm.engine.routes.certified.microfacet) and certified tables
(brdfnorm.lut.certified): enclosures against exact values, against the independent normal-incidence CDF route and
mpmath, and the float64 routes (azimuthal, microfacet, the generic engine on examples/ggx.brdf, lut auto tables)
judged against the enclosures."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pytest
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.errors import ArgumentError

flint = pytest.importorskip("flint", reason="python-flint (brdfnorm[certified]) is not installed")
arb = flint.arb

from brdfnorm.engine.routes import certified  # noqa: E402
from brdfnorm.lut import certified as certified_tables  # noqa: E402

SHADOWINGS = ("height-correlated", "separable")


def _ball(e: certified.Enclosure):
    """The reported decimal interval as an arb ball (what a user gets)."""
    old, flint.ctx.prec = flint.ctx.prec, 300
    try:
        lower, upper = arb(e.lower), arb(e.upper)
        return (lower + upper) / 2 + arb(0, float((upper - lower).upper()) / 2 * (1 + 1e-15))
    finally:
        flint.ctx.prec = old


def _enclose(distribution, mu, alpha, shadowing="height-correlated", digits=12):
    m = bn.load(distribution, alpha=alpha, shadowing=shadowing)
    (e,) = certified.enclose(m, 0.0, m.params, digits=digits, mu=mu)
    return e


def _covers(e: certified.Enclosure, value: float, estimate: float) -> bool:
    """``value`` lies within the enclosure widened by ``estimate`` (float64 bounds, rounded outward)."""
    return e.lower_float - estimate <= value <= e.upper_float + estimate


@pytest.mark.parametrize("shadowing", SHADOWINGS)
def test_ggx_at_normal_view_and_unit_alpha_encloses_one_minus_ln_2(shadowing):
    # At μ = 1 Λ(V) = 0, so both G2 are G1(L) and E = ∫₀¹ μ/(1 + μ) dμ·... = 1 − ln 2 (azimuthal module docstring).
    e = _enclose("ggx", 1.0, 1.0, shadowing, digits=25)
    old, flint.ctx.prec = flint.ctx.prec, 300
    try:
        exact = 1 - arb(2).log()
        assert arb(e.lower) <= exact.lower() and exact.upper() <= arb(e.upper)
        assert not (arb(e.lower) <= exact * (1 + arb("1e-24")) <= arb(e.upper))
    finally:
        flint.ctx.prec = old
    assert e.reached


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
@pytest.mark.parametrize("alpha", [1e-8, 0.3, 1.0])
def test_any_view_route_agrees_with_the_normal_incidence_cdf_route(distribution, alpha):
    """Two independent reductions at μ = 1: the azimuthal one (any view) and the distribution's CDF (V = N)."""
    e = _enclose(distribution, 1.0, alpha, digits=15)
    work = certified.Integrator(20)
    old, flint.ctx.prec = flint.ctx.prec, work.bits
    try:
        other = certified.microfacet_normal_albedo(work, arb(alpha), distribution, lambda c, analytic, beyond: 1)
        assert other.overlaps(_ball(e)) and float(other.rad()) < 1e-18
    finally:
        flint.ctx.prec = old


def test_the_grazing_mirror_cell_is_enclosed():
    """μ = 1e-4, α = 1e-8 (the corner of the usual table): enclosed to 12 digits, and the float64 route inside."""
    for shadowing in SHADOWINGS:
        e = _enclose("ggx", 1e-4, 1e-8, shadowing)
        assert e.reached and 0.999999994 < e.value < 0.999999996
        r = bn.albedo(bn.load("ggx", alpha=1e-8, shadowing=shadowing), math.acos(1e-4), rtol=1e-12)
        assert _covers(e, r.value[0], r.error[0])


def test_digits_are_met_on_the_reported_interval():
    for digits in (12, 20):
        e = _enclose("ggx", 0.37, 0.21, digits=digits)
        assert e.reached
        old, flint.ctx.prec = flint.ctx.prec, 400
        try:
            lower, upper = arb(e.lower), arb(e.upper)
            assert (upper - lower) / 2 <= arb(10) ** -digits * lower  # the relative radius, exactly
        finally:
            flint.ctx.prec = old


def test_relative_radius_check_is_exact():
    assert certified.core.relative_radius_within("0.995", "1.005", 2)
    assert not certified.core.relative_radius_within("0.99", "1.01", 2)  # 0.01 > 0.0099
    assert not certified.core.relative_radius_within("-1", "1", 1)


def test_outward_floats_bracket_the_ball():
    old, flint.ctx.prec = flint.ctx.prec, 200
    try:
        third = arb(1) / 3
        lo, hi = certified.core.outward_float(third.lower(), -1), certified.core.outward_float(third.upper(), +1)
        assert arb(lo) < third.lower() and third.upper() < arb(hi) and hi == np.nextafter(lo, 2.0)
        assert certified.core.outward_float(arb(0.5), -1) == 0.5  # exact endpoints stay
    finally:
        flint.ctx.prec = old


BECKMANN_MPMATH = [(0.5, 0.3), (0.2, 0.7)]


@pytest.mark.slow  # ~30 s each: mpmath's 2-D quadrature
@pytest.mark.parametrize(("mu", "alpha"), BECKMANN_MPMATH)
def test_beckmann_against_a_two_dimensional_mpmath_integral(mu, alpha):
    """Beckmann's moments J_k (Kummer functions) checked against the plain 2-D integral over (θ_L, φ) in mpmath."""
    import mpmath as mp

    e = _enclose("beckmann", mu, alpha, "separable", digits=12)
    with mp.workdps(20):
        sv = mp.sqrt(1 - mp.mpf(mu) ** 2)

        def lam(tan):
            if tan == 0:
                return mp.mpf(0)
            b = 1 / (alpha * tan)
            return (mp.erf(b) - 1) / 2 + mp.exp(-b * b) / (2 * b * mp.sqrt(mp.pi))

        lam_v = lam(sv / mu)

        def f(th, ph):
            sl, cl = mp.sin(th), mp.cos(th)
            h = (sl * mp.cos(ph) + sv, sl * mp.sin(ph), cl + mu)
            n2 = h[0] ** 2 + h[1] ** 2 + h[2] ** 2
            c2 = h[2] ** 2 / n2
            t2 = (1 - c2) / c2
            d = mp.exp(-t2 / alpha**2) / (mp.pi * alpha**2 * c2 * c2)
            g2 = 1 / ((1 + lam(sl / cl)) * (1 + lam_v))
            return d * g2 / (4 * mu) * sl * 2  # φ over [0, π], doubled

        peak = mp.acos(mu)
        value = mp.quad(f, [0, max(peak - 3 * alpha, 0.01), peak, min(peak + 3 * alpha, 1.5), mp.pi / 2],
                        [0, 0.05, 0.3, mp.pi])
    assert abs(float(value) - e.value) <= 1e-9


# -- the float64 routes judged against enclosures --------------------------------------------------------------

HONESTY = [(d, mu, alpha, s) for d in ("ggx", "beckmann") for mu, alpha in ((1e-3, 0.05), (0.3, 0.8), (0.95, 1e-3))
           for s in SHADOWINGS]


@pytest.mark.parametrize(("distribution", "mu", "alpha", "shadowing"), HONESTY)
def test_float64_routes_lie_inside_the_enclosure_widened_by_their_estimate(distribution, mu, alpha, shadowing):
    e = _enclose(distribution, mu, alpha, shadowing, digits=14)
    m = bn.load(distribution, alpha=alpha, shadowing=shadowing)
    for method, rtol in (("azimuthal", 1e-12), ("microfacet", 1e-8), ("auto", 1e-10)):
        r = bn.albedo(m, math.acos(mu), rtol=rtol, method=method)
        assert _covers(e, r.value[0], r.error[0]), (method, r.value[0], e.lower, e.upper, r.error[0])


@pytest.mark.parametrize("roughness", [0.1, 0.6])
def test_generic_engine_on_the_ggx_brdf_file_lies_inside_the_enclosure(roughness):
    """examples/ggx.brdf with f0 = 1 is the separable GGX lobe with F = 1 at α = roughness² (its float64)."""
    m = bn.load(str(EXAMPLES / "ggx.brdf"), roughness=roughness, f0=1.0)
    for mu in (0.2, 0.9):
        r = bn.albedo(m, math.acos(mu), rtol=1e-8)
        e = _enclose("ggx", mu, roughness * roughness, "separable", digits=12)
        assert _covers(e, r.value[0], r.error[0]), (mu, r.method, r.value[0], e.lower, e.upper, r.error[0])


# -- tables --------------------------------------------------------------------------------------------------------

def test_certified_table_encloses_the_auto_table():
    axes = {"mu": [1e-4, 0.5, 1.0], "alpha": [1e-8, 0.4, 1.0]}
    model = bn.load("ggx")
    table = certified_tables.compute(model, axes, digits=12, average=False)
    auto = bn.lut.compute(model, axes, rtol=1e-10, average=False)
    assert table.meta["unconverged"] == 0
    assert np.all(table["E_lower"] <= table["E"]) and np.all(table["E"] <= table["E_upper"])
    assert np.all(table["E_lower"] - auto["E_error"] <= auto["E"])
    assert np.all(auto["E"] <= table["E_upper"] + auto["E_error"])
    decimals = table.meta["certified"]["E"]
    assert all(float(lo) <= v <= float(hi) for lo, v, hi in
               zip(np.ravel(decimals["lower"]), table["E"].ravel(), np.ravel(decimals["upper"]), strict=True))


def test_certified_table_refuses_what_it_cannot_certify():
    with pytest.raises(ArgumentError, match="E_avg .* no certified route"):
        certified_tables.compute(bn.load("ggx"), {"mu": [0.5]}, digits=6)
    with pytest.raises(ArgumentError, match="fresnel=none"):
        certified_tables.compute(bn.load("ggx", fresnel="schlick"), {"mu": [0.5]}, average=False)
    with pytest.raises(ArgumentError, match="no certified table for blinn-phong"):
        certified_tables.compute(bn.load("blinn-phong"), {"mu": [0.5]}, average=False)
    with pytest.raises(ArgumentError, match="axes mu or theta and alpha"):
        certified_tables.compute(bn.load("ggx"), {"mu": [0.5], "f0": [0.1]}, average=False)
    with pytest.raises(ArgumentError, match="lut.certified"):
        bn.lut.compute(bn.load("ggx"), {"mu": [0.5]}, method="certified")
    with pytest.raises(ArgumentError, match="normal incidence"):
        bn.albedo(bn.load("ggx", fresnel="schlick"), 0.5, method="certified")


def test_cli_certified_table_json(tmp_path, run_cli):
    out = tmp_path / "E.json"
    code, _, err = run_cli("lut", "beckmann", "--axis", "mu=0.25,1", "--axis", "alpha=0.5", "--method",
                           "certified", "--digits", "10", "--no-average", "-o", str(out))
    assert code == 0, err
    document = json.loads(out.read_text())
    assert {"E", "E_lower", "E_upper", "E_error", "1-E"} <= set(document["tables"])
    bounds = document["meta"]["certified"]["E"]
    assert document["meta"]["certified"]["digits"] == 10 and len(bounds["lower"][0][0]) >= 12
    code, _, err = run_cli("lut", "ggx", "--axis", "mu=0.5", "--digits", "10", "-o", str(out))
    assert code == 2 and "--digits" in err and "Traceback" not in err
    code, _, err = run_cli("lut", "ggx", "--axis", "mu=0.5", "--method", "certified", "-o", str(out))
    assert code == 2 and "--no-average" in err


def test_cli_albedo_json_reports_the_radian_that_was_certified(run_cli):
    code, out, err = run_cli("albedo", "ggx", "-p", "alpha=0.3", "--theta", "60", "--method", "certified",
                             "--digits", "12", "--json")
    assert code == 0, err
    (row,) = json.loads(out)["results"]
    assert row["theta_rad"] == math.radians(60.0)  # the float64 radian, round-tripped exactly
    from decimal import Decimal

    assert Decimal(row["theta_rad_exact"]) == Decimal(math.radians(60.0))  # its exact decimal expansion
    assert float(row["lower"]) <= row["albedo"] <= float(row["upper"])


# -- the goal ------------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_32_by_32_ggx_table_certified_to_12_digits_within_10_minutes():
    axes = {"mu": np.linspace(0.0, 1.0, 32), "alpha": np.linspace(0.0, 1.0, 32)}
    clamp = {"mu": 1e-4, "alpha": 1e-8}
    model = bn.load("ggx")
    start = time.perf_counter()
    table = certified_tables.compute(model, axes, clamp=clamp, digits=12, average=False)
    seconds = time.perf_counter() - start
    assert table.meta["unconverged"] == 0 and seconds <= 600, seconds
    auto = bn.lut.compute(model, axes, clamp=clamp, rtol=1e-10, average=False)
    assert np.all(table["E_lower"] - auto["E_error"] <= auto["E"])
    assert np.all(auto["E"] <= table["E_upper"] + auto["E_error"])


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
def test_rough_beyond_one_and_a_theta_axis(distribution):
    """α = 2.5 (the reduction holds for every α > 0) on a θ axis: the float64 azimuthal values inside."""
    model = bn.load(distribution, alpha=2.5, shadowing="separable")
    theta = np.radians([0.0, 45.0, 80.0])
    table = certified_tables.compute(model, {"theta": theta}, digits=10, average=False)
    assert table.meta["unconverged"] == 0 and "radian" in table.meta["certified"]["view"]
    r = bn.albedo(model, theta, rtol=1e-12, method="azimuthal")
    assert np.all(table["E_lower"] - r.error[:, 0] <= r.value[:, 0])
    assert np.all(r.value[:, 0] <= table["E_upper"] + r.error[:, 0])
