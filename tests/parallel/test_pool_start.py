"""The default local pool starts only where it pays (brdfnorm.parallel.executors.Workers, issue 39 item 5): the first
chunk computes in this process, and the rest goes to a pool only where its time, predicted from the first's, is more
than the pool's start saves (POOL_START_SECONDS); an explicit ``workers`` count always uses its pool. Either way the
table is the in-process one, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.parallel import CellsJob, albedo_cells, executors


def _job() -> CellsJob:
    theta = np.radians(np.linspace(0, 85, 6))[None, :]
    return CellsJob.of(bn.load(str(EXAMPLES / "ggx.brdf"), f0=1.0), theta,
                       values={"roughness": np.array([0.1, 0.6])[:, None]}, rtol=1e-8, chunk_cells=3)


def _same(a, b) -> None:
    for name in ("value", "error", "evaluations", "converged", "theta", "phi"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.value.tobytes() == b.value.tobytes() and a.error.tobytes() == b.error.tobytes()


def test_the_pool_pays_where_the_work_outlasts_its_start():
    start = executors.POOL_START_SECONDS
    assert not executors.pool_pays(start, 2)  # 1.5 s of chunks: 1.5 + 0.75 s on two workers
    assert executors.pool_pays(2.5 * start, 2)
    assert not executors.pool_pays(100.0, 1)
    assert executors.pool_pays(1.01 * start * 4 / 3, 4) and not executors.pool_pays(0.99 * start * 4 / 3, 4)


def test_a_small_job_on_the_default_workers_stays_in_this_process(monkeypatch):
    monkeypatch.setattr(executors, "local_cores", lambda: 2)
    started = []
    monkeypatch.setattr(executors.Workers, "_local_pool", lambda self: started.append(1) or None)
    serial = albedo_cells(_job(), workers=1)
    default = albedo_cells(_job(), workers=None)
    assert not started and default.executor == "in-process" and default.workers == 1
    assert default.chunks == default.chunks_computed == 4
    _same(serial, default)


@pytest.mark.slow
def test_a_job_worth_a_pool_starts_it_after_its_first_chunk(monkeypatch):
    monkeypatch.setattr(executors, "local_cores", lambda: 2)
    monkeypatch.setattr(executors, "POOL_START_SECONDS", 0.0)
    progress = []
    serial = albedo_cells(_job(), workers=1)
    pooled = albedo_cells(_job(), workers=None, on_progress=lambda done, total: progress.append(done))
    assert pooled.executor == "local processes" and pooled.workers == 2
    assert progress == [0, 3, 6, 9, 12]  # the first chunk here, then three from the pool
    _same(serial, pooled)
