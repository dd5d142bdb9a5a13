"""`roughness` wherever α goes on the microfacet lobes (issue 31): α = roughness², as engines and .brdf files
index their tables; recorded in a table's metadata; unknown names answered with "did you mean"."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.errors import ParameterError


@pytest.mark.parametrize("name", ["ggx", "beckmann"])
def test_roughness_parameter_is_alpha_squared(name):
    r = np.array([0.1, 0.5, 0.9])[:, None]
    theta = np.radians([0.0, 60.0, 85.0])
    by_roughness = bn.albedo(bn.load(name, roughness=r), theta, rtol=1e-10).value
    by_alpha = bn.albedo(bn.load(name, alpha=r**2), theta, rtol=1e-10).value
    np.testing.assert_array_equal(by_roughness, by_alpha)
    assert bn.load(name, roughness=0.5).params["alpha"] == 0.25
    assert bn.load(name).with_params(roughness=0.3).params["alpha"] == pytest.approx(0.09, rel=1e-15)


def test_roughness_table_axis_and_metadata():
    roughness = [0.2, 0.6, 1.0]
    a = lut.compute(bn.load("ggx"), {"mu": [0.3, 1.0], "roughness": roughness}, rtol=1e-9)
    b = lut.compute(bn.load("ggx"), {"mu": [0.3, 1.0], "alpha": np.square(roughness)}, rtol=1e-9)
    np.testing.assert_array_equal(a["E"], b["E"])
    np.testing.assert_array_equal(a["E_avg"], b["E_avg"])
    assert list(a.axes) == ["mu", "roughness"] and list(a.axes["roughness"]) == roughness
    assert a.meta["aliases"] == {"roughness": "alpha = roughness²"} and "alpha" not in a.meta["parameters"]


def test_unknown_names_get_did_you_mean():
    with pytest.raises(ParameterError, match="did you mean 'roughness'"):
        bn.load("ggx", roughnes=0.5)
    with pytest.raises(ParameterError, match="did you mean 'alpha'"):
        bn.load("beckmann", alpah=0.5)
    with pytest.raises(ParameterError, match="give alpha or roughness, not both"):
        bn.load("ggx", roughness=0.5, alpha=0.2)
    with pytest.raises(ParameterError, match="did you mean 'alpha'"):
        bn.load("ggx").parameter("alfa")
    # sweeps and searches run over the parameter itself: said in one line, not "unknown parameter"
    with pytest.raises(ParameterError, match=r"roughness is not a parameter of its own here \(alpha = roughness²\)"):
        bn.load("ggx").parameter("roughness")


@pytest.mark.slow
def test_command_line(tmp_path):
    env = {**os.environ}

    def cli(*args):
        return subprocess.run([sys.executable, "-m", "brdfnorm", *args], capture_output=True, text=True,
                              timeout=120, cwd=tmp_path, env=env)

    ok = cli("albedo", "ggx", "-p", "roughness=0.5", "--theta", "30", "--csv")
    ref = cli("albedo", "ggx", "-p", "alpha=0.25", "--theta", "30", "--csv")
    assert ok.returncode == 0 and ok.stdout.splitlines()[1] == ref.stdout.splitlines()[1]
    bad = cli("albedo", "ggx", "-p", "roughnes=0.5", "--theta", "30")
    assert bad.returncode == 2 and bad.stderr.strip().endswith("did you mean 'roughness'?")
