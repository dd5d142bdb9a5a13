"""E_avg beside E (lut/table.py, issue 39 item 2's tables on every core): where a table is computed in this
process on more than one thread, its E_avg stage runs on a second thread while E runs — the same albedo calls, so
the same values; the progress callback still sees the stages in order, from the calling thread; the warning
filters are set once around both stages and restored after; a failure of E stops E_avg at its next batch."""

from __future__ import annotations

import threading
import warnings

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.lut import table
from brdfnorm.parallel import threads

AXES = {"mu": [0.2, 0.6, 1.0], "n": [5.0, 50.0]}


def _where_average_runs(monkeypatch) -> list[int]:
    idents: list[int] = []
    original = table.average_over_mu

    def recorded(*args, **kwargs):
        idents.append(threading.get_ident())
        return original(*args, **kwargs)

    monkeypatch.setattr(table, "average_over_mu", recorded)
    return idents


def test_average_beside_e_same_tables_progress_in_order(monkeypatch):
    model = bn.load("blinn-phong")
    progress: list[tuple[int, int, int]] = []
    idents = _where_average_runs(monkeypatch)
    filters = list(warnings.filters)
    paired = table.compute_tables(model, AXES, rtol=1e-8, threads=2,
                                  progress=lambda d, t: progress.append((d, t, threading.get_ident())))
    assert warnings.filters == filters  # nothing left behind
    assert idents and idents[0] != threading.get_ident()  # E_avg ran on a thread of its own
    assert {ident for _, _, ident in progress} == {threading.get_ident()}
    done = [d for d, _, _ in progress]
    assert done == sorted(done) and done[-1] == progress[-1][1] == 6 + 2  # E's 6 cells, then E_avg's 2 values
    alone = table.compute_tables(model, AXES, rtol=1e-8, threads=1)
    assert idents[1] == threading.get_ident()  # one thread: one stage after the other, here
    for name in ("E", "E_error", "E_avg", "E_avg_error"):
        assert np.array_equal(paired.tables[name], alone.tables[name]), name
    assert paired.evaluations == alone.evaluations


def test_albedo_warnings_stay_quiet_beside_and_come_back_after(monkeypatch):
    """Every albedo batch of both stages warning (as an unconverged batch does): none is shown; after the table
    the filters are as before, so the same warning outside a table is shown."""
    model = bn.load("blinn-phong")
    original = table.albedo
    batches = []

    def warning(*args, **kwargs):
        batches.append(threading.get_ident())
        warnings.warn("brdfnorm: 1 of 3 albedo integrals did not reach rtol", UserWarning, stacklevel=2)
        return original(*args, **kwargs)

    monkeypatch.setattr(table, "albedo", warning)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        table.compute_tables(model, AXES, rtol=1e-8, threads=2)
        assert len(set(batches)) > 1  # batches on several threads, each warned
        assert not [w for w in caught if issubclass(w.category, UserWarning)], [str(w.message) for w in caught]
        warnings.warn("outside", UserWarning, stacklevel=1)
    assert [str(w.message) for w in caught if issubclass(w.category, UserWarning)] == ["outside"]


def test_a_failing_stage_stops_the_one_beside():
    """The block raising: the stage beside it stops before its next batch (Stopped) and is waited for."""
    batches: list[int] = []
    release = threading.Event()

    def stage() -> int:
        for batch in range(1000):
            threads.run_tasks(lambda task, batch=batch: batches.append(batch), [np.arange(1)], 1)
            release.wait(0.001)
        return len(batches)

    with pytest.raises(RuntimeError, match="E failed"), threads.beside(stage) as result:
        while not batches:
            release.wait(0.001)
        raise RuntimeError("E failed")
    assert len(batches) < 1000
    with pytest.raises(threads.Stopped):
        result()
    with threads.beside(stage) as result:  # not failing: the stage runs to its end
        pass
    assert result() == len(batches)
