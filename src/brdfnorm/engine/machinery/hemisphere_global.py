"""The global tensor rule on the hemisphere's lobe-aligned coordinates: the entry point of the hemisphere route
(:mod:`brdfnorm.engine.routes.hemisphere`), tried before its adaptive panels.

The coordinates, the rule and its estimate are :mod:`brdfnorm.engine.machinery.tensor_rule`'s
(:class:`~brdfnorm.engine.machinery.tensor_rule.LobeAlignedGrid`); the levels loop is the one driver of
:mod:`brdfnorm.engine.machinery.global_driver`, which the half-vector rectangle
(:mod:`brdfnorm.engine.routes.halfvector_global`) shares.
"""

from __future__ import annotations

import numpy as np

from . import global_driver
from .result import RouteResult
from .tensor_rule import MAX_NODES, LobeAlignedGrid


def integrate_global(integrand, frame, widths, supports, cases: np.ndarray, noise_amplitude: np.ndarray, *,
                     rtol: float, atol: float, noise_bound, max_nodes: int = MAX_NODES,
                     max_nodes_per_call: int = 1_500_000, azimuthal_tail: np.ndarray | None = None) -> RouteResult:
    """The global tensor rule (:mod:`brdfnorm.engine.machinery.tensor_rule`) for ``cases`` (indices into the
    frame): ``converged`` says which cases it settled; unsettled cases keep their evaluation count and are left to
    the caller. ``noise_amplitude`` (K, C) and ``noise_bound`` give the integrand's float64 noise; where
    ``azimuthal_tail`` (K,) is True (lobes that are not rotation-invariant), the β estimate is at least
    :func:`~brdfnorm.engine.machinery.tensor_rule._azimuthal_tail`."""
    grid = LobeAlignedGrid(integrand, frame, widths, supports, noise_amplitude, noise_bound, max_nodes_per_call,
                           azimuthal_tail)
    return global_driver.integrate_global(grid, frame[0].shape[0], grid.admit(cases, max_nodes), rtol=rtol, atol=atol,
                                          max_nodes=max_nodes)
