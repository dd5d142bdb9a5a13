"""E_avg of the glass tables (brdfnorm.lut.glass): tanh-sinh in μ where η > 1, the generic route where η < 1.

Checked against the generic route (nested Clenshaw–Curtis in √μ + adaptive G7/K15: another rule over μ on the same
albedos), for honesty on a random sweep (true error ≤ estimate, estimate ≤ rtol·E_avg) and through `lut.compute`.
"""

from __future__ import annotations

import warnings

import numpy as np

import brdfnorm as bn
from brdfnorm import lut
from brdfnorm.lut import glass
from brdfnorm.lut.table import average_over_mu

MODEL = bn.load("ggx-dielectric")


def _quiet(route, *args, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return route(*args, **kwargs)


def test_agrees_with_the_generic_route():
    params = {"alpha": np.array([0.3, 0.8]), "eta": np.array([1.5, 2.2])}
    ours = _quiet(glass.average, MODEL, params, rtol=1e-10)
    generic = _quiet(average_over_mu, MODEL, params, rtol=1e-10)
    assert ours[2].all() and generic[2].all()
    assert np.all(np.abs(ours[0] - generic[0]) <= ours[1] + generic[1])
    assert np.all(np.abs(ours[0] - generic[0]) <= 1e-10)
    assert ours[3] < generic[3]  # fewer albedos: the reason for the route


def test_honest_on_a_random_sweep():
    """Random (α, η > 1): at rtol 1e-3 and 1e-6 the true error (against rtol 1e-10) is within the estimate, and the
    estimate within rtol·E_avg (a test that can fail both ways). η in [1.3, 2.5], α in [0.2, 1]: closer to 1 and
    smoother, the references take minutes (see the module's open items in the branch report)."""
    rng = np.random.default_rng(0)
    params = {"alpha": rng.uniform(0.2, 1.0, 2), "eta": rng.uniform(1.3, 2.5, 2)}
    ref, ref_error, ref_ok, _ = _quiet(glass.average, MODEL, params, rtol=1e-10)
    assert ref_ok.all()
    for rtol in (1e-3, 1e-6):
        value, error, ok, _ = _quiet(glass.average, MODEL, params, rtol=rtol)
        assert ok.all()
        assert np.all(np.abs(value - ref) <= error + ref_error), rtol
        assert np.all(error <= rtol * value), rtol


def test_table_takes_each_route_by_eta():
    """`lut.compute` over η on both sides: E_avg where η > 1 is glass.average's, where η < 1 the generic route's."""
    axes = {"mu": [0.3, 1.0], "alpha": [0.8], "eta": [1 / 1.5, 1.5]}
    table = _quiet(lut.compute, MODEL, axes, rtol=1e-6)
    outside = _quiet(glass.average, MODEL, {"alpha": np.array([0.8]), "eta": np.array([1.5])}, rtol=1e-6)
    inside = _quiet(average_over_mu, MODEL, {"alpha": np.array([0.8]), "eta": np.array([1 / 1.5])}, rtol=1e-6)
    assert table["E_avg"][0, 1] == outside[0][0] and table["E_avg_error"][0, 1] == outside[1][0]
    assert table["E_avg"][0, 0] == inside[0][0] and table["E_avg_error"][0, 0] == inside[1][0]
