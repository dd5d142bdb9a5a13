"""The global tensor rule's sums (:func:`brdfnorm.engine.machinery.tensor_rule.sums`) compiled: the rule Q and its
embedded coarser rules (every other and every fourth azimuth; every other and every fourth radial node, Fejér's
nested weights) and the |F| integral, per case and channel. Under the compiled backend these sums took more time
than the compiled integrand on the same grid (numpy's transposed matmuls over strided arrays: 1.4 of 8.3 s of a
16 × 16 DFG table).

Per azimuth first (:func:`row_sums`, the channels side by side), then over the azimuths (:func:`rows_total`): the
fused global rule (:mod:`.global_rule`) sums each row as it fills it and keeps the row sums, so a doubling along the
azimuth sums only its new rows; its sudden-agreement test from them (:func:`sudden`). Every sum is added in
the same order as the numpy driver's loops, bit for bit (docs/performance.md, seventh round, ``nodecost``)."""

from __future__ import annotations

import numpy as np
from numba import njit

from ..machinery.grid_estimate import ACCELERATION, RESOLVED

_EPS = np.finfo(np.float64).eps


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def row_sums(G, i, w, w_half, w_quarter, n_half, n_quarter, out, k):  # pragma: no cover - compiled
    """Row ``i`` of one case's grid G (M azimuths, N1 radial nodes, C channels): out[k, 0, c] = Σ_j G[i, j, c]
    w[j], out[k, 1, c] = Σ_j |G[i, j, c]| w[j], out[k, 2, c] and out[k, 3, c] the coarser radial rules on every
    other and every fourth node, with the first ``n_half`` and ``n_quarter`` weights of theirs (the fused driver's
    weight tables are padded rows). Each sum in index order, the channels side by side: each is a chain of dependent
    additions (no reassociation allowed), one channel at a time waits on the adder's latency, four chains side by
    side keep it busy."""
    for c0 in range(0, G.shape[2], 4):
        _four_sums(G, i, w, w_half, w_quarter, n_half, n_quarter, out, k, c0, min(G.shape[2] - c0, 4))


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def _four_sums(G, i, w, w_half, w_quarter, n_half, n_quarter, out, k, c0, C):  # pragma: no cover - compiled
    """:func:`row_sums` of the channels c0 … c0 + C − 1 (C ≤ 4)."""
    N1 = G.shape[1]
    s0 = s1 = s2 = s3 = a0 = a1 = a2 = a3 = 0.0
    for j in range(N1):
        wj = w[j]
        x = G[i, j, c0 + 0]
        s0 += x * wj
        a0 += abs(x) * wj
        if C > 1:
            x = G[i, j, c0 + 1]
            s1 += x * wj
            a1 += abs(x) * wj
        if C > 2:
            x = G[i, j, c0 + 2]
            s2 += x * wj
            a2 += abs(x) * wj
        if C > 3:
            x = G[i, j, c0 + 3]
            s3 += x * wj
            a3 += abs(x) * wj
    u0 = u1 = u2 = u3 = 0.0
    for j in range(n_half):
        wj = w_half[j]
        u0 += G[i, 2 * j + 1, c0 + 0] * wj
        if C > 1:
            u1 += G[i, 2 * j + 1, c0 + 1] * wj
        if C > 2:
            u2 += G[i, 2 * j + 1, c0 + 2] * wj
        if C > 3:
            u3 += G[i, 2 * j + 1, c0 + 3] * wj
    v0 = v1 = v2 = v3 = 0.0
    for j in range(n_quarter):
        wj = w_quarter[j]
        v0 += G[i, 4 * j + 3, c0 + 0] * wj
        if C > 1:
            v1 += G[i, 4 * j + 3, c0 + 1] * wj
        if C > 2:
            v2 += G[i, 4 * j + 3, c0 + 2] * wj
        if C > 3:
            v3 += G[i, 4 * j + 3, c0 + 3] * wj
    out[k, 0, c0 + 0], out[k, 1, c0 + 0], out[k, 2, c0 + 0], out[k, 3, c0 + 0] = s0, a0, u0, v0
    if C > 1:
        out[k, 0, c0 + 1], out[k, 1, c0 + 1], out[k, 2, c0 + 1], out[k, 3, c0 + 1] = s1, a1, u1, v1
    if C > 2:
        out[k, 0, c0 + 2], out[k, 1, c0 + 2], out[k, 2, c0 + 2], out[k, 3, c0 + 2] = s2, a2, u2, v2
    if C > 3:
        out[k, 0, c0 + 3], out[k, 1, c0 + 3], out[k, 2, c0 + 3], out[k, 3, c0 + 3] = s3, a3, u3, v3


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def rows_total(rows, M, out, r):  # pragma: no cover - compiled
    """(Q, Q(½ β), Q(¼ β), Q(½ u), Q(¼ u), ∫|F|) per channel into out[:, r, :] from the :func:`row_sums` ``rows``
    (M, 4, C) of a grid, before the azimuth step 2π/M: the rows added in order, every row, every other and every
    fourth for the periodic trapezoid rules on M, M/2 and M/4 azimuths."""
    for c in range(rows.shape[2]):
        q = q_b = q_bb = q_u = q_uu = magnitude = 0.0
        for i in range(M):
            s = rows[i, 0, c]
            q += s
            if i % 2 == 0:
                q_b += s
            if i % 4 == 0:
                q_bb += s
            q_u += rows[i, 2, c]
            q_uu += rows[i, 3, c]
            magnitude += rows[i, 1, c]
        out[0, r, c], out[1, r, c], out[2, r, c], out[3, r, c], out[4, r, c], out[5, r, c] = (
            q, q_b, q_bb, q_u, q_uu, magnitude)


@njit(cache=True, error_model="numpy", nogil=True)
def sudden(totals, c, e_b, magnitude):  # pragma: no cover - compiled
    """The β estimate ``e_b`` of channel ``c`` of a piece's grid at 16 azimuths, raised to d₁ + d₂ where the last
    fall is more than ACCELERATION times steeper than the square of the one before, as
    :func:`brdfnorm.engine.machinery.grid_estimate.sudden` (d_k the differences of the rules on every 1st, 2nd, 4th
    and 8th azimuth; each azimuth's radial sum its row sum, ``totals``, :func:`.global_rule._fill`)."""
    M = totals.shape[0]
    q = np.zeros(4)
    for i in range(M):
        s = totals[i, 0, c]
        for k in range(4):
            if i % (2**k) == 0:
                q[k] += s * (2 * np.pi * 2**k / M)
    d1, d2, d3 = abs(q[0] - q[1]), abs(q[1] - q[2]), abs(q[2] - q[3])
    if d2 * d2 * d2 > ACCELERATION * d1 * d3 * d3 and max(d1, d2) > RESOLVED * _EPS * magnitude:
        return max(e_b, d1 + d2)
    return e_b


@njit(cache=True, error_model="numpy", nogil=True, inline="always")
def canonical(i, M):  # pragma: no cover - compiled
    """The azimuth index whose node a mirrored case evaluates for index ``i`` of ``M`` (t ↔ π − t)."""
    i = i % M
    if i <= M // 4 or i >= 3 * M // 4:
        return i
    return (M // 2 - i) % M


@njit(cache=True, error_model="numpy", nogil=True)
def rows_sums(G, indices, mirrored, w, w_half, w_quarter, n_half, n_quarter, out):  # pragma: no cover - compiled
    """:func:`row_sums` of each row ``indices`` of G into out[index], but those of a grid of ``mirrored`` azimuths
    (0: none) that a mirrored case does not evaluate (:func:`canonical`): the one kernel that inlines the row sums,
    compiled once for the fused global rule (:func:`.global_rule._summed`) and :func:`tensor_sums`."""
    for a in range(indices.size):
        i = indices[a]
        if mirrored == 0 or canonical(i, mirrored) == i:
            row_sums(G, i, w, w_half, w_quarter, n_half, n_quarter, out, i)


@njit(cache=True, error_model="numpy", nogil=True)
def _tensor_sums(F, w, w_half, w_quarter, out):  # pragma: no cover - compiled
    rows = np.empty((F.shape[1], 4, F.shape[3]))
    every = np.arange(F.shape[1])
    for r in range(F.shape[0]):
        rows_sums(F[r], every, np.int64(0), w, w_half, w_quarter, w_half.size, w_quarter.size, rows)
        rows_total(rows, F.shape[1], out, r)


def tensor_sums(F: np.ndarray, w: np.ndarray, w_half: np.ndarray, w_quarter: np.ndarray) -> np.ndarray:
    """(Q, Q(½ β), Q(¼ β), Q(½ u), Q(¼ u), ∫|F|) per case and channel, before the azimuth step 2π/M: (6, n, C)."""
    out = np.empty((6, F.shape[0], F.shape[3]))
    _tensor_sums(np.ascontiguousarray(F, dtype=float), *(_read_only(x) for x in (w, w_half, w_quarter)), out)
    return out


def _read_only(weights: np.ndarray) -> np.ndarray:
    """A read-only contiguous float64 copy: the type of the fused global rule's weights (rows of a module constant,
    which Numba freezes read-only), so that :func:`rows_sums` is compiled once for both."""
    weights = np.array(weights, dtype=float)
    weights.flags.writeable = False
    return weights
