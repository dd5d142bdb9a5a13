"""The radial coordinates in which the half-vector integrals run over a microfacet slope distribution.

The half-vector routes (:mod:`brdfnorm.engine.routes.halfvector`, :mod:`~brdfnorm.engine.routes.dielectric`,
:mod:`~brdfnorm.engine.routes.dielectric_average`) integrate over the radial CDF u(s) of the standardized slope
radius s (Heitz 2014, "Understanding the masking-shadowing function in microfacet-based BRDFs", §5.2: P22 with
α = 1) in up to three pieces, each in its own coordinate t: ``pole(t)`` and ``tail(t)`` return (s, du/dt),
``pole_coordinate(s)`` and ``tail_coordinate(s)`` invert them; the piece next to the horizon is linear in s with
du/ds the distribution's ``slope_density(s)``. ``cap`` drops the slope radii beyond a distribution's truncation,
and ``truncated_moments`` bounds what that drops. These are the integrator's choices, not the physics: the
distribution (:class:`brdfnorm.models.microfacet.Distribution`) gives D, Λ and du/ds; :func:`slope_coordinates`
pairs it with its coordinates by the distribution's name (issue 40, item 5). A distribution without an entry
gets linear coordinates and no truncation.
"""

from __future__ import annotations

import numpy as np

from ...models.microfacet import Distribution


class SlopeCoordinates:
    """Linear s in every piece, nothing dropped: the coordinates of any distribution without its own."""

    #: The slope radius beyond which ``cap`` drops the mass; None where nothing is dropped (a heavy tail).
    CAP: float | None = None

    def __init__(self, distribution: Distribution) -> None:
        self.distribution = distribution

    def pole_coordinate(self, s: np.ndarray) -> np.ndarray:
        return s

    def pole(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return t, self.distribution.slope_density(t)

    def tail_coordinate(self, s: np.ndarray) -> np.ndarray:
        return s

    def tail(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return t, self.distribution.slope_density(t)

    def cap(self, s: np.ndarray) -> np.ndarray:
        """Slope radii beyond which the mass is dropped (bounded by ``truncated_moments``); none by default."""
        return s

    def truncated_moments(self) -> tuple[float, float]:
        """(∫ dP, ∫ s dP) over the slope radii dropped by ``cap``: what bounds the dropped part of the integral."""
        return 0.0, 0.0


class GGXCoordinates(SlopeCoordinates):
    """Trowbridge-Reitz, u(s) = s²/(1 + s²).

    Pole piece (s ≤ 1): t = atan s, u = sin²t, du/dt = sin 2t — flat, and analytic at the pole (in u itself
    the slope would be √u). Tail piece: t = asinh s, u = tanh²t, du/dt = 2 tanh t/cosh²t — the heavy tail
    decays like e^{−2t}, and the integrand, analytic in the real slope α s within a radius R ~ 1, stays
    analytic in a strip of half-width ~π/2 about the whole half-line (α sinh t = ±iR at t ≈ ln(2R/α) ± iπ/2),
    so the region where the reflected direction changes is an O(1)-wide bump in t whatever α is.
    """

    def pole_coordinate(self, s):
        return np.arctan(s)

    def pole(self, t):
        return np.tan(t), np.sin(2.0 * t)

    def tail_coordinate(self, s):
        return np.arcsinh(s)

    def tail(self, t):
        e2 = np.exp(-2.0 * t)  # 2 tanh t / cosh²t = 8e^{−2t}(1 − e^{−2t})/(1 + e^{−2t})³, without overflow
        return np.sinh(t), 8.0 * e2 * (1.0 - e2) / (1.0 + e2) ** 3


class BeckmannCoordinates(SlopeCoordinates):
    """Beckmann, u(s) = 1 − exp(−s²): linear s in every piece (the Gaussian has no heavy tail), truncated at
    s = 8 (dropped mass e⁻⁶⁴ ≈ 1.6e-28, bounded in the error estimate)."""

    CAP = 8.0

    def cap(self, s):
        return np.minimum(s, self.CAP)

    def truncated_moments(self):
        # ∫_S^∞ 2s e^{−s²} ds = e^{−S²};  ∫_S^∞ 2s² e^{−s²} ds = S e^{−S²} + (√π/2) erfc S ≤ (S + 1) e^{−S²}.
        mass = float(np.exp(-self.CAP**2))
        return mass, (self.CAP + 1.0) * mass


#: Each built-in distribution's coordinates, by :attr:`Distribution.name`.
COORDINATES: dict[str, type[SlopeCoordinates]] = {"ggx": GGXCoordinates, "beckmann": BeckmannCoordinates}


def slope_coordinates(distribution: Distribution) -> SlopeCoordinates:
    """The integration coordinates of ``distribution`` (linear ones where its name has no entry)."""
    return COORDINATES.get(distribution.name, SlopeCoordinates)(distribution)
