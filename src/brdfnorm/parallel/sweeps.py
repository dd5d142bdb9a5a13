"""Normalization factors over a parameter sweep (``brdfnorm.normalize`` with ``sweep=``), computed as a cells job.

``at="normal"`` and ``at="view"`` are albedo cells (sweep value × direction); ``at="max"`` is one cell per sweep
value of the ``"max"`` task (each cell runs the search of :func:`brdfnorm.normalize.normalize`). The result is
the :class:`~brdfnorm.normalize.NormalizationResult` the serial call returns, bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..errors import ArgumentError
from ..models import Model
from ..normalize import AT, NormalizationResult
from . import CellsResult, albedo_cells
from .job import CellsJob


def normalize_sweep(model: Model, at: str, name: str, values, theta=None, phi=0.0, *, over: str = "light",
                    rtol: float = 1e-10, method: str = "auto", workers: int | None = None,
                    scheduler: str | None = None, checkpoint: str | Path | None = None,
                    on_progress: Callable[[int, int], None] | None = None,
                    ) -> tuple[NormalizationResult, CellsResult]:
    """Factors 1/E for the sweep ``name`` over ``values`` under convention ``at``, and the run's record."""
    job = sweep_job(model, at, name, values, theta, phi, over=over, rtol=rtol, method=method)
    cells = albedo_cells(job, workers=workers, scheduler=scheduler, checkpoint=checkpoint, on_progress=on_progress)
    return normalization_result(job, at, name, cells), cells


def sweep_job(model: Model, at: str, name: str, values, theta=None, phi=0.0, **settings: object) -> CellsJob:
    """The cells of a normalization sweep: (value, θ) for ``view``, (value, 0) for ``normal``, values for ``max``."""
    if at not in AT:
        raise ArgumentError(f"unknown convention {at!r} (known: {', '.join(AT)})", where="at")
    values = np.asarray(values, dtype=float).ravel()
    if values.size == 0:
        raise ArgumentError(f"the sweep over {name} is empty", where="sweep")
    if at == "view":
        if theta is None:
            raise ArgumentError("at='view' needs the polar angles (theta)", where="theta")
        theta = np.atleast_1d(np.asarray(theta, dtype=float)).ravel()
        return CellsJob.of(model, theta[None, :], phi, {name: values[:, None]}, **settings)
    task = "max" if at == "max" else "albedo"
    return CellsJob.of(model, np.zeros((values.size, 1)), 0.0, {name: values[:, None]}, task=task, **settings)


def normalization_result(job: CellsJob, at: str, name: str, cells: CellsResult) -> NormalizationResult:
    """The computed sweep as :func:`brdfnorm.normalize.normalize` returns it."""
    with np.errstate(divide="ignore"):
        factor = 1.0 / cells.value
    return NormalizationResult(at=at, parameter=name, values=job.values[name].reshape(job.shape)[:, 0],
                               theta=cells.theta, phi=cells.phi, albedo=cells.value, error=cells.error,
                               factor=factor, method=cells.method, over=job.settings.over,  # type: ignore[arg-type]
                               converged=cells.converged)
