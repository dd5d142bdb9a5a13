"""Tables on threads of one process (brdfnorm.parallel.threads, brdfnorm.lut.table): the same tables bit for bit as
on one thread, under the compiled backend, cold (a shader's compiled kernel made by whichever thread reaches it
first) and warm; the numpy backend keeps one thread; the tasks cover every cell once."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.engine.compiled import backend
from brdfnorm.glsl import native as glsl_native
from brdfnorm.lut import table
from brdfnorm.parallel import cores
from brdfnorm.parallel.threads import cell_tasks, local_threads, run_tasks

pytest.importorskip("numba")

GGX_BRDF = EXAMPLES / "ggx.brdf"


@pytest.fixture
def spy(monkeypatch):
    """The thread counts and thread names the table's batches ran with."""
    seen = {"threads": [], "names": set()}

    def recorded(function, tasks, threads):
        seen["threads"].append(threads)

        def named(task):
            seen["names"].add(threading.current_thread().name)
            return function(task)

        return run_tasks(named, tasks, threads)

    monkeypatch.setattr(table, "run_tasks", recorded)
    return seen


def _tables(lut) -> dict[str, np.ndarray]:
    return {name: np.asarray(lut[name]) for name in lut}


def test_cell_tasks_cover_every_cell_once_strided_per_block_whatever_the_threads():
    for count, chunk in ((0, 4), (1, 4), (7, 3), (9, 2), (20, 4), (1030, 256)):
        tasks = cell_tasks(count, chunk)
        covered = np.concatenate(tasks).tolist() if tasks else []
        assert sorted(covered) == list(range(count))
        assert all(0 < t.size <= chunk for t in tasks)
    assert [t.tolist() for t in cell_tasks(9, 2)] == [[0, 2], [1, 3], [4, 6], [5, 7], [8]]
    assert [t.tolist() for t in cell_tasks(7, 3, split=1)] == [[0, 1, 2], [3, 4, 5], [6]]


def test_run_tasks_keeps_order_and_context_and_raises():
    with backend.scope("numpy"):
        out = run_tasks(lambda task: (task.tolist(), backend.requested(), threading.current_thread().name),
                        cell_tasks(10, 2), 2)
    assert [o[0] for o in out] == [t.tolist() for t in cell_tasks(10, 2)]
    assert {o[1] for o in out} == {"numpy"}  # the caller's backend scope, in every thread
    assert all(o[2].startswith("brdfnorm-cells") for o in out)

    def failing(task):
        if task[0] == 2:
            raise ValueError("task 2")
        return task

    with pytest.raises(ValueError, match="task 2"):
        run_tasks(failing, cell_tasks(6, 1), 2)


def test_thread_count_follows_backend_workers_and_scheduler(monkeypatch):
    monkeypatch.setattr(cores, "local_cores", lambda: 2)
    with backend.scope("compiled"):
        assert local_threads(None) == 2
        assert local_threads(3) == local_threads(np.int64(3)) == 3
        assert local_threads(1) == local_threads(True) == local_threads(2.5) == 1  # (Workers refuses 2.5)
        assert local_threads(None, scheduler="tcp://127.0.0.1:8786") == 1
    with backend.scope("numpy"):
        assert local_threads(None) == 1


def test_brdf_table_on_two_threads_equals_one_thread_cold_and_warm(monkeypatch, spy):
    """examples/ggx.brdf (the half-vector route's fused global rule, its panels and the hemisphere route at μ = 1e-4):
    E, E_avg and their estimates bit for bit, on one thread and on two; the first threaded table with the shader's
    compiled kernel not yet made in this process (both threads ask for it at once: the one that waits must get the
    kernel, not the numpy integrand — the values would then differ in their last bits)."""
    monkeypatch.setattr(cores, "local_cores", lambda: 2)
    model = bn.load(str(GGX_BRDF)).with_params(f0=1.0)
    axes = {"mu": np.linspace(0.0, 1.0, 6), "roughness": np.array([0.05, 0.3, 0.7, 1.0])}
    settings = dict(clamp={"mu": 1e-4}, rtol=1e-9, backend="compiled")
    monkeypatch.setattr(glsl_native, "_kernels", {})  # cold: the shader's kernel is made again, by the threads
    cold = table.compute(model, axes, workers=None, **settings)
    assert max(spy["threads"]) == 2 and {"brdfnorm-cells_0", "brdfnorm-cells_1"} <= spy["names"], spy
    one = table.compute(model, axes, workers=1, **settings)
    assert set(spy["threads"][-1:]) == {1}
    warm = table.compute(model, axes, workers=None, **settings)
    expected = _tables(one)
    for name, values in _tables(cold).items():
        np.testing.assert_array_equal(values, expected[name], err_msg=f"cold {name}")
    for name, values in _tables(warm).items():
        np.testing.assert_array_equal(values, expected[name], err_msg=f"warm {name}")
    assert cold.meta["evaluations"] == one.meta["evaluations"] == warm.meta["evaluations"]


@pytest.mark.slow  # (~50 s: E_avg's nodes at σ = 0.2 take up to 230 000 evaluations each)
def test_batch_dependent_route_gives_the_same_table_on_two_threads(monkeypatch, spy):
    """oren-nayar's generic panels settle some E_avg nodes differently within a batch than alone (at ~1e-11, within
    their estimates): the tasks must not depend on the number of threads (a split by thread count failed this)."""
    _assert_two_threads_equal_one(monkeypatch, spy, "oren-nayar",
                                  {"mu": np.linspace(0.0, 1.0, 6), "sigma": np.array([0.2, 0.9])},
                                  clamp={"mu": 1e-4}, rtol=1e-8)


def test_builtin_dfg_table_on_two_threads_equals_one_thread(monkeypatch, spy):
    """The built-in GGX's split-sum channels (its fused microfacet global rule): the same tables on two threads."""
    _assert_two_threads_equal_one(monkeypatch, spy, "ggx",
                                  {"mu": np.linspace(0.05, 1.0, 5), "alpha": np.array([0.1, 0.5, 0.9])},
                                  rtol=1e-9, channels=("dfg",))


def _assert_two_threads_equal_one(monkeypatch, spy, name: str, axes: dict, **settings) -> None:
    """The compiled backend's table of built-in ``name`` on two threads (checked to have used them) equals, array for
    array, the one on one thread."""
    monkeypatch.setattr(cores, "local_cores", lambda: 2)
    two = table.compute(bn.load(name), axes, workers=None, backend="compiled", **settings)
    assert max(spy["threads"]) == 2
    one = table.compute(bn.load(name), axes, workers=1, backend="compiled", **settings)
    for table_name, values in _tables(two).items():
        np.testing.assert_array_equal(values, _tables(one)[table_name], err_msg=table_name)


def test_numpy_backend_keeps_one_thread(monkeypatch, spy):
    monkeypatch.setattr(cores, "local_cores", lambda: 2)
    lut = table.compute(bn.load("blinn-phong"), {"mu": [0.5, 1.0], "n": [10.0, 100.0]}, rtol=1e-8, workers=None,
                        backend="numpy")
    assert lut["E"].shape == (2, 2)
    assert set(spy["threads"]) == {1} and spy["names"] == {threading.current_thread().name}
