"""Material files (brdfnorm.materials.files): TOML and JSON, validated, errors at FILE:LINE, usable by the commands."""

import json
import subprocess
import sys

import numpy as np
import pytest
from helpers import paths

import brdfnorm as bn
from brdfnorm.materials.files import MaterialFileError

EXAMPLES = paths.EXAMPLES / "materials"


def test_toml_and_json_bind_their_parameters(tmp_path):
    paint = bn.load(EXAMPLES / "car_paint.toml")
    assert paint.name == "openpbr" and paint.params["coat_weight"] == 1.0
    assert paint.params["base_color"] == (0.6, 0.05, 0.05)
    default = bn.load(EXAMPLES / "openpbr_default.json")
    assert default.params == bn.load("openpbr").params
    override = bn.load(EXAMPLES / "car_paint.toml", coat_weight=0.5)
    assert override.params["coat_weight"] == 0.5
    furnace = bn.albedo(bn.load(EXAMPLES / "white_furnace_coat.toml"), np.radians([0.0, 60.0, 89.0]))
    assert np.all(np.abs(furnace.value - 1.0) <= 1e-9)


@pytest.mark.parametrize("text,suffix,where,message", [
    ('model = "openpbr"\n[parameters]\nbase_color = [1, 1, 1]\ncoat_wieght = 1.0\n', ".toml", ":4",
     "did you mean 'coat_weight'"),
    ('model = "openpbr"\n[parameters]\nbase_color = [1, 1]\n', ".toml", ":3", "3 components"),
    ('model = "openpbr"\n[parameters]\ncoat_weight = 2.0\n', ".toml", ":3", r"outside \[0, 1\]"),
    ('model = "openpbr"\n[parameters\n', ".toml", ":2:", "invalid TOML"),
    ('model = "openpbr"\nlayer = 3\n', ".toml", ":2", "unknown key 'layer'"),
    ('{"model": "ggx", "parameters": {}}', ".json", "", "unknown material model 'ggx'"),
    ('{"model": "openpbr",\n "parameters": {\n  "layering": "sideways"}}', ".json", ":3", "expected one of view"),
    ('{"model": "openpbr", "parameters": [1]', ".json", ":1:", "invalid JSON"),
    ('parameters = {}\n', ".toml", ":1", "'model' must name"),
])
def test_errors_name_the_line(tmp_path, text, suffix, where, message):
    path = tmp_path / f"m{suffix}"
    path.write_text(text)
    with pytest.raises(MaterialFileError, match=message) as caught:
        bn.load(path)
    assert str(caught.value).startswith(f"{path}{where}")


def test_cli_one_line_error_and_commands(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('model = "openpbr"\n[parameters]\nfuzz_weight = "lots"\n')
    run = subprocess.run([sys.executable, "-m", "brdfnorm", "albedo", str(bad), "--theta", "0"], capture_output=True,
                         text=True, timeout=120)
    assert run.returncode == 2 and run.stderr.strip().count("\n") == 0 and f"{bad}:3" in run.stderr
    out = tmp_path / "lut.json"
    run = subprocess.run([sys.executable, "-m", "brdfnorm", "lut", str(EXAMPLES / "white_furnace_coat.toml"),
                          "--axis", "mu=0.2:1:3", "--axis", "coat_roughness=0.3:0.6:2", "-o", str(out)],
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr
    assert np.allclose(json.loads(out.read_text())["tables"]["E"], 1.0, atol=1e-9)


def test_explorer_opens_materials():
    from brdfnorm.explore import compute
    from brdfnorm.explore.catalog import Catalog

    catalog = Catalog.build([str(EXAMPLES / "white_furnace_coat.toml")], examples=None)
    assert "builtin:openpbr" in [entry.id for entry in catalog.entries()]
    for model_id in ("arg0", "builtin:openpbr"):
        view = compute.evaluate_view(catalog.get(model_id), 30.0, "normal", "coarse")
        assert view["channels"] == 3 and not view["warnings"]
