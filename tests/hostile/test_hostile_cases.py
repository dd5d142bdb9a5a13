"""The runner of :mod:`hostile_cases` (issue 35) and :mod:`round_four` (issues 41, 46): each case is one command
in a subprocess, under a 4 GB address-space limit (``RLIMIT_AS``), and must end within its time with exit 0 or 2,
exactly one ``error:`` line naming its input (for exit 2), a clean stdout, no warning, nothing written beside its
inputs, and at most 1 GB resident (the child's own ``ru_maxrss`` from ``os.wait4``).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
from helpers.limited import PEAK_RSS_KIB, run_limited

from hostile.hostile_cases import CASES, PYTHON_API, Case
from hostile.round_four import CASES as ROUND_FOUR


def _params():
    return [pytest.param(case, id=case.name, marks=[pytest.mark.slow] if case.slow else [])
            for case in [*CASES, *ROUND_FOUR]]


@pytest.mark.parametrize("case", _params())
def test_hostile_case(case: Case, tmp_path: Path) -> None:
    inputs = tmp_path / "inputs"
    inputs.mkdir()
    args = case.make(inputs)
    before = sorted(p.name for p in inputs.iterdir())
    if case.api:
        argv = [sys.executable, "-c", PYTHON_API.format(body=args[0])]
    else:
        argv = [sys.executable, "-m", "brdfnorm", *args]
    code, out, err, elapsed, peak, cpu = run_limited(argv, tmp_path, case.seconds)
    report = f"exit {code} in {elapsed:.1f} s ({cpu:.1f} s CPU), peak {peak / 1024:.0f} MiB\nstderr: {err[-2000:]}"
    print(f"{case.name}: {report.splitlines()[0]}")
    assert code == case.exit, report
    if not case.stdout_ok:
        assert out == "", report
    assert peak <= PEAK_RSS_KIB, report
    if case.cpu_seconds is not None:  # CPU time: the machine's load does not count against the case
        assert cpu <= case.cpu_seconds, report
    assert sorted(p.name for p in inputs.iterdir()) == before, "something was written beside the inputs"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["inputs"], "something was written"
    assert "Traceback" not in err and "internal error" not in err, report
    assert "Warning:" not in err, report  # no numpy (or other) warnings on stderr
    if case.exit == 2:
        errors = [line for line in err.splitlines() if line.startswith("error:")]
        assert len(errors) == 1 and err.count("\n") == 1, report  # the error line, and nothing else
        named = str(inputs) + os.sep if case.names == "INPUT" else case.names
        assert named in errors[0], report
        if "contains" in case.extra:
            assert case.extra["contains"] in errors[0], report
    if case.stderr:
        assert case.stderr in err, report
