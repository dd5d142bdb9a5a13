"""brdfnorm.engine.machinery.panels.adaptive_rectangles keeps ``max_evaluations`` as a bound: a case's last round
splits only as many panels as its budget can pay for, their halves evaluated and confirmed (it split every panel
over its share of the tolerance, whole batches past the budget: 77 295 evaluations at a budget of 50 000 below), and
a case stopped by the budget still carries an estimate that bounds its error, unconverged."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.special import erf

from brdfnorm.engine.machinery.panels import Panels, adaptive_rectangles

#: Two Gaussian bumps on the unit square and a ramp along the edge a = 0 beyond every K15 node: many panels carry
#: more than their share of an unreachable tolerance at once.
BUMPS = ((0.6, 0.4, 0.02), (0.2, 0.8, 0.005))
RAMP, WIDTH = 1.0, 2e-4


def _integrand(case, a, b, piece):
    value = RAMP * np.maximum(WIDTH - a, 0.0)
    for x, y, spread in BUMPS:
        value = value + np.exp(-((a - x) ** 2 + (b - y) ** 2) / spread)
    return value[..., None]


def _exact() -> float:
    total = RAMP * WIDTH**2 / 2
    for x, y, spread in BUMPS:
        s = math.sqrt(spread)
        total += math.prod(s * math.sqrt(math.pi) / 2 * (erf((1 - c) / s) + erf(c / s)) for c in (x, y))
    return total


@pytest.mark.parametrize("budget", [3_000, 8_000, 50_000, 100_000])
def test_the_budget_is_a_bound_and_the_stopped_estimate_honest(budget):
    # (before: 4 943, 10 111, 77 295 and 130 267 evaluations with one bump)
    initial = Panels(np.array([0, 0]), np.array([0.0, 0.5]), np.array([0.5, 1.0]), np.zeros(2), np.ones(2))
    result = adaptive_rectangles(_integrand, initial, 1, rtol=1e-15, atol=0.0, max_evaluations=budget)
    assert not result.converged[0]
    assert result.evaluations[0] <= budget
    assert result.evaluations[0] >= 0.7 * budget  # (the budget is spent, not left: the bound is not vacuous)
    assert abs(result.value[0, 0] - _exact()) <= result.error[0, 0]


def test_cases_within_their_budget_are_not_touched():
    # Two cases: one converges long before the budget, one cannot; the first's result is the same as alone.
    initial = Panels(np.array([0, 1]), np.zeros(2), np.ones(2), np.zeros(2), np.ones(2))
    both = adaptive_rectangles(_integrand, initial, 2, rtol=np.array([[1e-4], [1e-15]]), atol=0.0,
                               max_evaluations=30_000)
    alone = adaptive_rectangles(_integrand, initial.take(np.array([True, False])), 1, rtol=1e-4, atol=0.0,
                                max_evaluations=30_000)
    assert both.converged[0] and not both.converged[1]
    assert both.value[0, 0] == alone.value[0, 0] and both.evaluations[0] == alone.evaluations[0]
    assert both.evaluations[1] <= 30_000
