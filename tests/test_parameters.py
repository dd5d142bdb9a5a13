"""Parameter kinds (issue 31 item 5): η, k and f0 are per-channel numbers (``spectrum``), not colours; table sizes
are whole numbers (``int``); ``models``, ``info``, ``check`` and the explorer read one declaration; a spectrum is
a lookup-table axis, each cell checked against scipy's own integral of the lobe."""

from __future__ import annotations

import json

import numpy as np
import pytest
from helpers.references import dblquad_albedo

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.check.space import parameter_space
from brdfnorm.errors import ParameterError
from brdfnorm.explore.compute import bind_parameters, check_command, describe_parameters


def test_ggx_declares_spectra_and_a_whole_table_size():
    model = bn.load("ggx")
    kinds = {p.name: p.declaration() for p in model.parameters}
    for name in ("eta", "k", "f0", "f90"):
        assert kinds[name]["kind"] == "spectrum" and kinds[name]["channels"] == 3 and not kinds[name]["integer"]
    assert kinds["eta"]["minimum"] == 1e-3 and kinds["eta"]["maximum"] == 1e3 and kinds["eta"]["default"] == [1.5] * 3
    assert kinds["ms_table"]["kind"] == "int" and kinds["ms_table"]["integer"] and kinds["ms_table"]["default"] == 32
    assert kinds["alpha"]["channels"] == 1 and kinds["alpha"]["kind"] == "float"


def test_spectrum_values_are_numbers_not_colours():
    eta = bn.load("ggx").parameter("eta")
    assert eta.parse("2.5") == (2.5, 2.5, 2.5)  # one number for every channel, above 1
    assert eta.parse("1.45,1.5,1.55") == (1.45, 1.5, 1.55)
    f0 = bn.load("ggx", f0="0.123456789,0.5,0.987654321").params["f0"]
    assert f0 == (0.123456789, 0.5, 0.987654321)  # not quantized to 8 bits
    with pytest.raises(ParameterError, match="outside"):
        bn.load("ggx", f0=1.2)  # a reflectance keeps its declared range
    with pytest.raises(ParameterError, match="whole number"):
        bn.load("ggx", ms_table=32.5)
    assert bn.load("ggx", ms_table="64").params["ms_table"] == 64


def test_models_info_and_explore_read_the_same_declaration(run_cli):
    code, stdout, _ = run_cli("info", "ggx", "--json")
    assert code == 0
    declared = {p["name"]: p for p in json.loads(stdout)["parameters"]}
    for p in bn.load("ggx").parameters:
        assert {k: declared[p.name][k] for k in p.declaration()} == json.loads(json.dumps(p.declaration()))
    explored = {p["name"]: p for p in describe_parameters(bn.load("ggx"))}
    assert explored["eta"]["kind"] == "spectrum" and explored["eta"]["channels"] == 3
    assert explored["eta"]["control"] == "channels" and explored["eta"]["channels"] == 3  # numbers per channel
    assert explored["ms_table"]["control"] == "slider" and explored["ms_table"]["slider"]["step"] == 1
    code, stdout, _ = run_cli("models")
    assert code == 0 and "spectrum" in stdout and "whole" in stdout


def test_explore_binds_per_channel_numbers_and_whole_sizes():
    model = bind_parameters(bn.load("ggx"), {"eta": 2.4, "k": [3.0, 2.5, 2.0], "ms_table": 16, "fresnel": "conductor"})
    assert model.params["eta"] == (2.4, 2.4, 2.4) and model.params["k"] == (3.0, 2.5, 2.0)
    assert model.params["ms_table"] == 16
    command = check_command("ggx", model)
    assert "eta=2.4,2.4,2.4" in command and "ms_table=16" in command
    with pytest.raises(ParameterError):
        bind_parameters(bn.load("ggx"), {"ms_table": 16.5})


def test_check_searches_whole_table_sizes_only():
    space = parameter_space(bn.load("lambert"), None, ())
    assert not any(r.integer for r in space.ranges)

    from brdfnorm.check.space import _Range

    sizes = _Range("n", 2, 1024, False, integer=True).value(np.linspace(0, 1, 101))
    assert np.all(sizes == np.rint(sizes)) and sizes.min() == 2 and sizes.max() == 1024
    assert "whole numbers" in _Range("n", 2, 1024, False, integer=True).describe()


def test_eta_is_a_lut_axis_checked_against_scipy(tmp_path, run_cli):
    table = lut.compute(bn.load("ggx", fresnel="dielectric", alpha=0.5), {"mu": [0.7], "eta": [1.2, 2.5]},
                        rtol=1e-9, average=False)
    assert table["E"].shape == (1, 2) and table.meta["unconverged"] == 0
    for j, eta in enumerate([1.2, 2.5]):
        reference = dblquad_albedo(bn.load("ggx", fresnel="dielectric", alpha=0.5, eta=eta), 0.7, epsrel=1e-9)
        assert abs(table["E"][0, j] - reference) <= 1e-7 * reference, (eta, table["E"][0, j], reference)
    assert table["E"][0, 1] > 4 * table["E"][0, 0]  # η = 2.5 reflects far more than η = 1.2
    out = tmp_path / "eta.npz"
    code, _, stderr = run_cli("lut", "ggx", "-p", "fresnel=dielectric", "-p", "alpha=0.5", "--axis",
                              "mu=0.7", "--axis", "eta=1.2,2.5", "--no-average", "--rtol", "1e-9", "-o", str(out))
    assert code == 0, stderr
    assert np.array_equal(lut.load(out)["E"], table["E"])
