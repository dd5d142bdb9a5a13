"""Albedo method ``"material"``: a material's E(μ_o) term by term (see :mod:`brdfnorm.materials.model`).

E(μ_o) = Σ_k w_k A_k(μ_o) I_k(μ_o), A_k = Π_view (1 − E_t(μ_o)), I_k = ∫ Π_light (1 − E_t(μ_i)) f_k (N·L) dL:

* no light-side factor: I_k = E_k(μ_o), the lobe's own exact albedo;
* a Lambertian lobe ρ/π: I_k = ρ · 2∫₀¹ Π(1 − E_t(μ)) μ dμ (:func:`brdfnorm.models.fresnel.average_quadrature`
  over the factors as the material reads them: curves or tables);
* otherwise the generic adaptive cubature of the product f_k Π(1 − E_t(μ_i)) alone.

Errors: each E's own estimate through A_k (Σ_t δE_t Π_{s≠t}|1 − E_s|) and I_k's, times |w_k|; the curves' errors where
they are read (in the cubature branch as Σ_t δ_t · E_k(μ_o)). The generic ``"quadrature"`` of the whole BRDF does not
know the curves' errors (~1e-11): below rtol 1e-10 this method's estimate is the one to trust.
"""

from __future__ import annotations

import numpy as np

from ..engine.machinery.result import RouteResult
from ..models.base import Model
from ..validate import DEFAULT_RTOL
from .model import OpenPBR, parameter_sets, terms_of
from .terms import term_albedo


def material_albedo(model: OpenPBR, mu: np.ndarray, params: dict, *, rtol: float = DEFAULT_RTOL):
    """(value, error, transmitted) (K, 3) of the material's albedo over the light at view cosines μ (K,): the total
    (reflected + transmitted), its error, and the share of the terms that transmit (the translucent base's)."""
    K = mu.shape[0]
    value, error, transmitted = np.zeros((K, 3)), np.zeros((K, 3)), np.zeros((K, 3))
    for mask, scalar in parameter_sets(model.parameters, params, (K,)):
        rows = np.arange(K) if mask is None else np.flatnonzero(mask)
        source, size = scalar["albedo_source"], int(scalar["albedo_table"])
        for term in terms_of(scalar):
            if not np.any(term.weight):
                continue
            v, e = term_albedo(term, mu[rows], source, size, rtol)
            value[rows] += v
            error[rows] += e
            if term.component.transmits:
                transmitted[rows] += v
    return value, error + 4 * np.finfo(float).eps * np.abs(value), transmitted


def applies(model: Model, over: str) -> bool:
    return isinstance(model, OpenPBR) and over == "light"


def albedo_method(problem, *, rtol: float, atol: float = 0.0, **_: object):
    K = problem.fixed.shape[0]
    params = problem.case_params(np.arange(K))
    value, error, transmitted = material_albedo(problem.model, problem.fixed[:, 2], params, rtol=rtol)
    converged = np.all(error <= np.maximum(atol, rtol * np.abs(value)), axis=-1)
    extras = {"reflected": value - transmitted, "transmitted": transmitted} if problem.model.transmits else {}
    return RouteResult(value, error, np.zeros(K, dtype=np.int64), converged, extras=extras)
