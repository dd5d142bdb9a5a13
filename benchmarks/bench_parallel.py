"""One large table computed by 1 and 2 local worker processes and through a Dask scheduler with 2 workers
(issue #17): wall times and their ratios in one run, and whether the three tables are bit-for-bit identical.

The table: examples/ggx.brdf over roughness × θ_o (the issue #13 table) at rtol 1e-9 — every cell one
independent albedo integral, which is what spreads over processes. Times include starting the local pool (what
a user waits for); the Dask cluster (``distributed.LocalCluster``: a scheduler and two single-threaded worker
processes on 127.0.0.1) is started before the clock, as a cluster users point brdfnorm at is already running.
Run alone: ``.venv/bin/python benchmarks/bench_parallel.py [--quick]``.
"""

from __future__ import annotations

import logging
import sys
import time
import warnings
from pathlib import Path

import numpy as np

import brdfnorm as bn
from brdfnorm.parallel import CellsJob, albedo_cells, local_cores

ROOT = Path(__file__).resolve().parents[1]


def table_job(quick: bool) -> CellsJob:
    roughness = np.geomspace(0.05, 1.0, 8 if quick else 32)
    theta = np.radians(np.linspace(0.0, 89.0, 10 if quick else 90))
    model = bn.load(ROOT / "examples" / "ggx.brdf")
    # --quick: fixed small chunks, so that even the smoke run spreads several chunks
    return CellsJob.of(model, theta[None, :], values={"roughness": roughness[:, None]}, rtol=1e-9,
                       chunk_cells=10 if quick else None)


def w_parallel(cfg, refs=None) -> dict:
    """The workload as benchmarks/run.py reports it (``cfg.quick`` shrinks the table)."""
    try:
        from distributed import LocalCluster
    except ImportError:
        return {"title": "parallel tables", "status": "not available: the 'distributed' package is not installed"}
    job = table_job(cfg.quick)
    title = (f"examples/ggx.brdf table, {job.shape[0]} roughness × {job.shape[1]} θ_o = {job.size} cells at rtol "
             f"1e-9, on {local_cores()} cores")
    runs = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for name, kwargs in (("1 local worker", {"workers": 1}), ("2 local workers", {"workers": 2})):
            start = time.perf_counter()
            runs[name] = (albedo_cells(job, **kwargs), time.perf_counter() - start)
        with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                          dashboard_address=":0", silence_logs=logging.CRITICAL) as cluster:
            start = time.perf_counter()
            runs["dask, 2 workers"] = (albedo_cells(job, scheduler=cluster.scheduler_address),
                                       time.perf_counter() - start)
    baseline, base_time = runs["1 local worker"]
    methods = {}
    for name, (result, seconds) in runs.items():
        identical = all(np.array_equal(getattr(result, f), getattr(baseline, f))
                        for f in ("value", "error", "evaluations", "converged"))
        speedup = base_time / seconds
        methods[name] = {
            "time_s": seconds, "timing": "measured, once", "runs": 1, "points": job.size,
            "max_rel_error": float(np.max(np.abs(result.value - baseline.value) / np.abs(baseline.value))),
            "median_rel_error": float(np.median(np.abs(result.value - baseline.value) / np.abs(baseline.value))),
            "warnings": int(np.count_nonzero(~result.converged)),
            "note": f"{speedup:.2f}× the speed of 1 worker; {result.chunks} chunks; bit-identical to 1 worker: "
                    f"{'yes' if identical else 'NO'}",
            "speedup_vs_1_worker": speedup, "bit_identical": identical, "chunks": result.chunks,
            # the report's speed-up column: here, how many times faster than one worker
            "speedup_of_brdfnorm": None if result is baseline else speedup,
        }
    return {"title": title, "status": "ok", "reference": "the 1-worker table (errors are differences from it)",
            "methods": methods}


if __name__ == "__main__":
    class _Config:
        quick = "--quick" in sys.argv

    for method, line in w_parallel(_Config())["methods"].items():
        print(f"{method:18s} {line['time_s']:8.2f} s  {line['note']}")
