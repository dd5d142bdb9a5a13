"""Checkpoints of the anisotropic tables (:mod:`.anisotropy`): one directory per table (``E``, ``E_avg``,
``DFG_f0``, ``DFG_f90`` under ``lut --checkpoint DIR``), holding the table's definition and each finished chunk,
so that an interrupted three-axis table resumes where it stopped and ends bit-identical to an uninterrupted run.

The cells of these tables are not :class:`brdfnorm.parallel.CellsJob` cells (the compiled kernel takes
(μ, φ_v, α_x, α_y) and a weight, not a model's parameters), so they have their own job file; everything else is
:mod:`brdfnorm.parallel.checkpoint`'s discipline:

* ``job.json`` — the kernel's settings (distribution, shadowing, weight, rtol, averaged or not, chunk size), the
  brdfnorm version and a SHA-256 over them and the cells' float64 bytes: a directory holding another table's
  checkpoint, or a non-empty directory without one, or foreign files in one, is refused with one line;
* ``chunk-NNNNNN.npz`` — one per finished chunk of :data:`CHUNK_CELLS` cells: the job's hash, values, error
  estimates, evaluation counts, convergence flags; written to a temporary name and renamed (whole or absent),
  read back as data (:func:`brdfnorm.inputs.npz_arrays`, bounded, never pickled) and checked field by field — a
  chunk that fails is computed again with a warning, never used.

Chunks are fixed by the cells alone (never by the number of workers), so any resumption computes exactly the
chunks a single run would have.
"""

from __future__ import annotations

import hashlib
import json
import re
import warnings
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import ArgumentError, OutputError
from ..inputs import npz_arrays, parsing, read_bounded
from ..parallel.checkpoint import JOB_FILE, write_atomically
from ..parallel.job import canonical_json

KIND = "brdfnorm anisotropic table"
MAX_JOB_BYTES = 64 * 1024
_CHUNK = re.compile(r"chunk-([0-9]{6})\.npz\Z")
_FIELDS = {"value": np.float64, "error": np.float64, "evaluations": np.int64, "converged": np.bool_}


class ChunkStore:
    """The checkpoint of one table: ``settings`` (JSON scalars) and ``cells`` (float64 arrays of one length, the
    kernel's inputs) name it; :meth:`load` and :meth:`save` read and write its chunks of ``chunk`` cells."""

    def __init__(self, directory: str | Path, settings: dict, cells: Sequence[np.ndarray], chunk: int) -> None:
        from .. import __version__

        self.directory = Path(directory)
        self.size = int(cells[0].size)
        self.chunk = int(chunk)
        self.count = -(-self.size // self.chunk)
        digest = hashlib.sha256(canonical_json({"kind": KIND, "brdfnorm": __version__, "chunk": self.chunk,
                                                **settings}).encode())
        for array in cells:
            digest.update(np.ascontiguousarray(array, dtype="<f8").tobytes())
        self.digest = digest.hexdigest()
        self.header = {"kind": KIND, "brdfnorm": __version__, "chunk": self.chunk, "cells": self.size,
                       "settings": settings, "digest": self.digest}
        self._open()

    def _open(self) -> None:
        where, directory = "checkpoint", self.directory
        if directory.exists() and not directory.is_dir():
            raise ArgumentError(f"{directory} is not a directory", where=where)
        job = directory / JOB_FILE
        if job.is_file():
            try:
                stored = json.loads(read_bounded(job, MAX_JOB_BYTES, error=ArgumentError))
                digest = stored["digest"]
            except ArgumentError as error:
                raise ArgumentError(f"{job}: {error.message}; use another directory", where=where) from None
            except (ValueError, KeyError, TypeError, RecursionError) as error:
                raise ArgumentError(f"{job} is not a brdfnorm checkpoint ({type(error).__name__}); use another "
                                    "directory", where=where) from None
            if digest != self.digest:
                raise ArgumentError(f"{directory} holds the checkpoint of a different table (hash {str(digest)[:12]}"
                                    f"…, this table's is {self.digest[:12]}…); use another directory, or delete it "
                                    "to start over", where=where)
            foreign = sorted(p.name for p in directory.iterdir() if not self._own(p.name))
            if foreign:
                raise ArgumentError(f"{directory} holds files that are not this checkpoint's ({', '.join(foreign[:3])}"
                                    f"{', …' if len(foreign) > 3 else ''}); refusing to write into it", where=where)
            return
        if directory.is_dir() and any(not _temporary(p.name) for p in directory.iterdir()):
            raise ArgumentError(f"{directory} is not empty and holds no brdfnorm checkpoint ({JOB_FILE}); refusing "
                                "to write into it", where=where)
        try:
            directory.mkdir(parents=True, exist_ok=True)
        except OSError as error:
            raise OutputError(f"cannot create the checkpoint directory: {error.strerror}",
                              where=str(directory)) from None
        write_atomically(job, (canonical_json(self.header) + "\n").encode())

    def _own(self, name: str) -> bool:
        match = _CHUNK.match(name)
        return name == JOB_FILE or _temporary(name) or (match is not None and int(match.group(1)) < self.count)

    def path(self, index: int) -> Path:
        return self.directory / f"chunk-{index:06d}.npz"

    def cells(self, index: int) -> slice:
        return slice(index * self.chunk, min(self.size, (index + 1) * self.chunk))

    def load(self, index: int) -> tuple[np.ndarray, ...] | None:
        """Chunk ``index``'s (value, error, evaluations, converged) if it is on disk and passes every check;
        None if absent; a damaged or foreign chunk is reported (a warning) and None."""
        path = self.path(index)
        if not path.exists():
            return None
        n = self.cells(index).stop - self.cells(index).start
        try:
            data = read_bounded(path, 4096 + 64 * n, error=ArgumentError)
            with parsing(path, error=ArgumentError):
                arrays = npz_arrays(data, str(path), max_elements=max(n, 1), max_bytes=4096 + 64 * n,
                                    error=ArgumentError)
            problem = self._check(arrays, n)
        except ArgumentError as error:
            problem = f"unreadable ({error.message})"
        if problem is None:
            return tuple(arrays[name] for name in _FIELDS)
        warnings.warn(f"checkpoint {self.directory}: {path.name}: {problem}; computing that chunk again",
                      stacklevel=2)
        return None

    def _check(self, arrays: dict, n: int) -> str | None:
        digest = arrays.get("digest")
        if digest is None or digest.shape != () or str(digest) != self.digest:
            return "another table's chunk (hash differs)"
        for name, dtype in _FIELDS.items():
            array = arrays.get(name)
            if array is None or array.shape != (n,) or array.dtype != dtype:
                return f"{name}: missing or not ({n},) {np.dtype(dtype).name}"
        value, error, evaluations, converged = (arrays[name] for name in _FIELDS)
        if not np.all(np.isfinite(value[converged]) & np.isfinite(error[converged])):
            return "a converged cell is not finite"
        if np.any(~(error >= 0)[np.isfinite(error)]) or np.any(evaluations < 0):
            return "a negative error estimate or evaluation count"
        return None

    def save(self, index: int, result: Sequence[np.ndarray]) -> None:
        import io

        buffer = io.BytesIO()
        np.savez(buffer, digest=np.array(self.digest),
                 **{name: np.asarray(a, dtype=dtype) for (name, dtype), a in zip(_FIELDS.items(), result,
                                                                                  strict=True)})
        write_atomically(self.path(index), buffer.getvalue())


def _temporary(name: str) -> bool:
    return name.startswith(".") and name.endswith(".tmp")
