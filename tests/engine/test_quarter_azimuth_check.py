"""The half-azimuth check of u on a quarter of the azimuths (``global_driver.HALF_AZIMUTH_DEPTH`` = 2): where the
driver doubles β from M to 2M it measures u on M/2 of them, and takes that check along (to M of 4M) when β alone
doubles again. Each node is evaluated once, the value is the tensor rule's on the grid it settled, and Blinn-Phong
n = 100 at rtol 1e-9 settles as before, on fewer nodes, within its estimate, on both backends alike."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.machinery import global_driver
from brdfnorm.engine.machinery.tensor_rule import GlobalGrid, fejer, sums


class _Smooth(GlobalGrid):
    """A periodic analytic integrand in t times a smooth one in u, every evaluated node recorded; plain estimates."""

    half_azimuth = True
    rho, shift = 0.7, 0.02

    def __init__(self):
        self.nodes: list[tuple[float, float]] = []

    def evaluate(self, case, piece, index, M, u):
        t = index * (2 * np.pi / M)
        for x in t:
            self.nodes.extend((round(float(x), 9), round(float(y), 11)) for y in u)
        f = (1.0 / (1.0 - 2 * self.rho * np.cos(t) + self.rho**2))[:, None] / (u + self.shift)[None, :]
        return np.broadcast_to(f[None, :, :, None], (case.size,) + f.shape + (1,)).copy()

    def estimate(self, group, F, q, e_b, e_u, magnitude):
        floor = 50 * np.finfo(float).eps * magnitude
        return e_b, e_u, floor, 0.0 * floor, e_b + e_u + floor

    def exact(self) -> float:
        return 2 * np.pi / (1 - self.rho**2) * np.log((1 + self.shift) / self.shift)


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
    grid = _Smooth()
    # (its path: 32 × 63 → β doubled, u checked on 16 of the 64 azimuths → β again, the check taken along to 32 of
    # the 128 → settled on 128 × 63, u checked on 32 azimuths × 127 radial nodes)
    result = global_driver.integrate_global(grid, 1, np.arange(1), rtol=1e-6, atol=0.0, max_nodes=65_536)
    assert result.converged[0] and sum(halves) == 2
    assert len(grid.nodes) == len(set(grid.nodes)) == result.evaluations[0]  # no node twice
    assert abs(result.value[0, 0] - grid.exact()) <= result.error[0, 0]
    M, level_u = 128, 6
    assert set(grid.nodes) == {(round(2 * np.pi * i / M, 9), round(float(u), 11))
                               for i in range(M) for u in fejer(level_u)[0]} | {
        (round(2 * np.pi * i / M, 9), round(float(u), 11)) for i in range(0, M, 4) for u in fejer(level_u + 1)[0]}
    F = grid.evaluate(np.zeros(1, dtype=int), np.zeros(1, dtype=int), np.arange(M), M, fejer(level_u)[0])
    assert result.value[0, 0] == pytest.approx(float(sums(F, level_u)[0][0, 0]), rel=1e-14)


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
