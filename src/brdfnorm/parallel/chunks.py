"""A checkpoint's chunk read back as data and checked field by field before it is used (issue 35).

A chunk file whose digest matches the job could still hold anything: NaN values marked converged, negative error
estimates, a θ of 7 rad, negative evaluation counts, complex values. :func:`checked_chunk` accepts a chunk only
if every array has the shape and dtype :meth:`Checkpoint.save <brdfnorm.parallel.checkpoint.Checkpoint.save>`
writes, its θ and φ are the job's own cells (for the ``"max"`` task, whose θ is the direction found, a direction
of the upper hemisphere), values and errors are finite where the cell converged, error estimates and evaluation
counts are ≥ 0 (−1, "not counted", for the ``"max"`` task only) and the non-finite share lies in [0, 1].
Anything else raises :class:`BadChunk`; the checkpoint then computes that chunk again.
"""

from __future__ import annotations

import math

import numpy as np

from .executors import OPTIONAL_FIELDS, ChunkResult
from .job import CellsJob

#: Most channels one cell may hold (a colour is 3).
MAX_CHANNELS = 16


class BadChunk(Exception):
    """A chunk file that must not be used (the message says why)."""


def _text(arrays: dict, name: str, limit: int = 200) -> str:
    value = arrays.get(name)
    if value is None or value.dtype.kind != "U" or value.shape != ():
        raise BadChunk(f"no {name} text")
    text = str(value[()])
    if len(text) > limit:
        raise BadChunk(f"{name} longer than {limit} characters")
    return text


def _array(arrays: dict, name: str, kinds: str, shape: tuple[int, ...]) -> np.ndarray:
    value = arrays.get(name)
    if value is None:
        raise BadChunk(f"no {name} array")
    if value.dtype.kind not in kinds:
        kind = {"c": "complex", "U": "text", "b": "bool"}.get(value.dtype.kind, str(value.dtype))
        raise BadChunk(f"{name} holds {kind} values")
    if value.shape != shape:
        raise BadChunk(f"{name} has shape {value.shape}, expected {shape}")
    return value


def _first(mask: np.ndarray) -> int:
    return int(np.flatnonzero(mask.reshape(mask.shape[0], -1).any(axis=1))[0])


def checked_chunk(arrays: dict[str, np.ndarray], index: int, cells: np.ndarray, job: CellsJob) -> ChunkResult:
    """The :class:`ChunkResult` of chunk ``index`` (cells ``cells`` of ``job``) from its arrays, or
    :class:`BadChunk`."""
    if _text(arrays, "digest", 64) != job.digest:
        raise BadChunk("it belongs to another job")
    stored = arrays.get("cells")
    if stored is None or stored.dtype.kind not in "iu" or not np.array_equal(stored, cells):
        raise BadChunk("its cells are not this chunk's")
    n = cells.size
    method = _text(arrays, "method")
    seconds = arrays.get("seconds")
    if seconds is None or seconds.dtype.kind != "f" or seconds.shape != () or not math.isfinite(seconds) or \
            seconds < 0:
        raise BadChunk("no finite, non-negative seconds")
    value = arrays.get("value")
    channels = value.shape[1] if value is not None and value.ndim == 2 else 0
    if not 1 <= channels <= MAX_CHANNELS:
        raise BadChunk(f"value has shape {None if value is None else value.shape}, expected ({n}, channels)")
    value = _array(arrays, "value", "f", (n, channels)).astype(float)
    error = _array(arrays, "error", "f", (n, channels)).astype(float)
    evaluations = _array(arrays, "evaluations", "iu", (n,)).astype(np.int64)
    converged = _array(arrays, "converged", "b", (n,))
    fraction = _array(arrays, "nonfinite_fraction", "f", (n,)).astype(float)
    theta = _array(arrays, "theta", "f", (n,)).astype(float)
    phi = _array(arrays, "phi", "f", (n,)).astype(float)
    if job.task == "albedo":
        if not (np.array_equal(theta, job.theta[cells]) and np.array_equal(phi, job.phi[cells])):
            raise BadChunk("its θ or φ are not the job's cells")
    elif not (np.all(np.isfinite(theta)) and np.all(theta >= 0) and np.all(theta <= np.pi / 2)
              and np.all(np.isfinite(phi))):
        raise BadChunk("its θ lies outside [0, π/2] or its φ is not finite")
    lowest = -1 if job.task == "max" else 0
    if np.any(evaluations < lowest):
        raise BadChunk(f"a negative evaluation count (cell {_first(evaluations < lowest)} of the chunk)")
    if not np.all((fraction >= 0) & (fraction <= 1)):
        raise BadChunk("a non-finite share outside [0, 1]")
    settled = converged[:, None]
    for name, array in (("value", value), ("error estimate", error)):
        bad = settled & ~np.isfinite(array)
        if bad.any():
            raise BadChunk(f"a converged cell with a non-finite {name} (cell {_first(bad)} of the chunk)")
    if np.any(error < 0):  # NaN compares False: a non-finite error is allowed only where the cell did not converge
        raise BadChunk(f"a negative error estimate (cell {_first(error < 0)} of the chunk)")
    optional = {}
    for name, (tail, dtype) in OPTIONAL_FIELDS.items():
        if name not in arrays:
            continue
        shape = (n, channels) if tail == "channels" else (n,)
        array = _array(arrays, name, "U" if dtype is object else "f", shape)
        if dtype is not object and np.any(settled & ~np.isfinite(array)):
            raise BadChunk(f"a converged cell with a non-finite {name}")
        optional[name] = array.astype(dtype)
    return ChunkResult(index=index, method=method, seconds=float(seconds), value=value, error=error,
                       evaluations=evaluations, converged=converged.astype(bool), nonfinite_fraction=fraction,
                       theta=theta, phi=phi, **optional)
