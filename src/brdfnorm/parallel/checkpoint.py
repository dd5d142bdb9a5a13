"""Checkpoints: a directory holding a job's definition and each finished chunk, so a killed job resumes.

Layout of ``DIR``:

* ``job.json`` — the job's header (model source, settings, task, shape), its SHA-256 and the chunk size;
* ``cells.npz`` — the cells' arrays (θ, φ, per-cell parameter values): with ``job.json``, the whole definition;
* ``chunk-NNNNNN.npz`` — one per finished chunk: the job's hash, the chunk's cell indices, its values, error
  estimates, evaluation counts, convergence flags, directions and the seconds it took.

Every file is written to a temporary name in ``DIR`` and renamed over its final name (atomic on POSIX), so a
job killed at any moment (SIGTERM, SIGKILL, a lost machine) leaves only whole files: at most the chunks in
flight are lost. A directory holding another job's checkpoint, a non-empty directory without one, or a chunk
file that does not belong to this job is refused with a one-line error; nothing in it is overwritten. Files
are read with ``allow_pickle=False``: a checkpoint is data, never code.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import tempfile
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, OutputError
from .executors import OPTIONAL_FIELDS, ChunkResult
from .job import CellsJob, ChunkPlan, canonical_json, chunk_plan_order

JOB_FILE = "job.json"
CELLS_FILE = "cells.npz"
_RESULT_ARRAYS = ("value", "error", "evaluations", "converged", "nonfinite_fraction", "theta", "phi")


class Checkpoint:
    """A checkpoint directory bound to one job and its chunk plan (use :meth:`open`)."""

    def __init__(self, directory: Path, job: CellsJob, plan: ChunkPlan) -> None:
        self.directory = directory
        self.job = job
        self.plan = plan

    @classmethod
    def open(cls, directory: str | Path, job: CellsJob, make_plan: Callable[[], ChunkPlan]) -> Checkpoint:
        """Reopen ``directory`` if it holds ``job`` (with the chunk plan stored there), or create it with the plan
        ``make_plan()`` returns; refuse anything else."""
        directory = Path(directory)
        where = "checkpoint"
        if directory.exists() and not directory.is_dir():
            raise ArgumentError(f"{directory} is not a directory", where=where)
        job_file = directory / JOB_FILE
        if job_file.is_file():
            try:
                stored = json.loads(job_file.read_text(encoding="utf-8"))
                digest, bounds = stored["digest"], np.asarray(stored["plan"]["bounds"], dtype=np.int64)
            except (OSError, ValueError, KeyError, TypeError) as error:
                raise ArgumentError(f"{job_file} is not a brdfnorm checkpoint ({type(error).__name__}); use another "
                                    "directory", where=where) from None
            if digest != job.digest:
                raise ArgumentError(
                    f"{directory} holds the checkpoint of a different job (hash {str(digest)[:12]}…, this job's is "
                    f"{job.digest[:12]}…); use another directory, or delete it to start over", where=where)
            if bounds.ndim != 1 or bounds.size < 2 or bounds[0] != 0 or bounds[-1] != job.size or \
                    np.any(np.diff(bounds) <= 0):
                raise ArgumentError(f"{job_file}: damaged chunk plan; use another directory", where=where)
            # The plan stored with the job, not one probed again (a probe elsewhere could place boundaries
            # differently; the chunks on disk are cut by this one).
            return cls(directory, job, ChunkPlan(chunk_plan_order(job), bounds))
        # A directory holding only what an interrupted creation leaves (cells.npz, temporary files) is ours.
        if directory.is_dir() and any(p.name != CELLS_FILE and not (p.name.startswith(".") and p.name.endswith(".tmp"))
                                      for p in directory.iterdir()):
            raise ArgumentError(f"{directory} is not empty and holds no brdfnorm checkpoint ({JOB_FILE}); refusing "
                                "to write into it", where=where)
        plan = make_plan()
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise OutputError(f"cannot create the checkpoint directory: {error.strerror}",
                              where=str(directory)) from None
        checkpoint = cls(directory, job, plan)
        buffer = io.BytesIO()
        np.savez(buffer, **job.arrays())
        checkpoint._write(CELLS_FILE, buffer.getvalue())
        # job.json last: a directory with it is a complete definition.
        header = {**job.header(), "digest": job.digest, "plan": {"bounds": plan.bounds.tolist()}}
        checkpoint._write(JOB_FILE, (canonical_json(header) + "\n").encode())
        return checkpoint

    def chunk_path(self, index: int) -> Path:
        return self.directory / f"chunk-{index:06d}.npz"

    def finished(self) -> dict[int, ChunkResult]:
        """The chunks already on disk, checked against the job."""
        found = {}
        for index in range(self.plan.count):
            path = self.chunk_path(index)
            if path.is_file():
                found[index] = self._read(path, index)
        return found

    def save(self, result: ChunkResult) -> None:
        buffer = io.BytesIO()
        arrays = {name: getattr(result, name) for name in _RESULT_ARRAYS}
        # text (certified bounds, reasons) is held as Python strings; stored as fixed-width text, never pickled
        arrays |= {name: np.asarray(getattr(result, name), dtype=str if dtype is object else dtype)
                   for name, (_, dtype) in OPTIONAL_FIELDS.items() if getattr(result, name) is not None}
        np.savez(buffer, digest=np.array(self.job.digest), cells=self.plan.chunk(result.index),
                 method=np.array(result.method), seconds=np.array(result.seconds), **arrays)
        self._write(self.chunk_path(result.index).name, buffer.getvalue())

    def _read(self, path: Path, index: int) -> ChunkResult:
        try:
            with np.load(path, allow_pickle=False) as data:
                if str(data["digest"]) != self.job.digest or not np.array_equal(data["cells"], self.plan.chunk(index)):
                    raise ValueError("it belongs to another job")
                arrays = {name: data[name] for name in _RESULT_ARRAYS}
                arrays |= {name: data[name].astype(dtype) for name, (_, dtype) in OPTIONAL_FIELDS.items()
                           if name in data}
                method, seconds = str(data["method"]), float(data["seconds"])
        except (OSError, ValueError, KeyError, zipfile.BadZipFile, EOFError) as error:
            raise ArgumentError(f"{path} is unreadable or damaged ({error}); delete it to recompute that chunk",
                                where="checkpoint") from None
        n = self.plan.chunk(index).size
        if any(array.shape[:1] != (n,) for array in arrays.values()):
            raise ArgumentError(f"{path} has the wrong number of cells; delete it to recompute that chunk",
                                where="checkpoint")
        return ChunkResult(index=index, method=method, seconds=seconds, **arrays)

    def _write(self, name: str, data: bytes) -> None:
        write_atomically(self.directory / name, data)


def write_atomically(path: Path, data: bytes) -> None:
    """Write ``path`` through a temporary file in its directory and a rename (whole or not at all)."""
    try:
        fd, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as error:
        raise OutputError(f"cannot write the checkpoint: {error.strerror}", where=str(path.parent)) from None
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, path)
    except OSError as error:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise OutputError(f"cannot write the checkpoint: {error.strerror}", where=str(path)) from None
