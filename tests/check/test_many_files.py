"""`brdfnorm check` over several files (issue 31): one row per file printed as it finishes, one --budget for the
whole command, and "pass (partial: k of N points)" with exit status 3 when the budget cut the search short."""

from __future__ import annotations

import os
import subprocess
import sys

import pytest
from helpers.paths import EXAMPLES


def test_partial_and_share_units():
    """The verdict text and the budget split, without running a check."""
    from brdfnorm.check import Budget
    from brdfnorm.cli.check import _partial, _share, verdict_text

    class Report:
        status = "pass"
        coverage = {"parameter_points_planned": 96, "energy": {"parameter_points": 7},
                    "pairs": {"parameter_points": 96}}

    assert _partial(Report) == {"points": 7, "of": 96}
    assert verdict_text(Report) == "pass (partial: 7 of 96 points)"
    Report.coverage = {"parameter_points_planned": 96, "energy": {"parameter_points": 96}}
    assert _partial(Report) is None and verdict_text(Report) == "pass"
    assert _share(Budget(seconds=10.0), 4, 2.0, 0).seconds == pytest.approx(2.0)
    assert _share(Budget(seconds=None, evaluations=1000), 2, 0.0, 300).evaluations == 350


def check(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "brdfnorm", "check", *args], capture_output=True, text=True,
                          timeout=300, env={**os.environ, "COLUMNS": "200"})


@pytest.mark.slow
def test_partial_pass_has_its_own_exit_code_and_the_budget_is_shared():
    files = [str(EXAMPLES / "ggx.brdf"), str(EXAMPLES / "lambert.brdf")]
    result = check(*files, "--budget", "6e5evals", "--only", "energy")
    assert result.returncode == 3, result.stderr
    rows = result.stdout.strip().splitlines()
    assert len(rows) == 2 and rows[0].startswith(files[0]) and rows[1].startswith(files[1])
    for row in rows:
        assert "pass (partial: " in row and " of 48 points)" in row
    # one budget for the command: the first file is given half of it, the second what is left
    err = result.stderr.splitlines()
    assert "(budget 3e+05 evaluations)" in err[0]
    assert "(budget 3e+05 evaluations)" not in err[1]


@pytest.mark.slow
def test_rows_stream_as_each_file_finishes():
    """The first file's row is on stdout before the second file's check ends."""
    files = [str(EXAMPLES / "lambert.brdf"), str(EXAMPLES / "ggx.brdf")]
    process = subprocess.Popen([sys.executable, "-m", "brdfnorm", "check", *files, "--budget", "4e6evals",
                                "--only", "energy", "--points", "8"], stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True, env={**os.environ, "COLUMNS": "200"})
    try:
        first = process.stdout.readline()
        assert first.startswith(files[0]) and "pass" in first
        second_done = process.poll() is not None
        out, err = process.communicate(timeout=300)
    finally:
        if process.poll() is None:
            process.kill()
    assert out.startswith(files[1]) and process.returncode in (0, 3), err
    assert not second_done or out  # (when the machine is fast both may be done: the rows still come one by one)


@pytest.mark.slow
@pytest.mark.parametrize("budget", ["1e9evals"])
def test_a_full_search_is_a_plain_pass(budget):
    result = check(str(EXAMPLES / "lambert.brdf"), "--only", "energy", "--points", "4", "--budget", budget)
    assert result.returncode == 0 and "partial" not in result.stdout + result.stderr
