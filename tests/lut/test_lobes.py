"""``lut`` on the new lobes and the cloth channel of ``--channels dfg``, against closed forms (FON's albedo and
average, EON's white furnace, the cloth channel at μ = 1 by a 1-D integral written here) and the sheen lobe's
``.brdf`` twin."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers.paths import EXAMPLES
from scipy import integrate

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.models.fon import fon_albedo_exact, fon_average_exact


@pytest.mark.slow
def test_fon_and_eon_tables_against_closed_forms():
    # rtol 1e-7: at 1e-9 the generic cubature's E_avg for FON (r = 1) is off by 2.6e-9 with an error estimate of
    # 4.7e-10 — see test_lobes_diffuse.py::test_engine_error_estimate_on_fons_kinks (a known engine limitation).
    mu, r = np.array([0.05, 0.5, 1.0]), np.array([0.0, 0.6, 1.0])
    table = lut.compute(bn.load("fon"), {"mu": mu, "roughness": r}, rtol=1e-7)
    np.testing.assert_allclose(table["E"], fon_albedo_exact(mu[:, None], r[None, :]), atol=1e-7)
    np.testing.assert_allclose(table["E_avg"], fon_average_exact(r), atol=1e-7)
    white = lut.compute(bn.load("eon"), {"mu": mu, "roughness": r}, rtol=1e-7)
    np.testing.assert_allclose(white["E"], 1.0, atol=1e-7)
    np.testing.assert_allclose(white["E_avg"], 1.0, atol=1e-7)


def test_cli_charlie_table_matches_the_brdf_file(tmp_path, run_cli):
    out = tmp_path / "charlie.json"
    code, _, err = run_cli("lut", "charlie", "--axis", "mu=0.2,1", "--axis", "roughness=0.5,1",
                           "--no-average", "--rtol", "1e-9", "-o", str(out))
    assert code == 0, err
    data = json.loads(out.read_text())
    assert data["meta"]["model"] == "charlie" and data["meta"]["parameters"]["shadowing"] == "kulla"
    file = bn.load(EXAMPLES / "charlie.brdf", roughness=np.array([[0.5, 1.0]]))
    expected = bn.albedo(file, np.arccos(np.array([[0.2], [1.0]])), rtol=1e-10).value[..., 0]
    np.testing.assert_allclose(np.array(data["tables"]["E"]), expected, atol=1e-8)


def _cloth_at_normal(alpha: float) -> float:
    """∫ D V cos dL at V = N: θ_H = θ_L/2 and N·L + N·V − N·L N·V = 1, so 2π ∫ D(θ/2) cos θ sin θ / 4 dθ."""
    def integrand(theta):
        d = (2 + 1 / alpha) * np.sin(theta / 2) ** (1 / alpha) / (2 * np.pi)
        return 2 * np.pi * d * np.cos(theta) * np.sin(theta) / 4

    return integrate.quad(integrand, 0, np.pi / 2, epsabs=0, epsrel=1e-13)[0]


def test_dfg_gains_the_cloth_channel():
    table = lut.compute(bn.load("ggx"), {"mu": [0.3, 1.0], "alpha": [0.5, 1.0]}, channels=("dfg",), rtol=1e-10,
                        average=False)
    assert {"DFG_f0", "DFG_f90", "DFG_cloth", "DFG_cloth_error"} <= set(table)
    assert table["DFG_cloth"][1, 0] == pytest.approx(1 / 12, abs=1e-10)  # α = 1/2: D = (1 − cos θ_L)/π at V = N
    assert table["DFG_cloth"][1, 1] == pytest.approx(_cloth_at_normal(1.0), abs=1e-10)
    sheen = bn.albedo(bn.load("charlie", alpha=0.5, shadowing="neubelt"), np.arccos(0.3), rtol=1e-10).value[0]
    assert table["DFG_cloth"][0, 0] == pytest.approx(sheen, abs=1e-10)
    assert "DFG_cloth" in table.meta["dfg"]
    other = lut.compute(bn.load("ggx"), {"mu": [1.0], "alpha_x": [0.5]}, channels=("dfg",), rtol=1e-8, average=False)
    assert "DFG_cloth" not in other  # the cloth lobe has no alpha_x: only alpha/roughness axes carry over


def test_cli_three_channel_dfg_table_round_trips_through_npz(tmp_path, run_cli):
    out = tmp_path / "dfg.npz"
    code, _, err = run_cli("lut", "ggx", "--axis", "mu=0.25,1", "--axis", "alpha=0.5,1", "--channels", "dfg",
                           "--no-average", "--rtol", "1e-9", "-o", str(out))
    assert code == 0, err
    table = lut.load(out)
    assert {"DFG_f0", "DFG_f90", "DFG_cloth"} <= set(table) and "DFG_cloth" in table.meta["dfg"]
    assert table["DFG_cloth"][1, 0] == pytest.approx(1 / 12, abs=1e-9)
    # The split-sum pair still sums to E (the Schlick weights add to 1), the cloth channel is separate.
    np.testing.assert_allclose(table["DFG_f0"] + table["DFG_f90"], table["E"], atol=1e-9)
