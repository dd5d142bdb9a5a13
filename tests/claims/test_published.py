"""``brdfnorm verify``'s second group, the field's published numbers (brdfnorm.claims.published): every verdict
holds, the measured numbers are where an independent computation here puts them, and the checks can fail."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import optimize

from brdfnorm.claims import published
from brdfnorm.claims import verify as checks
from brdfnorm.models import fon

IDS = list(published.CHECKS)


@pytest.fixture(scope="module")
def claims() -> dict:
    return {c.id: c for c in checks.verify(only=IDS)}


def test_every_published_claim_holds_and_is_grouped(claims):
    assert set(claims) == set(IDS)
    assert all(c.ok for c in claims.values()), {i: c.detail for i, c in claims.items() if not c.ok}
    assert {c.group for c in claims.values()} == {"published numbers"}
    assert checks.verify(only=["phong-original"])[0].group == "seed claims"


def test_measured_numbers(claims):
    assert claims["ggx-normal-alpha-1"].formula_value == pytest.approx(1 - np.log(2), rel=1e-15)
    furnace = {(c["roughness"], c["mu"]): c["numeric_value"] for c in claims["ggx-furnace-numbers"].cases}
    assert furnace[(0.5, 0.5)] == pytest.approx(0.857263436, abs=1e-9)
    assert furnace[(1.0, 1.0)] == pytest.approx(1 - np.log(2), abs=1e-12)
    # The fit's error maximum, again by scipy's differential evolution over (μ, r) (another optimizer, no grid).
    found = optimize.differential_evolution(
        lambda x: -abs(fon.fon_albedo_approx(x[0], x[1]) - fon.fon_albedo_exact(x[0], x[1])),
        [(1e-4, 1.0), (0.0, 1.0)], seed=3, tol=1e-12, polish=True)
    assert claims["eon-approx-albedo-error"].formula_value == pytest.approx(-found.fun, rel=1e-6)
    assert 1e-4 < claims["eon-approx-furnace-excess"].formula_value < 2e-4


def test_perturbed_formulas_fail(monkeypatch):
    monkeypatch.setattr(fon, "fon_albedo_exact", lambda mu, r: 1.001 / (1 + fon.C1 * r) + r / np.pi
                        / (1 + fon.C1 * r) * fon.fon_g(mu))
    assert not checks.verify(only=["fon-albedo-closed-form"])[0].ok
    monkeypatch.undo()
    monkeypatch.setattr(published, "FURNACE_NUMBERS", {(0.5, 0.5): 0.858, (1.0, 1.0): 0.307})
    assert not checks.verify(only=["ggx-furnace-numbers"])[0].ok


def test_cli_json_has_groups(run_cli):
    code, out, err = run_cli("verify", "--json", "--claim", "schlick-f-avg", "--claim", "phong-original")
    assert code == 0, err
    groups = {c["id"]: c["group"] for c in json.loads(out)["claims"]}
    assert groups == {"schlick-f-avg": "published numbers", "phong-original": "seed claims"}
