"""A table job as data: the model as its source, the albedo settings, the cells, a hash, and fixed chunks.

Issue #17: a job travels to other processes and machines as *source* — a built-in lobe's name and parameter
values, or a ``.brdf`` file's text, display path and parameter values — never as a pickled closure, so any
worker running the same brdfnorm version rebuilds exactly the same model (:meth:`ModelSource.load`).

A :class:`CellsJob` is that source, the :class:`AlbedoSettings`, a task — ``"albedo"`` (E at each cell's
direction) or ``"max"`` (per cell, the direction of largest E, searched as ``normalize(at="max")`` does; the
cells' angles are then unused) — and the cells: polar angle, azimuth and the per-cell values of float
parameters, flattened from a table of shape :attr:`CellsJob.shape`. :attr:`CellsJob.digest` is a SHA-256
over a canonical encoding (sorted-key JSON for the scalars, little-endian float64 bytes for the arrays, the
brdfnorm version), which names the job in checkpoints.

Chunks (:func:`chunk_plan`) are a function of the job alone, never of the number of workers or where they
run: the cells are put in a canonical order (per-cell parameters, then θ, then φ — neighbours in parameter
space cost about the same, so each chunk groups cells of similar cost) and cut where the cost estimated by a
deterministic probe (evaluation counts of a few cells, interpolated along the order)
reaches multiples of about :data:`TARGET_EVALUATIONS` integrand evaluations — about a second of one core —
or every ``chunk_cells`` cells where the job fixes that. Each chunk is
one vectorized ``albedo`` batch, so whichever process computes it, it computes the same batch and the result
is bit-for-bit the same.
"""

from __future__ import annotations

import hashlib
import json
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Literal

import numpy as np

from .. import validate
from ..engine.methods import albedo as compute_albedo
from ..engine.methods import check_settings
from ..errors import ArgumentError
from ..models import REGISTRY, Model
from ..validate import DEFAULT_MAX_EVALUATIONS, DEFAULT_RTOL

Task = Literal["albedo", "max"]
TASKS = ("albedo", "max")
#: Version of the job encoding (part of the hash, so a format change never resumes an old checkpoint).
FORMAT = 1
#: About how many integrand evaluations one chunk should take (≈ 0.5–1.5 s of one core: 4–10 M evaluations/s).
TARGET_EVALUATIONS = 5_000_000
#: Most cells in one chunk (bounds a chunk's memory when its cells are cheap).
MAX_CELLS_PER_CHUNK = 1024
#: Jobs this small are one chunk: a probe would cost as much as the work.
SMALL_JOB = 32
#: Most cells the probe integrates (at the job's tolerance).
PROBE_CELLS = 32
#: Albedo integrals per cell of the "max" task (a 46-point grid, a 40-step golden-section search, the tie check).
MAX_TASK_INTEGRALS = 90


@dataclass(frozen=True)
class ModelSource:
    """A model as the data it was built from: ``kind`` "builtin" (``name`` is the registry name), "brdf"
    (``name`` is the file's display path, ``text`` its content) or "mitsuba" (``name`` is ``mitsuba:PLUGIN``, or an
    XML file's path with ``text`` its ``<bsdf>``), and the bound parameter values."""

    kind: Literal["builtin", "brdf", "mitsuba"]
    name: str
    params: Mapping[str, object] = field(default_factory=dict)
    text: str | None = field(default=None, repr=False)

    @classmethod
    def of(cls, model: Model) -> ModelSource:
        """The source the model declares (:meth:`~brdfnorm.models.base.Model.origin`: what :func:`brdfnorm.load`
        was given, and a file's text), with its scalar parameter values."""
        from ..models.mitsuba import is_mitsuba

        params = {}
        for p in model.parameters:
            value = model.params[p.name]
            if p.kind == "choice":  # a name (e.g. shadowing=separable) travels as itself
                params[p.name] = str(value)
                continue
            array = np.asarray(value, dtype=float)
            if array.ndim > (1 if p.per_channel else 0):
                raise ArgumentError(f"parameter {p.name} is bound to an array; give per-cell values as the job's "
                                    "cell values instead", where="model")
            params[p.name] = (bool(value) if p.kind == "bool" else
                              tuple(float(c) for c in array) if p.per_channel else
                              int(array) if p.kind == "int" else float(array))
        origin = model.origin()
        kind = "mitsuba" if is_mitsuba(origin.key) else "brdf" if origin.text is not None else "builtin"
        if origin.text is not None and not origin.text:
            raise ArgumentError(f"{model.name}: the model's file text is unknown (parse it with "
                                "brdfnorm.brdffile.parse_brdf or read_brdf)", where="model")
        if kind == "builtin" and REGISTRY.get(origin.key) is not type(model):
            raise ArgumentError(f"{type(model).__name__} cannot travel to other processes: only built-in lobes and "
                                "models read by brdfnorm.load have a source", where="model")
        return cls(kind, origin.key, {**origin.fixed, **params}, origin.text)

    def load(self) -> Model:
        """Rebuild the model by :func:`brdfnorm.load` (a name) or :func:`brdfnorm.load_text` (a file's text),
        the same functions that loaded it where the job was made."""
        from .. import load, load_text

        if self.text is None:
            return load(self.name, **self.params)
        return load_text(self.text, self.name, **self.params)

    def to_json(self) -> dict:
        params = {k: list(v) if isinstance(v, tuple) else v for k, v in sorted(self.params.items())}
        return {"kind": self.kind, "name": self.name, "params": params, "text": self.text}

    @classmethod
    def from_json(cls, data: Mapping) -> ModelSource:
        params = {k: tuple(v) if isinstance(v, list) else v for k, v in data["params"].items()}
        return cls(data["kind"], data["name"], params, data.get("text"))


@dataclass(frozen=True)
class AlbedoSettings:
    """The arguments of :func:`brdfnorm.albedo` a job fixes for all its cells."""

    rtol: float = DEFAULT_RTOL
    atol: float = 0.0
    method: str = "auto"
    over: str = "light"
    nonfinite: str = "raise"
    max_evaluations: int = DEFAULT_MAX_EVALUATIONS
    digits: int | None = None  # method "certified" only

    def to_json(self) -> dict:
        return {"rtol": float(self.rtol), "atol": float(self.atol), "method": self.method, "over": self.over,
                "nonfinite": self.nonfinite, "max_evaluations": int(self.max_evaluations),
                "digits": None if self.digits is None else int(self.digits)}

    def validate(self, model: Model) -> None:
        """Refuse bad settings in the calling process, before any work is sent out (the checks of
        :func:`brdfnorm.albedo` itself: :func:`brdfnorm.engine.methods.check_settings`)."""
        check_settings(model, over=self.over, rtol=self.rtol, atol=self.atol, method=self.method,
                       nonfinite=self.nonfinite, max_evaluations=self.max_evaluations, digits=self.digits)


@dataclass(frozen=True, eq=False)
class CellsJob:
    """A table of albedo cells: see the module docstring. Build one with :meth:`of`."""

    source: ModelSource
    settings: AlbedoSettings
    shape: tuple[int, ...]
    theta: np.ndarray  # (N,) radians
    phi: np.ndarray  # (N,) radians
    values: Mapping[str, np.ndarray]  # per-cell float parameter values, each (N,)
    task: Task = "albedo"
    chunk_cells: int | None = None  # fixed chunk size (None: chosen by the probe)
    #: The loaded model the job was made from (None for a job rebuilt from its data): computed with in this
    #: process, so one worker never parses or compiles the model again. Never hashed, never shipped.
    model: Model | None = field(default=None, repr=False)

    @classmethod
    def of(cls, model: Model, theta=0.0, phi=0.0, values: Mapping[str, object] | None = None, *,
           task: Task = "albedo", chunk_cells: int | None = None, **settings: object) -> CellsJob:
        """Cells at the broadcast shape of ``theta``, ``phi`` (radians) and the per-cell parameter ``values``;
        ``settings`` are :class:`AlbedoSettings` fields (rtol, atol, method, over, nonfinite, max_evaluations,
        digits)."""
        if task not in TASKS:
            raise ArgumentError(f"task must be one of {', '.join(TASKS)}, got {task!r}", where="task")
        validate_chunk_cells(chunk_cells)
        if task == "max" and len(values or {}) > 1:
            raise ArgumentError("the 'max' task searches one swept parameter at a time", where="values")
        theta, phi = validate.angles(theta, phi)
        per_cell = {}
        for name, value in sorted((values or {}).items()):
            parameter = model.parameter(name)
            if parameter.kind != "float":
                raise ArgumentError(f"only float parameters vary per cell; {name} is {parameter.kind}", where=name)
            per_cell[name] = np.asarray(parameter.validate(value), dtype=float)
        shape = np.broadcast_shapes(theta.shape, phi.shape, *(v.shape for v in per_cell.values()))
        if math.prod(shape) == 0:
            raise ArgumentError("the table has no cells", where="theta")
        validate.batch_size(shape)  # bounded memory: refused before any array of the table's size is made
        flat = {name: np.ascontiguousarray(np.broadcast_to(v, shape), dtype="<f8").ravel()
                for name, v in per_cell.items()}
        unknown = sorted(set(settings) - set(AlbedoSettings.__dataclass_fields__))
        if unknown:
            raise ArgumentError(f"unknown albedo settings: {', '.join(unknown)}", where="settings")
        chosen = AlbedoSettings(**settings)  # type: ignore[arg-type]
        ignored = sorted({"atol", "nonfinite", "max_evaluations", "digits"} & set(settings))
        if task == "max" and ignored:
            # normalize(at="max") takes rtol, method and over only; a setting it would ignore is refused
            raise ArgumentError(f"the 'max' task does not take {', '.join(ignored)}", where="settings")
        # Per-cell values replace whatever the model had bound for those parameters (a sweep's array).
        bound = model.with_params(**{name: model.parameter(name).default for name in per_cell})
        return cls(ModelSource.of(bound), chosen, tuple(int(s) for s in shape),
                   np.ascontiguousarray(np.broadcast_to(theta, shape), dtype="<f8").ravel(),
                   np.ascontiguousarray(np.broadcast_to(phi, shape), dtype="<f8").ravel(),
                   flat, task, None if chunk_cells is None else int(chunk_cells), bound)

    def loaded(self) -> Model:
        """The job's model: the one it was made from, else rebuilt from its source."""
        return self.model if self.model is not None else self.source.load()

    @property
    def size(self) -> int:
        return int(self.theta.size)

    def header(self) -> dict:
        """Everything but the cells' arrays, as JSON-ready data (what each chunk task carries)."""
        from .. import __version__

        return {"format": FORMAT, "brdfnorm": __version__, "task": self.task, "source": self.source.to_json(),
                "settings": self.settings.to_json(), "shape": list(self.shape), "per_cell": sorted(self.values),
                "chunk_cells": self.chunk_cells}

    def arrays(self) -> dict[str, np.ndarray]:
        """The cells' arrays by name, in the canonical order of the hash."""
        return {"theta": self.theta, "phi": self.phi, **{f"param:{k}": self.values[k] for k in sorted(self.values)}}

    @cached_property
    def digest(self) -> str:
        """SHA-256 of the job's definition (hex)."""
        sha = hashlib.sha256(canonical_json(self.header()).encode())
        for name, array in self.arrays().items():
            sha.update(f"\n{name}:{array.size}\n".encode())
            sha.update(np.ascontiguousarray(array, dtype="<f8").tobytes())
        return sha.hexdigest()

    def cells(self, index: np.ndarray) -> tuple[np.ndarray, np.ndarray, dict[str, np.ndarray]]:
        """θ, φ and per-cell parameter values of the cells ``index``."""
        return self.theta[index], self.phi[index], {k: v[index] for k, v in self.values.items()}


def validate_chunk_cells(chunk_cells: int | None) -> None:
    """Refuse a chunk size that is not a positive whole number (None: chosen by the probe)."""
    if chunk_cells is not None and (isinstance(chunk_cells, bool) or int(chunk_cells) != chunk_cells
                                    or chunk_cells < 1):
        raise ArgumentError(f"chunk_cells must be a positive whole number, got {chunk_cells!r}", where="chunk_cells")


def canonical_json(data: object) -> str:
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=True, allow_nan=False)


@dataclass(frozen=True)
class ChunkPlan:
    """Cells in canonical order cut at ``bounds``: chunk k is ``order[bounds[k]:bounds[k + 1]]``."""

    order: np.ndarray
    bounds: np.ndarray

    @property
    def count(self) -> int:
        return self.bounds.size - 1

    def chunk(self, k: int) -> np.ndarray:
        return self.order[self.bounds[k]:self.bounds[k + 1]]


def chunk_plan_order(job: CellsJob) -> np.ndarray:
    """The canonical order of the cells: by per-cell parameters (in name order), then θ, then φ."""
    keys = [job.phi, job.theta] + [job.values[k] for k in sorted(job.values, reverse=True)]
    return np.lexsort(keys)  # the last key is the primary one: the first per-cell parameter


def chunk_plan(job: CellsJob, model: Model) -> ChunkPlan:
    """The job's fixed chunks (see the module docstring); ``model`` is ``job.source.load()``."""
    order = chunk_plan_order(job)
    if job.chunk_cells is not None:
        return ChunkPlan(order, np.append(np.arange(0, job.size, job.chunk_cells), job.size))
    if job.size <= SMALL_JOB:
        return ChunkPlan(order, np.array([0, job.size]))
    cost = _probed_cost(job, model, order)
    total = cost[-1]
    count = max(math.ceil(total / TARGET_EVALUATIONS), math.ceil(job.size / MAX_CELLS_PER_CHUNK))
    inner = np.searchsorted(cost, total * np.arange(1, count) / count, side="left") + 1
    return ChunkPlan(order, np.unique(np.concatenate([[0], inner, [job.size]])))


def _probed_cost(job: CellsJob, model: Model, order: np.ndarray) -> np.ndarray:
    """Cumulative estimated evaluations along the canonical order, from the evaluation counts of a few cells
    spread over it at the job's own tolerance (about 1/16 of the cells at most, so ≤ 6 % extra work), linearly
    interpolated between them. Chunks are then cut at equal estimated cost, not equal cell counts: a cell's cost
    varies 25-fold across a GGX table. The estimate only places chunk boundaries, it never touches a value."""
    samples = min(PROBE_CELLS, max(2, job.size // 16))
    positions = np.unique(np.linspace(0, job.size - 1, samples).round().astype(int))
    theta, phi, values = job.cells(order[positions])
    settings = job.settings
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        probe = compute_albedo(model.with_params(**values), theta, phi, over=settings.over, rtol=settings.rtol,
                               atol=settings.atol, method=settings.method, nonfinite="zero",
                               max_evaluations=settings.max_evaluations)
    per_cell = np.maximum(probe.evaluations.astype(float), 1.0) * (MAX_TASK_INTEGRALS if job.task == "max" else 1)
    return np.cumsum(np.interp(np.arange(job.size), positions, per_cell))
