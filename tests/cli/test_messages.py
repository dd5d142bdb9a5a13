"""Messages a new user meets in the first hour (issue 43): one line naming the value, the range and the fix, no
flag name repeated, no numpy or pydantic text; and the range syntax that says what it means (``0:80:n=20``,
``0:80:step=5``, the older ``0:80:20`` still accepted)."""

from __future__ import annotations

import numpy as np
import pytest

from brdfnorm.cli.common import parse_range
from brdfnorm.errors import ArgumentError, ParameterError
from brdfnorm.models import REGISTRY

LEAKS = ("array(", "Value error", "Input should be", "pydantic", "Traceback")


def _one_line_error(run_cli, *argv: str) -> str:
    code, out, err = run_cli(*argv)
    assert code == 2 and out == "" and err.count("\n") == 1 and err.startswith("error: "), (code, out, err)
    assert not any(leak in err for leak in LEAKS), err
    return err


def test_axis_out_of_range_names_value_range_and_clamp(tmp_path, run_cli):
    err = _one_line_error(run_cli, "lut", "ggx", "--axis", "alpha=0:1:8", "--axis", "mu=0.1:1:4",
                          "-o", str(tmp_path / "t.npz"))
    assert "value 0 (1 of 8 values) outside [1e-12, 100]" in err and "--clamp alpha=1e-12" in err, err
    # a roughness axis: the clamp is on roughness, at √1e-12
    err = _one_line_error(run_cli, "lut", "ggx", "--axis", "roughness=0:1:n=8", "--axis", "mu=0.1:1:4",
                          "-o", str(tmp_path / "t.npz"))
    assert "--clamp roughness=1e-06" in err, err
    code, _, err = run_cli("lut", "ggx", "--axis", "roughness=0:1:n=3", "--axis", "mu=0.1:1:3",
                           "--clamp", "roughness=1e-6", "-o", str(tmp_path / "t.npz"), "--no-average")
    assert code == 0, err


def test_clamp_of_an_alias_target_says_which_axis(tmp_path, run_cli):
    err = _one_line_error(run_cli, "lut", "ggx", "--axis", "roughness=0:1:8", "--axis", "mu=0.1:1:4",
                          "--clamp", "alpha=1e-8", "-o", str(tmp_path / "t.npz"))
    assert "--clamp: --clamp" not in err, err  # was "--clamp: --clamp alpha: no axis of that name"
    assert "the axes: roughness, mu" in err and "--clamp roughness=0.0001" in err, err


def test_parameter_value_not_a_numpy_dump():
    parameter = REGISTRY["ggx"]().parameter("alpha")
    with pytest.raises(ParameterError, match=r"value 0 \(2 of 3 values\) outside \[1e-12, 100\]"):
        parameter.validate(np.array([0.0, 0.5, -1.0]))
    with pytest.raises(ParameterError, match=r"value 1000 outside \[1e-12, 100\]$"):
        parameter.validate(1000.0)


@pytest.mark.parametrize(("argv", "expected"), [
    (("normalize", "ggx", "--at", "maximum"), "'maximum' is not one of 'normal', 'max', 'view'; did you mean 'max'?"),
    (("albedo", "ggx", "--rtol", "abc"), "'abc' is not a number"),
    (("albedo", "ggx", "--over", "lite"), "did you mean 'light'?"),
    (("albedo", "ggx", "--rtol", "1e-20"), "--rtol: 1e-20 is below what float64 quadrature can honour"),
])
def test_usage_errors_in_our_words(argv, expected, run_cli):
    assert expected in _one_line_error(run_cli, *argv)


def test_range_syntax():
    np.testing.assert_array_equal(parse_range("0:80:n=5", "--theta", allow_log=False), [0, 20, 40, 60, 80])
    np.testing.assert_array_equal(parse_range("0:80:5", "--theta", allow_log=False), [0, 20, 40, 60, 80])
    np.testing.assert_array_equal(parse_range("0:80:step=20", "--theta", allow_log=False), [0, 20, 40, 60, 80])
    np.testing.assert_array_equal(parse_range("0:89:step=5", "--theta", allow_log=False), np.arange(0, 86, 5))
    stepped = parse_range("0:1:step=0.1", "--theta", allow_log=False)
    assert stepped.size == 11 and stepped[-1] == 1.0
    np.testing.assert_allclose(parse_range("1:1e4:n=5:log", "--sweep", allow_log=True), [1, 10, 100, 1e3, 1e4])
    for bad, words in (("0:80:k=3", "n=COUNT or step=STEP"), ("0:80:step=0", "step must be > 0"),
                       ("0:80:step=5:log", "a log range takes a count"), ("0:80:n=1", "n=1 needs START = STOP"),
                       ("0:1:2:3", "START:STOP:n=COUNT, START:STOP:step=STEP")):
        with pytest.raises(ArgumentError, match=words):
            parse_range(bad, "--theta", allow_log=True)


def test_theta_step_on_the_command_line(run_cli):
    code, out, err = run_cli("albedo", "lambert", "--theta", "0:80:step=20", "--csv")
    assert code == 0, err
    assert [line.split(",")[0] for line in out.splitlines()[1:]] == ["0.0", "20.0", "40.0", "60.0", "80.0"]
