"""One term's albedo: E_k(μ_o) = w_k A_k(μ_o) I_k(μ_o), the pieces of the ``"material"`` albedo method
(:mod:`brdfnorm.materials.route`, which documents the three cases and the error estimates) and of the base albedo
the coat's darkening needs (:func:`brdfnorm.materials.openpbr.build`).
"""

from __future__ import annotations

import numpy as np

from ..engine.methods import albedo as engine_albedo
from ..models.base import Lobe, Model, mirror, normal_lobe
from ..models.fresnel import average_quadrature
from .albedo import CACHE, top_albedo
from .components import Component, Diffuse, Microfacet
from .compose import Term, evaluate_terms


class _Product(Model):
    """One term's lobe times its light-side factors, as a model the generic cubature integrates."""

    name = "material-term"
    channels = 3

    def __init__(self, term: Term, source: str, size: int) -> None:
        super().__init__()
        self.term, self.source, self.size = Term(term.component, np.ones(3), (), term.light), source, size

    def evaluate(self, L, V, params):
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(L[..., 2:3] > 0, self.projected(L, V, params) / L[..., 2:3], 0.0)

    def projected(self, L, V, params):
        return evaluate_terms([self.term], L, V, self.source, self.size)

    def lobe(self, fixed, params, over):
        component = self.term.component
        if isinstance(component, Microfacet):
            shape = np.shape(fixed)[:-1]
            width = np.full(shape, np.clip(2.0 * component.alpha, 1e-3, 1.0))
            return Lobe(mirror(fixed), width, np.full(shape, np.pi))
        return normal_lobe(fixed)


def _albedo_with_error(top: Component, mu: np.ndarray, source: str, size: int) -> tuple[np.ndarray, np.ndarray]:
    if source == "table":
        return top_albedo(top, mu, source, size), np.zeros(mu.shape + (3,))
    return top.albedo(mu)


def _light_average(tops: tuple[Component, ...], source: str, size: int, rtol: float):
    """2∫₀¹ Π(1 − E_t(μ)) μ dμ per channel, and its error (quadrature plus the curves' own)."""
    def integrand(x: np.ndarray, channel: np.ndarray) -> np.ndarray:
        value = np.ones(x.shape + (3,))
        for top in tops:
            value = value * (1.0 - top_albedo(top, x, source, size))
        return 2.0 * x * np.take_along_axis(value, channel[..., None], axis=-1)[..., 0]

    value, error = average_quadrature(integrand, 3, rtol=min(rtol, 1e-12))
    if source != "table":
        error = error + sum(CACHE.curve(top).error for top in tops)
    return value, error


def term_albedo(term: Term, mu: np.ndarray, source: str, size: int, rtol: float):
    """(value, error) (K, 3) of one term at the view cosines μ (K,)."""
    weight = np.abs(term.weight)
    factor, factor_error = np.ones(mu.shape + (3,)), np.zeros(mu.shape + (3,))
    for top in term.view:
        e, de = _albedo_with_error(top, mu, source, size)
        factor_error = factor_error * np.abs(1.0 - e) + np.abs(factor) * de
        factor = factor * (1.0 - e)
    if not term.light:
        inner, inner_error = term.component.albedo(mu)
    elif isinstance(term.component, Diffuse) and term.component.roughness == 0.0:
        average, average_error = _light_average(term.light, source, size, rtol)
        rho = np.asarray(term.component.rho, dtype=float)
        inner = np.broadcast_to(rho * average, mu.shape + (3,))
        inner_error = np.broadcast_to(rho * average_error, mu.shape + (3,))
    else:
        result = engine_albedo(_Product(term, source, size), np.arccos(np.clip(mu, 0.0, 1.0)), method="quadrature",
                               rtol=rtol)
        inner, inner_error = result.value.reshape(mu.shape + (3,)), result.error.reshape(mu.shape + (3,))
        if source != "table":  # the curves' own error δ_t, through ∫ f_k (N·L) dL = E_k (each factor ≤ 1 + δ_t)
            own, _ = term.component.albedo(mu)
            inner_error = inner_error + sum(CACHE.curve(top).error for top in term.light) * np.abs(own)
    value = term.weight * factor * inner
    error = weight * (factor_error * np.abs(inner) + np.abs(factor) * inner_error)
    return value, error
