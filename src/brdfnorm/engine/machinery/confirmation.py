"""The confirmation of the adaptive panels before a case stops, shared by the hemisphere route
(:mod:`brdfnorm.engine.routes.hemisphere`) and the rectangle driver of the half-vector and dielectric routes
(:func:`brdfnorm.engine.machinery.panels.adaptive_rectangles`).

An embedded Gauss–Kronrod pair (:func:`.panels.kronrod_estimate`) bounds the error of a panel where the integrand is
smooth on it; both rules can still agree on a feature that lies between all their nodes — the sliver a Blinn-Phong
lobe becomes at grazing views, a kink or jump next to a panel's edge or clipping its corner, beyond every Gauss and
Kronrod node (:mod:`.kinks`, docs/kinks.md). So before a case stops — meeting its tolerance, out of budget, stalled
or rounding-limited — every panel of it not yet confirmed is recomputed on new nodes that include its edges, and the
difference joins its error (:func:`confirm_before_stop`): an unconverged case's estimate must bound its error too,
as Berntsen, Espelid & Genz's adaptive cubature (ACM TOMS 17, 1991) asks of every estimate it returns. What is here:

- :func:`confirm_before_stop` — the one mechanism: which panels to confirm (the unchecked panels of the cases within
  tolerance or stopping), the route's own confirmation of them, their marks and cost;
- :func:`out_of_budget` — the budget stop, which keeps what confirming a case's unchecked panels costs, so that the
  confirmation at the stop fits in ``max_evaluations``;
- :func:`check_with_corners` — the hemisphere route's confirmation of a panel: its halves along either direction by
  Gauss–Lobatto-9 ⊗ G7 (:func:`check_by_halves`), and with the halves along u, the same halves by
  Lobatto-9 ⊗ Lobatto-9, whose nodes include the panel's four corners (a kink clipping a corner within 0.8% of its
  sides: Oren-Nayar's max(0, cos Δφ), tests/engine/test_honesty_hemisphere.py); the rectangle driver's is its
  quarters by Lobatto-7 ⊗ Lobatto-7 (:func:`.panels.quarters`), whose nodes include the quarters' edges;
- :func:`stopping` and :func:`stalled` — the hemisphere route's fail-fast stops: rounding-limited (the noise alone
  exceeds the tolerance and the quadrature error is already below it) and stalled (the estimate no longer halves
  when the evaluations double).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from .kinks import LOBATTO_NODES, LOBATTO_WEIGHTS, refinement_change
from .kronrod import GAUSS_NODES, GAUSS_WEIGHTS, NODES
from .tensor_rule import normalized

#: Evaluations of one panel's confirmation by :func:`check_with_corners`: Lobatto-9 ⊗ G7 halves along β and along
#: u, and the halves along u again by Lobatto-9 ⊗ Lobatto-9.
CHECK_EVALUATIONS = 4 * LOBATTO_NODES.size * GAUSS_NODES.size + 2 * LOBATTO_NODES.size**2
#: What one split may cost in the hemisphere route: its two halves evaluated and confirmed.
SPLIT_EVALUATIONS = 2 * (NODES.size**2 + CHECK_EVALUATIONS)
#: Evaluations after which a case whose error estimate no longer halves when its evaluations double stops.
STALL_EVALUATIONS = 50_000

#: ``sums(halves, (nodes_a, nodes_b), (weights_a, weights_b))``: the integrals (2R, C) of the halves of R panels
#: (:class:`.panels.Panels`) on the tensor rule given, with the route's own node map. (The pool's type is not
#: imported here: the rectangle driver in :mod:`.panels` imports this module.)
HalfSums = Callable[..., np.ndarray]


def out_of_budget(unsettled: np.ndarray, evaluations: np.ndarray, unchecked: np.ndarray, check_cost: int,
                  split_cost: int, max_evaluations: int) -> np.ndarray:
    """The ``unsettled`` cases (K,) that stop on the budget: one more split (``split_cost``) would leave too little
    of ``max_evaluations`` to confirm their ``unchecked`` panels (``check_cost`` each) before they stop."""
    return unsettled & (evaluations + unchecked * check_cost + split_cost > max_evaluations)


def confirm_before_stop(pool, within: np.ndarray, stopping: np.ndarray,
                        confirm: Callable[..., None], evaluations: np.ndarray, cost: int) -> np.ndarray:
    """Confirm the panels not yet confirmed of every case (K,) ``within`` its tolerance or ``stopping`` (budget,
    stall, rounding), before it may stop: ``confirm(pool, mask)`` adds what the route's confirmation of the panels
    ``pool[mask]`` found to their errors; they are then marked checked and ``cost`` evaluations each are counted.
    Returns the mask (R,) of the panels confirmed. (Halves of a panel split later are confirmed again: a split
    keeps the edges, and a kink next to one, out of the K15 nodes' sight.)"""
    confirming = (within | stopping)[pool.case] & ~pool.checked
    if confirming.any():
        confirm(pool, confirming)
        pool.checked[confirming] = True
        np.add.at(evaluations, pool.case[confirming], cost)
    return confirming


def check_by_halves(panels, along_a: bool, sums: HalfSums) -> np.ndarray:
    """|K15⊗K15 of each panel − the sum over its two halves (split along a or b)| (R, C), less rounding noise: the
    halves by Gauss-Lobatto in the split direction ⊗ G7 across, ``sums(halves, (nodes_a, nodes_b), (weights_a,
    weights_b))`` giving their integrals (2R, C) with the route's own node map (non-finite values counted as 0).
    Lobatto's end nodes see a kink or jump in the 0.43% of a panel next to an edge, beyond all Gauss-Kronrod nodes
    (FON at θ_V = 53.6°: 2.8e-7 off, |K − G| = 2e-15): with δ < 0.0043 h and a jump J in slope, the error J δ²/2 is
    below the end node's h/(2n(n − 1)) J δ (n = 9: 3.9 times; a jump 1.9). G7 across, as Lobatto was weaker than G7
    on steep integrands (Phong n = 1e4, rtol 1e-12). docs/kinks.md has the details."""
    halves = panels.halves(np.full(panels.case.size, along_a))
    nodes, weights = (LOBATTO_NODES, GAUSS_NODES), (LOBATTO_WEIGHTS, GAUSS_WEIGHTS)
    if not along_a:
        nodes, weights = nodes[::-1], weights[::-1]
    total = sums(halves, nodes, weights)
    half = panels.case.size
    return refinement_change(panels.value, total[:half], total[half:])


def check_with_corners(panels, along_a: bool, sums: HalfSums) -> tuple[np.ndarray, np.ndarray | None]:
    """:func:`check_by_halves` of each panel split along a (β) or b (u) with the route's ``sums``; with the
    halves along b, also their corner check: the same halves with Lobatto-9 across (along a) too, whose nodes
    include the panel's four corners (else None)."""
    corners = []

    def sums_and_corners(halves, nodes: tuple, weights: tuple) -> np.ndarray:
        total = sums(halves, nodes, weights)
        if not along_a:
            across = sums(halves, (LOBATTO_NODES, nodes[1]), (LOBATTO_WEIGHTS, weights[1]))
            half = panels.case.size
            corners.append(refinement_change(total[:half] + total[half:], across[:half], across[half:]))
        return total

    change = check_by_halves(panels, along_a, sums_and_corners)
    return change, (corners[0] if corners else None)


def stopping(history, unsettled, noise, quadrature_error, tolerance, evaluations, confirmations, since, unchecked,
             stall_after, max_evaluations):
    """Which ``unsettled`` cases stop without meeting their tolerance: (rounding-limited stop, stalled, out of
    budget, rounding-limited). Fail fast where more nodes cannot help: the rounding noise alone exceeds the
    tolerance and the quadrature error is already below it, or the estimate stopped improving (see :func:`stalled`).
    The stall check counts the evaluations that refined (``history`` holds them): a confirmation is spent once per
    panel and raises the estimate by what it finds, which would read as a stall (so the check compares only the
    rounds since a confirmation last raised the estimate, ``since``). The budget keeps what confirming
    the case's ``unchecked`` panels costs (:data:`CHECK_EVALUATIONS` each: :func:`out_of_budget`)."""
    rounding_limited = unsettled & np.any(normalized(noise, tolerance) > 1.0, axis=1)
    stop = rounding_limited & np.all(quadrature_error <= noise, axis=1)
    stuck = unsettled & ~stop & stalled(history, evaluations - confirmations, stall_after, since)
    budget = out_of_budget(unsettled, evaluations, unchecked, CHECK_EVALUATIONS, SPLIT_EVALUATIONS, max_evaluations)
    return stop, stuck, budget, rounding_limited


def stalled(history: list[tuple[np.ndarray, np.ndarray]], evaluations: np.ndarray,
            after: np.ndarray | int = STALL_EVALUATIONS, since: np.ndarray | int = 0) -> np.ndarray:
    """Cases whose error estimate shrank by less than 2× since they had half their evaluations, once past
    a modest budget (``after``, per case): refining further only spends evaluations (rounding noise, a
    singularity). ``history`` holds (evaluations, error estimate) per round; rounds before ``since`` (per case)
    are not compared."""
    result = np.zeros(evaluations.size, dtype=bool)
    compared = np.zeros(evaluations.size, dtype=bool)
    current = history[-1][1]
    for spent, estimate in reversed(history[:-1]):  # the latest round with at most half the evaluations
        latest = (spent <= evaluations / 2) & (spent >= since) & ~compared
        with np.errstate(invalid="ignore"):
            result |= latest & (current > 0.5 * estimate)
        compared |= latest
    return result & (evaluations > after)
