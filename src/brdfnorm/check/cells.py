"""A check's albedo integrals through :mod:`brdfnorm.parallel` (issue #17): local processes, a Dask cluster, and
a checkpoint that a rerun resumes from.

Each batch the search asks for — a chunk of the coarse grid, the azimuth scan, a refinement round, the final
integral, the normalization grid — becomes one :class:`~brdfnorm.parallel.CellsJob` per bool combination (the
per-case parameter values travel as the job's per-cell values, the model as its source), computed by
:func:`~brdfnorm.parallel.run_job` on one :class:`~brdfnorm.parallel.Workers` held open for the whole check: a
batch of one chunk runs in the calling process, a larger one on the pool or the cluster. A cell's albedo does not
depend on its batch (``tests/parallel/test_parallel.py``), so the values are bit for bit those of the in-process
integrals, the search takes the same path and the report says the same. That holds under a budget of
evaluations; under a budget of seconds which integrals a search asks for depends on the clock — in one process
as on many — and more workers buy more coverage in the same seconds. Without ``chunk_cells`` a batch of more than
32 cells is cut by the layer's probe (a few of its cells integrated first, ≤ 6 % more work): the clock sees
that work, a budget of evaluations counts only the integrals the search asked for. The pointwise checks
(reciprocity, positivity, finiteness: BRDF evaluations, no integrals) run in the calling process.

Checkpoint ``DIR``: ``check.json`` names the check (the SHA-256 of its definition: model source, checks,
parameter space, tolerance, budget, brdfnorm version); each job saves its chunks in ``DIR/<its hash>/``
(:mod:`brdfnorm.parallel.checkpoint`). A rerun of the same check asks for the same jobs in the same order (the
budget counts a restored cell's evaluations as spent, so every decision repeats) and computes only the chunks
that are missing. Refused under a budget of seconds: the rerun would ask for other integrals, and a checkpoint
it cannot use is worse than none.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import warnings
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, OutputError
from ..models.base import Model
from ..parallel import CellsJob, ModelSource, Workers, run_job, sigterm_as_interrupt
from ..parallel.checkpoint import write_atomically
from ..parallel.job import canonical_json, validate_chunk_cells
from .core import Budget

CHECK_FILE = "check.json"
#: Version of the check's checkpoint layout (part of its hash).
FORMAT = 1


class SpreadAlbedo:
    """The check's albedo batches on open workers (see the module docstring); a context manager."""

    def __init__(self, model: Model, definition: dict, budget: Budget, *, workers: int | None = 1,
                 scheduler: str | None = None, checkpoint: str | Path | None = None,
                 chunk_cells: int | None = None) -> None:
        validate_chunk_cells(chunk_cells)
        self.pool = Workers(workers, scheduler)
        ModelSource.of(model)  # a model that cannot travel is refused before any work
        self.chunk_cells = chunk_cells
        self.pool.placement(1)  # an unreachable scheduler, or one without workers, fails before any work
        try:
            self.directory = None if checkpoint is None else _open(Path(checkpoint), model, definition, budget)
        except BaseException:
            self.pool.close()
            raise
        self.jobs = self.chunks = self.chunks_restored = self.evaluations_computed = 0
        self.executors: set[str] = set()

    def __enter__(self) -> SpreadAlbedo:
        # SIGTERM anywhere in the check (not only while a job runs) stops it like Ctrl-C, and the pool with it
        self._stack = contextlib.ExitStack()
        self._stack.callback(self.pool.close)
        self._stack.enter_context(sigterm_as_interrupt())
        return self

    def __exit__(self, *exc_info: object) -> None:
        self._stack.close()

    def albedo(self, model: Model, theta: np.ndarray, phi: np.ndarray, values: dict[str, np.ndarray], *, over: str,
               rtol: float, max_evaluations: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """Albedo (K, C), error (K, C), non-finite share (K,) and evaluations spent of the K cases at ``theta``,
        ``phi`` with the per-case float parameter ``values`` (``model`` carries the rest), as
        ``brdfnorm.albedo(..., nonfinite="zero")`` gives them."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # slider ranges are searched on purpose; unconverged cells are reported
            job = CellsJob.of(model, theta, phi, values, over=over, rtol=rtol, nonfinite="zero",
                              max_evaluations=max_evaluations, chunk_cells=self.chunk_cells)
            checkpoint = None if self.directory is None else self.directory / job.digest[:32]
            cells = run_job(job, self.pool, checkpoint=checkpoint)
        self.jobs += 1
        self.chunks += cells.chunks
        self.chunks_restored += cells.chunks - cells.chunks_computed
        self.evaluations_computed += cells.evaluations_computed
        if cells.chunks_computed:
            self.executors.add(cells.executor)
        # All cells' evaluations, restored ones included: the budget's decisions repeat on a resumed run.
        return cells.value, cells.error, cells.nonfinite_fraction, int(cells.evaluations.sum())

    def coverage(self) -> dict:
        """Where the integrals ran, for the report's coverage."""
        return {"executors": sorted(self.executors), "workers": self.pool.count, "jobs": self.jobs,
                "chunks": self.chunks, "chunks_from_checkpoint": self.chunks_restored,
                "evaluations_computed": self.evaluations_computed,
                "checkpoint": None if self.directory is None else str(self.directory)}


def _open(directory: Path, model: Model, definition: dict, budget: Budget) -> Path:
    """The checkpoint directory of this check: reopened if it holds this check, created if absent or empty."""
    if budget.seconds is not None:
        raise ArgumentError("a check resumes only under a budget of evaluations (on the command line --budget "
                            "COUNTevals): under a budget of seconds, which integrals its search asks for depends "
                            "on the clock, so a rerun would not ask for the saved ones", where="checkpoint")
    from .. import __version__

    header = {"format": FORMAT, "brdfnorm": __version__, "model": ModelSource.of(model).to_json(), **definition}
    digest = hashlib.sha256(canonical_json(header).encode()).hexdigest()
    marker = directory / CHECK_FILE
    if directory.exists() and not directory.is_dir():
        raise ArgumentError(f"{directory} is not a directory", where="checkpoint")
    if marker.is_file():
        try:
            stored = json.loads(marker.read_text(encoding="utf-8"))["digest"]
        except (OSError, ValueError, KeyError, TypeError) as error:
            raise ArgumentError(f"{marker} is not a brdfnorm check checkpoint ({type(error).__name__}); use another "
                                "directory", where="checkpoint") from None
        if stored != digest:
            raise ArgumentError(f"{directory} holds the checkpoint of a different check (hash {str(stored)[:12]}…, "
                                f"this check's is {digest[:12]}…); use another directory, or delete it to start "
                                "over", where="checkpoint")
        return directory
    if directory.is_dir() and any(not (p.name.startswith(".") and p.name.endswith(".tmp"))
                                  for p in directory.iterdir()):
        raise ArgumentError(f"{directory} is not empty and holds no brdfnorm check checkpoint ({CHECK_FILE}); "
                            "refusing to write into it", where="checkpoint")
    try:
        directory.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OutputError(f"cannot create the checkpoint directory: {error.strerror}", where=str(directory)) \
            from None
    write_atomically(marker, (canonical_json({**header, "digest": digest}) + "\n").encode())
    return directory
