"""Certified albedo (brdfnorm.engine.routes.certified): enclosures against closed forms in Arb, independent 1-D routes,
and the
float64 engine's error estimates judged against the enclosures."""

from __future__ import annotations

import json
import math
import sys

import numpy as np
import pytest
from helpers.references import phong_like_reference

import brdfnorm as bn
from brdfnorm.engine.routes.series import blinn_phong_albedo_series
from brdfnorm.errors import ArgumentError, MissingExtraError

flint = pytest.importorskip("flint", reason="python-flint (brdfnorm[certified]) is not installed")
arb = flint.arb

SEED_000_EXPONENTS = (0.5, 1.0, 8.86, 512.0, 1e4)


def _closed_forms(n: float) -> dict[str, object]:
    """Seed 000's three closed forms, evaluated in Arb from the exact float exponent."""
    with _precision(200):
        x, pi = arb(n), arb.pi()
        return {
            "phong": 2 * pi / (x + 1),
            "modified-phong": 2 * pi / (x + 2),
            "blinn-phong": 8 * pi * (arb(2) ** (-x / 2) + x) / ((x + 2) * (x + 4)),
        }


class _precision:
    def __init__(self, bits: int) -> None:
        self.bits = bits

    def __enter__(self):
        self.old = flint.ctx.prec
        flint.ctx.prec = self.bits

    def __exit__(self, *_):
        flint.ctx.prec = self.old


def _ball(result) -> object:
    """The enclosure as an arb ball, rebuilt from the reported decimal bounds (what a user gets)."""
    with _precision(300):
        lower, upper = arb(str(np.ravel(result.lower)[0])), arb(str(np.ravel(result.upper)[0]))
        return (lower + upper) / 2 + arb(0, float((upper - lower).upper()))


@pytest.mark.parametrize("n", SEED_000_EXPONENTS)
@pytest.mark.parametrize("model", ["phong", "modified-phong", "blinn-phong"])
def test_seed_000_closed_forms_lie_inside_their_enclosures(model, n):
    result = bn.albedo(bn.load(model, n=n), 0.0, method="certified")
    closed = _closed_forms(n)[model]
    with _precision(300):
        lower, upper = arb(str(result.lower[0])), arb(str(result.upper[0]))
        assert lower <= closed.lower() and closed.upper() <= upper, (model, n, result.lower, result.upper)
        assert float((upper - lower).upper()) <= 2e-25 * float(abs(closed).upper())  # radius ≤ 1e-25 relative
    assert result.converged.all() and result.method == "certified"


def test_enclosure_excludes_a_wrong_value():
    """The bounds are tight enough to refuse seed 000's folklore (n+8)/8π factor and a 1e-20 perturbation."""
    n = 512.0
    result = bn.albedo(bn.load("blinn-phong", n=n), 0.0, method="certified")
    with _precision(300):
        lower, upper = arb(str(result.lower[0])), arb(str(result.upper[0]))
        exact = _closed_forms(n)["blinn-phong"]
        for wrong in (8 * arb.pi() / (arb(n) + 8), exact * (1 + arb("1e-20"))):
            assert not (lower <= wrong <= upper)


def test_grazing_blinn_phong_is_certified_to_twenty_digits():
    result = bn.albedo(bn.load("blinn-phong", n=1e4), math.radians(89.9), method="certified")
    with _precision(300):
        lower, upper = arb(str(result.lower[0])), arb(str(result.upper[0]))
        assert float(((upper - lower) / lower).upper()) <= 1e-20
    series = blinn_phong_albedo_series(np.array([1e4]), math.radians(89.9), rtol=1e-13)
    assert abs(series.value[0] - result.value[0]) <= series.error[0] + result.error[0]


@pytest.mark.parametrize(("model", "original"), [("phong", True), ("modified-phong", False)])
@pytest.mark.parametrize("n", [0.5, 3.5, 100.0])
@pytest.mark.parametrize("degrees", [20.0, 60.0, 85.0, 89.9])
def test_phong_lobes_agree_with_an_independent_one_dimensional_route(model, original, n, degrees):
    theta = math.radians(degrees)
    result = bn.albedo(bn.load(model, n=n), theta, method="certified", digits=25)
    reference = phong_like_reference(n, theta, original=original)  # scipy quad, polar about the mirror direction
    assert abs(result.value[0] - reference) <= 1e-12 * reference


@pytest.mark.parametrize("n", [0.3, 7.0, 512.0, 1e4])
@pytest.mark.parametrize("degrees", [0.0, 30.0, 75.0, 88.0])
def test_blinn_phong_agrees_with_seed_002_series(n, degrees):
    theta = math.radians(degrees)
    result = bn.albedo(bn.load("blinn-phong", n=n), theta, method="certified", digits=20)
    series = blinn_phong_albedo_series(np.array([n]), theta, rtol=1e-13)
    assert abs(series.value[0] - result.value[0]) <= max(series.error[0], 1e-13 * series.value[0])


def test_over_the_view_readings():
    theta = math.radians(40.0)
    modified = bn.albedo(bn.load("modified-phong", n=20.0), theta, method="certified")
    original_view = bn.albedo(bn.load("phong", n=20.0), theta, over="view", method="certified")
    quadrature = bn.albedo(bn.load("phong", n=20.0), theta, over="view", method="quadrature", rtol=1e-12)
    assert abs(original_view.value[0] - modified.value[0] / math.cos(theta)) <= 1e-15
    assert abs(original_view.value[0] - quadrature.value[0]) <= quadrature.error[0] + original_view.error[0]


@pytest.mark.parametrize("model", ["phong", "modified-phong", "blinn-phong", "blinn-phong-gaussian"])
def test_constant_lobe_at_zero_exponent(model):
    expected = {"phong": 2 * math.pi}.get(model, math.pi)
    if model == "blinn-phong-gaussian":  # n = 0: c = 0 and f = exp(−(N·H − 1)²), not constant
        quadrature = bn.albedo(bn.load(model, n=0.0), 0.5, method="quadrature", rtol=1e-12)
        expected = quadrature.value[0]
    result = bn.albedo(bn.load(model, n=0.0), 0.5, method="certified")
    assert abs(result.value[0] - expected) <= 1e-11 * expected


def test_lambert_is_its_reflectance_exactly():
    result = bn.albedo(bn.load("lambert", reflectance=0.3), np.radians([0.0, 45.0, 89.0]), method="certified")
    assert np.all(result.value[:, 0] == 0.3) and np.all(result.error == 0.0)
    from decimal import Decimal  # the float 0.3 exactly, between the outward-rounded 30-digit decimals
    bounds = zip(result.lower[:, 0], result.upper[:, 0], strict=True)
    assert all(Decimal(lo) <= Decimal(0.3) <= Decimal(hi) for lo, hi in bounds)


# -- the float64 engine judged against enclosures ----------------------------------------------------------------

HONESTY_CASES = [
    (model, n, degrees, rtol)
    for model in ("phong", "modified-phong", "blinn-phong", "blinn-phong-gaussian")
    for n, degrees in ((1.0, 0.0), (8.86, 45.0), (512.0, 80.0), (1e4, 89.0))
    for rtol in (1e-6, 1e-10)
]


@pytest.mark.parametrize(("model", "n", "degrees", "rtol"), HONESTY_CASES)
def test_quadrature_estimate_covers_the_certified_error(model, n, degrees, rtol):
    m = bn.load(model, n=n)
    theta = math.radians(degrees)
    certified = bn.albedo(m, theta, method="certified", digits=25)
    estimate = bn.albedo(m, theta, method="quadrature", rtol=rtol)
    with _precision(300):
        ball = _ball(certified)
        # the least the float64 result can be off: its distance to the enclosure
        off = abs(arb(float(estimate.value[0])) - ball.mid()) - ball.rad()
        assert float(off.upper()) <= estimate.error[0], (model, n, degrees, rtol)


# -- errors ------------------------------------------------------------------------------------------------------

def test_no_certified_route_names_the_model_and_the_reason(tmp_path):
    source = (bn.__file__.rsplit("/src/", 1)[0] + "/examples/ggx.brdf")
    model = bn.load(source)
    with pytest.raises(ArgumentError, match="no certified route for .*use method 'quadrature'"):
        bn.albedo(model, 0.0, method="certified")


def test_without_python_flint_the_method_says_how_to_install_it(monkeypatch):
    monkeypatch.setitem(sys.modules, "flint", None)  # import flint now raises ImportError
    with pytest.raises(MissingExtraError, match=r"pip install 'brdfnorm\[certified\]'"):
        bn.albedo(bn.load("phong", n=2.0), 0.0, method="certified")


@pytest.mark.parametrize("digits", [0, -3, 10**6, 2.5, "30", True])
def test_bad_digits_are_refused(digits):
    with pytest.raises(ArgumentError, match="digits"):
        bn.albedo(bn.load("phong", n=2.0), 0.0, method="certified", digits=digits)


def test_digits_with_another_method_is_refused():
    with pytest.raises(ArgumentError, match="digits applies to method 'certified' only"):
        bn.albedo(bn.load("phong", n=2.0), 0.0, method="quadrature", digits=20)


def test_more_digits_tighten_the_enclosure():
    m = bn.load("modified-phong", n=3.0)
    radii = []
    for digits in (15, 30, 60):
        r = bn.albedo(m, 0.7, method="certified", digits=digits)
        with _precision(400):
            radii.append(float((arb(str(r.upper[0])) - arb(str(r.lower[0]))).upper()))
    assert radii[0] > radii[1] > radii[2] and radii[2] < 1e-55


# -- command line ------------------------------------------------------------------------------------------------

def test_cli_json_carries_the_bounds_as_decimal_strings(run_cli):
    code, out, err = run_cli("albedo", "blinn-phong", "-p", "n=512", "--theta", "0,60",
                             "--method", "certified", "--digits", "35", "--json")
    assert code == 0, err
    rows = json.loads(out)["results"]
    closed = _closed_forms(512.0)["blinn-phong"]
    with _precision(300):
        lower, upper = arb(rows[0]["lower"]), arb(rows[0]["upper"])
        assert lower <= closed.lower() and closed.upper() <= upper
    assert all(len(row["lower"].replace(".", "").lstrip("0")) >= 35 for row in rows)
    assert rows[1]["method"] == "certified" and rows[1]["converged"] is True


def test_cli_errors_map_to_flags(run_cli):
    code, _, err = run_cli("albedo", "phong", "--theta", "0", "--digits", "12")
    assert code == 2 and "--digits" in err and "Traceback" not in err
    code, _, err = run_cli("albedo", "examples/ggx.brdf", "--theta", "0", "--method", "certified")
    assert code == 2 and "--method" in err and "no certified route" in err


# -- verify --certified and the report -----------------------------------------------------------------------------

def test_verify_certified_checks_every_albedo_claim(run_cli):
    from brdfnorm.claims import verify

    ids = list(verify.CERTIFIABLE)
    claims = verify.verify([0.5, 8.86, 512.0], only=ids, certified=True)
    for claim in claims:
        assert claim.certified is not None and claim.certified["ok"], claim.id
        assert len(claim.certified["cases"]) == 3
        assert all(c["lower"] < c["upper"] for c in claim.certified["cases"])
    code, out, err = run_cli("verify", "--certified", "--claim", "blinn-phong-normal", "--n", "8.86,1e4",
                             "--json")
    assert code == 0, err
    (claim,) = json.loads(out)["claims"]
    assert claim["certified"]["exact_formula"] and all(c["inside"] for c in claim["certified"]["cases"])


def test_verify_certified_fails_a_closed_form_that_is_off_by_1e_minus_25(monkeypatch):
    from brdfnorm.claims import verify
    from brdfnorm.engine.routes import certified

    exact = certified.NORMAL_INCIDENCE_CLOSED_FORMS["phong"]
    monkeypatch.setitem(certified.NORMAL_INCIDENCE_CLOSED_FORMS, "phong",
                        lambda n, pi, arb: exact(n, pi, arb) * (1 + arb("1e-25")))
    (claim,) = verify.verify([8.86], only=["phong-original"], certified=True)
    assert not claim.ok and not claim.certified["cases"][0]["inside"]


def test_report_factor_table_is_certified():
    from brdfnorm.report import sections, study

    n = np.array([1.0, 64.0, 4096.0])
    quadrature, error = {}, {}
    for lobe in study.SEED_LOBES:
        r = bn.normalize(bn.load(lobe), "normal", sweep={"n": n}, rtol=1e-10, method="quadrature")
        quadrature[lobe], error[lobe] = r.factor[:, 0, 0], r.error[:, 0, 0] / r.albedo[:, 0, 0]
    cert = study.certified_factors(n, quadrature, error)
    assert all(np.all(v) for v in cert.closed_inside.values())
    assert all(np.all(v) for v in cert.quadrature_covered.values())
    assert max(float(np.max(r)) for r in cert.radius.values()) < 1e-28
    table = study.FactorTable(n, {}, quadrature, error, {}, {}, cert)
    line = sections._certified_line(table)
    assert line.startswith("Certified to 30 digits") and "inside" in line and "DO NOT" not in line


def test_converged_says_whether_the_digits_were_reached(monkeypatch):
    from brdfnorm.engine.routes import certified

    m = bn.load("modified-phong", n=3.0)
    exact = bn.albedo(m, 0.7, method="certified", digits=30)
    assert exact.converged.all()
    monkeypatch.setattr(certified.core, "EVAL_LIMIT", 40)  # Arb stops early and returns the wider ball it has
    with pytest.warns(UserWarning, match="did not reach"):
        wide = bn.albedo(m, 0.7, method="certified", digits=30)
    assert not wide.converged.all()  # still a valid enclosure, only wider than 30 digits
    assert float(wide.lower[0]) <= exact.value[0] <= float(wide.upper[0])


# -- microfacet lobes at normal incidence (the reduction itself; the models route through it) -------------------

def _microfacet_reference(alpha: float, distribution: str, eta: float | None) -> float:
    """E at V = N by mpmath in the half-vector polar angle θ_h (D, Smith Λ and Fresnel as published, not the CDF
    form), split at the lobe's widths and at the critical angle."""
    import mpmath as mp

    with mp.workdps(30):
        a = mp.mpf(alpha)

        def integrand(th):
            t2, c = mp.tan(th) ** 2, mp.cos(th)
            if distribution == "ggx":
                d = a**2 / (mp.pi * c**4 * (a**2 + t2) ** 2)
                lam = (-1 + mp.sqrt(1 + a**2 * mp.tan(2 * th) ** 2)) / 2
            else:
                d = mp.exp(-t2 / a**2) / (mp.pi * a**2 * c**4)
                x = 1 / (a * mp.tan(2 * th))
                lam = (mp.erf(x) - 1) / 2 + mp.exp(-x * x) / (2 * x * mp.sqrt(mp.pi))
            f = 1
            if eta is not None and eta**2 - 1 + c * c >= 0:
                g = mp.sqrt(eta**2 - 1 + c * c)
                r = (c * (g + c) - 1) / (c * (g - c) + 1)
                f = (g - c) ** 2 / (2 * (g + c) ** 2) * (1 + r * r)
            return d * c / (1 + lam) * f * 2 * mp.pi * mp.sin(th)

        points = {mp.mpf(0), mp.pi / 4, *(w * alpha for w in (0.1, 0.3, 1, 3) if w * alpha < 0.78)}
        if eta is not None and eta < 1:
            points.add(mp.acos(mp.sqrt(1 - mp.mpf(eta) ** 2)))
        return float(mp.quad(integrand, sorted(points)))


@pytest.mark.parametrize(("distribution", "alpha", "eta"), [
    ("ggx", 0.3, None), ("ggx", 1.0, None), ("beckmann", 0.3, None), ("beckmann", 1.0, None),
    ("ggx", 0.5, 1.5), ("ggx", 0.5, 0.6), ("beckmann", 0.7, 0.5),
])
def test_microfacet_normal_incidence_against_mpmath(distribution, alpha, eta):
    from brdfnorm.engine.routes import certified

    params = {"alpha": alpha, "fresnel": "none" if eta is None else "dielectric", "eta": eta}
    work = certified.Integrator(25)
    with _precision(work.bits):
        ball = certified.REDUCTIONS[distribution].compute(work, arb(0), params, "light")[0]
        reference = _microfacet_reference(alpha, distribution, eta)
        assert float(ball.rad()) < 1e-24
        assert abs(float(ball.mid()) - reference) <= 1e-14 * reference


def test_ggx_at_unit_alpha_encloses_one_minus_ln_2():
    from brdfnorm.engine.routes import certified

    work = certified.Integrator(30)
    with _precision(work.bits):
        (ball,) = certified.REDUCTIONS["ggx"].compute(work, arb(0), {"alpha": 1.0}, "light")
        exact = 1 - arb(2).log()
        assert ball.contains(exact) and float(ball.rad()) < 1e-28


def test_mirror_like_microfacet_lobes_reflect_everything():
    from brdfnorm.engine.routes import certified

    for distribution in ("ggx", "beckmann"):
        work = certified.Integrator(25)
        with _precision(work.bits):
            (ball,) = certified.REDUCTIONS[distribution].compute(work, arb(0), {"alpha": 1e-8}, "light")
            assert abs(float(ball.mid()) - 1.0) < 1e-15 and float(ball.rad()) < 1e-24


MICROFACET_CASES = [
    dict(alpha=0.3), dict(alpha=1e-6), dict(alpha=1.0, shadowing="separable"),
    dict(alpha=0.3, fresnel="dielectric", eta=1.5), dict(alpha=0.5, fresnel="dielectric", eta=(0.6, 1.5, 0.9)),
    dict(alpha=0.4, fresnel="schlick", f0=(0.04, 0.5, 0.9), f90=(1.0, 0.8, 1.0)),
]


@pytest.mark.parametrize("distribution", ["ggx", "beckmann"])
@pytest.mark.parametrize("params", MICROFACET_CASES, ids=lambda p: ",".join(f"{k}={v}" for k, v in p.items()))
def test_microfacet_models_certified_at_normal_incidence_cover_the_half_vector_engine(distribution, params):
    m = bn.load(distribution, **params)
    certified = bn.albedo(m, 0.0, method="certified", digits=25)
    assert certified.converged.all()
    # What auto picks (the 1-D azimuthal route for isotropic GGX with F = 1), and the half-vector cubature.
    for method in ("auto", "microfacet"):
        engine = bn.albedo(m, 0.0, rtol=1e-12, method=method)
        assert engine.method != "certified"
        off = np.abs(engine.value - certified.value) - certified.error
        assert np.all(off <= engine.error) and np.all(np.abs(engine.value - certified.value) <= 1e-12)


def test_microfacet_certified_route_refuses_what_it_cannot_enclose():
    with pytest.raises(ArgumentError, match="normal incidence only"):  # any view: F = 1 only
        bn.albedo(bn.load("ggx", alpha=0.3, fresnel="schlick"), 0.5, method="certified")
    with pytest.raises(ArgumentError, match="isotropic"):
        bn.albedo(bn.load("ggx", alpha=0.3, alpha_x=0.1), 0.0, method="certified")
    with pytest.raises(ArgumentError, match="conductor"):
        bn.albedo(bn.load("beckmann", alpha=0.3, fresnel="conductor", eta=0.2, k=3.0), 0.0, method="certified")
