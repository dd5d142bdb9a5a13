"""Normalization factors 1/E under a named convention, optionally swept over a parameter.

Conventions (``at=``):

* ``"normal"`` — the fixed direction at N (seed 000's L = N; for reciprocal lobes the same as V = N).
* ``"max"`` — the global maximum of E over the fixed direction's θ ∈ [0°, 89.9°] and, for anisotropic
  models, φ: the smallest factor that keeps the lobe energy-conserving everywhere. Seeds 000 and 003 assume the
  maximum is at normal incidence ("I have no proof"); here it is searched: a coarse grid evaluated in one batch,
  then a vectorized golden-section refinement of every sweep point's bracket (θ, then φ, alternately).
* ``"view"`` — per direction on a θ grid (seed 002's open problem): a factor for every (parameter, θ).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from .albedo import albedo, sweep_model
from .errors import ArgumentError
from .models.base import Model, Over

AT = ("normal", "max", "view")
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


def normalize(
    model: Model,
    at: str = "normal",
    sweep: Mapping[str, object] | None = None,
    theta=None,
    phi=0.0,
    *,
    over: Over = "light",
    rtol: float = 1e-10,
    method: str = "auto",
    search_points: int = 46,
) -> NormalizationResult:
    """Normalization factor(s) of ``model``; see the module docstring for the conventions."""
    if at not in AT:
        raise ArgumentError(f"unknown convention {at!r} (known: {', '.join(AT)})", where="at")
    swept, name, values = sweep_model(model, sweep)
    kwargs = dict(over=over, rtol=rtol, method=method)
    if at == "normal":
        result = albedo(swept, np.zeros((1, 1)), 0.0, **kwargs)
    elif at == "view":
        if theta is None:
            raise ArgumentError("at='view' needs the polar angles (theta)", where="theta")
        theta = np.atleast_1d(np.asarray(theta, dtype=float)).ravel()
        result = albedo(swept, theta[None, :], np.asarray(phi, dtype=float), **kwargs)
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
        reason=np.broadcast_to(result.reason, value.shape[:2]),
    )


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
