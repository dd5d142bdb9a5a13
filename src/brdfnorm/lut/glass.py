"""E_avg of the rough-dielectric (glass) tables, from outside (η > 1) and inside (η < 1).

The generic route (:func:`brdfnorm.lut.table.average_over_mu`, which the table passes in as ``generic``)
integrates 2∫₀¹ E(μ) μ dμ over albedos. A dielectric's E(μ) has a multi-scale grazing behaviour (E − E(0) grows
like a small, drifting power of μ) and, from inside, the critical angle's near-kink and further edges: that route
needed 270–360 albedos per value of the other axes from outside and 450–650 from inside (GGX α = 0.3, η = 1/1.5:
454 albedos, 23.5 s). Here E_avg is instead the 3-D integral of :mod:`brdfnorm.engine.routes.dielectric_average`,
over the facet normal and the view about it, with total internal reflection and every range's end on a cut
(0.1–1.5 s per value at rtol 1e-9). A combination it does not settle, or a table computed with a forced albedo
method, takes the generic route. :func:`brdfnorm.lut.table.compute` calls :func:`average` for every model that
transmits.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping

import numpy as np

from ..engine.routes.dielectric_average import average_albedo
from ..models.base import Model
from ..models.dielectric import MicrofacetDielectric

#: Albedo methods under which the 3-D route stands in for the μ-average of albedos.
ROUTE_METHODS = ("auto", "dielectric")
#: Chunks of (α, η) combinations per worker (their costs differ up to tenfold: smaller chunks even them out).
CHUNKS_PER_WORKER = 4


def average(model: Model, params: Mapping[str, np.ndarray], *, rtol: float, generic: Callable, method: str = "auto",
            spread: Mapping[str, object] | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """E_avg of a dielectric for M parameter combinations (name -> (M,)): (value, error, converged, albedo
    integrals computed), as ``generic`` (:func:`brdfnorm.lut.table.average_over_mu`) returns them, which takes
    the combinations this route does not settle. With ``spread`` (``workers``, ``scheduler``) the combinations run
    where the table's cells do, in :data:`CHUNKS_PER_WORKER` chunks per worker; each combination's value does not
    depend on where it ran."""
    if method not in ROUTE_METHODS or not isinstance(model, MicrofacetDielectric):  # a material that transmits too
        return generic(model, params, rtol=rtol, method=method)
    M = len(next(iter(params.values()))) if params else 1
    flat = {n: np.broadcast_to(np.asarray(v, dtype=float).ravel(), (M,)) for n, v in params.items()}
    alpha, eta = (flat.get(name, np.full(M, float(model.params[name]))) for name in ("alpha", "eta"))
    from ..parallel.executors import Workers  # (the process pool, imported where a glass table uses it)

    spread = spread or {}
    with Workers(spread.get("workers", 1), spread.get("scheduler")) as pool:
        pool.start()
        chunks = np.array_split(np.arange(M), max(1, min(M, CHUNKS_PER_WORKER * pool.count)))
        tasks = [(model.distribution, alpha[c], eta[c], model.params["shadowing"],
                  str(model.params.get("refraction_shadowing", "auto"))) for c in chunks if c.size]
        parts = pool.map(functools.partial(average_albedo, rtol=rtol), tasks)
    value, error = np.concatenate([p.value for p in parts]), np.concatenate([p.error for p in parts])
    converged = np.concatenate([p.converged for p in parts])
    integrals = 0
    rest = np.flatnonzero(~converged)
    if rest.size:
        v, e, c, integrals = generic(model, {k: x[rest] for k, x in flat.items()}, rtol=rtol, method=method)
        value[rest], error[rest], converged[rest] = v, e, c
    return value, error, converged, integrals
