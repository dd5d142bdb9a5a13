"""The half-azimuth check of u on a quarter of the azimuths (``global_driver.HALF_AZIMUTH_DEPTH`` = 2): where the
driver doubles β from M to 2M it measures u on M/2 of them, and takes that check along (to M of 4M) when β alone
doubles again. Each node is evaluated once, the value is the tensor rule's on the grid it settled, and Blinn-Phong
n = 100 at rtol 1e-9 settles as before, on fewer nodes, within its estimate, on both backends alike."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from helpers.global_grid import SmoothGrid, assert_settled_with_check

import brdfnorm as bn
from brdfnorm.engine.machinery import global_driver


def _albedo(model, theta, backend="numpy", **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return bn.albedo(model, np.atleast_1d(theta), method="quadrature", backend=backend, **kwargs)


def test_the_quarter_check_evaluates_each_node_once(monkeypatch):
    monkeypatch.setattr(global_driver, "HALF_AZIMUTH_DEPTH", 2)
    monkeypatch.setattr(global_driver, "HALF_AZIMUTH_NEEDED", 1)
    halves = []
    decide = global_driver._halves

    def observed(grid, group, more_b, more_u, short, needed_u):
        half = decide(grid, group, more_b, more_u, short, needed_u)
        halves.append(0 if half is None else int(half.sum()))
        if group.check is not None:  # the check lies on every fourth azimuth of the grid
            assert group.check.shape[1] == 2**group.level_b // 4 and group.checked
        return half

    monkeypatch.setattr(global_driver, "_halves", observed)
    grid = SmoothGrid()
    # (its path: 32 × 63 → β doubled, u checked on 16 of the 64 azimuths → β again, the check taken along to 32 of
    # the 128 → settled on 128 × 63, u checked on 32 azimuths × 127 radial nodes)
    result = global_driver.integrate_global(grid, 1, np.arange(1), rtol=1e-6, atol=0.0, max_nodes=65_536)
    assert result.converged[0] and sum(halves) == 2
    assert_settled_with_check(grid, result, M=128, level_u=6, check_step=4)


def test_fewer_evaluations_for_blinn_phong(monkeypatch):
    # Blinn-Phong n = 100, rtol 1e-9 (with the rounding-noise survey): 50–81° settle on 64 × 63 with u checked on
    # 16 azimuths × 127 (5 320; on 32 azimuths: 6 344; 77°: 8 392, both doubled), 82–87° on 128 × 63 with u
    # checked on 32 azimuths (10 376; 12 424).
    model = bn.load("blinn-phong", n=100.0)
    theta = np.radians([55.0, 75.0, 77.0, 84.0])
    exact = bn.albedo(model, theta, method="series", rtol=1e-13)
    result = _albedo(model, theta, rtol=1e-9)
    assert np.all(np.abs(result.value[:, 0] - exact.value[:, 0]) + exact.error[:, 0] <= result.error[:, 0])
    assert result.evaluations.tolist() == [5_320, 5_320, 8_392, 10_376]
    monkeypatch.setattr(global_driver, "HALF_AZIMUTH_DEPTH", 1)
    monkeypatch.setattr(global_driver, "HALF_AZIMUTH_NEEDED", 1)
    assert _albedo(model, theta, rtol=1e-9).evaluations.tolist() == [6_344, 6_344, 8_392, 12_424]


def test_both_backends_evaluate_the_same_nodes():
    pytest.importorskip("numba")
    model = bn.load("blinn-phong", n=100.0)
    theta = np.radians([20.0, 55.0, 77.0, 84.0, 89.0])
    numpy, compiled = _albedo(model, theta, rtol=1e-9), _albedo(model, theta, "compiled", rtol=1e-9)
    assert numpy.evaluations.tolist() == compiled.evaluations.tolist()
    assert np.all(np.abs(numpy.value - compiled.value) <= np.minimum(numpy.error, compiled.error))
