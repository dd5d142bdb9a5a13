"""The global tensor rule's sums (:func:`brdfnorm.engine.machinery.tensor_rule.sums`) as one compiled pass over
the grid: the rule Q and its embedded coarser rules (every other and every fourth azimuth; every other and every
fourth radial node, Fejér's nested weights) and the |F| integral, per case and channel. Under the compiled backend
these sums took more time than the compiled integrand on the same grid (numpy's transposed matmuls over strided
arrays: 1.4 of 8.3 s of a 16 × 16 DFG table)."""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", nogil=True)
def grid_sums(G, c, w, w_half, w_quarter, n_half, n_quarter):  # pragma: no cover - compiled
    """(Q, Q(½ β), Q(¼ β), Q(½ u), Q(¼ u), ∫|F|) of channel ``c`` of one case's grid G (M azimuths, N1 radial
    nodes, C), before the azimuth step 2π/M, with the first ``n_half`` and ``n_quarter`` weights of the coarser radial
    rules (the fused driver's weight tables are padded rows): the one loop of the global rule's sums."""
    M, N1 = G.shape[0], G.shape[1]
    q = q_b = q_bb = q_u = q_uu = magnitude = 0.0
    for i in range(M):
        s = 0.0
        s_abs = 0.0
        for j in range(N1):
            x = G[i, j, c]
            s += x * w[j]
            s_abs += abs(x) * w[j]
        s_u = 0.0
        for j in range(n_half):
            s_u += G[i, 2 * j + 1, c] * w_half[j]
        s_uu = 0.0
        for j in range(n_quarter):
            s_uu += G[i, 4 * j + 3, c] * w_quarter[j]
        q += s
        if i % 2 == 0:
            q_b += s
        if i % 4 == 0:
            q_bb += s
        q_u += s_u
        q_uu += s_uu
        magnitude += s_abs
    return q, q_b, q_bb, q_u, q_uu, magnitude


@njit(cache=True, error_model="numpy", nogil=True)
def grid_sums_all(G, w, w_half, w_quarter, n_half, n_quarter, out):  # pragma: no cover - compiled
    """:func:`grid_sums` of every channel of G at once into ``out`` (6, C), bit for bit: each channel's sums in the
    same order, but up to four channels side by side in one pass over the grid. Why: each sum is a chain of
    dependent additions (no reassociation allowed), so one channel at a time waits on the adder's latency; four
    chains side by side keep it busy (the fused global rule's sums of a three-channel DFG grid, ~2× faster)."""
    M, N1, C = G.shape[0], G.shape[1], G.shape[2]
    if C > 4:
        for c in range(C):
            out[0, c], out[1, c], out[2, c], out[3, c], out[4, c], out[5, c] = grid_sums(
                G, c, w, w_half, w_quarter, n_half, n_quarter)
        return
    for r in range(6):
        for c in range(C):
            out[r, c] = 0.0
    s = np.empty((3, 4))  # per row: the rule, the half and the quarter radial rules, per channel
    for i in range(M):
        s0 = s1 = s2 = s3 = a0 = a1 = a2 = a3 = 0.0
        for j in range(N1):
            wj = w[j]
            x = G[i, j, 0]
            s0 += x * wj
            a0 += abs(x) * wj
            if C > 1:
                x = G[i, j, 1]
                s1 += x * wj
                a1 += abs(x) * wj
            if C > 2:
                x = G[i, j, 2]
                s2 += x * wj
                a2 += abs(x) * wj
            if C > 3:
                x = G[i, j, 3]
                s3 += x * wj
                a3 += abs(x) * wj
        s[0, 0], s[0, 1], s[0, 2], s[0, 3] = s0, s1, s2, s3
        s0 = s1 = s2 = s3 = 0.0
        for j in range(n_half):
            wj = w_half[j]
            s0 += G[i, 2 * j + 1, 0] * wj
            if C > 1:
                s1 += G[i, 2 * j + 1, 1] * wj
            if C > 2:
                s2 += G[i, 2 * j + 1, 2] * wj
            if C > 3:
                s3 += G[i, 2 * j + 1, 3] * wj
        s[1, 0], s[1, 1], s[1, 2], s[1, 3] = s0, s1, s2, s3
        s0 = s1 = s2 = s3 = 0.0
        for j in range(n_quarter):
            wj = w_quarter[j]
            s0 += G[i, 4 * j + 3, 0] * wj
            if C > 1:
                s1 += G[i, 4 * j + 3, 1] * wj
            if C > 2:
                s2 += G[i, 4 * j + 3, 2] * wj
            if C > 3:
                s3 += G[i, 4 * j + 3, 3] * wj
        s[2, 0], s[2, 1], s[2, 2], s[2, 3] = s0, s1, s2, s3
        for c in range(C):
            row = s[0, c]
            out[0, c] += row
            if i % 2 == 0:
                out[1, c] += row
            if i % 4 == 0:
                out[2, c] += row
            out[3, c] += s[1, c]
            out[4, c] += s[2, c]
        out[5, 0] += a0
        if C > 1:
            out[5, 1] += a1
        if C > 2:
            out[5, 2] += a2
        if C > 3:
            out[5, 3] += a3


@njit(cache=True, error_model="numpy", nogil=True)
def _tensor_sums(F, w, w_half, w_quarter, out):  # pragma: no cover - compiled
    for r in range(F.shape[0]):
        for c in range(F.shape[3]):
            out[0, r, c], out[1, r, c], out[2, r, c], out[3, r, c], out[4, r, c], out[5, r, c] = grid_sums(
                F[r], c, w, w_half, w_quarter, w_half.size, w_quarter.size)


def tensor_sums(F: np.ndarray, w: np.ndarray, w_half: np.ndarray, w_quarter: np.ndarray) -> np.ndarray:
    """(Q, Q(½ β), Q(¼ β), Q(½ u), Q(¼ u), ∫|F|) per case and channel, before the azimuth step 2π/M: (6, n, C)."""
    out = np.empty((6, F.shape[0], F.shape[3]))
    _tensor_sums(np.ascontiguousarray(F, dtype=float), np.ascontiguousarray(w), np.ascontiguousarray(w_half),
                 np.ascontiguousarray(w_quarter), out)
    return out
