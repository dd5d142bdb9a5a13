"""E_avg of lut/table.py (issue 39, item 3): the rounding-noise floor of its node albedos, the error estimate of its
Clenshaw–Curtis rule from three differences (rule_error), and the verdict from its honest total — each against an
independent route: the built-in GGX with separable Smith shadowing (the albedo of examples/ggx.brdf with f0 = 1),
averaged by the other μ rule (globally adaptive G7/K15, lut.table._average_adaptive) over its azimuthal 1-D
albedos."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.quiet import quietly

import brdfnorm as bn
from brdfnorm.lut import table
from brdfnorm.lut.table import average_over_mu, clenshaw_curtis, rule_error

ROUGHNESS = np.array([0.05, 0.3, 1.0])




@pytest.fixture(scope="module")
def reference_e_avg():
    """E_avg of the built-in separable GGX (α = roughness²) by the adaptive G7/K15 rule at rtol 1e-12."""
    value, error, converged, _ = quietly(table._average_adaptive, bn.load("ggx", shadowing="separable"),
                                        {"alpha": ROUGHNESS**2}, rtol=1e-12, method="azimuthal")
    assert converged.all() and np.all(error <= 1.1e-12 * value)
    return value, error


def _counting(monkeypatch) -> list[int]:
    """Evaluations of every node albedo E_avg computes from here on (one entry per batched call)."""
    counts: list[int] = []
    original = table.compute_cells

    def counted(*args, **kwargs):
        cells = original(*args, **kwargs)
        counts.append(int(cells.evaluations.sum()))
        return cells

    monkeypatch.setattr(table, "compute_cells", counted)
    return counts


@pytest.mark.slow
def test_shader_e_avg_within_its_estimate_and_converged(ggx_shader, reference_e_avg, monkeypatch):
    """At rtol 1e-10 every roughness converges, the narrowest (0.05: α = 0.0025, the shader's float64 noise ~6e-11
    of the albedo, above the nodes' rtol/4) too, and each value is within its estimate of the reference — in a
    bounded number of evaluations (42 million for the 32 roughnesses of the benchmark before the noise floor)."""
    counts = _counting(monkeypatch)
    value, error, converged, integrals = quietly(average_over_mu, ggx_shader, {"roughness": ROUGHNESS}, rtol=1e-10)
    reference, reference_error = reference_e_avg
    assert converged.all(), error / value
    assert np.all(error <= 1e-10 * value)
    assert np.all(np.abs(value - reference) <= error + reference_error), np.abs(value - reference) / error
    assert integrals <= 3 * 65
    assert sum(counts) < 3_500_000, sum(counts)


def test_rounding_limited_node_stops_early_with_an_honest_estimate(ggx_shader):
    """A node of roughness 0.05 asked for rtol/4 = 2.5e-11 is rounding-limited: the route refines until its noise
    test stops it. With its combination's noise floor (what E_avg learns from its node at μ = 1) the same node is
    asked no finer than the noise and costs a fraction, with an estimate as small (the noise bound) that still
    covers its true error."""
    mu, weight, params = np.array([0.12, 0.5]), np.array([1.0, 1.0]), {"roughness": np.array([0.05, 0.05])}
    reference = bn.albedo(bn.load("ggx", alpha=0.0025, shadowing="separable"), np.arccos(mu), rtol=1e-13)
    assert reference.method == "azimuthal"
    evaluations = {}
    original = table.compute_cells

    def counted(*args, **kwargs):
        cells = original(*args, **kwargs)
        evaluations[kwargs["rtol"]] = int(cells.evaluations.sum())
        return cells

    results = {}
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(table, "compute_cells", counted)
        for label, floor in (("plain", None), ("floored", np.full(2, 6e-11))):
            results[label] = quietly(table._node_albedos, ggx_shader, mu, weight, params, 1e-10, "auto", floor)
    plain, floored = results["plain"], results["floored"]
    assert plain[3].all() and plain[2].all()  # rounding-limited: final, and flagged as noisy
    assert floored[2].all()
    assert sum(v for k, v in evaluations.items() if k > 5e-11) * 3 < evaluations[2.5e-11], evaluations
    for value, error, *_ in (plain, floored):
        true = np.abs(value - reference.value[:, 0])
        assert np.all(true <= error + reference.error[:, 0]), true / error
        assert np.all(error <= 2e-10 * value)


def _cc(f, n: int) -> float:
    x, w = clenshaw_curtis(n)
    return float(w @ f(x))


@pytest.mark.parametrize("f, exact", [
    (np.exp, np.e - 1.0),
    (lambda x: 1.0 / (1.0 + 25.0 * (2 * x - 1) ** 2), np.arctan(5.0) / 5.0),  # Runge: poles near [0, 1]
    (lambda x: 4 * x**3 / (1.0 + 100.0 * (x - 0.3) ** 2), None),
    (lambda x: np.abs(x - 0.3), 0.29),  # a kink: algebraic convergence, the test keeps d_2n
    (lambda x: np.sqrt(x), 2.0 / 3.0),  # an endpoint singularity
])
def test_rule_error_covers_the_true_error(f, exact):
    """Q_2n's estimate from d_2n and d_n is never above d_2n and, on analytic, kinked and singular integrands,
    never below Q_2n's true error (exact, or the 1024-interval rule where there is no closed form)."""
    exact = _cc(f, 1024) if exact is None else exact
    for n in (16, 32, 64, 128):
        d2, d1, d0 = (abs(_cc(f, m) - _cc(f, m // 2)) for m in (n, n // 2, n // 4))
        estimate = float(rule_error(np.array(d2), np.array(d1), np.array(d0)))
        assert estimate <= d2
        assert abs(_cc(f, n) - exact) <= estimate + 4e-16, (n, abs(_cc(f, n) - exact), estimate)


def test_rule_error_keeps_the_difference_where_the_rule_does_not_converge():
    d2, d1 = np.array([1e-3, 1e-6, 1e-9, 1e-9, 0.0]), np.array([2e-3, 1e-6, 1e-5, 1e-5, 0.0])
    d0 = np.array([1.0, 1.0, 1.0, 1e-5, 0.0])
    estimate = rule_error(d2, d1, d0)
    # not falling by RULE_CONVERGING at the last doubling, or at the one before (Phong n = 19 300's case): d_2n
    assert np.array_equal(estimate[[0, 1, 3]], d2[[0, 1, 3]])
    assert estimate[2] == pytest.approx(table.RULE_SAFETY * 1e-9 * 1e-4**table.RULE_POWER)
    assert estimate[4] == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("name, params", [
    ("ggx", {"alpha": 0.025, "fresnel": "schlick", "f0": 0.04}),  # where the power 1 was 2× optimistic
    ("beckmann", {"alpha": 0.002}),
    ("ggx", {"alpha": 0.3}),
    ("phong", {"n": 19306.98}),  # where one test (the last doubling's) was 25–165× optimistic
])
def test_rule_error_covers_e_avg_of_lobes(name, params):
    """The rule's estimate at 32 and 64 intervals, E_avg's integrand 4x³E(x²) with albedos to rtol 1e-13, against
    the 128-interval rule (its own error: its difference from 64 and the albedo errors through the weights)."""
    x, w = clenshaw_curtis(128)
    result = quietly(bn.albedo, bn.load(name, **params), np.arccos(np.maximum(x[1:] ** 2, 1e-7)), rtol=1e-13)
    E, E_error = (np.concatenate([[0.0], a[:, 0]]) for a in (result.value, result.error))

    def rule(n: int, values: np.ndarray) -> float:
        nodes, weights = clenshaw_curtis(n)
        return float(weights * 4 * nodes**3 @ values[:: 128 // n])

    Q = {n: rule(n, E) for n in (4, 8, 16, 32, 64, 128)}
    slack = abs(Q[128] - Q[64]) + rule(128, E_error) + 1e-15
    for n in (32, 64):
        estimate = float(rule_error(*(np.array(abs(Q[m] - Q[m // 2])) for m in (n, n // 2, n // 4))))
        assert abs(Q[n] - Q[128]) <= estimate + rule(n, E_error) + slack, (n, abs(Q[n] - Q[128]), estimate)
