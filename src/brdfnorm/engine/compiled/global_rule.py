"""The half-vector route's global tensor rule (:func:`brdfnorm.engine.routes.halfvector_global.integrate_global`)
for the built-in microfacet lobes, fused into one compiled kernel that loops over the cases: per case its three
radial pieces (pole, tail, horizon layer) start on 2^3 × (2^4 − 1) nodes and double along the azimuth t and/or the
radial coordinate u, in lockstep, each doubling evaluating only the new nodes and reusing the nested old ones, until
each piece's estimate meets its third of the case's tolerance, or the doubling prediction, the node cap or a
non-finite value sends the case to the panels.

The same rule as the numpy driver, term for term: the periodic trapezoid rule in t on the Möbius map tan φ = λ tan t
or the graded map (:func:`brdfnorm.engine.routes.halfvector_global.azimuth_map`), Fejér's second rule in u, the
mirror nodes t ↔ π − t of a symmetric case evaluated once, the sums and estimates of
:func:`brdfnorm.engine.machinery.tensor_rule.sums` (d₁ + min(d₂, 9 d₁) along each direction plus the rounding floor),
the choice of direction, the doubling prediction (:func:`brdfnorm.engine.machinery.tensor_rule.doublings`) and the
graded map's late prediction. Why: the numpy driver's interleaving of old and new nodes, its merges and filters of
the grids of all cases cost ~30 % of a 32 × 32 DFG table under the compiled backend (docs/performance.md); per case,
the grids stay in cache. The values differ from the numpy driver's by the rounding of the transcendental functions
(libm against numpy's), well within the estimates (tests/engine/test_compiled_global_rule.py).

Compiled in pieces: only the loop over a row's radial nodes, which calls the weight, is inlined into each of the two
cached callers (:func:`fused_global`, :func:`shader_global`); the case state, the doubled grids, the per-azimuth
map, the mirror copies, the sums, estimates and decisions are small cached kernels that both share, compiled once
per machine (:func:`shared_kernels`): inlined whole, the loop cost each caller 7–10 s of CPU to compile, now 2.6–3.1
(docs/performance.md, seventh round); the values are bit-identical.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Iterator
from pathlib import Path

import numba
import numpy as np
from numba import njit
from numba.core.errors import NumbaError

from ..machinery.tensor_rule import FLOOR, MAX_LEVEL_B, SAFETY, START_LEVELS
from .backend import tell_once
from .marks import await_other, cache_mark, compile_marked, first_class_argtypes, holding, in_cache
from .rules import canonical, rows_sums, rows_total, sudden
from .slopes import azimuth_node, microfacet_case, microfacet_node, piece_extent, shader_case, shader_node, slope_node

_OPTIONS = dict(cache=True, error_model="numpy", nogil=True)
#: Radial levels tabulated (a piece's grid of 2^3 azimuths and 2^12 − 1 radial nodes is already 32 760 nodes).
_LEVELS = 14
#: Nodes per piece at most that the tables allow (the route's cap is 32 768).
MAX_NODES = 2 ** START_LEVELS[0] * (2 ** (_LEVELS - 1) - 1)
#: The radial pieces of a case (pole, tail, horizon layer), and the columns of a case's switches (:func:`_begin`).
_PIECES = 3
_ALIVE, _DONE, _FINITE, _MORE_B, _MORE_U = range(5)


def fejer_fft(level: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`brdfnorm.engine.machinery.tensor_rule.fejer` (Fejér's second rule on [0, 1], N = 2^level) with the
    weights as the inverse FFT of their Chebyshev moments (Waldvogel, BIT 46, 2006, section 2): O(N log N) where
    that sum is O(N²) — all the levels took 1.1 s at import, ~1 ms so; the weights agree to ~1e-17."""
    N = 2**level
    k = np.arange(N // 2)
    moments = 2.0 / (1.0 - 4.0 * k * k)
    v = np.concatenate([moments, [(N - 3) / (2 * (N // 2) - 1) - 1], moments[:0:-1]])
    return (1.0 - np.cos(np.arange(1, N) * np.pi / N)) / 2.0, np.fft.ifft(v).real[1:] / 2.0


def _fejer_tables() -> tuple[np.ndarray, np.ndarray]:
    nodes, weights = np.zeros((_LEVELS, 2 ** (_LEVELS - 1))), np.zeros((_LEVELS, 2 ** (_LEVELS - 1)))
    for level in range(1, _LEVELS):
        u, w = fejer_fft(level)
        nodes[level, :u.size], weights[level, :w.size] = u, w
    return nodes, weights


_NODES, _WEIGHTS = _fejer_tables()


@njit(**_OPTIONS, inline="always")
def _azimuth(t, lam, width):  # pragma: no cover - compiled
    """φ(t), dφ/dt of halfvector_global.azimuth_map (the graded map where ``width`` > 0)."""
    if width > 0:
        kappa = math.asinh(1.0 / width)
        turns = math.floor(t / math.pi + 0.5)  # np.round: half to even
        if turns - t / math.pi == 0.5 and turns % 2.0 != 0.0:
            turns -= 1.0
        sin_t, cos_t = math.sin(t - turns * math.pi), math.cos(t - turns * math.pi)
        y = width * math.sinh(kappa * sin_t)
        phi = math.atan2(y, cos_t) + turns * math.pi
        return phi, (cos_t * cos_t * width * kappa * math.cosh(kappa * sin_t) + y * sin_t) / (cos_t * cos_t + y * y)
    y = t - math.pi
    sin_y, cos_y = math.sin(y), math.cos(y)
    return t + (math.atan2(lam * sin_y, cos_y) - math.atan2(sin_y, cos_y)), lam / (cos_y * cos_y
                                                                                    + lam * lam * sin_y * sin_y)


@njit(error_model="numpy", inline="always")
def _fill(grid, totals, rows, M, col_step, radial, q, kind, mirrored, lam, width, scale, linear, log_horizon,
          beckmann, geometry, case, value, extra, largest, flags):  # pragma: no cover - compiled
    """The weighted values at the azimuth indices ``rows`` of ``M`` (t = 2π·index/M) and the radial nodes
    ``radial`` of piece ``kind`` of case ``q``, written to grid[index, col_step·j]; a mirrored case's indices
    outside t ∈ [−π/2, π/2] take their mirror's sums (which ``rows`` holds). The weight at a node is that of
    :func:`.slopes.slope_loop`: ``case(q, extra)`` -> the case's parameters, ``value(...)`` -> (g, a, b, keep,
    flag), g[c]·a·b (0 where not ``keep``), the last channel the largest |·| where ``largest``, ``flag`` marking
    flags[q]; ``geometry``: the slope map's per-case arrays (slopes.SLOPE_MAP). The rows filled have their sums
    written to ``totals`` (:func:`_summed`), so that a round sums the grid's rows that changed only, not the whole
    grid. Returns the nodes evaluated."""
    vz, ax, ay = geometry[0], geometry[4], geometry[5]
    # (the case's slope map as numbers, not arrays: an array passed to _row would be reference-counted per row)
    here = (vz[q], geometry[1][q], geometry[2][q], geometry[3][q], ax[q], ay[q], geometry[6][q], geometry[7][q],
            geometry[8][q], geometry[9][q])
    C = grid.shape[2] - 1 if largest else grid.shape[2]
    parameters = case(q, extra)
    count = 0
    for a in range(rows.size):
        index = rows[a]
        if mirrored and canonical(index, M) != index:
            continue
        # (bool(): shader_global's beckmann is the literal False, which would be another signature of _row)
        factor, dx, dy, d2, p, q_minus_p, s_h, s_split, s_end, azimuth, start, length, log_ratio = _row(
            index, M, kind, lam, width, scale, linear, log_horizon, bool(beckmann), here)
        for j in range(radial.size):
            s, weight_t, one_sp, n2, Lz = slope_node(kind, (kind + radial[j]) - kind, start, length, log_ratio, s_h,
                                                     s_split, s_end, log_horizon, beckmann, d2, p, q_minus_p, vz[q])
            g, w_a, w_b, keep, flag = value(s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, vz[q], ax[q], ay[q],
                                            parameters)
            if flag:
                flags[q] = True
            most = 0.0
            for c in range(C):
                x = g[c] * w_a * w_b if keep else 0.0
                most = max(most, abs(x))
                grid[index, col_step * j, c] = x * factor
            if largest:
                grid[index, col_step * j, C] = most * factor
        count += radial.size
    _summed(grid, totals, rows, M, mirrored)
    return count


@njit(**_OPTIONS)
def _row(index, M, kind, lam, width, scale, linear, log_horizon, beckmann, here):  # pragma: no cover - compiled
    """What :func:`_fill` needs of azimuth ``index`` of ``M`` for radial piece ``kind`` of a case whose slope map
    (:data:`.slopes.SLOPE_MAP`) is ``here``: the azimuth map's Jacobian times ``scale``, :func:`.slopes.azimuth_node`'s
    values but s_middle, and :func:`.slopes.piece_extent`'s. A kernel of its own, called once per azimuth (not per
    node): compiled once and shared by :func:`fused_global` and :func:`shader_global`, not inlined into each; its
    arguments are numbers (arrays would be reference-counted at every call)."""
    vz, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity = here
    phi, dphi = _azimuth(index * (2 * np.pi / M), lam, width)
    dx, dy, d2, p, q_minus_p, s_h, s_split, s_middle, s_end, azimuth = azimuth_node(
        phi, linear, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity, vz, beckmann)
    start, length, log_ratio = piece_extent(kind, s_middle, s_split, s_end, log_horizon, beckmann)
    return dphi * scale, dx, dy, d2, p, q_minus_p, s_h, s_split, s_end, azimuth, start, length, log_ratio


@njit(**_OPTIONS)
def _summed(grid, totals, rows, M, mirrored):  # pragma: no cover - compiled
    """The sums (:func:`.rules.row_sums`) of the rows ``rows`` of ``M`` just filled by :func:`_fill` into
    totals[index]; a mirrored case's indices outside t ∈ [−π/2, π/2] their mirror's. Not their values: nothing reads
    a mirrored row's values after its sums (:func:`_grown` and :func:`_settle` skip them). One call per fill, a
    kernel compiled once and shared by both callers (inlined into each, the sums cost ~2 s of CPU to compile)."""
    level_u = 1
    while 2 ** level_u - 1 < grid.shape[1]:
        level_u += 1
    w, w_half, w_quarter = _WEIGHTS[level_u], _WEIGHTS[level_u - 1], _WEIGHTS[level_u - 2]
    rows_sums(grid, rows, M if mirrored else np.int64(0), w, w_half, w_quarter, 2 ** (level_u - 1) - 1,
              2 ** (level_u - 2) - 1, totals)
    if mirrored:
        for a in range(rows.size):
            index = rows[a]
            source = canonical(index, M)
            if source != index:
                for r in range(4):
                    for c in range(grid.shape[2]):
                        totals[index, r, c] = totals[source, r, c]


@njit(**_OPTIONS, inline="always")
def _margin(deviation, coarser):  # pragma: no cover - compiled
    return deviation + min(coarser, SAFETY * deviation)


@njit(**_OPTIONS)
def piece_sums(totals, M, sums, raw):  # pragma: no cover - compiled
    """The fused global rule's q, e_b, e_u, magnitude per channel (rows of ``sums``) of a piece's grid of M
    azimuths from its row sums ``totals`` (:func:`_fill`), as :func:`.rules.rows_total` (``raw`` (6, 1, C):
    its sums before the azimuth step). Returns whether every magnitude is finite (then so is every value of the grid:
    the magnitude sums their |·| with positive weights)."""
    C = totals.shape[2]
    step = 2 * np.pi / M
    rows_total(totals, M, raw, 0)
    finite = True
    for c in range(C):
        q, q_b, q_bb, q_u, q_uu, magnitude = (raw[0, 0, c], raw[1, 0, c], raw[2, 0, c], raw[3, 0, c], raw[4, 0, c],
                                              raw[5, 0, c])
        finite &= math.isfinite(magnitude)
        q, q_u, q_uu, magnitude = q * step, q_u * step, q_uu * step, magnitude * step
        q_b, q_bb = q_b * (2 * step), q_bb * (4 * step)
        sums[0, c] = q
        sums[1, c] = _margin(abs(q - q_b), abs(q_b - q_bb))
        sums[2, c] = _margin(abs(q - q_u), abs(q_u - q_uu))
        sums[3, c] = magnitude
    return finite


@njit(**_OPTIONS, inline="always")
def _normalized(error, share):  # pragma: no cover - compiled
    if share > 0:
        return error / share
    return math.inf if error > 0 else 0.0


@njit(**_OPTIONS, inline="always")
def _doublings(ratio, last):  # pragma: no cover - compiled
    """tensor_rule.doublings for one direction."""
    if not ratio > 1.0:
        return 0
    reduction = ratio / last if (math.isfinite(last) and last > 0) else 0.0
    if reduction != reduction:
        reduction = 0.0
    if reduction >= 1.0:
        return 99
    exponent = math.log(max(ratio, 1.0)) / -math.log(min(max(reduction, 1e-300), 1.0))
    needed = math.ceil(math.log2(exponent + 2.0)) - 1.0
    if needed != needed:
        return 0
    return int(min(max(needed, 0.0), 99.0))


@njit(**_OPTIONS)
def _begin(C):  # pragma: no cover - compiled
    """A case's state at its start: levels (pieces, 2: β, u), the ratios last extrapolated from (pieces, 2),
    switches (pieces, 5: alive, done, finite, more along β, more along u), numbers (pieces, 7, C: the latest value,
    the value and error of a done piece, then the sums q, e_b, e_u, magnitude), and each piece's first grid and
    its row sums (M, 4, C: :func:`.rules.row_sums`)."""
    levels = np.empty((_PIECES, 2), dtype=np.int64)
    lasts = np.empty((_PIECES, 2))
    switches = np.zeros((_PIECES, 5), dtype=np.bool_)
    for kind in range(_PIECES):
        levels[kind, 0], levels[kind, 1] = START_LEVELS[0], START_LEVELS[1]
        lasts[kind, 0] = lasts[kind, 1] = np.inf
        switches[kind, _ALIVE] = switches[kind, _FINITE] = True
    M0, N0 = 2 ** START_LEVELS[0], 2 ** START_LEVELS[1] - 1
    return (levels, lasts, switches, np.zeros((_PIECES, 7, C)), np.empty((M0, N0, C)), np.empty((M0, N0, C)),
            np.empty((M0, N0, C)), np.empty((M0, 4, C)), np.empty((M0, 4, C)), np.empty((M0, 4, C)))


@njit(**_OPTIONS)
def _grown(grid, totals, step, kind, levels, mirrored):  # pragma: no cover - compiled
    """What :func:`_fill` fills at ``step`` of piece ``kind``: (grid, row sums, rows, M, col_step, radial) — the
    first grid (step 0), or a new grid doubled along t (1) or u (2) with the old nodes copied in place (and along t
    the old rows' sums, which the new rows leave as they were), whose level it raises; a ``mirrored`` case's rows
    outside t ∈ [−π/2, π/2] only their sums (:func:`_summed`)."""
    C = grid.shape[2]
    M, N1 = 2 ** levels[kind, 0], 2 ** levels[kind, 1] - 1
    if step == 0:
        return grid, totals, np.arange(M), M, 1, _NODES[levels[kind, 1]][:N1]
    if step == 1:
        target = np.empty((2 * M, N1, C))
        rows = np.empty((2 * M, 4, C))
        for i in range(M):
            if not mirrored or canonical(i, M) == i:
                for j in range(N1):
                    for c in range(C):
                        target[2 * i, j, c] = grid[i, j, c]
            for r in range(4):
                for c in range(C):
                    rows[2 * i, r, c] = totals[i, r, c]
        levels[kind, 0] += 1
        return target, rows, 2 * np.arange(M) + 1, 2 * M, 1, _NODES[levels[kind, 1]][:N1]
    target = np.empty((M, 2 * N1 + 1, C))
    for i in range(M):
        if not mirrored or canonical(i, M) == i:
            for j in range(N1):
                for c in range(C):
                    target[i, 2 * j + 1, c] = grid[i, j, c]
    lu = levels[kind, 1] + 1
    levels[kind, 1] = lu
    return target, np.empty((M, 4, C)), np.arange(M), M, 2, _NODES[lu][0:2 ** lu - 1:2]


@njit(**_OPTIONS)
def _settle(grid0, grid1, grid2, totals0, totals1, totals2, mirrored, k, levels, lasts, switches, numbers, rtol,
            atol, width, max_nodes, graded_predicts, out_value, out_error, settled):  # pragma: no cover - compiled
    """After a round of grids: each live piece's sums and estimates, the tolerance, and per piece whether it is
    done, goes on (along which directions) or sends the case to the panels. Returns whether case ``k`` is over, its
    outputs then written."""
    C = numbers.shape[2]
    sums, raw = np.empty((4, C)), np.empty((6, 1, C))
    failed = False
    for kind in range(_PIECES):
        if not switches[kind, _ALIVE]:
            continue
        grid = grid0 if kind == 0 else (grid1 if kind == 1 else grid2)
        totals = totals0 if kind == 0 else (totals1 if kind == 1 else totals2)
        # (a finite magnitude: every value finite, no pass of its own over the grid; else the values looked at)
        finite = piece_sums(totals, 2 ** levels[kind, 0], sums, raw)
        if not finite:
            finite = True
            M = grid.shape[0]
            for i in range(M):
                if mirrored and canonical(i, M) != i:
                    continue
                for x in grid[i].flat:
                    finite &= math.isfinite(x)
        switches[kind, _FINITE] = finite
        if not finite:
            grid.fill(0.0)
            totals.fill(0.0)  # (the row sums of zeros)
            failed = True
            piece_sums(totals, 2 ** levels[kind, 0], sums, raw)
        for c in range(C):
            for row in range(4):
                numbers[kind, 3 + row, c] = sums[row, c]
            numbers[kind, 0, c] = sums[0, c]
            if levels[kind, 0] == START_LEVELS[0] + 1:  # a sudden agreement at 16 azimuths (grid_estimate)
                numbers[kind, 4, c] = sudden(totals, c, sums[1, c], sums[3, c])
    tolerance = np.empty(C)
    for c in range(C):
        total = 0.0
        for kind in range(_PIECES):
            total += numbers[kind, 1, c] if switches[kind, _DONE] else numbers[kind, 0, c]
        tolerance[c] = max(atol[k], rtol[k] * abs(total)) / _PIECES
    for kind in range(_PIECES):
        if not switches[kind, _ALIVE]:
            continue
        within, more_b, more_u, larger_b = True, False, False, False
        ratio_b = ratio_u = 0.0
        for c in range(C):
            e_b, e_u, magnitude = numbers[kind, 4, c], numbers[kind, 5, c], numbers[kind, 6, c]
            floor = FLOOR * magnitude
            if not e_b + e_u + floor <= tolerance[c]:
                within = False
            share = max(tolerance[c] - floor, 0.0) / 2
            more_b |= e_b > share
            more_u |= e_u > share
            larger_b |= e_b >= e_u
            ratio_b = max(ratio_b, _normalized(e_b, share))
            ratio_u = max(ratio_u, _normalized(e_u, share))
        finite = switches[kind, _FINITE]
        lb, lu = levels[kind, 0], levels[kind, 1]
        # never on the start azimuths (global_driver: their embedded rules are blind to what the 8 alias)
        done = within and finite and lb > START_LEVELS[0]
        if done:
            for c in range(C):
                numbers[kind, 1, c] = numbers[kind, 3, c]
                numbers[kind, 2, c] = numbers[kind, 4, c] + numbers[kind, 5, c] + FLOOR * numbers[kind, 6, c]
            switches[kind, _DONE] = True
        if lb == START_LEVELS[0]:  # (confirmed along β there, as the numpy driver does)
            larger_b = True
        if not (more_b or more_u):
            more_b, more_u = larger_b, not larger_b
        size = 2 ** (lb + more_b) * (2 ** (lu + more_u) - 1)
        need_b, need_u = _doublings(ratio_b, lasts[kind, 0]), _doublings(ratio_u, lasts[kind, 1])
        # (int64 powers, as the numpy driver's)
        hopeless = (need_b + lb > MAX_LEVEL_B) or (np.int64(2) ** (lb + need_b)
                                                   * (np.int64(2) ** (lu + need_u) - 1) > max_nodes)
        hopeless = hopeless and (lb >= graded_predicts or width[k] == 0)
        go_on = finite and not done and size <= max_nodes and not hopeless and not failed
        if finite and not done and not go_on:
            failed = True
        switches[kind, _ALIVE] = go_on
        switches[kind, _MORE_B], switches[kind, _MORE_U] = more_b, more_u
        if go_on:  # the ratios this doubling extrapolates from (the first from the start is skipped)
            if more_b and lb > START_LEVELS[0]:
                lasts[kind, 0] = ratio_b
            if more_u and lu > START_LEVELS[1]:
                lasts[kind, 1] = ratio_u
    alive = False
    for kind in range(_PIECES):
        alive |= switches[kind, _ALIVE]
    if alive and not failed:
        return False
    ok = not failed
    for kind in range(_PIECES):
        ok &= switches[kind, _DONE]
    for c in range(C):
        total_value = total_error = 0.0
        for kind in range(_PIECES):
            total_value += numbers[kind, 1, c]
            total_error += numbers[kind, 2, c]
        out_value[k, c], out_error[k, c] = total_value, total_error
        if not total_error <= max(atol[k], rtol[k] * abs(total_value)):
            ok = False
    settled[k] = ok
    return True


@njit(error_model="numpy", inline="always")
def fused_loop(cases, lam, width, symmetric, scale, rtol, atol, max_nodes, graded_predicts, linear, log_horizon,
               beckmann, geometry, case, value, extra, largest, flags, outputs):  # pragma: no cover - compiled
    """The global rule of every case of ``cases``: fills ``outputs`` = (value, error (K, C), evaluations,
    settled (K,)); the weight at a node is ``case``/``value``'s (:func:`_fill`). (Arguments packed in tuples: a
    call of more than 30 arguments is compiled by Python as a call with ``*args``, which Numba does not inline.)

    Not cached and always inlined, like :func:`.slopes.slope_loop`: ``case`` and ``value`` are first-class function
    arguments; each cached caller (:func:`fused_global` for the microfacet lobes,
    :func:`shader_global` for the shaders, which calls the shader through a first-class function) compiles the
    loop with its weight. Only the node filling depends on the weight: the state, the doubled grids, the sums,
    estimates and decisions are the cached kernels :func:`_begin`, :func:`_grown` and :func:`_settle`, compiled
    once and shared by both callers (inlined, the loop cost each caller ~5 s of CPU more to compile). One call site
    of :func:`_fill` (which inlines the weight): the first grids and both doublings; no array assigned to a slice
    (Numba compiles the shape-mismatch error's message for each)."""
    out_value, out_error, evaluations, settled = outputs
    C = out_value.shape[1]
    for n in range(cases.size):
        k = cases[n]
        levels, lasts, switches, numbers, grid0, grid1, grid2, totals0, totals1, totals2 = _begin(C)
        first = True
        while True:
            # the grids: the first ones, then each piece's doublings along t (1) and u (2), one _fill call site
            for kind in range(_PIECES):
                if not switches[kind, _ALIVE]:
                    continue
                grid = grid0 if kind == 0 else (grid1 if kind == 1 else grid2)
                totals = totals0 if kind == 0 else (totals1 if kind == 1 else totals2)
                for step in range(3):
                    if (step == 0) != first or (step > 0 and not switches[kind, _MORE_B + step - 1]):
                        continue
                    target, target_totals, rows, M, col_step, radial = _grown(grid, totals, step, kind, levels,
                                                                              symmetric[k])
                    evaluations[k] += _fill(target, target_totals, rows, M, col_step, radial, k, kind, symmetric[k],
                                            lam[k], width[k], scale[k], linear, log_horizon, beckmann, geometry,
                                            case, value, extra, largest, flags)
                    grid, totals = target, target_totals
                if kind == 0:
                    grid0, totals0 = grid, totals
                elif kind == 1:
                    grid1, totals1 = grid, totals
                else:
                    grid2, totals2 = grid, totals
            first = False
            if _settle(grid0, grid1, grid2, totals0, totals1, totals2, symmetric[k], k, levels, lasts, switches,
                       numbers, rtol, atol, width, max_nodes, graded_predicts, out_value, out_error, settled):
                break


@njit(**_OPTIONS)
def fused_global(cases, lam, width, symmetric, scale, rtol, atol, max_nodes, graded_predicts, linear, log_horizon,
                 beckmann, separable, vz, vx, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa,
                 multiplicity, lambda_v, fresnel_kind, fresnel, value, error, evaluations,
                 settled):  # pragma: no cover - compiled
    """The global rule of the microfacet lobes (the weight of :func:`.slopes.microfacet_grid`): :func:`fused_loop`."""
    fused_loop(cases, lam, width, symmetric, scale, rtol, atol, max_nodes, graded_predicts, linear, log_horizon,
               beckmann, (vz, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity),
               microfacet_case, microfacet_node, (beckmann, vx, lambda_v, separable, fresnel_kind, fresnel), False,
               np.zeros(0, dtype=np.bool_), (value, error, evaluations, settled))


@njit(**_OPTIONS)
def shader_global(cases, lam, width, symmetric, scale, rtol, atol, max_nodes, graded_predicts, linear, log_horizon,
                  vz, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity, F, rows, fixed, U,
                  over_light, shader, failed, value, error, evaluations, settled):  # pragma: no cover - compiled
    """The global rule of a ``.brdf`` shader (the generic weight of :func:`.slopes.reflected_value`, the largest
    |value| as a last channel, ``failed[k]`` where a value above the horizon is not finite): :func:`fused_loop`.
    ``shader`` is a first-class function (:func:`shader_kernel`): this kernel is compiled once and cached with the
    package, not once per shader (~9 s of CPU each); the shader returns at least :data:`PADDED` outputs (a shader of
    fewer comes padded with zeros), of which the channels of ``value`` are used: one compile serves shaders of one,
    two and three channels (a fresh machine's report needs one and three)."""
    fused_loop(cases, lam, width, symmetric, scale, rtol, atol, max_nodes, graded_predicts, linear, log_horizon,
               False, (vz, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity),
               shader_case, shader_node, (F, rows, fixed, U, over_light, shader), True, failed,
               (value, error, evaluations, settled))


#: The outputs of the shader :func:`shader_global` calls, at least: a shader of fewer channels is called through its
#: kernels' copy's ``padded_shader`` (its outputs, then zeros), so that its first-class function type, and with it
#: the kernel's signature, is the same for one, two and three channels.
PADDED = 3


def shader_kernel(arguments: list, shader: int, outputs: int):
    """:func:`shader_global` compiled (or loaded from the cache) for ``arguments``, the one at index ``shader`` (a
    jitted shader of ``outputs`` outputs) typed as a first-class function f(6 × float64, u (P,)) -> ``outputs``
    float64s: called with the jitted function itself, Numba would type the kernel by that function object and
    compile it anew in every process. Returns the compiled entry point, which takes the shader's dispatcher.

    The compile (~9 s of CPU) under a mark (:mod:`.marks`): where another process is compiling the same signature
    (:mod:`brdfnorm.parallel.warm`'s child, or the command while its child reaches a lobe), this one waits for it
    and loads its result from Numba's cache instead of compiling it beside it."""
    argtypes = first_class_argtypes(arguments, shader, outputs)
    if argtypes not in shader_global.overloads:
        if _LEFT["to_others"] and shader_global._cache.load_overload(argtypes, shader_global.targetctx) is None:
            raise NumbaError("the shaders' global rule is left to the command to compile")
        if not in_cache(shader_global, argtypes):
            shared_kernels()
        compile_marked(shader_global, "shader_global", argtypes)
    return shader_global.overloads[argtypes].entry_point


def shared_kernels() -> None:
    """Compile (or load) :func:`_begin`, :func:`_grown`, :func:`_row`, :func:`_summed` and :func:`_settle`, which
    :func:`fused_global` and :func:`shader_global` both call, for the types those callers give them (~3.5 s of CPU,
    once per machine), under
    one mark beside Numba's cache: on a fresh machine :mod:`brdfnorm.parallel.warm`'s child (compiling
    :func:`fused_global`) and the command (:func:`shader_global`) reach them a few seconds apart, and the second
    loads the first's instead of compiling them beside it."""
    if _settle.overloads:
        return
    from numba import types

    real, whole, truth = types.float64, types.int64, types.boolean
    grid, vector, indices = types.Array(real, 3, "C"), types.Array(real, 1, "C"), types.Array(whole, 1, "C")
    matrix = types.Array(real, 2, "C")
    plan = ((_begin, (whole,)), (_grown, (grid, grid, whole, whole, types.Array(whole, 2, "C"), truth)),
            (_row, (whole, whole, whole, real, real, real, truth, truth, truth, types.UniTuple(real, 10))),
            (_summed, (grid, grid, indices, whole, truth)),
            (_settle, (grid, grid, grid, grid, grid, grid, truth, whole, types.Array(whole, 2, "C"), matrix,
                       types.Array(truth, 2, "C"), grid, vector, vector, vector, whole, whole, matrix, matrix,
                       types.Array(truth, 1, "C"))))
    mark = cache_mark(_settle, "global_rule_shared", plan[-1][1])
    if mark is not None:
        await_other(mark)
    with holding(mark) if mark is not None else contextlib.nullcontext():
        for kernel, argtypes in plan:
            kernel.compile(argtypes)


_LEFT = {"to_others": False}


@contextlib.contextmanager
def shader_rule_left_to_others() -> Iterator[None]:
    """Within the block, :func:`shader_kernel` loads :func:`shader_global` where Numba's cache has it, and does not
    compile it where not (a NumbaError: the route's panels compute instead). For :mod:`brdfnorm.parallel.warm`'s
    child: it and the command reach this kernel at their first lobe, a few seconds in, and whichever is second
    waits for the other's compile; the command, which cannot go on without it, compiles it while the child compiles
    the lobes the command needs next."""
    _LEFT["to_others"] = True
    try:
        yield
    finally:
        _LEFT["to_others"] = False


def compile_mark(argtypes: tuple) -> Path | None:
    """The mark a process holds while it compiles :func:`shader_global` for ``argtypes``, beside Numba's cache of it
    (None where Numba caches nothing)."""
    return cache_mark(shader_global, "shader_global", argtypes)


def route_mark() -> Path | None:
    """The mark held while the microfacet route's kernels compile (:func:`fused_global` here, by the command or
    :mod:`brdfnorm.parallel.warm`'s child, which compiles :func:`.slopes.microfacet_grid` with it), beside Numba's
    cache of :func:`fused_global` (None where Numba caches nothing): the second process to need them waits for the
    first's, ~14 s of CPU, rather than compiling them beside it."""
    directory = getattr(fused_global._cache, "_cache_path", None)
    return None if directory is None else Path(directory) / "microfacet-route.compiling"


def integrate(cases: np.ndarray, lam: np.ndarray, width: np.ndarray, symmetric: np.ndarray, scale: np.ndarray,
              rtol: np.ndarray, atol: np.ndarray, max_nodes: int, graded_predicts: int,
              lobe: tuple) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(value (K, C), error (K, C), evaluations (K,), settled (K,)) of the global rule for ``cases`` (the others
    zero and unsettled); ``lobe``: a compiled rectangle integrand's ``fused`` attribute, (kind, channels C, the
    kernel's arguments of the lobe): kind "microfacet" for :func:`fused_global`
    (:func:`brdfnorm.engine.compiled.slopes.microfacet_rectangle`), "shader" for :func:`shader_global`
    (:func:`brdfnorm.engine.compiled.drivers.slope_rectangle`: the shader second to last, returning
    max(C − 1, :data:`PADDED`) outputs, of which the first C − 1 are the channels)."""
    if max_nodes > MAX_NODES:
        raise ValueError(f"max_nodes: at most {MAX_NODES} per piece in the fused global rule, got {max_nodes}")
    kind, channels, arguments = lobe
    K = lam.size
    value, error = np.zeros((K, channels)), np.zeros((K, channels))
    evaluations, settled = np.zeros(K, dtype=np.int64), np.zeros(K, dtype=bool)
    # (writeable contiguous copies: the kernel's argument types do not change with how the caller's arrays came)
    every = [np.array(cases, dtype=np.int64), *(np.array(x, dtype=float) for x in (lam, width)),
             np.array(symmetric, dtype=bool), *(np.array(x, dtype=float) for x in (scale, rtol, atol)), max_nodes,
             graded_predicts, *arguments, value, error, evaluations, settled]
    if kind == "microfacet":
        if not fused_global.overloads:  # the first call here: compiled (or loaded), under the route's mark
            mark = route_mark()
            if mark is not None:
                await_other(mark)
                with holding(mark):
                    if not in_cache(fused_global, tuple(numba.typeof(x) for x in every)):
                        shared_kernels()
                    fused_global(*every)
                return value, error, evaluations, settled
        kernel = fused_global
    else:
        try:
            kernel = shader_kernel(every, 9 + len(arguments) - 2, max(channels - 1, PADDED))
        except NumbaError as failure:  # (settling no case here, the route's panels compute them all)
            tell_once(f"brdfnorm: the fused global rule does not compile for this shader ({type(failure).__name__})"
                       "; its panels compute")
            return value, error, evaluations, settled
    kernel(*every)
    return value, error, evaluations, settled

