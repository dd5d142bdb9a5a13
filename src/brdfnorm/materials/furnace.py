"""The white furnace of a material: E(μ) against 1 with its largest residual and where, the reciprocity error with
where, the average albedo E_avg, and the coat-layering study of openpbr-bsdf PR #30 (view-side against symmetric and
reciprocal albedo scaling over white bases, across coat roughness and IOR).

A material passes the furnace when every lobe is white and lossless: the residual E(μ) − 1 is then what its
composition rule and its lobes' single scattering lose (or gain). Each E is the material's albedo by the engine's
``"auto"`` method (``"material"``: term by term, :mod:`brdfnorm.materials.route`), with its error estimate.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..engine.machinery.directions import random_hemisphere
from ..engine.methods import albedo
from ..models.base import Model
from ..validate import DEFAULT_RTOL

#: The views of a furnace: μ from 1 down to cos 89.9° (30 points, denser towards grazing).
DEFAULT_THETA = np.radians(np.concatenate([np.linspace(0.0, 80.0, 17), np.linspace(82.0, 89.9, 13)]))
_GL_X, _GL_W = np.polynomial.legendre.leggauss(16)
_GL8_X, _GL8_W = np.polynomial.legendre.leggauss(8)
_AVERAGE_PANELS = (0.0, 0.05, 0.3, 1.0)


@dataclass(frozen=True)
class Furnace:
    """E(θ) per channel, its residual E − 1 and the largest |residual| with its view; the reciprocity error."""

    theta: np.ndarray  # (n,) radians
    value: np.ndarray  # (n, C)
    error: np.ndarray  # (n, C)
    max_residual: float  # the residual of largest magnitude (signed)
    argmax_theta: float  # radians
    average: np.ndarray  # (C,) E_avg = 2∫E μ dμ
    average_error: np.ndarray
    reciprocity: float  # max |f(L,V) − f(V,L)| / max f over the pairs
    reciprocity_at: tuple[np.ndarray, np.ndarray]  # (L, V) where it is largest

    def rows(self) -> list[dict]:
        return [{"theta_deg": float(np.degrees(t)), "mu": float(np.cos(t)), "E": [float(x) for x in v],
                 "residual": [float(x - 1.0) for x in v], "error_estimate": [float(x) for x in e]}
                for t, v, e in zip(self.theta, self.value, self.error, strict=True)]


def average_albedo(model: Model, *, rtol: float = DEFAULT_RTOL) -> tuple[np.ndarray, np.ndarray]:
    """E_avg = 2∫₀¹ E(μ) μ dμ by 16-point Gauss–Legendre on the panels μ ∈ [0, 0.05, 0.3, 1]; the error is the
    difference from the 8-point rule on the same nodes' panels plus the albedos' own estimates."""
    mus, weights, weights8, mus8 = [], [], [], []
    for a, b in zip(_AVERAGE_PANELS[:-1], _AVERAGE_PANELS[1:], strict=True):
        mus.append((a + b) / 2 + (b - a) / 2 * _GL_X)
        weights.append((b - a) / 2 * _GL_W)
        mus8.append((a + b) / 2 + (b - a) / 2 * _GL8_X)
        weights8.append((b - a) / 2 * _GL8_W)
    mu, w, mu8, w8 = (np.concatenate(x) for x in (mus, weights, mus8, weights8))
    result = albedo(model, np.arccos(np.concatenate([mu, mu8])), rtol=rtol)
    value, error = result.value.reshape(-1, model.channels), result.error.reshape(-1, model.channels)
    fine = np.sum((2 * mu * w)[:, None] * value[:mu.size], axis=0)
    coarse = np.sum((2 * mu8 * w8)[:, None] * value[mu.size:], axis=0)
    return fine, np.abs(fine - coarse) + np.sum((2 * mu * w)[:, None] * error[:mu.size], axis=0)


def reciprocity(model: Model, pairs: int = 4096, seed: int = 7) -> tuple[float, tuple[np.ndarray, np.ndarray]]:
    """max |f(L, V) − f(V, L)| over random pairs, relative to the largest f there, and the pair where it is."""
    rng = np.random.default_rng(seed)
    L, V = random_hemisphere(rng, pairs), random_hemisphere(rng, pairs)
    forward, backward = model.eval(L, V), model.eval(V, L)
    gap = np.abs(forward - backward).max(axis=-1)
    scale = max(float(np.abs(forward).max()), float(np.abs(backward).max()), np.finfo(float).tiny)
    i = int(np.argmax(gap))
    return float(gap[i] / scale), (L[i], V[i])


def furnace(model: Model, theta=None, *, rtol: float = DEFAULT_RTOL, pairs: int = 4096) -> Furnace:
    """The furnace of ``model`` at the views ``theta`` (radians; default :data:`DEFAULT_THETA`)."""
    theta = DEFAULT_THETA if theta is None else np.atleast_1d(np.asarray(theta, dtype=float))
    result = albedo(model, theta, rtol=rtol)
    value = result.value.reshape(theta.size, -1)
    residual = value - 1.0
    i, c = np.unravel_index(np.argmax(np.abs(residual)), residual.shape)
    average, average_error = average_albedo(model, rtol=rtol)
    gap, at = reciprocity(model, pairs)
    return Furnace(theta, value, result.error.reshape(theta.size, -1), float(residual[i, c]), float(theta[i]),
                   average, average_error, gap, at)


#: The coat study's white bases: a Lambertian one (ρ = 1, no specular interface) and a white metal (F = 1).
WHITE_BASES = {
    "lambert": dict(base_color=(1.0, 1.0, 1.0), specular_weight=0.0, base_metalness=0.0),
    "metal": dict(base_color=(1.0, 1.0, 1.0), specular_color=(1.0, 1.0, 1.0), base_metalness=1.0,
                  specular_roughness=0.5),
}


def coat_study(load, roughness=(0.1, 0.3, 0.5, 0.8), ior=(1.3, 1.5, 1.6, 2.0), *, base: str = "lambert",
               theta=None, rtol: float = DEFAULT_RTOL) -> list[dict]:
    """Per coat (roughness, IOR) and rule: min and max E over the views, the largest loss against the view-side
    rule (E_view − E_rule) and its view. ``load`` is :func:`brdfnorm.load` (the model registry lives above)."""
    theta = np.radians([0.0, 30.0, 50.0, 65.0, 75.0, 82.0, 86.0, 89.0]) if theta is None else np.asarray(theta)
    rows = []
    for r in roughness:
        for eta in ior:
            values = {}
            for rule in ("view", "symmetric", "reciprocal"):
                # coat_adjustments none: the rule alone (the darkening and roughening would change the metal base)
                model = load("openpbr", coat_weight=1.0, coat_roughness=r, coat_ior=eta, layering=rule,
                             coat_adjustments="none", **WHITE_BASES[base])
                values[rule] = albedo(model, theta, rtol=rtol).value[:, 0]
            for rule in ("view", "symmetric", "reciprocal"):
                loss = values["view"] - values[rule]
                i = int(np.argmax(np.abs(loss)))
                rows.append({"base": base, "coat_roughness": r, "coat_ior": eta, "layering": rule,
                             "E_min": float(values[rule].min()), "E_max": float(values[rule].max()),
                             "loss_vs_view": float(loss[i]), "argmax_theta_deg": float(np.degrees(theta[i])),
                             "E": [float(x) for x in values[rule]]})
    return rows
