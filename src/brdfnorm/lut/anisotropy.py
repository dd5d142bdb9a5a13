"""Anisotropic energy tables: E(μ, α, anisotropy) of GGX and Beckmann, averaged over the view azimuth (or along a
φ_v axis), with E_avg(α, anisotropy) — the table no engine ships (issue #45).

Engines compensate anisotropic GGX by looking up their isotropic table at the geometric-mean roughness (Cycles'
``sqrtf(sqrtf(alpha_x * alpha_y))``, MaterialX's ``mx_average_alpha``); :mod:`brdfnorm.lut.anisotropy_audit`
measures what that costs. Here the lobe's own white (F = 1) single-scattering albedo, by the compiled half-vector
cubature of :mod:`brdfnorm.engine.routes.anisotropic` (its view-azimuth average and E_avg included), over an
anisotropy axis in one of the engines' parameterizations (:data:`PARAMETERIZATIONS`), each mapping (α, value) to
(α_x, α_y), α_x along the tangent (X):

* ``aspect`` — the axis is the aspect ratio a ∈ (0, 1]: α_x = α/a, α_y = α·a (√(α_x α_y) = α);
* ``burley`` — Burley 2012 ("Physically-based shading at Disney", §5.4), OSPRay and Blender's Principled BSDF:
  a = √(1 − 0.9·anisotropy), α_x = α/a, α_y = α·a, anisotropy ∈ [0, 1];
* ``materialx`` — MaterialX's ``mx_roughness_anisotropy`` (standard_surface): a = √(1 − min(anisotropy, 0.98)),
  α_x = min(α/a, 1), α_y = α·a, α = clamp(roughness², 1e-8, 1) — give a ``roughness`` axis for the clamp to be
  MaterialX's;
* ``openpbr`` — OpenPBR 1.x's ``open_pbr_anisotropy`` graph: α_x = α·√(2/(1 + (1 − anisotropy)²)),
  α_y = (1 − anisotropy)·α_x.

Axes: ``mu`` or ``theta`` (the view), ``alpha`` or ``roughness`` (α = roughness²), the anisotropy axis (named
``anisotropy``, or ``aspect`` for that parameterization) and optionally ``phi_v`` (the view azimuth from the tangent,
radians in the API) — without it every E is the average over φ_v. Cells are independent: ``workers`` and
``scheduler`` spread fixed chunks of them (:meth:`brdfnorm.parallel.Workers.map`), bit-identical to one process.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..engine.routes import anisotropic as kernel
from ..errors import ArgumentError
from ..models.base import Model
from ..registry import Registry
from .axes import DIRECTION_AXES, VIEW_AZIMUTH_AXIS
from .splitsum import DFG_F0, DFG_F90
from .table import Lut, plain_params

#: Cells per task sent to a worker (fixed, so that the chunks — and the results — do not depend on the workers).
CHUNK_CELLS = 64
#: The anisotropy axis leaves the lobe no flatter than this ratio α_y/α_x (the cubature's cost grows as its root).
MIN_ASPECT = 0.01


@dataclass(frozen=True)
class Parameterization:
    """How an engine maps (α, anisotropy value) to (α_x, α_y)."""

    name: str
    axis: str
    formula: str
    domain: tuple[float, float]
    widths: Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]

    def __call__(self, alpha, value) -> tuple[np.ndarray, np.ndarray]:
        alpha, value = np.broadcast_arrays(np.asarray(alpha, dtype=float), np.asarray(value, dtype=float))
        lo, hi = self.domain
        if np.any(~((value >= lo) & (value <= hi))):
            raise ArgumentError(f"{self.axis} must lie in [{lo:g}, {hi:g}] ({self.name}: {self.formula})",
                                where=self.axis)
        return self.widths(alpha, value)


def _aspect(alpha, a):
    return alpha / a, alpha * a


def _burley(alpha, anisotropy):
    return _aspect(alpha, np.sqrt(1.0 - 0.9 * anisotropy))


def _materialx(alpha, anisotropy):
    a = np.sqrt(1.0 - np.minimum(anisotropy, 0.98))
    alpha = np.clip(alpha, 1e-8, 1.0)
    return np.minimum(alpha / a, 1.0), alpha * a


def _openpbr(alpha, anisotropy):
    ax = alpha * np.sqrt(2.0 / (1.0 + (1.0 - anisotropy) ** 2))
    return ax, (1.0 - anisotropy) * ax


PARAMETERIZATIONS: Registry[Parameterization] = Registry("anisotropy parameterization", "anisotropy")
for _p in (
    Parameterization("aspect", "aspect", "alpha_x = alpha/a, alpha_y = alpha*a", (MIN_ASPECT, 1.0), _aspect),
    Parameterization("burley", "anisotropy", "a = sqrt(1 - 0.9*anisotropy), alpha_x = alpha/a, alpha_y = alpha*a "
                     "(Burley 2012, OSPRay, Blender)", (0.0, 1.0), _burley),
    Parameterization("materialx", "anisotropy", "a = sqrt(1 - min(anisotropy, 0.98)), alpha = clamp(alpha, 1e-8, 1), "
                     "alpha_x = min(alpha/a, 1), alpha_y = alpha*a (mx_roughness_anisotropy)", (0.0, 1.0), _materialx),
    Parameterization("openpbr", "anisotropy", "alpha_x = alpha*sqrt(2/(1 + (1 - anisotropy)^2)), "
                     "alpha_y = (1 - anisotropy)*alpha_x (OpenPBR open_pbr_anisotropy)", (0.0, 1.0 - MIN_ASPECT),
                     _openpbr),
):
    PARAMETERIZATIONS.register(_p.name, _p)


def _cells_task(distribution: str, shadowing: str, mu, phi, ax, ay, average: bool, rtol: float, weight: str):
    """One chunk's cells (a module-level function: it travels to pool processes and Dask workers)."""
    return kernel.albedo(distribution, shadowing, mu, ax, ay, None if average else phi, rtol=rtol, weight=weight)


def _averages_task(distribution: str, shadowing: str, ax, ay, rtol: float):
    return kernel.average_albedo(distribution, shadowing, ax, ay, rtol=rtol)


def _task(kind: str, args: tuple):
    """One chunk of any stage (a module-level function: one ``map`` carries every stage's chunks, each task the
    same two arguments)."""
    return (_cells_task if kind == "cells" else _averages_task)(*args)


@dataclass
class _Stage:
    """One table's cells: ``kind`` ``cells`` (:func:`_cells_task`) or ``averages``, the fixed arguments around
    the chunk's arrays (``fixed[:2]`` before them, ``fixed[2:]`` after), and the cells' arrays."""

    name: str
    kind: str
    fixed: tuple
    arrays: list[np.ndarray]

    def tasks(self) -> list[tuple]:
        n = self.arrays[0].size
        return [(self.kind, (*self.fixed[:2], *(a[s:s + CHUNK_CELLS] for a in self.arrays), *self.fixed[2:]))
                for s in range(0, n, CHUNK_CELLS)]


def _run(stages: Sequence[_Stage], workers, scheduler, checkpoint: str | Path | None) -> dict[str, list]:
    """Every stage's chunks of CHUNK_CELLS cells, computed here (``workers`` 1, no ``scheduler``) or by one pool
    of workers for all stages — E_avg's chunks first, the costliest (a chunk is 64 hemispherical averages), so
    that no worker waits at the end — and each stage's (value, error, evaluations, converged) joined in order.
    With ``checkpoint`` (a directory) each stage's chunks found in ``checkpoint/NAME`` are read instead of computed
    and each computed one is saved — with workers after each batch of 2 chunks per worker (what an interruption
    can lose)."""
    tasks = {stage.name: stage.tasks() for stage in stages}
    parts: dict[str, list] = {stage.name: [None] * len(tasks[stage.name]) for stage in stages}
    stores = {}
    if checkpoint is not None:
        from .anisotropy_checkpoint import ChunkStore

        for stage in stages:
            store = ChunkStore(Path(checkpoint) / stage.name, {"task": stage.kind, "fixed": list(stage.fixed)},
                               stage.arrays, CHUNK_CELLS)
            stores[stage.name] = store
            parts[stage.name] = [store.load(k) for k in range(len(tasks[stage.name]))]
    order = sorted(stages, key=lambda stage: stage.kind != "averages")
    missing = [(stage.name, k) for stage in order for k, part in enumerate(parts[stage.name]) if part is None]

    def keep(name: str, k: int, part) -> None:
        parts[name][k] = part
        if name in stores:
            stores[name].save(k, part)

    if workers == 1 and scheduler is None:
        for name, k in missing:
            keep(name, k, _task(*tasks[name][k]))
    elif missing:
        from ..parallel import Workers

        with Workers(workers, scheduler) as pool:
            batch = len(missing) if not stores else 2 * max(1, pool.count or 1)
            for start in range(0, len(missing), batch):
                chosen = missing[start:start + batch]
                for (name, k), part in zip(chosen, pool.map(_task, [tasks[name][k] for name, k in chosen]),
                                           strict=True):
                    keep(name, k, part)
    return {name: [np.concatenate([p[i] for p in chunks]) for i in range(4)] for name, chunks in parts.items()}


def lobe_of(model: Model) -> tuple[str, str]:
    """(distribution, shadowing) of a white ggx/beckmann lobe; anything else is refused."""
    from ..models.microfacet import MicrofacetModel

    if not isinstance(model, MicrofacetModel) or model.distribution.name not in kernel.DISTRIBUTIONS:
        raise ArgumentError("anisotropic tables are for the ggx and beckmann lobes", where="model")
    p = model.params
    if p["fresnel"] != "none" or p["ms"] != "none":
        raise ArgumentError("anisotropic tables are the white single-scattering albedo: fresnel=none, ms=none",
                            where="model")
    return model.distribution.name, str(p["shadowing"])


def compute(model: Model, axes: Mapping[str, Sequence[float]], *, anisotropy: str = "burley",
            clamp: Mapping[str, float] | None = None, rtol: float = 1e-6, average: bool = True,
            grid: str | None = None, source: str | None = None, workers: int | None = 1,
            scheduler: str | None = None, channels: Sequence[str] = (), checkpoint: str | Path | None = None) -> Lut:
    """E (and E_error, 1-E; E_avg, E_avg_error over the non-view axes) of ``model`` (ggx or beckmann, white) over
    ``axes`` (name -> values, in the arrays' order): ``mu`` or ``theta`` (radians), ``alpha`` or ``roughness``, the
    ``anisotropy`` parameterization's axis and optionally ``phi_v`` (radians from the tangent; without it E is the
    view-azimuth average). ``clamp`` raises axis values below a minimum before evaluation. ``channels=("dfg",)``
    adds the split-sum pair DFG_f0, DFG_f90 (with their errors) over the same axes, averaged over φ_v like E.
    ``checkpoint`` (a directory): each table resumable in its own subdirectory (:mod:`.anisotropy_checkpoint`).

    >>> import brdfnorm as bn
    >>> t = compute(bn.load("ggx"), {"mu": [1.0], "alpha": [0.5], "anisotropy": [0.0, 1.0]}, rtol=1e-5)
    >>> t["E"].shape, t.meta["anisotropy"]["parameterization"]
    ((1, 1, 2), 'burley')
    """
    from .. import __version__

    distribution, shadowing = lobe_of(model)
    parameterization = PARAMETERIZATIONS[PARAMETERIZATIONS.validate(anisotropy)]
    for c in channels:
        if c != "dfg":
            raise ArgumentError(f"unknown channel set {c!r} (known: dfg)", where="channels")

    clamp = dict(clamp or {})
    names = list(axes)
    values = {n: np.asarray(axes[n], dtype=float) for n in names}
    for n, v in values.items():
        if v.ndim != 1 or v.size == 0 or not np.all(np.isfinite(v)):
            raise ArgumentError(f"axis {n!r} needs a non-empty list of finite numbers", where="axes")
    for n in clamp:
        if n not in values:
            raise ArgumentError(f"clamp {n}: no axis of that name", where="clamp")
    evaluated = {n: np.maximum(v, clamp[n]) if n in clamp else v for n, v in values.items()}
    direction = [n for n in names if n in DIRECTION_AXES]
    roughness = [n for n in names if n in ("alpha", "roughness")]
    if len(direction) != 1 or len(roughness) != 1 or parameterization.axis not in names:
        raise ArgumentError(f"an anisotropic table needs one view axis (mu or theta), one of alpha or roughness and "
                            f"the {parameterization.axis} axis ({parameterization.name}); got {names}", where="axes")
    allowed = {direction[0], roughness[0], parameterization.axis, VIEW_AZIMUTH_AXIS}
    if set(names) - allowed:
        raise ArgumentError(f"unknown axes {sorted(set(names) - allowed)} (known here: {sorted(allowed)})",
                            where="axes")
    mu = evaluated["mu"] if "mu" in evaluated else np.cos(evaluated["theta"])
    if np.any(~(mu > 0)) or np.any(mu > 1):
        raise ArgumentError("the view must lie above the horizon: mu in (0, 1], theta in [0, π/2); clamp mu, e.g. "
                            "mu=1e-4", where="axes")
    alpha = evaluated[roughness[0]] ** 2 if roughness[0] == "roughness" else evaluated[roughness[0]]
    if np.any(~(alpha >= 1e-12)) or np.any(alpha > 10):
        raise ArgumentError("alpha must lie in [1e-12, 10]; clamp it, e.g. alpha=1e-8", where="axes")
    shape = tuple(values[n].size for n in names)

    def along(name: str, array: np.ndarray, order: list[str]) -> np.ndarray:
        index = [1] * len(order)
        index[order.index(name)] = -1
        return array.reshape(index)

    ax, ay = parameterization(along(roughness[0], alpha, names), along(parameterization.axis,
                                                                       evaluated[parameterization.axis], names))
    if np.any(np.minimum(ax, ay) / np.maximum(ax, ay) < MIN_ASPECT * (1 - 1e-12)):
        raise ArgumentError(f"the lobe's aspect α_y/α_x must be ≥ {MIN_ASPECT:g}", where=parameterization.axis)
    phi = along(VIEW_AZIMUTH_AXIS, evaluated[VIEW_AZIMUTH_AXIS], names) if VIEW_AZIMUTH_AXIS in names else 0.0
    full = [np.ascontiguousarray(np.broadcast_to(a, shape), dtype=float).ravel()
            for a in (along(direction[0], mu, names), phi, ax, ay)]
    averaged = VIEW_AZIMUTH_AXIS not in names
    grids = [("E", "white")] + ([(DFG_F0, "f0"), (DFG_F90, "f90")] if channels else [])
    stages = [_Stage(name, "cells", (distribution, shadowing, averaged, float(rtol), weight), full)
              for name, weight in grids]
    if average:
        others = [n for n in names if n not in (direction[0], VIEW_AZIMUTH_AXIS)]
        avg_shape = tuple(values[n].size for n in others)
        a_x, a_y = parameterization(along(roughness[0], alpha, others),
                                    along(parameterization.axis, evaluated[parameterization.axis], others))
        pairs = [np.ascontiguousarray(np.broadcast_to(a, avg_shape), dtype=float).ravel() for a in (a_x, a_y)]
        stages.append(_Stage("E_avg", "averages", (distribution, shadowing, float(rtol)), pairs))
    results = _run(stages, workers, scheduler, checkpoint)
    tables, table_axes = {}, {}
    converged, unconverged, count = np.ones(full[0].size, dtype=bool), 0, 0
    for stage in stages:
        value, error, evaluations, ok = results[stage.name]
        cells = stage.kind == "cells"
        table_shape = shape if cells else avg_shape
        tables[stage.name], tables[f"{stage.name}_error"] = value.reshape(table_shape), error.reshape(table_shape)
        table_axes[stage.name] = table_axes[f"{stage.name}_error"] = tuple(names) if cells else tuple(others)
        if cells:  # a cell counts once, whichever of its channels missed
            converged &= ok
        else:
            unconverged += int(np.count_nonzero(~ok))
        count += int(evaluations.sum())
    unconverged += int(np.count_nonzero(~converged))
    tables["1-E"] = 1.0 - tables["E"]
    table_axes["1-E"] = tuple(names)
    fixed = {k: v for k, v in model.params.items() if k not in ("alpha", "alpha_x", "alpha_y")}
    meta = {"model": source or model.name, "parameters": plain_params(fixed), "grid": grid, "clamp": clamp,
            "rtol": rtol,
            "method": "anisotropic", "units": {"mu": "cos theta_o", "theta": "radians", VIEW_AZIMUTH_AXIS: "radians"},
            "brdfnorm": __version__, "unconverged": unconverged, "evaluations": count,
            "anisotropy": {"parameterization": parameterization.name, "axis": parameterization.axis,
                           "formula": parameterization.formula,
                           "view_azimuth": ("phi_v axis, from the tangent (alpha_x's direction)"
                                            if VIEW_AZIMUTH_AXIS in names else
                                            "E averaged over the view azimuth phi_v (E_avg over the hemisphere)")}}
    if roughness[0] == "roughness":
        meta["aliases"] = {"roughness": "alpha = roughness²"}
    if channels:
        meta["dfg"] = ("the lobe times 1 - (1 - V.H)^5 (DFG_f0) and (1 - V.H)^5 (DFG_f90), white, by the same "
                       "cubature as E" + ("" if VIEW_AZIMUTH_AXIS in names else ", averaged over phi_v"))
    order = ["E", "E_error", "E_avg", "E_avg_error", "1-E", DFG_F0, f"{DFG_F0}_error", DFG_F90, f"{DFG_F90}_error"]
    return Lut({n: tables[n] for n in order if n in tables}, axes, meta, table_axes)
