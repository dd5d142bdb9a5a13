"""The core commands as a user runs them: output formats, numbers, and one-line errors."""

from __future__ import annotations

import json

import numpy as np
import pytest

from brdfnorm.models import closed_forms


def test_albedo_json_matches_the_closed_form(run_cli):
    code, out, _ = run_cli("albedo", "blinn-phong", "-p", "n=512", "--theta", "0", "--method", "quadrature",
                       "--rtol", "1e-12", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["model"] == "blinn-phong" and data["params"] == {"n": 512.0}
    (row,) = data["results"]
    assert {"theta_deg", "phi_deg", "albedo", "error_estimate", "method"} <= row.keys()
    assert abs(row["albedo"] / closed_forms.blinn_phong_albedo_normal(512) - 1) < 1e-12
    assert f"{row['albedo']:.15f}".startswith("0.04851734197924")


def test_albedo_theta_ranges_are_inclusive(run_cli):
    code, out, _ = run_cli("albedo", "lambert", "--theta", "0:80:5", "--json")
    assert code == 0
    rows = json.loads(out)["results"]
    assert [r["theta_deg"] for r in rows] == [0, 20, 40, 60, 80]
    np.testing.assert_allclose([r["albedo"] for r in rows], 1.0, rtol=1e-10)


def test_albedo_table_is_readable(run_cli):
    code, out, _ = run_cli("albedo", "modified-phong", "-p", "n=10", "--theta", "0")
    assert code == 0
    assert "0.523598775598" in out  # 2π/12, printed to 12 digits, not truncated


def test_normalize_json_and_csv(run_cli):
    code, out, _ = run_cli("normalize", "phong", "--sweep", "n=1:100:3:log", "--at", "normal", "--json")
    assert code == 0
    data = json.loads(out)
    values = [r["params"]["n"] for r in data["results"]]
    np.testing.assert_allclose(values, [1, 10, 100])
    for row in data["results"]:
        assert row["at"] == "normal"
        assert abs(row["factor"] / ((row["params"]["n"] + 1) / (2 * np.pi)) - 1) < 1e-9
    code, out, _ = run_cli("normalize", "blinn-phong", "--sweep", "n=8,64", "--csv")
    lines = out.strip().splitlines()
    assert lines[0].startswith("n,theta_deg")
    factor = float(lines[2].split(",")[5])
    assert abs(factor * closed_forms.blinn_phong_albedo_normal(64) - 1) < 1e-9


def test_normalize_writes_output_atomically(tmp_path, run_cli):
    target = tmp_path / "factors.json"
    code, _, _ = run_cli("normalize", "lambert", "--json", "-o", str(target))
    assert code == 0 and json.loads(target.read_text())["results"][0]["factor"] == pytest.approx(1.0)
    before = target.read_text()
    code, _, err = run_cli("normalize", "lambert", "--sweep", "reflectance=0.5,2", "--json", "-o", str(target))
    assert code == 2 and target.read_text() == before
    assert not [p for p in tmp_path.iterdir() if p.name != "factors.json"]


@pytest.mark.parametrize(
    ("argv", "where"),
    [
        (["albedo", "blinn-phong", "-p", "n=abc"], "parameter n"),
        (["albedo", "blinn-phong", "-p", "q=1"], "unknown parameter 'q'"),
        (["albedo", "blinn-phong", "-p", "n"], "-p"),
        (["albedo", "blinn-phong", "-p", "n=-1"], "parameter n"),
        (["albedo", "blinn-phong", "--theta", "90"], "--theta"),
        (["albedo", "blinn-phong", "--theta", "-5"], "--theta"),
        (["albedo", "blinn-phong", "--theta", "a:b:c"], "--theta"),
        (["albedo", "blinn-phong", "--rtol", "0"], "--rtol"),
        (["albedo", "blinn-phong", "--rtol", "-1e-3"], "--rtol"),
        (["albedo", "blinn-phong", "--rtol", "5"], "--rtol"),
        (["albedo", "blinn-phong", "--rtol", "1e-30"], "--rtol"),
        (["albedo", "no-such-model"], "MODEL"),
        (["albedo", "missing/file.brdf"], "missing/file.brdf"),
        (["albedo", "blinn-phong", "--method", "simpson"], "--method"),
        (["albedo", "blinn-phong-gaussian", "--theta", "0", "--method", "closed-form"], "--method"),
        (["normalize", "blinn-phong", "--sweep", "n=10:1:5"], "--sweep"),
        (["normalize", "blinn-phong", "--sweep", "n=1:10:0"], "--sweep"),
        (["normalize", "blinn-phong", "--sweep", "n"], "--sweep"),
        (["normalize", "blinn-phong", "--sweep", "n=0:10:3:log"], "--sweep"),
        (["normalize", "blinn-phong", "--sweep", "m=1,2"], "unknown parameter"),
        (["normalize", "blinn-phong", "--json", "-o", "/nonexistent-dir/x.json"], "/nonexistent-dir/x.json"),
        (["albedo", "blinn-phong", "--bogus"], "--bogus"),
        (["normalize", "blinn-phong", "--at", "middle"], "--at"),
    ],
)
def test_bad_input_is_one_line_with_exit_code_2(argv, where, run_cli):
    code, out, err = run_cli(*argv)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and where in lines[0], err
    assert "Traceback" not in err


def test_models_lists_every_builtin(run_cli):
    code, out, _ = run_cli("models")
    assert code == 0
    for name in ("lambert", "phong", "modified-phong", "blinn-phong", "blinn-phong-gaussian"):
        assert name in out
