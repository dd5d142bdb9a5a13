"""The albedo engine: E(V) = ∫ f(L, V)(N·L) dL for any model, with an honest error estimate.

Layout (docs/architecture.md explains the design):

- :mod:`.methods` — the front door: :func:`albedo`, the batch of cases it makes from angles and parameters
  (:class:`~.methods.Problem`), and the registry of methods (``"auto"`` takes the first that applies).
- :mod:`.routes` — one module per way of computing the integral: the generic hemisphere quadrature and its
  half-vector route for any lobe, and the exact routes of particular lobes (series, azimuthal, microfacet,
  dielectric, certified).
- :mod:`.machinery` — what several routes share: the global tensor rule and its coordinates, the starting panels
  at grazing views, and float64 rounding noise.

Models sit below the engine (it imports them, never the other way round); conventions, tables, fits, checks and
the command line sit above it.
"""

from .methods import METHODS, AlbedoResult, Method, albedo, register_method, resolve_method

__all__ = ["METHODS", "AlbedoResult", "Method", "albedo", "register_method", "resolve_method"]
