"""E_avg's node tolerances by their share of the rule (lut/table.py, issue 39 item 3): each node albedo of the
Clenshaw–Curtis rule in x = √μ is asked NODE_SHARE·rtol over its share n·w·4x³ of the integral, and where the
nodes' estimates (not the rule's) keep a combination open its heaviest nodes are asked again, tighter
(``_tighten``), rather than a finer rule or the adaptive route afresh. The values are checked against an
independent route: the built-in GGX with separable Smith shadowing (the albedo of examples/ggx.brdf with f0 = 1,
its own microfacet route, not the shader's), averaged at rtol 1e-12."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.quiet import quietly

import brdfnorm as bn
from brdfnorm.lut import table

ROUGHNESS = np.array([0.1, 0.5, 1.0])
RTOL = 1e-9




@pytest.fixture(scope="module")
def reference():
    """E_avg of the built-in separable GGX (α = roughness²) by the adaptive G7/K15 rule at rtol 1e-12."""
    value, error, converged, _ = quietly(table._average_adaptive, bn.load("ggx", shadowing="separable"),
                                        {"alpha": ROUGHNESS**2}, rtol=1e-12)
    assert converged.all() and np.all(error <= 1.1e-12 * value)
    return value, error


def _recording(monkeypatch) -> list[tuple[np.ndarray, float, int]]:
    """(μ of the cells, rtol asked, evaluations) of every node albedo call E_avg makes from here on."""
    calls: list[tuple[np.ndarray, float, int]] = []
    original = table.compute_cells

    def recorded(model, theta, params, **kwargs):
        cells = original(model, theta, params, **kwargs)
        calls.append((np.cos(np.asarray(theta)), kwargs["rtol"], int(cells.evaluations.sum())))
        return cells

    monkeypatch.setattr(table, "compute_cells", recorded)
    return calls


def _check(value, error, converged, reference):
    reference_value, reference_error = reference
    assert converged.all(), error / value
    assert np.all(error <= RTOL * value), error / value
    assert np.all(np.abs(value - reference_value) <= error + reference_error), np.abs(value - reference_value) / error


def test_nodes_asked_by_their_share(ggx_shader, reference, monkeypatch):
    """Every node is asked at least NODE_SHARE·rtol (the old rule asked rtol/4 of the heaviest nodes and of the one
    at μ = 1, whose share of the 16-interval rule is 1/8); the grazing nodes, of shares below 1e-4, at
    NODE_RTOL_MAX; and the values stay within their estimates of the reference."""
    calls = _recording(monkeypatch)
    value, error, converged, integrals = quietly(table.average_over_mu, ggx_shader, {"roughness": ROUGHNESS}, rtol=RTOL)
    _check(value, error, converged, reference)
    asked = {}
    for mu, rtol, _ in calls:
        for m in mu:
            asked[round(float(m), 12)] = min(rtol, asked.get(round(float(m), 12), np.inf))
    assert min(asked.values()) >= table.NODE_SHARE * RTOL * (1 - 1e-12)
    assert asked[1.0] >= table.NODE_SHARE * RTOL
    x, w = table.clenshaw_curtis(table.CC_FIRST)
    grazing = x[1] ** 2  # share 1e-6 of the first rule
    assert table.CC_FIRST * w[1] * 4 * x[1] ** 3 < 1e-4
    assert asked[round(float(grazing), 12)] == table.NODE_RTOL_MAX
    assert integrals <= ROUGHNESS.size * (table.CC_MAX + 1)


def test_loose_nodes_are_asked_again_not_a_finer_rule(ggx_shader, reference, monkeypatch):
    """With every node asked NODE_RTOL_MAX (NODE_SHARE raised far above its value) the rule settles at 32
    intervals but the nodes' estimates do not: the heaviest nodes are asked again, tighter, and every combination
    converges within its estimate of the reference without the adaptive route — without ``_tighten`` the
    64-interval rule could not shrink the old nodes' estimates either, and the combinations went to the adaptive
    route afresh (hundreds of albedos more)."""
    monkeypatch.setattr(table, "NODE_SHARE", 1e6)

    def refused(*args, **kwargs):
        raise AssertionError("a combination went to the adaptive route")

    monkeypatch.setattr(table, "_average_adaptive", refused)
    calls = _recording(monkeypatch)
    value, error, converged, integrals = quietly(table.average_over_mu, ggx_shader, {"roughness": ROUGHNESS}, rtol=RTOL)
    _check(value, error, converged, reference)
    first = {round(float(m), 12) for m in calls[0][0]} | {round(float(m), 12) for m in calls[1][0]}
    again = [rtol for mu, rtol, _ in calls if rtol < table.NODE_RTOL_MAX and any(round(float(m), 12) in first
                                                                               for m in mu)]
    assert again, [rtol for _, rtol, _ in calls]
    assert integrals <= 2 * ROUGHNESS.size * (table.CC_MAX + 1), integrals


def test_tighten_leaves_noisy_and_already_tight_nodes():
    """A node whose estimate is its combination's float64 noise, or that was already asked as tightly as its
    allowance needs, is not asked again (that would cost a full albedo and return the same estimate)."""
    n = 4
    weight = np.full(n + 1, 0.25)
    weight[0] = 0.0
    node = {"value": np.ones((1, n + 1)), "error": np.full((1, n + 1), 1e-6), "asked": np.full((1, n + 1), 1e-4),
            "ok": np.ones((1, n + 1), dtype=bool), "noisy": np.zeros((1, n + 1), dtype=bool)}
    node["noisy"][0, 1] = True
    node["asked"][0, 2] = 1e-12
    asked = []

    def fill(rows, columns, share, tolerance):
        asked.append((rows.tolist(), columns.ravel().tolist(), tolerance.ravel().tolist()))

    assert table._tighten(node, np.array([0]), np.array([1e-8]), weight, np.zeros(1), fill)
    rows, columns, tolerance = asked[0]
    assert columns == [3, 4]
    # the allowance TIGHTEN_FILL·1e-8/4 through the weight 0.25 and value 1: 5e-9, rounded down to 1e-9
    assert tolerance == pytest.approx([1e-9, 1e-9])
    node["noisy"][0, 3:] = True
    assert not table._tighten(node, np.array([0]), np.array([1e-8]), weight, np.zeros(1), fill)


@pytest.mark.parametrize("name, parameter, values", [
    ("beckmann", "alpha", [0.02, 1.0]),
    ("burley", "roughness", [0.2, 0.9]),
    pytest.param("phong", "n", [5.0, 500.0], marks=pytest.mark.slow),  # its reference takes ~3 s
])
def test_other_lobes_within_their_estimates(name, parameter, values):
    """Lobes on other routes, with the shares at rtol 1e-9, against the adaptive G7/K15 rule at rtol 1e-12 (its
    nodes asked rtol/4 each): converged, within rtol, within their estimates."""
    model, params = bn.load(name), {parameter: np.array(values)}
    value, error, converged, _ = quietly(table.average_over_mu, model, params, rtol=RTOL)
    reference, reference_error, reference_converged, _ = quietly(table._average_adaptive, model, params, rtol=1e-12)
    assert reference_converged.all()
    assert converged.all() and np.all(error <= RTOL * np.abs(value))
    assert np.all(np.abs(value - reference) <= error + reference_error), np.abs(value - reference) / error
