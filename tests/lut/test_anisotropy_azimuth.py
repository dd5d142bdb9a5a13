"""The view-azimuth average of :mod:`brdfnorm.engine.routes.anisotropic` (issue #45, speed): its error estimate —
the nested trapezoid's last change, times the change ratio once two doublings show geometric convergence, plus
the views' own errors — is never smaller than the error, against a 129-view stretched trapezoid whose views are
computed to rtol 1e-11 (the 64- and 128-interval rules' difference counted as its own error)."""

from __future__ import annotations

import numpy as np
import pytest

from brdfnorm.engine.routes import anisotropic as kernel


def reference(name: str, mu: float, ax: float, ay: float) -> tuple[float, float]:
    chi = np.linspace(0.0, np.pi / 2, 129)
    k = np.sqrt(ax / ay)
    psi = np.arctan2(k * np.sin(chi), np.cos(chi))  # the kernel's stretch, written out here
    dpsi = k / (np.cos(chi) ** 2 + (k * np.sin(chi)) ** 2)
    value, error, _, converged = kernel.albedo(name, "height-correlated", mu, ax, ay, psi, rtol=1e-11)
    assert np.all(converged)
    f, fe = value * dpsi, error * dpsi

    def trapezoid(g, step):
        return (0.5 * (g[0] + g[-1]) + g[step:-1:step].sum()) / (128 // step)

    return trapezoid(f, 1), abs(trapezoid(f, 1) - trapezoid(f, 2)) + trapezoid(fe, 1)


CASES = [("ggx", 0.5, 1.0, 0.1)]
SLOW_CASES = [(name, mu, a / s, a * s) for name in ("ggx", "beckmann") for mu in (1e-4, 1e-2, 0.4, 1.0)
              for a, s in ((0.02, 0.1), (1.0, 0.1), (3.0, 0.3), (0.05, 0.7), (0.3, 0.1))]  # s = 0.1: α_y/α_x = 0.01


@pytest.mark.parametrize(("name", "mu", "ax", "ay"), CASES + [pytest.param(*c, marks=pytest.mark.slow)
                                                             for c in SLOW_CASES])
def test_average_estimate_is_not_smaller_than_the_error(name, mu, ax, ay):
    exact, own = reference(name, mu, ax, ay)
    for rtol in (1e-5, 1e-7):
        value, error, _, converged = kernel.albedo(name, "height-correlated", mu, ax, ay, rtol=rtol)
        assert converged[0] and error[0] <= rtol * value[0]
        assert abs(value[0] - exact) <= error[0] + own, (rtol, value[0], exact, error[0], own)


@pytest.mark.xfail(strict=True, reason="known estimate miss of the view cubature at grazing views of narrow lobes "
                   "(also in the kernel before issue 45's speed work): on the wide initial θ panels of the first "
                   "radial piece |KK − KG| is about 3 times below the K15 error (1.3e-6 off, estimate 4e-7 on "
                   "θ ∈ [0.196, 1.571]) and the initial pass is accepted unrefined")
def test_known_miss_at_grazing_narrow_lobe():
    """μ = 1/64, α ≈ 1/64: the initial panels are accepted with an estimate of 1.6e-6 where the error is 3.0e-6
    (found comparing the 32 × 32 × 16 table's cells with rtol-1e-10 references)."""
    ax, ay = 0.015625 / 0.8618, 0.015625 * 0.8618
    value, error, _, _ = kernel.albedo("ggx", "height-correlated", 0.015625, ax, ay, 0.3, rtol=2.5e-6)
    exact, exact_error, _, _ = kernel.albedo("ggx", "height-correlated", 0.015625, ax, ay, 0.3, rtol=1e-11)
    assert abs(value[0] - exact[0]) <= error[0] + exact_error[0]


def test_principal_direction_edges_catch_the_band_near_the_short_axis():
    """(α_x, α_y) = (2.82, 0.282), μ = 0.734, φ_v = 1.363: before the edges at the lobe's principal directions a
    band of θ within 0.03 of π/2 fell between a quarter panel's nodes (4.2e-5 missed at rtol 5e-6, estimate 6e-7)."""
    ax, ay, mu, phi_v = 2.8164035410874626, 0.28164035410874627, 0.734375, 1.362562585561002
    exact, exact_error, _, _ = kernel.albedo("ggx", "height-correlated", mu, ax, ay, phi_v, rtol=1e-11)
    for rtol in (1e-4, 1e-5, 5e-6):
        value, error, _, _ = kernel.albedo("ggx", "height-correlated", mu, ax, ay, phi_v, rtol=rtol)
        assert abs(value[0] - exact[0]) <= error[0] + exact_error[0], rtol
