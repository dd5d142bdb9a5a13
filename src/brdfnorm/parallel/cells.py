"""The tables of albedo cells of :mod:`brdfnorm.parallel`: :func:`albedo_cells`, :func:`run_job` and their result
(:class:`CellsResult`); the package exports them, imported at first use (the package's docstring says what they do).
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..engine.methods import warn_about
from .checkpoint import Checkpoint
from .executors import OPTIONAL_FIELDS, ChunkResult, Scheduler, Workers
from .job import CellsJob, ChunkPlan, chunk_plan

__all__ = ["CellsResult", "albedo_cells", "run_job", "sigterm_as_interrupt"]


@dataclass(frozen=True)
class CellsResult:
    """A computed job: arrays of the job's shape S (``value``/``error`` (*S, C)) and what the run did."""

    digest: str  # the job's hash
    value: np.ndarray  # (*S, C)
    error: np.ndarray  # (*S, C) absolute error estimate
    evaluations: np.ndarray  # (*S,) integrand evaluations per cell (-1: not counted, task "max")
    converged: np.ndarray  # (*S,)
    nonfinite_fraction: np.ndarray | None  # (*S,) with nonfinite="zero", else None
    theta: np.ndarray  # (*S,) radians: the cell's direction (the argmax for task "max")
    phi: np.ndarray  # (*S,)
    method: str
    chunks: int  # chunks in the job
    chunks_computed: int  # by this run (the rest came from the checkpoint)
    evaluations_computed: int  # integrand evaluations this run spent
    workers: int
    executor: str  # "in-process", "local processes" or "dask tcp://…"
    seconds: float
    lower: np.ndarray | None = None  # (*S, C) decimal strings: guaranteed bounds (method "certified")
    upper: np.ndarray | None = None
    reason: np.ndarray | None = None  # (*S,) why a cell did not converge ("" where it did), where albedo says
    reflected: np.ndarray | None = None  # (*S, C) the parts of a BSDF's albedo (models that transmit)
    transmitted: np.ndarray | None = None


def albedo_cells(job: CellsJob, *, workers: int | None = None, scheduler: str | Scheduler | None = None,
                 checkpoint: str | Path | None = None,
                 on_progress: Callable[[int, int], None] | None = None) -> CellsResult:
    """Compute every cell of ``job``.

    ``workers``: local processes (default: all cores of this machine; 1 computes in this process);
    ``scheduler``: a Dask scheduler address, or a :class:`Scheduler` with its own connection deadline (then the
    cluster's workers compute, and ``workers`` must be None);
    ``checkpoint``: a directory to save finished chunks in and resume from; ``on_progress(done, total)`` is
    called with cell counts as chunks finish (anywhere). SIGTERM stops the run like Ctrl-C
    (:class:`KeyboardInterrupt`), losing at most the chunks in flight. A caller with many jobs holds one
    :class:`Workers` open and calls :func:`run_job` with it instead.
    """
    with Workers(workers, scheduler) as pool:
        return run_job(job, pool, checkpoint=checkpoint, on_progress=on_progress)


def run_job(job: CellsJob, pool: Workers, *, checkpoint: str | Path | None = None,
            on_progress: Callable[[int, int], None] | None = None) -> CellsResult:
    """Compute every cell of ``job`` on the open ``pool`` (see :func:`albedo_cells`)."""
    start = time.perf_counter()
    model = job.loaded()  # a job rebuilt from data refuses a bad source here, once, with its own warnings
    job.settings.validate(model)
    if checkpoint is not None:
        store = Checkpoint.open(checkpoint, job, lambda: chunk_plan(job, model))
        plan = store.plan
    else:
        store, plan = None, chunk_plan(job, model)
    done = store.finished() if store is not None else {}
    missing = [k for k in range(plan.count) if k not in done]
    executor, count = pool.placement(len(missing))
    cells_done = sum(plan.chunk(k).size for k in done)
    if on_progress is not None:
        on_progress(cells_done, job.size)
    spent = 0
    # closing(): stop waiting on the chunks as soon as anything here fails, not when the generator is collected
    with sigterm_as_interrupt(), contextlib.closing(pool.run(job, plan, missing, model)) as results:
        for result in results:
            if store is not None:
                store.save(result)
            done[result.index] = result
            spent += int(np.maximum(result.evaluations, 0).sum())
            cells_done += result.value.shape[0]
            if on_progress is not None:
                on_progress(cells_done, job.size)
    if missing:  # (where they ran: the default pool starts only where it pays, after the first chunk)
        executor, count = pool.placed
    return _assemble(job, plan, done, len(missing), spent, count, executor, time.perf_counter() - start)


def _assemble(job: CellsJob, plan: ChunkPlan, done: dict[int, ChunkResult], computed: int, spent: int,
              workers: int, executor: str, seconds: float) -> CellsResult:
    """Scatter the chunks back into the job's cell order and shape; warn once for the whole table."""
    parts = [done[k] for k in range(plan.count)]  # concatenated, they follow plan.order
    channels = parts[0].value.shape[1]

    def gather(name: str, tail: tuple = ()) -> np.ndarray:
        out = np.empty((job.size, *tail), dtype=getattr(parts[0], name).dtype)  # text bounds: object arrays
        out[plan.order] = np.concatenate([getattr(p, name) for p in parts])
        return out.reshape(job.shape + tail)

    methods = sorted({p.method for p in parts})
    converged = gather("converged")
    fraction = gather("nonfinite_fraction") if job.settings.nonfinite == "zero" else None
    reason = gather("reason") if getattr(parts[0], "reason", None) is not None else None
    warn_about(job.source.name, job.settings.rtol, converged, reason, fraction, stacklevel=4)
    return CellsResult(
        digest=job.digest, value=gather("value", (channels,)), error=gather("error", (channels,)),
        evaluations=gather("evaluations"), converged=converged, nonfinite_fraction=fraction,
        theta=gather("theta"), phi=gather("phi"), method="+".join(methods), chunks=plan.count,
        chunks_computed=computed, evaluations_computed=spent, workers=workers, executor=executor, seconds=seconds,
        **{name: gather(name, (channels,) if tail == "channels" else ())
           for name, (tail, _) in OPTIONAL_FIELDS.items() if getattr(parts[0], name) is not None})


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[None]:
    """Turn SIGTERM into KeyboardInterrupt while chunks run, so workers are stopped and files stay whole."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt("SIGTERM")

    previous = signal.signal(signal.SIGTERM, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
