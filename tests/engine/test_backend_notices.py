"""brdfnorm.engine.compiled.backend.tell_once: one line per message and process, with a table's threads at once."""

from __future__ import annotations

import threading
import time

from brdfnorm.engine.compiled import backend


class _SlowSet(set):
    """A set whose membership test takes a while: without a lock every thread would pass it before any adds."""

    def __contains__(self, item) -> bool:
        found = super().__contains__(item)
        time.sleep(0.01)  # (after the look-up: the answer goes stale while the others look)
        return found


def test_a_message_is_told_once_however_many_threads_reach_it(monkeypatch, capsys):
    monkeypatch.setattr(backend, "_TOLD", _SlowSet())
    start = threading.Barrier(8)

    def tell() -> None:
        start.wait()
        backend.tell_once("brdfnorm: told once")

    threads = [threading.Thread(target=tell) for _ in range(8)]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert capsys.readouterr().err.splitlines() == ["brdfnorm: told once"]


def test_a_notice_names_the_numpy_backend_once(monkeypatch, capsys):
    monkeypatch.setattr(backend, "_TOLD", set())
    backend.notice("Numba cannot be imported (test)")
    backend.notice("Numba cannot be imported (test)")
    assert capsys.readouterr().err.splitlines() == [
        "brdfnorm: Numba cannot be imported (test); using the numpy backend"]
