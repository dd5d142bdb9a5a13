"""The anisotropic kernel's view-azimuth average by brute force, the reference of the azimuth-average tests."""

from __future__ import annotations

import numpy as np

from brdfnorm.engine.routes import anisotropic as kernel


def stretched_reference(name: str, mu: float, ax: float, ay: float, k: float | None = None) -> tuple[float, float]:
    """Ē by the 128-interval trapezoid in χ with φ_v = atan2(k sin χ, cos χ) (a fixed k, by default √(α_x/α_y)),
    views at rtol 1e-11; its own error: the 64- and 128-interval rules' difference plus the views' errors."""
    k = np.sqrt(ax / ay) if k is None else k
    chi = np.linspace(0.0, np.pi / 2, 129)
    psi = np.arctan2(k * np.sin(chi), np.cos(chi))
    dpsi = k / (np.cos(chi) ** 2 + (k * np.sin(chi)) ** 2)
    value, error, _, converged = kernel.albedo(name, "height-correlated", mu, ax, ay, psi, rtol=1e-11)
    assert np.all(converged)
    f, fe = value * dpsi, error * dpsi

    def trapezoid(g, step):
        return (0.5 * (g[0] + g[-1]) + g[step:-1:step].sum()) / (128 // step)

    return trapezoid(f, 1), abs(trapezoid(f, 1) - trapezoid(f, 2)) + trapezoid(fe, 1)


def view_misses(names, mu, ax, ay, phi, rtol) -> list[tuple]:
    """The views (arrays of one length) whose kernel albedo at ``rtol`` is farther from its rtol-1e-11 value than
    both estimates together: (name, μ, α_x, α_y, φ_v, rtol, error / estimate) each. Every view must converge."""
    misses = []
    for case in zip(names, mu, ax, ay, phi, rtol, strict=True):
        name, *view, tolerance = case
        exact, exact_error, _, ok = kernel.albedo(str(name), "height-correlated", *view, rtol=1e-11)
        value, error, _, converged = kernel.albedo(str(name), "height-correlated", *view, rtol=tolerance)
        assert ok[0] and converged[0]
        if abs(value[0] - exact[0]) > error[0] + exact_error[0]:
            misses.append((*case, abs(value[0] - exact[0]) / error[0]))
    return misses
