"""``threads`` in one place (issue 39, item 2's tables on every core): :func:`brdfnorm.parallel.threads.scope` sets
the threads a batch of cells runs on, as the backend's scope does for the backend, and every stage of a table (E,
E_avg's node batches, the DFG channels) and the audit's reference cells read it — nothing passes it by hand."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.audit.reference import Reference
from brdfnorm.lut import table
from brdfnorm.parallel import threads


@pytest.fixture
def seen(monkeypatch) -> list[int]:
    """The thread count of every batch of cells computed from here on."""
    counts: list[int] = []
    original = table.run_tasks

    def recorded(function, tasks, count):
        counts.append(count)
        return original(function, tasks, 1)  # (the values do not depend on it: one thread keeps the test cheap)

    monkeypatch.setattr(table, "run_tasks", recorded)
    return counts


def test_scope_nests_and_restores():
    assert threads.current() == 1
    with threads.scope(3):
        assert threads.current() == 3
        with threads.scope(None):  # None: no change
            assert threads.current() == 3
        with threads.scope(2):
            assert threads.current() == 2
        assert threads.current() == 3
    assert threads.current() == 1


def test_every_stage_of_a_table_reads_the_scope(seen):
    """compute_tables(threads=2): E, E_avg's node batches and the DFG channels all on 2 threads; outside any scope
    the same calls on 1; compute_cells' own argument wins over the scope."""
    model = bn.load("blinn-phong")
    axes = {"mu": [0.3, 1.0], "n": [10.0, 100.0]}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        table.compute_tables(model, axes, rtol=1e-6, channels=["dfg"], threads=2)
        stages = len(seen)
        assert stages >= 5 and set(seen) == {2}, seen
        table.compute_tables(model, axes, rtol=1e-6, channels=["dfg"])
        assert set(seen[stages:]) == {1}, seen
        del seen[:]
        with threads.scope(2):
            table.average_over_mu(model, {"n": np.array([10.0])}, rtol=1e-6)
            table.compute_cells(model, np.array([0.5]), {"n": np.array([10.0])}, rtol=1e-6, threads=3)
        assert set(seen[:-1]) == {2} and seen[-1] == 3, seen


def test_the_audit_reference_runs_on_the_local_threads(seen, monkeypatch):
    monkeypatch.setattr("brdfnorm.audit.reference.local_threads", lambda: 2)
    reference = Reference(bn.load("ggx"))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        reference.values("E", "height-correlated", np.array([0.5, 1.0]), np.array([0.1, 0.3]))
    assert seen and set(seen) == {2}, seen
