"""Normalization factors 1/E under a named convention, optionally swept over a parameter.

Conventions (``at=``):

* ``"normal"`` — the fixed direction at N (seed 000's L = N; for reciprocal lobes the same as V = N).
* ``"max"`` — the global maximum of E over the fixed direction's θ ∈ [0°, 89.9°] and, for anisotropic
  models, φ: the smallest factor that keeps the lobe energy-conserving everywhere. Seeds 000 and 003 assume the
  maximum is at normal incidence ("I have no proof"); here it is searched: a coarse grid evaluated in one batch,
  then a vectorized golden-section refinement of every sweep point's bracket (θ, then φ, alternately).
* ``"view"`` — per direction on a θ grid (seed 002's open problem): a factor for every (parameter, θ).

(The module is ``brdfnorm.normalization`` so that the function ``brdfnorm.normalize`` does not shadow it.)
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from . import validate
from .engine.methods import albedo, sweep_model
from .errors import ArgumentError
from .models.base import Model, Over
from .output.formats import Column, Records, channel_value, degrees
from .validate import DEFAULT_RTOL

AT = ("normal", "max", "view")
#: Batches a sweep is split into when progress is reported (``on_progress``).
PROGRESS_CHUNKS = 16
#: Largest polar angle searched by ``at="max"`` (the integrand degenerates at exactly 90°).
THETA_MAX = np.radians(89.9)
_GOLDEN = (np.sqrt(5.0) - 1.0) / 2.0


@dataclass(frozen=True)
class NormalizationResult:
    """Factors over S sweep values × T directions (T = 1 for ``normal`` and ``max``)."""

    at: str
    parameter: str | None
    values: np.ndarray  # (S,)
    theta: np.ndarray  # (S, T) radians (the argmax for "max")
    phi: np.ndarray  # (S, T)
    albedo: np.ndarray  # (S, T, C)
    error: np.ndarray  # (S, T, C)
    factor: np.ndarray  # (S, T, C)
    method: str
    over: Over
    converged: np.ndarray  # (S, T)
    reason: np.ndarray | None = None  # (S, T) str: "" where converged, else why not (AlbedoResult.reason)
    model: str = ""  # the model's name
    params: dict = field(default_factory=dict)  # the model's bound parameter values (the swept one overridden)
    rtol: float = 0.0

    def records(self) -> Records:
        """One row per (sweep value, direction), for :mod:`brdfnorm.output.formats`."""
        rows = []
        S, T = self.theta.shape
        for s in range(S):
            params = dict(self.params)
            if self.parameter:
                params[self.parameter] = float(self.values[s])
            for t in range(T):
                rows.append({
                    "params": params, "theta_deg": degrees(self.theta[s, t]),
                    "phi_deg": degrees(self.phi[s, t]), "albedo": channel_value(self.albedo[s, t]),
                    "error_estimate": channel_value(self.error[s, t]), "factor": channel_value(self.factor[s, t]),
                    "method": self.method, "at": self.at, "converged": bool(self.converged[s, t]),
                    "reason": "" if self.reason is None else str(self.reason[s, t]),
                })
        columns = tuple(Column(f"params.{name}", name, 12, in_table=name == self.parameter) for name in self.params)
        return Records(
            title=f"{self.model}: normalization factor 1/E at {self.at} (over the {self.over})",
            meta={"model": self.model, "params": self.params, "at": self.at, "over": self.over, "rtol": self.rtol},
            columns=columns + (Column("theta_deg", "θ (deg)", 6), Column("phi_deg", "φ (deg)", 6),
                               Column("albedo", "albedo"), Column("error_estimate", "error estimate", 3, bound=True),
                               Column("factor", "factor"), Column("method", "method", None),
                               Column("at", "at", None, in_table=False),
                               Column("converged", "converged", None, in_table=False),
                               Column("reason", "reason", None)),
            rows=rows,
        )


def normalize(
    model: Model,
    at: str = "normal",
    sweep: Mapping[str, object] | None = None,
    theta=None,
    phi=0.0,
    *,
    over: Over = "light",
    rtol: float = DEFAULT_RTOL,
    method: str = "auto",
    search_points: int = 46,
    on_progress: Callable[[int, int], None] | None = None,
) -> NormalizationResult:
    """Normalization factor(s) of ``model``; see the module docstring for the conventions.

    ``on_progress(done, total)``, if given, is called with the number of sweep values finished: the sweep then
    runs in up to :data:`PROGRESS_CHUNKS` batches (each still vectorized) instead of one.
    """
    validate.choice(at, AT, "at")
    validate.count(search_points, "search_points", minimum=2, maximum=10_000)
    if on_progress is not None:
        return _in_chunks(model, sweep, on_progress, dict(at=at, theta=theta, phi=phi, over=over, rtol=rtol,
                                                          method=method, search_points=search_points))
    swept, name, values = sweep_model(model, sweep)
    kwargs = dict(over=over, rtol=rtol, method=method)
    if at == "normal":
        result = albedo(swept, np.zeros((1, 1)), 0.0, **kwargs)
    elif at == "view":
        if theta is None:
            raise ArgumentError("at='view' needs the polar angles (theta)", where="theta")
        theta = np.atleast_1d(validate.polar_angles(theta)).ravel()
        result = albedo(swept, theta[None, :], validate.real_array(phi, "phi"), **kwargs)
    else:
        theta_best, phi_best = _search_max(swept, values.size, search_points, kwargs)
        result = albedo(swept, theta_best[:, None], phi_best[:, None], **kwargs)
    S = values.size
    value = np.broadcast_to(result.value, (S,) + result.value.shape[1:])
    with np.errstate(divide="ignore"):
        factor = 1.0 / value
    return NormalizationResult(
        at=at, parameter=name, values=values,
        theta=np.broadcast_to(result.theta, value.shape[:2]), phi=np.broadcast_to(result.phi, value.shape[:2]),
        albedo=value, error=np.broadcast_to(result.error, value.shape), factor=factor, method=result.method,
        over=over, converged=np.broadcast_to(result.converged, value.shape[:2]),
        reason=np.broadcast_to(result.reason, value.shape[:2]), model=model.name,
        params=model.params if name is None else {**model.params, name: values}, rtol=rtol,
    )


def _in_chunks(model: Model, sweep, on_progress: Callable[[int, int], None], kwargs: dict) -> NormalizationResult:
    """:func:`normalize` over the sweep in batches, reporting progress after each; the same numbers."""
    swept, name, values = sweep_model(model, sweep)
    total = values.size
    on_progress(0, total)
    if name is None:
        result = normalize(model, **kwargs)
        on_progress(total, total)
        return result
    parts = []
    for chunk in np.array_split(values, min(total, PROGRESS_CHUNKS)):
        parts.append(normalize(model, sweep={name: chunk}, **kwargs))
        on_progress(sum(p.values.size for p in parts), total)
    fields = ("theta", "phi", "albedo", "error", "factor", "converged", "reason")
    return dataclasses.replace(parts[0], values=values, params={**parts[0].params, name: values},
                               **{f: np.concatenate([getattr(p, f) for p in parts]) for f in fields})


def _search_max(model: Model, S: int, points: int, kwargs: dict) -> tuple[np.ndarray, np.ndarray]:
    """(θ, φ) of the largest albedo for each of the S sweep values (max over channels)."""
    coarse = dict(kwargs, rtol=max(kwargs["rtol"], 1e-7))
    theta_grid = np.linspace(0.0, THETA_MAX, points)
    phi_grid = np.array([0.0]) if model.isotropic else np.linspace(0.0, 2 * np.pi, 16, endpoint=False)
    # The grid runs along the second axis; the sweep values are bound with shape (S, 1).
    theta_pairs, phi_pairs = (g.ravel()[None, :] for g in np.meshgrid(theta_grid, phi_grid, indexing="ij"))
    grid = albedo(model, theta_pairs, phi_pairs, **coarse)
    energy = np.broadcast_to(grid.value.max(axis=-1), (S, theta_pairs.size))
    i, j = np.unravel_index(energy.argmax(axis=1), (points, phi_grid.size))
    theta = theta_grid[i]
    phi = phi_grid[j]
    step_t = theta_grid[1] - theta_grid[0]
    step_p = (phi_grid[1] - phi_grid[0]) if phi_grid.size > 1 else 0.0
    for _ in range(1 if model.isotropic else 3):
        theta = _golden_max(lambda t, p=phi: _energy(model, t, p, kwargs),
                            np.maximum(theta - step_t, 0.0), np.minimum(theta + step_t, THETA_MAX))
        if not model.isotropic:
            phi = _golden_max(lambda p, t=theta: _energy(model, t, p, kwargs), phi - step_p, phi + step_p)
    # On a plateau (a narrow lobe far from the horizon) every θ gives the same energy to within the
    # quadrature tolerance; break such ties towards normal incidence, the seeds' convention.
    at_normal = _energy(model, np.zeros_like(theta), phi, kwargs)
    tie = at_normal >= _energy(model, theta, phi, kwargs) * (1.0 - 10.0 * kwargs["rtol"])
    return np.where(tie, 0.0, theta), np.where(tie & model.isotropic, 0.0, np.mod(phi, 2 * np.pi))


def _energy(model: Model, theta: np.ndarray, phi: np.ndarray, kwargs: dict) -> np.ndarray:
    """Largest channel of the albedo for per-sweep-value angles (S,) — one batched call."""
    result = albedo(model, theta[:, None], np.asarray(phi, dtype=float)[:, None] if np.ndim(phi) else phi,
                    **kwargs)
    return result.value[:, 0].max(axis=-1)


def _golden_max(energy, low: np.ndarray, high: np.ndarray, iterations: int = 40) -> np.ndarray:
    """Vectorized golden-section search for the maximum of ``energy`` on [low, high] per sweep value.

    One batched evaluation per iteration (the bracket shrinks by 0.618 each time); the best point ever
    evaluated is returned, so a maximum at an end of the bracket (θ = 0) is found too.
    """
    low, high = np.array(low, dtype=float), np.array(high, dtype=float)
    x1 = high - _GOLDEN * (high - low)
    x2 = low + _GOLDEN * (high - low)
    f1, f2 = energy(x1), energy(x2)
    best_x, best_f = low, energy(low)
    for x, f in ((high, energy(high)), (x1, f1), (x2, f2)):
        best_x, best_f = np.where(f > best_f, x, best_x), np.maximum(f, best_f)
    for _ in range(iterations):
        left = f1 >= f2  # the maximum lies in [low, x2]
        high = np.where(left, x2, high)
        low = np.where(left, low, x1)
        x_new = np.where(left, high - _GOLDEN * (high - low), low + _GOLDEN * (high - low))
        f_new = energy(x_new)
        best_x, best_f = np.where(f_new > best_f, x_new, best_x), np.maximum(f_new, best_f)
        x1, f1, x2, f2 = (np.where(left, x_new, x2), np.where(left, f_new, f2),
                          np.where(left, x1, x_new), np.where(left, f1, f_new))
    return best_x
