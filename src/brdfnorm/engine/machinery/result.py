"""The one result of every route of the engine: a batch of K integrals, scipy.integrate style.

Each route (``engine/routes/``) and each rule of the machinery (the lobe-aligned global tensor rule, the adaptive
panels, the 1-D integrators) returns a :class:`RouteResult`; the front door (:func:`brdfnorm.engine.methods.albedo`)
builds the public :class:`brdfnorm.engine.methods.AlbedoResult` from it. A result names its fields instead of a
position in a tuple, so adding what one route knows (the transmitted part of a BSDF, the certified bounds, the share
of the hemisphere where the integrand was not finite) goes into ``extras`` and changes no other route.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

#: Why a case ends unconverged: its integrand's float64 rounding noise exceeds the tolerance
#: ("rounding-limited"), its estimate stopped improving ("stalled"), or the evaluation budget ran out ("budget").
REASONS = ("rounding-limited", "stalled", "budget")


@dataclass(frozen=True)
class RouteResult:
    """K integrals: ``value`` and ``error`` (an absolute estimate) of shape (K, C) — or of a route's own batch shape
    where it documents one —, ``evaluations`` and ``converged`` per case, ``reason`` per case ("" where converged,
    else one of :data:`REASONS`; None: "budget" wherever a case did not converge) and ``extras``, further arrays
    by name (``reflected``/``transmitted``, ``lower``/``upper``, ``nonfinite_fraction``), also readable as
    attributes (``result.reflected``)."""

    value: np.ndarray
    error: np.ndarray
    evaluations: np.ndarray
    converged: np.ndarray
    reason: np.ndarray | None = None
    extras: Mapping[str, np.ndarray] = field(default_factory=dict)

    def __getattr__(self, name: str) -> np.ndarray:
        # Only called where no field has the name: an extra by name (never a dunder, so that copy and pickle,
        # which look their hooks up before the fields exist, see AttributeError).
        extras = self.__dict__.get("extras", {})
        if not name.startswith("__") and name in extras:
            return extras[name]
        raise AttributeError(f"{type(self).__name__} has no field or extra {name!r}")

    def reasons(self) -> np.ndarray:
        """``reason`` as an array of str: "" where converged, "budget" where a route gave no reason."""
        if self.reason is None:
            return np.where(np.asarray(self.converged), "", "budget")
        return np.asarray(self.reason, dtype=str)

    def with_(self, **changes: object) -> RouteResult:
        """A copy with some fields (or extras, by name) replaced."""
        extras = {name: changes.pop(name) for name in list(changes) if name not in _FIELDS}
        return replace(self, **changes, extras={**self.extras, **extras}) if extras else replace(self, **changes)


_FIELDS = frozenset(("value", "error", "evaluations", "converged", "reason", "extras"))
