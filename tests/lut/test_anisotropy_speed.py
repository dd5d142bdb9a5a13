"""The speed-ups of the anisotropic kernel (issue #45 item 5) keep every estimate honest: the view-azimuth stretch
of :func:`brdfnorm.engine.routes.anisotropic.view_stretch`, the principal-direction edges only for lobes flatter
than α_y/α_x = 1/4 (:data:`~brdfnorm.engine.routes.anisotropic.PRINCIPAL_EDGES`), and E_avg's nodes whose tolerance
the bound E ∈ [0, 1] meets — each against a computation that shares none of it: view averages by an unstretched
(or differently stretched) trapezoid of views at rtol 1e-11, and E_avg by composite Gauss–Legendre over x = √μ of
view-azimuth trapezoids of brdfnorm's generic numpy microfacet route (``bn.albedo``)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.anisotropy_reference import stretched_reference, view_misses

import brdfnorm as bn
from brdfnorm.engine.routes import anisotropic as kernel


def test_view_stretch_limits():
    ax, ay = 1.0, 0.1
    assert kernel.view_stretch(1e-9, ax, ay) == pytest.approx(np.sqrt(ax / ay), rel=1e-12)  # grazing: √(α_x/α_y)
    assert kernel.view_stretch(1.0, ax, ay) == pytest.approx((ax / ay) ** 0.25, rel=1e-12)  # normal view
    assert kernel.view_stretch(0.3, ay, ax) == pytest.approx(1.0 / kernel.view_stretch(0.3, ax, ay), rel=1e-12)
    assert kernel.view_stretch(0.3, 0.4, 0.4) == 1.0


NARROW_FLAT = [("ggx", 0.4, 0.2, 0.002)]
SLOW_NARROW_FLAT = [("ggx", 0.2046, 0.1933, 0.02429), ("ggx", 0.3792, 0.1922, 0.02903),
                    ("beckmann", 0.4, 0.2, 0.002), ("ggx", 0.0116, 0.02497, 0.004409)]


@pytest.mark.parametrize(("name", "mu", "ax", "ay"), NARROW_FLAT + [pytest.param(*c, marks=pytest.mark.slow)
                                                                   for c in SLOW_NARROW_FLAT])
def test_narrow_flat_lobes_at_mid_views(name, mu, ax, ay):
    """Where a stretch balanced for Λ(V) alone, ((μ² + (1 − μ²)α_x²)/(μ² + (1 − μ²)α_y²))^{1/4}, converged fast
    but not geometrically (two singularities of E(φ_v)): at (0.4, 0.2, 0.002) it stopped at M = 4, 6.1e-7 off
    with an estimate of 4.8e-8. The kernel's stretch, the geometric mean with √(α_x/α_y), holds."""
    exact, own = stretched_reference(name, mu, ax, ay, np.sqrt(ax / ay))
    for rtol in (1e-5, 1e-7):
        value, error, _, converged = kernel.albedo(name, "height-correlated", mu, ax, ay, rtol=rtol)
        assert converged[0] and error[0] <= rtol * value[0]
        assert abs(value[0] - exact) <= error[0] + own, (rtol, value[0], exact, error[0], own)


def principal_sweep(count: int, seed: int) -> list:
    """Random views of lobes with α_y/α_x in [0.25, 0.6] (no principal-direction edges from 0.25 on) against
    rtol-1e-11 values: the misses."""
    rng = np.random.default_rng(seed)
    names = np.where(rng.random(count) < 0.5, "ggx", "beckmann")
    alpha = np.exp(rng.uniform(np.log(0.003), np.log(3.0), count))
    ratio = rng.uniform(0.25, 0.6, count)
    mu = np.exp(rng.uniform(np.log(1e-4), 0.0, count))
    phi = rng.uniform(0.0, np.pi / 2, count)
    rtol = np.exp(rng.uniform(np.log(1e-7), np.log(1e-4), count))
    ax, ay = alpha / np.sqrt(ratio), alpha * np.sqrt(ratio)
    return view_misses(names, mu, ax, ay, phi, rtol)


def test_lobes_without_principal_edges():
    assert kernel.PRINCIPAL_EDGES == 0.25
    assert not principal_sweep(8, 451)


@pytest.mark.slow
def test_lobes_without_principal_edges_sweep():
    assert not principal_sweep(60, 452)


def generic_average(name: str, ax: float, ay: float, x_edges, order: int, views: int) -> tuple[float, float]:
    """E_avg = ∫₀¹ 4x³ Ē(x²) dx by composite Gauss–Legendre (``order`` and ``order`` + 4 nodes a panel between
    ``x_edges``), Ē by the unstretched trapezoid over φ_v ∈ [0, π/2] with ``views`` intervals (and half of them),
    the views by the generic numpy microfacet route at rtol 1e-9. Returns the finer value and the two rules'
    differences plus the views' errors as its own error."""
    model = bn.load(name).with_params(alpha_x=ax, alpha_y=ay)
    phi = np.linspace(0.0, np.pi / 2, views + 1)
    results = []
    for n in (order, order + 4):
        t, w = np.polynomial.legendre.leggauss(n)
        edges = np.asarray(x_edges, dtype=float)
        half, mid = np.diff(edges)[:, None] / 2, (edges[:-1] + edges[1:])[:, None] / 2
        x, wx = (mid + half * t).ravel(), (half * w).ravel()
        theta = np.arccos(np.repeat(x * x, phi.size))
        r = bn.albedo(model, theta, phi=np.tile(phi, x.size), rtol=1e-9)
        e, ee = r.value[:, 0].reshape(x.size, phi.size), r.error[:, 0].reshape(x.size, phi.size)

        def trapezoid(g, step):
            return (0.5 * (g[:, 0] + g[:, -1]) + g[:, step:-1:step].sum(axis=1)) / (views // step)

        weight = wx * 4.0 * x ** 3
        results.append((weight @ trapezoid(e, 1), weight @ abs(trapezoid(e, 1) - trapezoid(e, 2)),
                        weight @ trapezoid(ee, 1)))
    (coarse, _, _), (fine, aliasing, views_error) = results
    return fine, abs(fine - coarse) + aliasing + views_error


@pytest.mark.parametrize(("name", "ax", "ay", "edges", "views"), [
    ("ggx", 0.5 / 0.8, 0.5 * 0.8, [0.0, 0.3, 0.6, 1.0], 16),
    pytest.param("ggx", 0.3 / 0.6, 0.3 * 0.6, [0.0, 0.1, 0.25, 0.5, 1.0], 32, marks=pytest.mark.slow),
    pytest.param("beckmann", 0.8 / 0.55, 0.8 * 0.55, [0.0, 0.15, 0.35, 0.6, 1.0], 32, marks=pytest.mark.slow),
    pytest.param("ggx", 0.03 / 0.8, 0.03 * 0.8, [0.0, 0.02, 0.05, 0.1, 0.2, 0.4, 1.0], 16,
                 marks=pytest.mark.slow),  # narrow: E_avg starts from two halves
    pytest.param("ggx", 1.2 / 0.5, 1.2 * 0.5, [0.0, 0.1, 0.25, 0.5, 0.75, 1.0], 64,
                 marks=pytest.mark.slow)])  # very wide: from two halves too
def test_average_albedo_against_the_generic_route(name, ax, ay, edges, views):
    """E_avg with the weight-loosened node tolerances, the bound E ∈ [0, 1] at the x = 0 end and (narrow and very
    wide lobes) the two halves as the first level: the error never above the estimate, against the generic route
    integrated over μ and φ_v by other rules."""
    exact, own = generic_average(name, ax, ay, edges, 10, views)
    assert own < 2e-6, own
    value, error, evaluations, converged = kernel.average_albedo(name, "height-correlated", ax, ay, rtol=1e-5)
    assert converged[0] and error[0] <= 1e-5 * value[0]
    assert abs(value[0] - exact) <= error[0] + own, (value[0], exact, error[0], own)


def test_tiny_weight_node_takes_the_bound():
    """The first K15 node of [0, 1] (x = 0.0043, weight 4x³ = 3e-7) needs no view at rtol 1e-5: a panel over
    [0, 1] costs no more than its 14 other nodes' averages."""
    x, wk, wg = kernel._X, kernel._WK, kernel._WG
    ax, ay = 0.4, 0.2
    _, _, evaluations, ok = kernel._average_panel(0.0, 1.0, ax, ay, 0, 0, 1e-5, 0.5, x, wk, wg)
    nodes = 0
    for xi in 0.5 * (x + 1.0):
        if 1e-5 * kernel.INNER_SHARE * 0.5 / (4 * xi ** 3) < 0.5:
            nodes += kernel.azimuth_average(max(xi * xi, kernel.MU_FLOOR), ax, ay, 0, 0, 1e-5 * kernel.INNER_SHARE,
                                            1e-5 * kernel.INNER_SHARE * 0.5 / (4 * xi ** 3), 0, x, wk, wg)[2]
    assert ok and evaluations == nodes
    assert np.count_nonzero(1e-5 * kernel.INNER_SHARE * 0.5 / (4 * (0.5 * (x + 1.0)) ** 3) >= 0.5) == 1
