"""A stand-in grid for the global driver's tests (tests/engine/test_half_azimuth_check.py,
test_quarter_azimuth_check.py): an analytic integrand whose every evaluated node is recorded."""

from __future__ import annotations

import numpy as np

from brdfnorm.engine.machinery.tensor_rule import GlobalGrid


class SmoothGrid(GlobalGrid):
    """A periodic analytic integrand in t times a smooth one in u, with every evaluated node recorded; its
    estimate is the plain one (no extrapolation), and it may use the half-azimuth check."""

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


def assert_settled_with_check(grid: SmoothGrid, result, M: int, level_u: int, check_step: int) -> None:
    """``result`` of the global driver on ``grid`` evaluated each node once — the M × (level_u's radial rule) grid and
    the next radial level on every ``check_step``-th azimuth (the u check) — and reports the tensor rule's value on
    the M-azimuth grid it settled, within its estimate of the exact integral."""
    import pytest

    from brdfnorm.engine.machinery.tensor_rule import fejer, sums

    assert len(grid.nodes) == len(set(grid.nodes)) == result.evaluations[0]  # no node twice
    assert abs(result.value[0, 0] - grid.exact()) <= result.error[0, 0]
    assert set(grid.nodes) == {(round(2 * np.pi * i / M, 9), round(float(u), 11))
                               for i in range(M) for u in fejer(level_u)[0]} | {
        (round(2 * np.pi * i / M, 9), round(float(u), 11)) for i in range(0, M, check_step)
        for u in fejer(level_u + 1)[0]}
    F = grid.evaluate(np.zeros(1, dtype=int), np.zeros(1, dtype=int), np.arange(M), M, fejer(level_u)[0])
    assert result.value[0, 0] == pytest.approx(float(sums(F, level_u)[0][0, 0]), rel=1e-14)
