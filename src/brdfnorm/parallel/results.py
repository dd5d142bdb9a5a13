"""Computed cells as the serial API's result objects, and normalization sweeps as cells jobs.

:func:`albedo_result` gives the :class:`~brdfnorm.engine.methods.AlbedoResult` that ``brdfnorm.albedo`` returns for the
same cells; :func:`sweep_job` / :func:`normalization_result` (or :func:`normalize_sweep`, both in one call) give
what ``brdfnorm.normalize`` with ``sweep=`` returns: ``at="normal"`` and ``at="view"`` are albedo cells (sweep
value × direction), ``at="max"`` is one cell per sweep value of the ``"max"`` task (each cell runs the search of
:func:`brdfnorm.normalization.normalize`). Values are bit for bit those of the serial calls.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np

from ..engine.methods import AlbedoResult
from ..errors import ArgumentError
from ..models import Model
from ..normalization import AT, NormalizationResult
from ..validate import DEFAULT_RTOL
from . import CellsResult, albedo_cells
from .job import CellsJob


def normalize_sweep(model: Model, at: str, name: str, values, theta=None, phi=0.0, *, over: str = "light",
                    rtol: float = DEFAULT_RTOL, method: str = "auto", workers: int | None = None,
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
    """The computed sweep as :func:`brdfnorm.normalization.normalize` returns it."""
    with np.errstate(divide="ignore"):
        factor = 1.0 / cells.value
    values = job.values[name].reshape(job.shape)[:, 0]
    return NormalizationResult(at=at, parameter=name, values=values, theta=cells.theta, phi=cells.phi,
                               albedo=cells.value, error=cells.error, factor=factor, method=cells.method,
                               over=job.settings.over, converged=cells.converged,  # type: ignore[arg-type]
                               reason=cells.reason, model=_model_name(job), params={**_bound(job), name: values},
                               rtol=job.settings.rtol)


def albedo_result(job: CellsJob, cells: CellsResult) -> AlbedoResult:
    """The computed cells of an ``"albedo"`` job as :func:`brdfnorm.albedo` returns them."""
    if job.task != "albedo":
        raise ArgumentError(f"a {job.task!r} job's cells are not albedos at their directions", where="task")
    params = {}
    for name, value in job.source.params.items():
        if name in job.values:
            params[name] = job.values[name].reshape(job.shape)
        elif isinstance(value, str):  # a choice parameter: the same name for every cell
            params[name] = value
        else:  # as brdfnorm.albedo reports bound values: broadcast to the cells (colours keep their 3)
            array = np.asarray(value, dtype=float)
            params[name] = np.broadcast_to(array, job.shape + array.shape)
    return AlbedoResult(value=cells.value, error=cells.error, evaluations=cells.evaluations,
                        converged=cells.converged, method=cells.method, theta=cells.theta, phi=cells.phi,
                        over=job.settings.over, params=params,  # type: ignore[arg-type]
                        nonfinite_fraction=cells.nonfinite_fraction, lower=cells.lower, upper=cells.upper,
                        reason=cells.reason, reflected=cells.reflected, transmitted=cells.transmitted,
                        model=_model_name(job), bound=_bound(job), rtol=job.settings.rtol)


def _model_name(job: CellsJob) -> str:
    """The model's name as brdfnorm.load gives it (a .brdf file's stem)."""
    return job.source.name if job.source.kind == "builtin" else Path(job.source.name).stem


def _bound(job: CellsJob) -> dict:
    """The model's bound parameter values as the serial results report them (colours as tuples)."""
    return dict(job.source.params)
