"""The white furnace of materials (brdfnorm.materials.furnace), CI references (brdfnorm.materials.reference), the
``furnace``/``reference`` commands and ``brdfnorm.testing.assert_material_furnace``."""

import json
import subprocess
import sys

import numpy as np
import pytest
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.engine.routes.microfacet import average_albedo as engine_average
from brdfnorm.materials.furnace import furnace
from brdfnorm.materials.reference import reference, to_csv
from brdfnorm.models.microfacet import GGXDistribution
from brdfnorm.testing import assert_material_furnace

FURNACE = EXAMPLES / "materials" / "white_furnace_coat.toml"
THETA = np.radians([0.0, 40.0, 70.0, 85.0])


def test_furnace_reports_the_symmetric_loss_and_its_argmax():
    m = bn.load(FURNACE, layering="symmetric")
    result = furnace(m, THETA, pairs=512)
    e_c = bn.albedo(bn.load("ggx", alpha=0.25), THETA).value[:, 0]
    e_avg = engine_average(GGXDistribution(), "height-correlated", 0.25, rtol=1e-12)[0][0]
    residual = e_c + (1 - e_c) * (1 - e_avg) - 1
    assert result.max_residual == pytest.approx(residual[np.argmax(np.abs(residual))], abs=1e-10)
    assert result.argmax_theta == THETA[np.argmax(np.abs(residual))]
    assert result.reciprocity < 1e-12  # the symmetric rule is reciprocal
    # E_avg of the material: 2∫(E_c + (1 − E_c)(1 − E_avg))μ dμ = E_avg + (1 − E_avg)² (over white Lambert)
    assert result.average[0] == pytest.approx(e_avg + (1 - e_avg) ** 2, abs=max(1e-9, result.average_error[0]))
    view = furnace(bn.load(FURNACE), THETA, pairs=512)
    assert abs(view.max_residual) <= 1e-12 and view.reciprocity > 1e-3  # conserves, not reciprocal


def test_reference_document_and_csv():
    m = bn.load(FURNACE, layering="symmetric")
    document = reference(m, {"coat_weight": [0.0, 1.0]}, [0.25, 1.0])
    assert document["format"] == "brdfnorm-material-reference" and document["brdfnorm"] == bn.__version__
    assert document["material"]["source"] == str(FURNACE) and "albedo" in document["conventions"]
    off, on = document["points"]
    assert np.allclose(off["E"], 1.0, atol=1e-12)  # no coat: white Lambert
    direct = bn.albedo(m, np.arccos([0.25, 1.0])).value
    assert np.allclose(on["E"], direct, atol=0, rtol=0)
    assert on["max_residual"] == pytest.approx((direct - 1).flat[np.argmax(np.abs(direct - 1))], abs=0)
    text = to_csv(document)
    rows = [line for line in text.splitlines() if not line.startswith("#")]
    assert rows[0].startswith("coat_weight,mu,E_R") and len(rows) == 1 + 4


def test_commands(tmp_path):
    run = subprocess.run([sys.executable, "-m", "brdfnorm", "furnace", str(FURNACE), "--theta", "0,60", "--json"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    summary = json.loads(run.stdout)
    assert abs(summary["max_residual"]) <= 1e-12 and len(summary["views"]) == 2
    out = tmp_path / "ref.json"
    run = subprocess.run([sys.executable, "-m", "brdfnorm", "reference", str(FURNACE), "--grid", "coat_weight=0,1",
                          "--mu", "0.5,1", "-o", str(out)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert len(json.loads(out.read_text())["points"]) == 2
    run = subprocess.run([sys.executable, "-m", "brdfnorm", "reference", str(FURNACE), "--grid", "layering=1"],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 2 and "error:" in run.stderr


def test_assertion():
    result = assert_material_furnace(FURNACE, theta=THETA)
    assert np.all(np.abs(result.value - 1) <= 1e-9)
    with pytest.raises(AssertionError, match="fails the white furnace"):
        assert_material_furnace(FURNACE, theta=THETA, layering="symmetric")
