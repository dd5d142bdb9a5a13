"""Hostile command lines outside the GLSL compiler (issue 14, classes 2, 6, 7, 10): clear limits instead of
MemoryError, non-finite reports that name the real (L, V) pair and the file as given, no numpy warning on the
terminal, FIFOs neither read (hang) nor replaced, and output paths that are never clobbered."""

from __future__ import annotations

import os
import stat
import subprocess
import sys

import numpy as np
import pytest
from helpers.paths import REPO

import brdfnorm as bn
from brdfnorm.errors import EvaluationError
from brdfnorm.models.base import Model

ROOT = REPO
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
DIVISION_BY_ZERO = ("analytic\n::begin parameters\nfloat n 1 100 10\n::end parameters\n::begin shader\n"
                    "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(1.0 / (dot(N, L) - dot(N, L))); }"
                    "\n::end shader\n")


def _one_line_error(code: int, err: str, *needles: str) -> None:
    assert code == 2, err
    assert err.startswith("error: ") and err.count("\n") == 1, err
    for needle in needles:
        assert needle in err, err


@pytest.mark.parametrize("argv, needle", [
    (["albedo", "lambert", "--theta", "0:89:10000000000000"], "--theta"),
    (["normalize", "blinn-phong", "--sweep", "n=1:1e4:100000000"], "--sweep"),
    (["normalize", "blinn-phong", "--at", "view", "--theta", "0:80:2000000"], "--theta"),
    (["fit", "blinn-phong", "--sweep", "n=1:1e4:100000000"], "--sweep"),
    (["albedo", "lambert", "--theta", "0:80:1e4"], "whole number"),
    (["albedo", "lambert", "--theta", "0:80:-5"], "at least 1"),
    (["albedo", "lambert", "--rtol", "nan"], "--rtol"),
    (["albedo", "lambert", "--phi", "inf"], "--phi"),
    (["normalize", "blinn-phong", "--at", "view", "--theta", "0:89:5000", "--sweep", "n=1:10:5000"], "limit"),
])
def test_huge_or_bad_counts_are_a_clear_limit_error(argv, needle, run_cli):
    code, out, err = run_cli(*argv)
    _one_line_error(code, err, needle)
    assert out == ""


def test_nonfinite_report_names_the_file_as_given_and_a_real_pair(tmp_path):
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "division_by_zero.brdf").write_text(DIVISION_BY_ZERO)
    done = subprocess.run([sys.executable, "-m", "brdfnorm", "albedo", "sub/division_by_zero.brdf", "--theta", "0"],
                          cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=120)
    _one_line_error(done.returncode, done.stderr, "error: sub/division_by_zero.brdf: ", "L=(", "V=(0, 0, 1)")
    assert "nan, nan" not in done.stderr and "Warning" not in done.stderr


class _Huge(Model):
    """A BRDF of 2e307 everywhere: finite, but its sums overflow float64."""

    name = "huge"

    def evaluate(self, L, V, params):
        return np.full(np.broadcast_shapes(L.shape[:-1], V.shape[:-1]) + (1,), 2e307)


def test_huge_finite_values_integrate_and_numpy_stays_quiet(recwarn):
    """2e307 is finite: ∫ 2e307 (N·L) dL = 2e307·π ≈ 6.3e307 < 1.8e308, though naive sums of it overflow."""
    with np.errstate(all="warn"):
        result = bn.albedo(_Huge(), [0.3, 1.2])
    np.testing.assert_allclose(result.value[:, 0], 2e307 * np.pi, rtol=1e-12)
    assert np.all(result.converged) and np.all(result.error[:, 0] <= 1e-9 * result.value[:, 0])
    assert not [w for w in recwarn if issubclass(w.category, RuntimeWarning)]


def test_a_brdf_nan_everywhere_is_reported_at_a_real_pair():
    """The lobe search finds no peak in NaN values; the report still names a real (L, V) pair, never NaN."""

    class AllNaN(_Huge):
        def evaluate(self, L, V, params):
            return super().evaluate(L, V, params) * np.nan

    with pytest.raises(EvaluationError, match=r"not finite \(value \[nan\]\) at L=\(") as caught:
        bn.albedo(AllNaN(), 0.3)
    assert "nan," not in str(caught.value) and "V=(0.295520207, 0, 0.955336489)" in str(caught.value)


def test_an_albedo_beyond_float64_is_an_evaluation_error():
    class Beyond(_Huge):
        def evaluate(self, L, V, params):
            return super().evaluate(L, V, params) * 5.0  # 1e308: the albedo, π·1e308, is not a float64

    with pytest.raises(EvaluationError, match="exceeds float64's range"):
        bn.albedo(Beyond(), 0.3)


@pytest.mark.parametrize("command", ["albedo", "info"])
def test_a_fifo_as_model_file_is_refused_without_reading_it(tmp_path, command):
    fifo = tmp_path / "model.brdf"
    os.mkfifo(fifo)
    done = subprocess.run([sys.executable, "-m", "brdfnorm", command, str(fifo)], env=ENV, capture_output=True,
                          text=True, timeout=60)
    _one_line_error(done.returncode, done.stderr, str(fifo), "not a regular file")


def test_output_to_dev_null_and_to_a_fifo_keeps_them(tmp_path, run_cli):
    code, _, err = run_cli("normalize", "lambert", "--json", "-o", "/dev/null")
    assert code == 0, err
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    code, _, err = run_cli("normalize", "lambert", "--json", "-o", str(fifo))
    _one_line_error(code, err, str(fifo), "no reader")
    assert stat.S_ISFIFO(fifo.stat().st_mode)


def test_output_keeps_an_existing_files_mode_and_a_symlink(tmp_path, run_cli):
    real = tmp_path / "real.json"
    real.write_text("{}")
    real.chmod(0o640)
    link = tmp_path / "link.json"
    link.symlink_to(real)
    code, _, err = run_cli("normalize", "lambert", "--json", "-o", str(link))
    assert code == 0, err
    assert link.is_symlink() and '"factor"' in real.read_text() and stat.S_IMODE(real.stat().st_mode) == 0o640


@pytest.mark.slow
@pytest.mark.parametrize("target", ["", "."])
def test_report_refuses_dangerous_output_directories(tmp_path, target):
    (tmp_path / "keep.txt").write_text("precious")
    done = subprocess.run([sys.executable, "-m", "brdfnorm", "report", "lambert", "-o", target], cwd=tmp_path,
                          env=ENV, capture_output=True, text=True, timeout=120)
    _one_line_error(done.returncode, done.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.txt"]


def test_error_messages_quote_at_most_40_characters_of_a_value(run_cli):
    code, _, err = run_cli("albedo", "lambert", "--theta", "x" * 500)
    _one_line_error(code, err, "--theta")
    assert "x" * 41 not in err


@pytest.mark.slow
def test_report_draws_a_mathtext_unsafe_file_name_as_text(tmp_path):
    name = "a$\\foo{$b.brdf"
    (tmp_path / name).write_text((ROOT / "examples" / "lambert.brdf").read_text())
    done = subprocess.run([sys.executable, "-m", "brdfnorm", "report", name, "--sweep", "reflectance=0.5,1", "-o",
                           "out"], cwd=tmp_path, env=ENV, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / "index.html").is_file()
    assert "a$\\foo{$b" in (tmp_path / "out" / "index.html").read_text(encoding="utf-8")


@pytest.mark.parametrize("argv", [
    ["albedo", "lambert", "--theta", "0:89:10000000000000"],
    ["normalize", "blinn-phong", "--sweep", "n=1:1e4:100000000"],
    ["normalize", "blinn-phong", "--at", "view", "--theta", "0:89:999999", "--sweep", "n=1:10:999999"],
])
def test_huge_counts_end_in_exit_2_under_a_2_gb_address_space_limit(argv):
    limit = 2 * 1024**3
    code = (f"import resource, sys; resource.setrlimit(resource.RLIMIT_AS, ({limit}, {limit})); "
            "from brdfnorm.cli import main; main(sys.argv[1:])")
    env = {**ENV, "OPENBLAS_NUM_THREADS": "1", "OMP_NUM_THREADS": "1"}
    done = subprocess.run([sys.executable, "-c", code, *argv], env=env, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr  # a clean exit, not a signal (negative) or MemoryError (1)
    assert done.stderr.startswith("error: ") and "limit" in done.stderr


@pytest.mark.parametrize("argv", [
    ["albedo", "{path}", "--theta", "0"],
    ["normalize", "{path}"],
    ["info", "{path}", "--samples", "16"],
    ["fit", "{path}", "--sweep", "reflectance=0.2:1:6", "--form", "linear"],
])
def test_file_names_are_text_not_rich_markup(tmp_path, monkeypatch, argv, run_cli):
    """A name such as `[a]x[/a]b.brdf` is printed as it is: rich markup would drop `[a]` or fail on `[/a]`."""
    (tmp_path / "[a]x[").mkdir()
    (tmp_path / "[a]x[" / "a]b.brdf").write_text((ROOT / "examples" / "lambert.brdf").read_text())
    monkeypatch.chdir(tmp_path)
    code, out, err = run_cli(*(a.format(path="[a]x[/a]b.brdf") for a in argv))
    assert code == 0, err
    assert "a]b" in out + err and "internal error" not in err
    if argv[0] == "info":
        assert "[a]x[/a]b.brdf" in out


@pytest.mark.slow
def test_three_concurrent_reports_to_one_directory_all_succeed_and_leave_nothing_behind(tmp_path):
    argv = [sys.executable, "-m", "brdfnorm", "report", "lambert", "--sweep", "reflectance=0.5,1", "-o", "same"]
    runs = [subprocess.Popen(argv, cwd=tmp_path, env=ENV, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
            for _ in range(3)]
    errors = [run.communicate(timeout=300)[1] for run in runs]
    assert [run.returncode for run in runs] == [0, 0, 0], errors
    assert sorted(p.name for p in tmp_path.iterdir()) == ["same"]
    assert (tmp_path / "same" / "index.html").is_file()
