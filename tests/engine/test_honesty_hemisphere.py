"""Issue 39, "honesty kept", in the hemisphere route's adaptive panels (brdfnorm.engine.routes.hemisphere): an
estimate the sweeps found smaller than its true error, against the independent reference of
helpers.references.oren_nayar_reference (closed azimuth, scipy's quad split at the kink)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.paths import EXAMPLES
from helpers.references import oren_nayar_reference

import brdfnorm as bn
from brdfnorm.engine.machinery.panels import Panels
from brdfnorm.engine.routes import hemisphere
from brdfnorm.validate import DEFAULT_MAX_EVALUATIONS

SIGMA, THETA = 1.325, np.radians(57.1)


@pytest.fixture(scope="module")
def oren_nayar():
    return bn.load(str(EXAMPLES / "oren_nayar.brdf")).with_params(sigma=np.array([SIGMA]))


@pytest.mark.slow  # 2e7 evaluations: ~2 s of CPU idle, 6-14 s on a loaded machine
@pytest.mark.parametrize("backend", ["numpy", "compiled"])
def test_oren_nayar_shader_whose_kink_clips_a_panel_corner_stays_within_its_estimate(oren_nayar, backend):
    # The kink max(0, L·V − N·L N·V) clipped a corner of the panel [π/4, 3π/8] × [1/4, 3/8] within 0.8% of
    # its sides, beyond every node of K15, G7 and both Lobatto-9 ⊗ G7 checks: |K − G| 1e-16, true error 8.5e-11.
    # The case ran out of budget with the panel never confirmed: 1.33× outside its estimate (1.57× converged, with
    # a budget of 2e8).
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(oren_nayar, np.array([THETA]), method="quadrature", backend=backend, rtol=1e-10)
    exact = oren_nayar_reference(THETA, SIGMA, 0.8)
    assert abs(result.value[0, 0] - exact) <= result.error[0, 0]
    assert result.evaluations[0] <= DEFAULT_MAX_EVALUATIONS  # the confirmation at the stop is within the budget


def test_corner_check_sees_a_kink_that_clips_a_panel_corner(oren_nayar):
    V = np.array([np.sin(THETA), 0.0, np.cos(THETA)])

    def integrand(omega, case):
        return oren_nayar.evaluate(omega, np.broadcast_to(V, omega.shape), oren_nayar.params) * omega[:, 2:3]

    # the lobe frame and width the route's lobe search found for this case
    frame = hemisphere.lobe_frame(np.array([[0.52622861, 0.04557213, 0.84912109]]))
    width, support = np.array([0.95138151]), np.array([np.pi])

    def panels(a0, a1, b0, b1):
        out = Panels(np.zeros(np.size(a0), dtype=int), *(np.atleast_1d(x) for x in (a0, a1, b0, b1)))
        hemisphere._evaluate(out, integrand, frame, width, support, "raise", 10**6)
        return out

    panel = panels(np.pi / 4, 3 * np.pi / 8, 0.25, 0.375)
    n = 16
    i, j = np.divmod(np.arange(n * n), n)
    fine = panels(np.pi / 4 + np.pi / 8 * i / n, np.pi / 4 + np.pi / 8 * (i + 1) / n, 0.25 + 0.125 * j / n,
                  0.25 + 0.125 * (j + 1) / n)
    error = abs(fine.value[:, 0].sum() - panel.value[0, 0])
    assert error > 5e-11
    assert panel.err_a[0, 0] + panel.err_b[0, 0] < 1e-15  # the rule pair sees nothing
    along_beta, none = hemisphere._check_by_halves(panel, True, integrand, frame, width, support, 10**6)
    along_u, corner = hemisphere._check_by_halves(panel, False, integrand, frame, width, support, 10**6)
    assert none is None and along_beta[0, 0] + along_u[0, 0] < 1e-15  # nor the Lobatto-9 ⊗ G7 halves
    assert corner[0, 0] >= 4 * error  # the corners' Lobatto nodes do
