"""A command in a subprocess under the hostile rounds' limits: a 4 GB address space (``RLIMIT_AS``), a time bound,
and its peak resident memory and CPU read from ``os.wait4`` (the runner of tests/hostile and the large-input tests)."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import time
from pathlib import Path

import pytest

ADDRESS_SPACE = 4 * 1024**3
PEAK_RSS_KIB = 1024**2  # 1 GiB (ru_maxrss is in KiB on Linux)


def _limit_address_space() -> None:
    resource.setrlimit(resource.RLIMIT_AS, (ADDRESS_SPACE, ADDRESS_SPACE))


def run_limited(argv: list[str], cwd: Path, seconds: float) -> tuple[int, str, str, float, int, float]:
    """(exit code, stdout, stderr, wall seconds, peak resident KiB, CPU seconds) of ``argv`` under the
    address-space limit; killed (and failed) past ``seconds``."""
    out, err = cwd / ".stdout", cwd / ".stderr"
    start = time.monotonic()
    with open(out, "wb") as stdout, open(err, "wb") as stderr:
        process = subprocess.Popen(argv, cwd=cwd, stdin=subprocess.DEVNULL, stdout=stdout, stderr=stderr,
                                   preexec_fn=_limit_address_space, env={**os.environ, "COLUMNS": "200"})
    while True:
        pid, status, usage = os.wait4(process.pid, os.WNOHANG)
        if pid:
            break
        if time.monotonic() - start > seconds:
            process.send_signal(signal.SIGKILL)
            os.wait4(process.pid, 0)
            process.returncode = -9
            pytest.fail(f"still running after {seconds} s: {' '.join(argv)[:300]}")
        time.sleep(0.02)
    elapsed = time.monotonic() - start
    process.returncode = os.waitstatus_to_exitcode(status)  # reaped here: keep Popen from waiting again
    text_out, text_err = out.read_text(errors="replace"), err.read_text(errors="replace")
    out.unlink()
    err.unlink()
    return process.returncode, text_out, text_err, elapsed, usage.ru_maxrss, usage.ru_utime + usage.ru_stime
