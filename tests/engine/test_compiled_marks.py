"""The compiling marks of :mod:`brdfnorm.engine.compiled.marks`: a process holds one while it compiles a lobe's
kernels, another waits while a live process holds it, and a mark of a dead process (or of itself) holds nothing."""

from __future__ import annotations

import subprocess
import sys
import time

from brdfnorm.engine.compiled import marks


def test_a_mark_holds_the_pid_within_the_block_only(tmp_path):
    mark = tmp_path / "k.compiling"
    with marks.holding(mark):
        assert mark.read_text() == str(__import__("os").getpid())
        assert marks.holder(mark) is None  # this process's own mark does not make it wait
    assert not mark.exists() and marks.holder(mark) is None


def test_another_process_is_waited_for_until_it_lets_go(tmp_path):
    mark = tmp_path / "k.compiling"
    script = (f"import time; from pathlib import Path; from brdfnorm.engine.compiled import marks\n"
              f"with marks.holding(Path({str(mark)!r})):\n    print('held', flush=True); time.sleep(1.0)")
    child = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "held"
        assert marks.holder(mark) == child.pid
        waited = marks.await_other(mark)
        assert 0.3 < waited < 30 and not mark.exists()
    finally:
        child.wait(timeout=60)


def test_a_dead_holder_holds_nothing_and_patience_ends_a_wait(tmp_path):
    mark = tmp_path / "k.compiling"
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    mark.write_text(str(child.pid))  # left by a process stopped mid-compile
    assert marks.holder(mark) is None
    start = time.monotonic()
    assert marks.await_other(mark) < 1.0 and time.monotonic() - start < 1.0
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        mark.write_text(str(sleeper.pid))
        assert marks.holder(mark) == sleeper.pid
        assert 0.2 <= marks.await_other(mark, patience=0.2) < 5.0
    finally:
        sleeper.kill()
        sleeper.wait()
    assert marks.holder(mark) is None


def test_an_old_mark_holds_nothing_and_a_stopped_childs_marks_are_released(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(30)"])
    try:
        mark, other = tmp_path / "a.compiling", tmp_path / "b.compiling"
        mark.write_text(str(sleeper.pid))
        other.write_text("1")  # another holder's (init: alive)
        old = time.time() - 2 * marks.PATIENCE
        __import__("os").utime(mark, (old, old))
        assert marks.holder(mark) is None  # its pid alive, but older than any compile (a reused pid)
        marks.release(tmp_path, sleeper.pid)
        assert not mark.exists() and other.exists()
    finally:
        sleeper.kill()
        sleeper.wait()
