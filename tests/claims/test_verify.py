"""brdfnorm verify: every claim's verdict as the mathematics says, the JSON shape, and that checks can fail.

Independent references here: closed forms re-derived in the test (the folklore error by scipy's bounded
minimizer, 2π/5 for ∫z⁴), brdfnorm's hemisphere cubature for the 1-D Phong route, and deliberate perturbations
of the formulas the checks use (a checker that cannot fail is no checker).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from brdfnorm.claims import seed000, seed002
from brdfnorm.claims import verify as checks
from brdfnorm.cli import main
from brdfnorm.errors import ArgumentError
from brdfnorm.models import closed_forms

REQUIRED = {
    "phong-original", "phong-modified", "blinn-phong-normal", "blinn-phong-n+8-approximation",
    "phong-peak-at-normal", "blinn-phong-peak-at-normal", "bp-half-vector-length", "bp-spherical-form",
    "bp-delta-theta-2f1", "bp-hypergeometric-series", "bp-weierstrass", "stokes-cosine", "stokes-z-cubed-fails",
    "divergence-cosine", "gaussian-fit", "gaussian-fit-small-n-error", "gaussian-hyperbola-beats-line",
}  # fmt: skip


@pytest.fixture(scope="module")
def claims() -> dict[str, checks.Claim]:
    return {c.id: c for c in checks.verify()}


def test_every_required_claim_is_present_and_holds(claims):
    assert REQUIRED <= set(claims) and len(claims) >= 14
    failing = {i: c.detail for i, c in claims.items() if not c.ok}
    assert not failing


def test_closed_form_claims_agree_to_quadrature_precision(claims):
    for claim_id in ("phong-original", "phong-modified", "blinn-phong-normal", "bp-spherical-form"):
        claim = claims[claim_id]
        assert claim.rel_error <= 1e-10 and len(claim.cases) == len(checks.DEFAULT_EXPONENTS)


def test_folklore_error_matches_its_maximum(claims):
    def error(log_n):
        n = np.exp(log_n)
        return -abs((n + 8) * (2 ** (-n / 2) + n) / ((n + 2) * (n + 4)) - 1)

    best = minimize_scalar(error, bounds=(np.log(0.5), np.log(100)), method="bounded", options={"xatol": 1e-10})
    claim = claims["blinn-phong-n+8-approximation"]
    assert claim.rel_error == pytest.approx(-best.fun, rel=1e-4)
    assert claim.rel_error == pytest.approx(0.0752, abs=1e-4)


def test_stokes_z_cubed_shows_both_values(claims):
    claim = claims["stokes-z-cubed-fails"]
    assert claim.ok
    assert abs(claim.formula_value) <= 1e-12  # F̄ vanishes on the base circle z = 0
    assert claim.numeric_value == pytest.approx(2 * np.pi / 5, rel=1e-13)


def test_seed_003_numbers(claims):
    assert claims["gaussian-fit-small-n-error"].rel_error == pytest.approx(0.421, abs=1e-3)
    assert (
        claims["gaussian-hyperbola-beats-line"].formula_value
        < 0.1
        < claims["gaussian-hyperbola-beats-line"].numeric_value
    )


def test_peak_premises_hold_for_both_lobe_families(claims):
    for claim_id in ("phong-peak-at-normal", "blinn-phong-peak-at-normal"):
        assert claims[claim_id].ok and "holds for every n" in claims[claim_id].detail


def test_phong_one_dimensional_route_matches_hemisphere_cubature():
    from brdfnorm.engine.methods import albedo
    from brdfnorm.models import PhongModified, PhongOriginal

    n, theta = np.array([0.5, 7.0, 300.0]), np.radians(70.0)
    for original, cls in ((True, PhongOriginal), (False, PhongModified)):
        cubature = albedo(cls(n=n[:, None]), theta, method="quadrature", rtol=1e-12).value.ravel()
        np.testing.assert_allclose(seed000.phong_energy(original, n, theta), cubature, rtol=1e-10)


def test_perturbed_formula_fails(monkeypatch):
    monkeypatch.setattr(closed_forms, "phong_original_albedo_normal", lambda n: 2 * np.pi / (np.asarray(n) + 1.001))
    assert not checks.verify([10.0], only=["phong-original"])[0].ok


def test_folklore_claim_fails_if_the_folklore_were_exact(monkeypatch):
    monkeypatch.setattr(
        closed_forms, "blinn_phong_folklore_factor", lambda n: 1 / closed_forms.blinn_phong_albedo_normal(n)
    )
    assert not checks.verify(only=["blinn-phong-n+8-approximation"])[0].ok


def test_stokes_failure_claim_fails_for_a_divergence_free_field(monkeypatch):
    # G = (0, 0, x²) is divergence-free: Stokes then works, so "it fails" is not reproduced.
    def field(r):
        out = np.zeros(np.shape(r))
        out[..., 2] = np.asarray(r)[..., 0] ** 2
        return out

    monkeypatch.setattr(seed002, "z_cubed_field", field)
    assert not checks.verify(only=["stokes-z-cubed-fails"])[0].ok


def test_bad_exponents_and_ids_raise():
    with pytest.raises(ArgumentError):
        checks.verify([-1.0])
    with pytest.raises(ArgumentError):
        checks.verify(only=["no-such-claim"])


def run(args: list[str]) -> int:
    try:
        main(args)
    except SystemExit as done:
        return int(done.code or 0)
    return 0


def test_cli_json_shape(capsys):
    assert run(["verify", "--json", "--n", "2,20", "--claim", "phong-modified", "--claim", "stokes-cosine"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [c["id"] for c in data["claims"]] == ["phong-modified", "stokes-cosine"]
    for claim in data["claims"]:
        assert {"id", "source", "statement", "formula_value", "numeric_value", "rel_error", "ok"} <= set(claim)
        assert claim["ok"] is True
    assert [case["n"] for case in data["claims"][0]["cases"]] == [2.0, 20.0]


def test_cli_table_and_errors(capsys):
    assert run(["verify", "--claim", "divergence-cosine"]) == 0
    assert "divergence-cosine" in capsys.readouterr().out
    assert run(["verify", "--n", "abc"]) == 2
    assert capsys.readouterr().err.startswith("error: --n:")


def test_cli_exit_status_reports_a_failing_claim(monkeypatch, capsys):
    monkeypatch.setattr(closed_forms, "phong_modified_albedo_normal", lambda n: 2 * np.pi / (np.asarray(n) + 2.5))
    assert run(["verify", "--json", "--claim", "phong-modified"]) == 1
    assert json.loads(capsys.readouterr().out)["claims"][0]["ok"] is False
