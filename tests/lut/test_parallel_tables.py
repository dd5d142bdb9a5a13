"""`brdfnorm lut` through the parallel layer: local processes and checkpoints give the in-process table, bit for
bit (a BSDF's E_R and E_T included), and a resumed job computes nothing again."""

from __future__ import annotations

import os

import numpy as np
import pytest
from helpers.paths import SRC

import brdfnorm as bn
from brdfnorm.lut import compute

AXES = {"mu": [0.2, 0.6, 1.0], "alpha": [0.1, 0.5]}


def test_lut_on_two_processes_with_a_checkpoint_equals_the_in_process_table(tmp_path):
    model = bn.load("ggx-dielectric", eta=1.5)
    serial = compute(model, AXES, rtol=1e-8, average=False)
    spread = compute(model, AXES, rtol=1e-8, average=False, workers=2, checkpoint=str(tmp_path / "ck"))
    for name in ("E", "E_error", "E_R", "E_T", "1-E"):
        assert np.array_equal(serial[name], spread[name]), name
    assert (tmp_path / "ck" / "E").is_dir()
    again = compute(model, AXES, rtol=1e-8, average=False, workers=1, checkpoint=str(tmp_path / "ck"))
    assert np.array_equal(again["E"], serial["E"]) and again.meta["evaluations"] == serial.meta["evaluations"]


def _running(pid: int) -> bool:
    """Whether process ``pid`` exists and is not a zombie."""
    try:
        with open(f"/proc/{pid}/stat", "rb") as stat:
            return stat.read().rsplit(b")", 1)[1].split()[0] != b"Z"
    except OSError:
        return False


def _descendants(pid: int) -> set[int]:
    """Every process below ``pid``, from /proc's parent links."""
    parents = {}
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat", "rb") as stat:
                    parents[int(entry)] = int(stat.read().rsplit(b")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                continue
    found, frontier = set(), {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier} - found
        found |= frontier
    return found


@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads process links from /proc (Linux)")
def test_pool_workers_end_when_the_parent_is_killed(tmp_path):
    """``brdfnorm lut --workers 2`` killed outright (SIGKILL: no clean-up runs) and left unreaped (a zombie, as a
    harness that has not waited yet leaves it): its pool workers notice within seconds and end, rather than wait
    for tasks forever (they were found orphaned after test time-outs)."""
    import signal
    import subprocess
    import sys
    import time

    env = dict(os.environ, PYTHONPATH=str(SRC))
    process = subprocess.Popen([sys.executable, "-m", "brdfnorm", "lut", "beckmann", "--axis", "mu=0.01:1:40",
                                "--axis", "alpha=0.01:1:40", "--rtol", "1e-12", "--workers", "2", "-o",
                                str(tmp_path / "t.npz")], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 60
        workers: set[int] = set()
        while time.monotonic() < deadline and len(workers) < 3:  # the forkserver and two workers
            time.sleep(0.2)
            workers = _descendants(process.pid)
        assert len(workers) >= 3, "the pool did not start"
        os.kill(process.pid, signal.SIGKILL)  # not waited for yet: a zombie
        deadline = time.monotonic() + 15
        while time.monotonic() < deadline and any(_running(pid) for pid in workers):
            time.sleep(0.2)
        assert not [pid for pid in workers if _running(pid)], "pool processes still running"
    finally:
        process.kill()
        process.wait()
