"""Checkpoints: a directory holding a job's definition and each finished chunk, so a killed job resumes.

Layout of ``DIR``:

* ``job.json`` — the job's header (model source, settings, task, shape), its SHA-256 and the chunk size;
* ``cells.npz`` — the cells' arrays (θ, φ, per-cell parameter values): with ``job.json``, the whole definition;
* ``chunk-NNNNNN.npz`` — one per finished chunk: the job's hash, the chunk's cell indices, its values, error
  estimates, evaluation counts, convergence flags, directions and the seconds it took.

Every file is written to a temporary name in ``DIR`` and renamed over its final name (atomic on POSIX), so a
job killed at any moment (SIGTERM, SIGKILL, a lost machine) leaves only whole files: at most the chunks in
flight are lost. A directory holding another job's checkpoint, a non-empty directory without one, or a checkpoint
holding files that are not its own is refused with a one-line error; nothing in it is overwritten. The directory
is created atomically (a complete hidden copy renamed onto it), so two processes starting the same job on a new
directory at once both succeed, one joining the other's. Chunk files are read as data through
:func:`brdfnorm.inputs.npz_arrays` (never pickled, shapes checked before arrays exist) and checked field by field
(:mod:`.chunks`); a chunk that fails is computed again, with a warning, never used (issue 35).
"""

from __future__ import annotations

import contextlib
import errno
import io
import json
import os
import re
import shutil
import tempfile
import warnings
from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, OutputError
from ..inputs import npz_arrays, parsing, read_bounded
from .chunks import BadChunk
from .chunks import checked_chunk as _checked_chunk
from .executors import OPTIONAL_FIELDS, ChunkResult
from .job import CellsJob, ChunkPlan, canonical_json, chunk_plan_order

JOB_FILE = "job.json"
CELLS_FILE = "cells.npz"
_RESULT_ARRAYS = ("value", "error", "evaluations", "converged", "nonfinite_fraction", "theta", "phi")
#: A job file's bytes (its chunk plan has one bound per chunk).
MAX_JOB_FILE_BYTES = 64 * 1024**2
#: A chunk file's bytes: a fixed part plus so much per cell (values, errors and certified bounds as text).
MAX_CHUNK_BYTES = 1024**2
CHUNK_BYTES_PER_CELL = 16 * 1024
_CHUNK_NAME = re.compile(r"chunk-([0-9]{6})\.npz\Z")


def _leftover(name: str) -> bool:
    """What an interrupted run leaves: the cells' file, temporary files."""
    return name == CELLS_FILE or (name.startswith(".") and name.endswith(".tmp"))


def _chunk_index(name: str, count: int) -> bool:
    match = _CHUNK_NAME.match(name)
    return match is not None and int(match.group(1)) < count


class Checkpoint:
    """A checkpoint directory bound to one job and its chunk plan (use :meth:`open`)."""

    def __init__(self, directory: Path, job: CellsJob, plan: ChunkPlan) -> None:
        self.directory = directory
        self.job = job
        self.plan = plan

    @classmethod
    def open(cls, directory: str | Path, job: CellsJob, make_plan: Callable[[], ChunkPlan]) -> Checkpoint:
        """Reopen ``directory`` if it holds ``job`` (with the chunk plan stored there), or create it with the plan
        ``make_plan()`` returns; refuse anything else.

        Creation is atomic and safe against a second process starting the same job at the same moment: the whole
        definition (``cells.npz``, ``job.json``) is written into a fresh hidden directory beside ``directory`` and
        renamed onto it — ``rename(2)`` replaces a missing or empty directory in one step, and fails if another
        process got there first, which is then joined (its ``job.json`` is read like any checkpoint's)."""
        directory = Path(directory)
        if directory.is_symlink():  # renamed onto, a link would be replaced: its target is the checkpoint
            directory = directory.resolve()
        where = "checkpoint"
        if directory.exists() and not directory.is_dir():
            raise ArgumentError(f"{directory} is not a directory", where=where)
        if (directory / JOB_FILE).is_file():
            return cls._join(directory, job)
        # A directory holding only what an interrupted creation of the old layout left (cells.npz, temporary
        # files) is ours; anything else is someone's.
        if directory.is_dir() and any(not _leftover(p.name) for p in directory.iterdir()):
            if (directory / JOB_FILE).is_file():  # created by another process since the check above
                return cls._join(directory, job)
            raise ArgumentError(f"{directory} is not empty and holds no brdfnorm checkpoint ({JOB_FILE}); refusing "
                                "to write into it", where=where)
        plan = make_plan()
        try:
            directory.parent.mkdir(parents=True, exist_ok=True)
            staging = Path(tempfile.mkdtemp(prefix=f".{directory.name}.", suffix=".tmp", dir=directory.parent))
        except OSError as error:
            raise OutputError(f"cannot create the checkpoint directory: {error.strerror}",
                              where=str(directory)) from None
        checkpoint = cls(staging, job, plan)
        buffer = io.BytesIO()
        np.savez(buffer, **job.arrays())
        checkpoint._write(CELLS_FILE, buffer.getvalue())
        header = {**job.header(), "digest": job.digest, "plan": {"bounds": plan.bounds.tolist()}}
        checkpoint._write(JOB_FILE, (canonical_json(header) + "\n").encode())
        try:
            try:
                os.rename(staging, directory)  # onto a missing or empty directory: in one step
            except OSError as error:
                if error.errno not in (errno.ENOTEMPTY, errno.EEXIST):
                    raise
                if not (directory / JOB_FILE).is_file() and all(_leftover(p.name) for p in directory.iterdir()):
                    # the old layout's interrupted creation: completed in place; os.link creates job.json only
                    # if no other process has meanwhile (EEXIST: join it)
                    os.replace(staging / CELLS_FILE, directory / CELLS_FILE)
                    os.link(staging / JOB_FILE, directory / JOB_FILE)
                elif not (directory / JOB_FILE).is_file():
                    raise ArgumentError(f"{directory} is not empty and holds no brdfnorm checkpoint ({JOB_FILE}); "
                                        "refusing to write into it", where=where) from None
                else:
                    return cls._join(directory, job)  # another process created it first: the same job, or refused
        except FileExistsError:
            return cls._join(directory, job)
        except OSError as error:
            raise OutputError(f"cannot create the checkpoint directory: {error.strerror}",
                              where=str(directory)) from None
        finally:
            shutil.rmtree(staging, ignore_errors=True)  # gone already when it was renamed
        return cls(directory, job, plan)

    @classmethod
    def _join(cls, directory: Path, job: CellsJob) -> Checkpoint:
        """The checkpoint in ``directory`` (which holds ``job.json``) if it is ``job``'s and holds nothing else."""
        where = "checkpoint"
        job_file = directory / JOB_FILE
        try:
            stored = json.loads(read_bounded(job_file, MAX_JOB_FILE_BYTES, error=ArgumentError))
            digest, bounds = stored["digest"], np.asarray(stored["plan"]["bounds"], dtype=np.int64)
        except ArgumentError as error:
            raise ArgumentError(f"{job_file}: {error.message}; use another directory", where=where) from None
        except (OSError, ValueError, KeyError, TypeError, RecursionError) as error:
            raise ArgumentError(f"{job_file} is not a brdfnorm checkpoint ({type(error).__name__}); use another "
                                "directory", where=where) from None
        if digest != job.digest:
            raise ArgumentError(
                f"{directory} holds the checkpoint of a different job (hash {str(digest)[:12]}…, this job's is "
                f"{job.digest[:12]}…); use another directory, or delete it to start over", where=where)
        if bounds.ndim != 1 or bounds.size < 2 or bounds[0] != 0 or bounds[-1] != job.size or \
                np.any(np.diff(bounds) <= 0):
            raise ArgumentError(f"{job_file}: damaged chunk plan; use another directory", where=where)
        foreign = sorted(p.name for p in directory.iterdir()
                         if not (_leftover(p.name) or p.name == JOB_FILE or _chunk_index(p.name, bounds.size - 1)))
        if foreign:
            raise ArgumentError(f"{directory} holds files that are not this checkpoint's ({', '.join(foreign[:3])}"
                                f"{', …' if len(foreign) > 3 else ''}); refusing to write into it", where=where)
        # The plan stored with the job, not one probed again (a probe elsewhere could place boundaries
        # differently; the chunks on disk are cut by this one).
        return cls(directory, job, ChunkPlan(chunk_plan_order(job), bounds))

    def chunk_path(self, index: int) -> Path:
        return self.directory / f"chunk-{index:06d}.npz"

    def finished(self) -> dict[int, ChunkResult]:
        """The chunks already on disk that pass :meth:`_read`'s checks; a chunk that fails is left to be computed
        again (and overwritten), with a warning saying why — never used."""
        found, channels = {}, None
        for index in range(self.plan.count):
            path = self.chunk_path(index)
            if path.exists():
                try:
                    chunk = self._read(path, index)
                    if channels is not None and chunk.value.shape[1] != channels:
                        raise BadChunk(f"{chunk.value.shape[1]} channels, other chunks {channels}")
                    found[index], channels = chunk, chunk.value.shape[1]
                except BadChunk as bad:
                    warnings.warn(f"checkpoint {self.directory}: {path.name}: {bad}; computing that chunk again",
                                  stacklevel=2)
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
        """Chunk ``index`` as data, checked field by field against the job (raises :class:`BadChunk`): the file
        bounded before it is read, the job's hash and the chunk's cells, every array's shape and dtype, θ and φ
        the job's own (task "max": a direction of the hemisphere), values and errors finite where converged,
        error estimates and evaluation counts ≥ 0."""
        cells = self.plan.chunk(index)
        n = cells.size
        try:
            data = read_bounded(path, MAX_CHUNK_BYTES + n * CHUNK_BYTES_PER_CELL, error=ArgumentError)
            with parsing(path, error=ArgumentError):
                arrays = npz_arrays(data, str(path), max_elements=64 * n + 64,
                                    max_bytes=MAX_CHUNK_BYTES + n * CHUNK_BYTES_PER_CELL, error=ArgumentError)
        except ArgumentError as error:
            raise BadChunk(f"unreadable ({error.message})") from None
        return _checked_chunk(arrays, index, cells, self.job)

    def _write(self, name: str, data: bytes) -> None:
        write_atomically(self.directory / name, data)


def check_root(directory: str | Path) -> None:
    """Refuse a directory meant to hold several checkpoints (``lut --checkpoint DIR``: one per table) that holds
    anything else: each entry must be a checkpoint directory (with its ``job.json``) or a hidden ``.tmp`` leftover."""
    directory = Path(directory)
    if directory.exists() and not directory.is_dir():
        raise ArgumentError(f"{directory} is not a directory", where="checkpoint")
    if not directory.is_dir():
        return
    foreign = sorted(p.name for p in directory.iterdir()
                     if not (p.name.startswith(".") and p.name.endswith(".tmp"))
                     and not (p.is_dir() and not p.is_symlink() and (p / JOB_FILE).is_file()))
    if foreign:
        raise ArgumentError(f"{directory} holds files that are not brdfnorm checkpoints ({', '.join(foreign[:3])}"
                            f"{', …' if len(foreign) > 3 else ''}); refusing to write into it", where="checkpoint")


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
