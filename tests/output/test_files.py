"""brdfnorm.output: the one atomic file writer and the staged directory writer (issue 14, classes 2 and 8)."""

from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest
from helpers import paths

from brdfnorm.errors import OutputError
from brdfnorm.output import write_file
from brdfnorm.output.directories import MARKER, check_target, staged

SRC = str(paths.SRC)


def _listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


@pytest.mark.parametrize("data", ["héllo\n", b"\x00\xffbytes"])
def test_new_file_gets_the_content_and_honours_the_umask(tmp_path, data):
    target = tmp_path / "out.txt"
    previous = os.umask(0o027)
    try:
        write_file(target, data)
    finally:
        os.umask(previous)
    assert target.read_bytes() == (data.encode() if isinstance(data, str) else data)
    assert stat.S_IMODE(target.stat().st_mode) == 0o640
    assert _listing(tmp_path) == ["out.txt"]


def test_existing_file_keeps_its_mode_and_is_replaced_whole(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("old")
    target.chmod(0o604)
    write_file(str(target), "new")
    assert target.read_text() == "new"
    assert stat.S_IMODE(target.stat().st_mode) == 0o604


def test_read_only_file_is_refused_not_replaced(tmp_path):
    target = tmp_path / "out.txt"
    target.write_text("keep")
    target.chmod(0o444)
    with pytest.raises(OutputError, match="read-only"):
        write_file(target, "new")
    assert target.read_text() == "keep" and _listing(tmp_path) == ["out.txt"]


def test_symlink_stays_a_link_and_its_target_is_replaced(tmp_path):
    real = tmp_path / "real.txt"
    real.write_text("old")
    link = tmp_path / "link.txt"
    link.symlink_to(real)
    write_file(link, "new")
    assert link.is_symlink() and real.read_text() == "new"


def test_dangling_symlink_into_a_missing_directory_is_refused(tmp_path):
    link = tmp_path / "link.txt"
    link.symlink_to(tmp_path / "missing" / "x.txt")
    with pytest.raises(OutputError, match="symlink"):
        write_file(link, "x")
    assert link.is_symlink()


def test_character_device_is_written_not_replaced():
    before = os.stat("/dev/null")
    write_file("/dev/null", "discarded")
    after = os.stat("/dev/null")
    assert stat.S_ISCHR(after.st_mode) and after.st_ino == before.st_ino


def test_fifo_with_a_reader_is_written_in_place(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received = []
    reader_open = threading.Event()

    def read():
        with open(fifo, "rb") as handle:
            reader_open.set()
            received.append(handle.read())

    thread = threading.Thread(target=read)
    thread.start()
    deadline = time.monotonic() + 5
    while True:  # the reader's open() blocks until a writer appears, so try until it is there
        try:
            write_file(fifo, "through the pipe")
            break
        except OutputError:
            assert time.monotonic() < deadline
            time.sleep(0.01)
    thread.join(5)
    assert received == [b"through the pipe"]
    assert stat.S_ISFIFO(fifo.stat().st_mode)


def test_fifo_without_a_reader_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match="no reader"):
        write_file(fifo, "nobody listens")
    assert stat.S_ISFIFO(fifo.stat().st_mode)


@pytest.mark.parametrize("bad", ["", "  ", ".", "..", "/"])
def test_empty_or_directory_paths_are_refused(bad):
    with pytest.raises(OutputError):
        write_file(bad, "x")


def test_directory_target_and_missing_parent_are_refused(tmp_path):
    with pytest.raises(OutputError, match="directory"):
        write_file(tmp_path, "x")
    with pytest.raises(OutputError, match="does not exist"):
        write_file(tmp_path / "missing" / "x.txt", "x")


def test_dash_means_stdout(capsysbinary):
    write_file("-", "to stdout\n")
    write_file("-", b"bytes too\n")
    assert capsysbinary.readouterr().out == b"to stdout\nbytes too\n"


def test_a_failed_rename_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    target = tmp_path / "out.txt"
    target.write_text("old")

    def refuse(*args):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(os, "replace", refuse)
    with pytest.raises(OutputError, match="Permission denied"):
        write_file(target, "new")
    assert target.read_text() == "old" and _listing(tmp_path) == ["out.txt"]


def test_non_text_data_is_a_type_error(tmp_path):
    with pytest.raises(TypeError):
        write_file(tmp_path / "x", 3.0)  # type: ignore[arg-type]


#: Prefixed to each child's code: Python's own SIGINT handler, which a child inherits ignored where the suite was
#: started as a background job of a non-interactive shell (``cmd &``); the tests interrupt it as a user would.
_INTERRUPTIBLE = "import signal; signal.signal(signal.SIGINT, signal.default_int_handler)\n"


def _python(code: str, cwd: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": SRC}
    return subprocess.Popen([sys.executable, "-c", _INTERRUPTIBLE + textwrap.dedent(code)], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _wait_for(path: Path, timeout: float = 20.0) -> None:
    deadline = time.monotonic() + timeout
    while not path.exists():
        assert time.monotonic() < deadline, f"{path} never appeared"
        time.sleep(0.02)


def test_sigterm_while_writing_a_file_removes_the_temporary(tmp_path):
    process = _python("""
        import os, time, pathlib
        from brdfnorm.output import write_file
        real = os.replace
        def slow(a, b):
            pathlib.Path("started").touch()
            time.sleep(30)
        os.replace = slow
        write_file("out.txt", "x")
    """, tmp_path)
    _wait_for(tmp_path / "started")
    process.send_signal(signal.SIGTERM)
    assert process.wait(20) == 128 + signal.SIGTERM
    assert _listing(tmp_path) == ["started"]


@pytest.mark.slow
@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_signal_while_building_a_directory_removes_the_stage(tmp_path, signum):
    process = _python("""
        import pathlib, time
        from brdfnorm.output.directories import staged
        with staged("report", "test") as stage:
            stage.write("index.html", "partial")
            pathlib.Path("started").touch()
            time.sleep(30)
    """, tmp_path)
    _wait_for(tmp_path / "started")
    process.send_signal(signum)
    assert process.wait(20) != 0
    assert _listing(tmp_path) == ["started"]


@pytest.mark.slow
def test_concurrent_writers_of_one_directory_serialize_and_leave_nothing_behind(tmp_path):
    code = """
        import sys
        from brdfnorm.output.directories import staged
        with staged("report", "test") as stage:
            for i in range(200):
                stage.write(f"file{i}.txt", sys.argv[1] * 1000)
            stage.write("who", sys.argv[1])
    """
    env = {**os.environ, "PYTHONPATH": SRC}
    processes = [subprocess.Popen([sys.executable, "-c", textwrap.dedent(code), str(i)], cwd=tmp_path, env=env,
                                  stderr=subprocess.PIPE, text=True) for i in range(4)]
    errors = [p.communicate(60)[1] for p in processes]
    assert [p.returncode for p in processes] == [0, 0, 0, 0], errors
    assert _listing(tmp_path) == ["report"]
    report = tmp_path / "report"
    assert (report / MARKER).is_file() and len(list(report.iterdir())) == 202
    winner = (report / "who").read_text()
    assert all((report / f"file{i}.txt").read_text() == winner * 1000 for i in range(200))


@pytest.mark.parametrize("target", ["", " ", "/", ".", "..", "{cwd}", "{parent}"])
def test_dangerous_report_directories_are_refused(tmp_path, monkeypatch, target):
    work = tmp_path / "work"
    work.mkdir()
    (work / MARKER).write_text("a report lives here")  # even a directory that looks like a report
    monkeypatch.chdir(work)
    with pytest.raises(OutputError):
        check_target(target.format(cwd=work, parent=tmp_path))
    assert (work / MARKER).is_file()


def test_staged_directory_honours_the_umask(tmp_path):
    previous = os.umask(0o022)
    try:
        with staged(tmp_path / "report", "test") as stage:
            stage.write("index.html", "<html>")
    finally:
        os.umask(previous)
    report = tmp_path / "report"
    assert stat.S_IMODE(report.stat().st_mode) == 0o755
    assert stat.S_IMODE((report / "index.html").stat().st_mode) == 0o644
    assert _listing(tmp_path) == ["report"]
