"""Exact reference values on every cell of a large table at a bounded cost: computed on a coarse subgrid, read
between its nodes by a tensor-product cubic spline, with a per-cell interpolation error estimate, and computed
exactly wherever a verdict depends on the difference (:func:`brdfnorm.audit.infer.full_hypothesis`).

The nodes along each array axis are the first and last three indices and evenly spaced ones between them, as many
as a budget of reference cells allows (:func:`coarse_index`): the endpoint clamps of a convention (μ = 0 or α = 0
raised to a floor) change only the first or last index, so no spline interval spans a kink. The reference
quantities are smooth in the table's index elsewhere (its axis values are smooth functions of the index: texel
centres, nodes, r² or θ), so the spline is fourth-order accurate. The error estimate of a cell is the difference
between that spline and the spline through every other node (the error of the coarser spline, about 16 times the
finer one's: a safety factor of ~16), widened to its largest value within two coarse intervals (the difference
crosses 0 where the two splines' errors cross). It is then checked against exact values at CHECK_CELLS cells off
the nodes (seeded, so that an audit is repeatable), and scaled up if any of them is wrong by more than its
estimate.

A cell whose verdict the estimate leaves open (its residual within the estimate of the tolerance) is computed
exactly, as is every cell a fix would rewrite (:func:`measured`, up to a budget): an interpolated value never
makes a cell fit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy import ndimage
from scipy.interpolate import CubicSpline

from .fits import MAJORITY, ChannelFit

#: Exact cells off the nodes that check the interpolation error estimate.
CHECK_CELLS = 64
#: The estimate is scaled up to this multiple of the worst ratio of a checked cell's true error to its estimate.
CHECK_SAFETY = 2.0
#: The smallest interpolation error estimate, relative to the value: a spline's rounding.
ROUNDING = 16 * np.finfo(float).eps

#: Rounds of computing the open cells (computed values move the noise estimate, and so the tolerance).
RESOLVE_ROUNDS = 4

Evaluate = Callable[[list[np.ndarray]], tuple[np.ndarray, np.ndarray]]


@dataclass
class GridReference:
    """Reference values of one meaning over every cell of a table."""

    value: np.ndarray
    error: np.ndarray  # the engine's error estimate (of the nodes around a cell, for an interpolated cell)
    spread: np.ndarray  # interpolation error estimate (0 where computed exactly)
    computed: np.ndarray  # cells computed exactly
    nodes: int = 0  # cells computed on the coarse subgrid
    checked: int = 0  # cells computed to check the estimate
    resolved: int = 0  # cells computed because a verdict or a fix needed them

    def resolve(self, evaluate: Evaluate, cells: np.ndarray) -> None:
        """Compute exactly the cells at flat indices ``cells``."""
        cells = cells[~self.computed.ravel()[cells]]
        if not cells.size:
            return
        index = list(np.unravel_index(cells, self.value.shape))
        value, error = evaluate(index)
        flat = [a.reshape(-1) for a in (self.value, self.error, self.spread, self.computed)]
        flat[0][cells], flat[1][cells], flat[2][cells], flat[3][cells] = value, error, 0.0, True
        self.resolved += int(cells.size)


def coarse_index(n: int, count: int) -> np.ndarray:
    """At most max(``count``, 6) node indices of an axis of ``n`` samples (every index if ``count`` ≥ n): the first
    and last three, and evenly spaced ones between."""
    if count >= n:
        return np.arange(n)
    inner = np.rint(np.linspace(2, n - 3, max(2, count - 4))).astype(int)
    return np.unique(np.concatenate([[0, 1, 2, n - 3, n - 2, n - 1], inner]))


def per_axis(shape: tuple[int, ...], budget: int) -> list[int]:
    """Nodes per axis (at least 6 or every index) so that their product stays within ``budget`` (≥ 6 per axis):
    small axes keep every index, the budget left is shared evenly by the others."""
    order = sorted(range(len(shape)), key=lambda a: shape[a])
    counts = [0] * len(shape)
    left = float(budget)
    for position, axis in enumerate(order):
        share = max(6, int(math.floor(left ** (1.0 / (len(shape) - position)) + 1e-9)))
        counts[axis] = min(shape[axis], share)
        left = max(1.0, left / counts[axis])
    return counts


def _spline(nodes: list[np.ndarray], values: np.ndarray, shape: tuple[int, ...]) -> np.ndarray:
    """The tensor-product cubic spline through ``values`` at the node mesh, at every cell (axis by axis)."""
    out = values
    for axis, (index, n) in enumerate(zip(nodes, shape, strict=True)):
        if index.size == n:
            continue
        if index.size < 2:
            out = np.repeat(out, n, axis=axis)
            continue
        out = CubicSpline(index, out, axis=axis, bc_type="not-a-knot" if index.size >= 4 else "natural")(
            np.arange(n))
    return out


def on_grid(evaluate: Evaluate, shape: tuple[int, ...], budget: int, seed: int = 11) -> GridReference:
    """Reference values over ``shape`` from about ``budget`` exact cells, with their error estimates."""
    nodes = [coarse_index(n, k) for n, k in zip(shape, per_axis(shape, budget), strict=True)]
    mesh = np.meshgrid(*nodes, indexing="ij")
    node_value, node_error = evaluate([m.ravel() for m in mesh])
    node_value = node_value.reshape(mesh[0].shape)
    node_error = node_error.reshape(mesh[0].shape)
    value = np.ascontiguousarray(_spline(nodes, node_value, shape))
    halves = [index if index.size == n else np.unique(np.append(index[::2], index[-1]))
              for index, n in zip(nodes, shape, strict=True)]
    pick = np.ix_(*[np.searchsorted(index, half) for index, half in zip(nodes, halves, strict=True)])
    spread = np.abs(value - _spline(halves, node_value[pick], shape))
    # the difference of two splines passes through 0 where their errors cross: each cell takes the largest
    # difference within two coarse intervals along every axis; and at least the spline's rounding
    for axis, half in enumerate(halves):
        if half.size < shape[axis]:
            spread = ndimage.maximum_filter1d(spread, 2 * int(np.max(np.diff(half))) + 1, axis=axis, mode="nearest")
    spread = np.maximum(spread, ROUNDING * np.abs(value))
    error = np.full(shape, float(np.max(node_error)))
    computed = np.zeros(shape, dtype=bool)
    computed[np.ix_(*nodes)] = True
    spread[computed] = 0.0
    error[np.ix_(*nodes)] = node_error
    g = GridReference(value, error, spread, computed, nodes=int(node_value.size))
    off = np.flatnonzero(~computed.ravel())
    if off.size:
        cells = np.random.default_rng(seed).choice(off, size=min(CHECK_CELLS, off.size), replace=False)
        guess, estimate = value.ravel()[cells].copy(), spread.ravel()[cells].copy()
        g.resolve(evaluate, cells)
        g.checked, g.resolved = int(cells.size), 0
        # the part of the miss beyond the engine's own error estimates (of the cell and of the nodes), which the
        # tolerance carries separately
        wrong = np.maximum(np.abs(value.ravel()[cells] - guess) - g.error.ravel()[cells] - float(np.max(node_error)),
                           0.0)
        ratio = float(np.max(wrong / np.maximum(estimate, np.finfo(float).tiny)))
        if ratio > 1.0:  # the estimate missed a checked cell: every estimate is scaled up
            g.spread *= CHECK_SAFETY * ratio
    return g


def measured(data: np.ndarray, evaluate: Evaluate, judge: Callable[[np.ndarray, np.ndarray], ChannelFit],
             probe: int, nodes: int, resolve: int) -> ChannelFit:
    """One channel ``data`` judged (``judge(exact, error)``: :func:`brdfnorm.audit.infer._fit`) against reference
    values interpolated from a coarse subgrid. A probe on ``probe`` nodes first: a channel it shows cannot be named
    however its open verdicts fall (a table no convention fits) is left there. Otherwise, on ``nodes`` nodes, the
    cells whose verdict the estimate leaves open, and for a named channel the cells outside the tolerance (listed,
    and rewritten by a fix), are computed exactly, nearest the tolerance first, up to ``resolve`` cells; a cell
    still open after that is outside the tolerance (an interpolated value never makes a cell fit), and a bad cell
    whose exact value was not computed is marked ``estimated``."""
    g = on_grid(evaluate, data.shape, probe)
    fit = judge(g.value, g.error)
    if fit.fits or _could_be_named(fit, g):
        g = on_grid(evaluate, data.shape, nodes)
        fit = judge(g.value, g.error)
    for _ in range(RESOLVE_ROUNDS):
        magnitude = np.where(np.isfinite(data), np.abs(data - g.value), np.inf)
        wanted = ~g.computed & (np.abs(magnitude - fit.tolerance) <= g.spread)
        if fit.fits:
            wanted |= ~g.computed & (magnitude > fit.tolerance)
        elif not _could_be_named(fit, g):
            break
        cells = np.flatnonzero(wanted)
        budget = resolve - g.resolved
        if not cells.size or budget <= 0:
            break
        margin = np.abs(magnitude - fit.tolerance).ravel()[cells] - g.spread.ravel()[cells]
        g.resolve(evaluate, cells[np.argsort(margin, kind="stable")[:budget]])
        fit = judge(g.value, g.error)
    magnitude = np.where(np.isfinite(data), np.abs(data - g.value), np.inf)
    unsure = ~g.computed & (np.abs(magnitude - fit.tolerance) <= g.spread)
    if unsure.any():
        fit.bad = fit.bad | unsure
        fit.within = int(np.sum(~fit.bad))
    fit.estimated = ~g.computed & fit.bad
    fit.interpolation = {"nodes": g.nodes, "checked": g.checked, "resolved": g.resolved,
                         "max_estimate": float(np.max(g.spread))}
    return fit


def _could_be_named(fit: ChannelFit, g: GridReference) -> bool:
    """Whether the channel would be named if every cell whose verdict ``g`` leaves open were within the tolerance."""
    magnitude = np.abs(fit.residual)
    open_ = ~g.computed & (np.abs(magnitude - fit.tolerance) <= g.spread)
    return not fit.too_noisy and int(np.sum(~fit.bad | open_)) > MAJORITY * fit.cells
