"""brdfnorm.engine.compiled.rules: the global rule's sums per azimuth (row_sums, the channels side by side) and over
the azimuths (rows_total, global_rule.piece_sums) equal, bit for bit, the plain sums in the numpy driver's order; a
grid with a value that is not finite has a magnitude that is not; and slopes.borrowed's view reads its array's
values."""

from __future__ import annotations

import numpy as np
import pytest

from brdfnorm.engine.compiled import global_rule, rules
from brdfnorm.engine.machinery.tensor_rule import fejer


def _plain(G: np.ndarray, w, w_half, w_quarter) -> np.ndarray:
    """(Q, Q(½ β), Q(¼ β), Q(½ u), Q(¼ u), ∫|F|) per channel of one grid, one channel at a time in Python floats
    (the order of the numpy driver's loops, which the compiled sums must keep: no reassociation)."""
    M, N1, C = G.shape
    out = np.zeros((6, C))
    for c in range(C):
        q = q_b = q_bb = q_u = q_uu = magnitude = 0.0
        for i in range(M):
            s = s_abs = 0.0
            for j in range(N1):
                x = float(G[i, j, c])
                s += x * float(w[j])
                s_abs += abs(x) * float(w[j])
            s_u = 0.0
            for j in range(w_half.size):
                s_u += float(G[i, 2 * j + 1, c]) * float(w_half[j])
            s_uu = 0.0
            for j in range(w_quarter.size):
                s_uu += float(G[i, 4 * j + 3, c]) * float(w_quarter[j])
            q += s
            if i % 2 == 0:
                q_b += s
            if i % 4 == 0:
                q_bb += s
            q_u += s_u
            q_uu += s_uu
            magnitude += s_abs
        out[:, c] = q, q_b, q_bb, q_u, q_uu, magnitude
    return out


@pytest.mark.parametrize("channels", [1, 2, 3, 4, 6])
@pytest.mark.parametrize(("M", "level"), [(8, 3), (16, 4)])
def test_the_sums_are_the_plain_sums_bit_for_bit(rng, channels, M, level):
    w, w_half, w_quarter = (fejer(level - k)[1] for k in range(3))
    F = rng.standard_normal((3, M, w.size, channels)) * rng.uniform(0.1, 1e3, (3, 1, 1, channels))
    out = rules.tensor_sums(F, w, w_half, w_quarter)
    for r in range(F.shape[0]):
        expected = _plain(F[r], w, w_half, w_quarter)
        assert np.array_equal(out[:, r, :], expected), (r, np.abs(out[:, r, :] - expected).max())


def test_piece_sums_read_a_value_that_is_not_finite_off_the_magnitude(rng):
    w, w_half, w_quarter = (fejer(4 - k)[1] for k in range(3))
    G = rng.standard_normal((8, w.size, 2))
    totals = np.empty((8, 4, 2))
    sums, raw = np.empty((4, 2)), np.empty((6, 1, 2))
    for bad in (None, np.nan, np.inf, -np.inf):
        if bad is not None:
            G[5, 3, 1] = bad
        _rows(G, w, w_half, w_quarter, totals)
        assert global_rule.piece_sums(totals, 8, sums, raw) == (bad is None)
        assert np.isfinite(sums[3, 0])  # (the other channel's magnitude stays finite)


def _rows(G, w, w_half, w_quarter, totals) -> None:
    """totals[i] = row_sums of row i, through tensor_sums on one-row grids (row_sums is inlined in the kernels)."""
    for i in range(G.shape[0]):
        part = rules.tensor_sums(G[None, i:i + 1], w, w_half, w_quarter)[:, 0, :]
        totals[i, 0], totals[i, 1], totals[i, 2], totals[i, 3] = part[0], part[5], part[3], part[4]


def test_borrowed_views_read_their_arrays_values(rng):
    from numba import njit

    from brdfnorm.engine.compiled.slopes import borrowed

    @njit
    def total(U):
        s = 0.0
        for row in range(U.shape[0]):
            view = borrowed(U[row])
            for k in range(view.size):
                s += view[k] * (row + 1)
        return s

    U = rng.uniform(size=(5, 7))
    assert total(U) == sum(float(U[row, k]) * (row + 1) for row in range(5) for k in range(7))
