"""The one driver of the global tensor rules (brdfnorm.engine.machinery.global_driver) on a grid of its own: a
:class:`GlobalGrid` subclass with closed-form integrals, so that the driver's levels loop is checked apart from the
two coordinate systems that use it (the lobe-aligned grid and the half-vector rectangle, whose results the recorded
grid and test_halfvector_global.py pin)."""

from __future__ import annotations

import numpy as np
import pytest

from brdfnorm.engine.machinery import global_driver
from brdfnorm.engine.machinery.tensor_rule import FLOOR, START_LEVELS, GlobalGrid


class Rectangle(GlobalGrid):
    """F(t, u) = e^{s(p + u)}/(1 − a cos t) on piece p of each case (a pole at distance ~√(1 − a²) from the real
    t axis): ∫∫ over [0, 2π) × [0, 1] summed over the pieces is 2π/√(1 − a²) · (e^{s·P} − 1)/s. ``bad`` cases
    are NaN on their last piece; the grid counts what it evaluates."""

    def __init__(self, a, s, pieces, bad=()):
        self.a, self.s, self.pieces, self.bad = np.asarray(a), np.asarray(s), pieces, set(bad)
        self.evaluated = np.zeros(self.a.size, dtype=np.int64)

    def evaluate(self, case, piece, index, M, u):
        t = index * (2 * np.pi / M)
        F = np.exp(
            self.s[case][:, None, None] * (piece[:, None, None] + u[None, None, :])) / (
            1 - self.a[case][:, None, None] * np.cos(t)[None, :, None])
        for row, (k, p) in enumerate(zip(case, piece, strict=True)):
            if k in self.bad and p == self.pieces - 1:
                F[row] = np.nan
        np.add.at(self.evaluated, case, index.size * u.size)
        return F[..., None]

    def estimate(self, group, F, q, e_b, e_u, magnitude):
        floor = FLOOR * magnitude
        estimate = e_b + e_u + floor
        return e_b, e_u, floor, 0.0, estimate


def _exact(a, s, pieces):
    return 2 * np.pi / np.sqrt(1 - a * a) * np.expm1(s * pieces) / s


@pytest.mark.parametrize("pieces", [1, 3])
@pytest.mark.parametrize("rtol", [1e-6, 1e-11])
def test_settles_closed_forms_within_honest_estimates(pieces, rtol):
    a, s = np.array([0.0, 0.5, 0.9, 0.99]), np.array([0.5, 1.0, 2.0, 4.0])
    grid = Rectangle(a, s, pieces)
    result = global_driver.integrate_global(grid, a.size, np.arange(a.size), rtol=rtol, atol=0.0, max_nodes=32_768)
    exact = _exact(a, s, pieces)
    assert result.converged.all()
    true_error = np.abs(result.value[:, 0] - exact)
    assert np.all(true_error <= result.error[:, 0])
    assert np.all(result.error[:, 0] <= rtol * np.abs(result.value[:, 0]))
    # every evaluation is counted once: the driver's count is the grid's own, and the nested levels reuse nodes
    np.testing.assert_array_equal(result.evaluations, grid.evaluated)
    # the sharp case (a = 0.99) was doubled far beyond the start grid; the others at least confirmed
    start = 2 ** START_LEVELS[0] * (2 ** START_LEVELS[1] - 1) * pieces
    assert result.evaluations[3] > start and result.evaluations[0] >= start


def test_a_case_with_one_bad_piece_fails_as_a_whole_and_others_settle():
    a, s = np.array([0.5, 0.5]), np.array([1.0, 1.0])
    result = global_driver.integrate_global(Rectangle(a, s, 3, bad={1}), 2, np.arange(2), rtol=1e-9, atol=0.0,
                                            max_nodes=32_768)
    assert result.converged.tolist() == [True, False]
    assert abs(result.value[0, 0] - _exact(0.5, 1.0, 3)) <= result.error[0, 0]


def test_cases_left_out_are_untouched_and_a_node_cap_gives_up():
    a, s = np.array([0.5, 0.999, 0.5]), np.array([1.0, 1.0, 1.0])
    grid = Rectangle(a, s, 1)
    # case 1 (a = 0.999: a pole 0.045 from the real t axis) would need ~600 azimuths at rtol 1e-12, more than
    # 2048 nodes; case 2 is not asked
    result = global_driver.integrate_global(grid, 3, np.arange(2), rtol=1e-12, atol=0.0, max_nodes=2048)
    assert result.converged.tolist() == [True, False, False]
    assert result.evaluations[2] == 0 and result.value[2, 0] == 0.0
    assert 0 < result.evaluations[1] <= 2048
