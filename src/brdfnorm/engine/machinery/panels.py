"""The adaptive panels every 2-D route of the engine refines: one panel pool, one rule on it, one rectangle driver.

- :class:`Panels` — the pool: rectangles [a₀, a₁] × [b₀, b₁] of K cases' domains (the hemisphere route's (β, u),
  the half-vector and dielectric routes' (φ, v)), their estimates once evaluated, what their confirmation found
  and the kink floor (:func:`brdfnorm.engine.machinery.kinks.algebraic_floor`) their ancestry left them;
- :func:`kronrod_estimate` — the rule pair on a panel: the tensor K15 ⊗ K15 value (QUADPACK's G7/K15 pair,
  :mod:`.kronrod`) and the plain |KK − GK|, |KK − KG| of the embedded G7 rules as the error in each direction (not
  QUADPACK's rescaling), each at least the rounding-noise floor 50ε∫|g| (QUADPACK's), with ∫|g| itself (the scale
  of the integrand's own float64 noise, :mod:`.rounding`);
- :func:`adaptive_rectangles` — the driver of the half-vector and dielectric routes over a rectangle integrand: it
  bisects panels along their worse direction while their case misses the tolerance, and confirms a case's panels on
  their quarters with Gauss–Lobatto nodes that include the edges (:data:`.kinks.QUARTER_NODES`) before the case may
  stop, within tolerance or out of budget (:mod:`.confirmation`, as the hemisphere route). The hemisphere route
  (:mod:`brdfnorm.engine.routes.hemisphere`) drives the same pool with its own loop, which adds what only a lobe
  sampled in lobe-aligned coordinates needs: the rounding-noise bound, the stall check and non-finite values.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import partial

import numpy as np

from . import kinks
from .confirmation import confirm_before_stop, out_of_budget
from .kinks import QUARTER_NODES, QUARTER_WEIGHTS, algebraic_floor
from .kronrod import GAUSS, KRONROD, NODES
from .result import RouteResult

_EPS = np.finfo(float).eps

#: Panels per integrand call: arrays of 64 × 225 nodes stay in cache (1000 was ~1.5x slower); an integrand with
#: much work per azimuth node (transmission's ray search) asks for more, to amortize numpy's per-call overhead.
PANELS_PER_CHUNK = 64

#: Rectangle integrand: (case (R,), a (R, n, 1), b (R, 1, n), piece floor(b₀) (R,)) -> (R, n, n, C).
RectangleIntegrand = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@dataclass
class Panels:
    """Panels: case index and (a, b) bounds, and — once evaluated — their estimates (R rows; (R, C) per channel)."""

    case: np.ndarray
    a0: np.ndarray
    a1: np.ndarray
    b0: np.ndarray
    b1: np.ndarray
    value: np.ndarray | None = None  # (R, C) K15⊗K15
    err_a: np.ndarray | None = None  # (R, C) |KK − GK|: the error along a
    err_b: np.ndarray | None = None  # (R, C) |KK − KG|: the error along b
    #: (R, C) what a refinement check found and the error keeps: the change of the split that made the panel
    #: (hemisphere route) or the difference to its quarters once confirmed (rectangle driver)
    change: np.ndarray | None = None
    checked: np.ndarray | None = None  # (R,) bool: confirmed on new nodes (its finding is in the error)
    floor: np.ndarray | None = None  # (R, C) where its ancestors converged algebraically (kinks.algebraic_floor)
    magnitude: np.ndarray | None = None  # (R, C) K15⊗K15 integral of |g| (the scale of rounding noise)
    bad: np.ndarray | None = None  # (R,) measure of the panel where the integrand was non-finite (zeroed)

    FIELDS = ("case", "a0", "a1", "b0", "b1", "value", "err_a", "err_b", "change", "checked", "floor", "magnitude",
              "bad")

    def take(self, index) -> Panels:
        return Panels(*(None if (x := getattr(self, f)) is None else x[index] for f in self.FIELDS))

    @staticmethod
    def join(first: Panels | None, second: Panels) -> Panels:
        """``first`` then ``second`` (``first`` None: ``second``); a field either lacks is left out."""
        if first is None:
            return second
        return Panels(*(None if (x := getattr(first, f)) is None or (y := getattr(second, f)) is None
                        else np.concatenate([x, y]) for f in Panels.FIELDS))

    def error(self) -> np.ndarray:
        """The panel's error estimate (R, C): both directions' |K − G|, the check's finding and the kink floor."""
        return self.err_a + self.err_b + self.change + self.floor

    def halves(self, along_a: np.ndarray) -> Panels:
        """The two halves of every panel (first halves, then second halves), split along a or b (R,)."""
        a_mid = (self.a0 + self.a1) / 2
        b_mid = (self.b0 + self.b1) / 2
        return Panels(
            np.concatenate([self.case, self.case]),
            np.concatenate([self.a0, np.where(along_a, a_mid, self.a0)]),
            np.concatenate([np.where(along_a, a_mid, self.a1), self.a1]),
            np.concatenate([self.b0, np.where(along_a, self.b0, b_mid)]),
            np.concatenate([np.where(along_a, self.b1, b_mid), self.b1]),
        )


def kronrod_estimate(weighted: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """From the integrand times its Jacobian and the panel's area factor at the K15 ⊗ K15 nodes (R, 15, 15, C):
    the K15⊗K15 value, the errors |KK − GK| (along a) and |KK − KG| (along b), each at least the rounding floor
    50ε∫|g|, and ∫|g| (R, C each)."""
    over_b_k = np.einsum("rabc,b->rac", weighted, KRONROD)
    over_b_g = np.einsum("rabc,b->rac", weighted, GAUSS)
    kk = np.einsum("rac,a->rc", over_b_k, KRONROD)
    gk = np.einsum("rac,a->rc", over_b_k, GAUSS)
    kg = np.einsum("rac,a->rc", over_b_g, KRONROD)
    magnitude = np.einsum("rabc,a,b->rc", np.abs(weighted), KRONROD, KRONROD)
    floor = 50.0 * _EPS * magnitude  # rounding noise: QUADPACK's floor on |K − G|
    return kk, np.maximum(np.abs(kk - gk), floor), np.maximum(np.abs(kk - kg), floor), magnitude


def per_case(K: int, case: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Sums per case (K, C) of per-panel values (R, C), each by pairwise summation (numpy's ``add.reduceat`` over
    the panels sorted by case): its rounding error grows like ε log₂ R, where ``np.add.at``'s running sum grows
    like ε R and is in no estimate — 1.4e-14 over 10 821 panels of GGX α = 1.9e-7 at μ = 6.1e-6 against an
    estimate of 5.6e-14, 3e-13 over 129 000 (math.fsum of the same panels: 1.1e-16 off the 1-D azimuthal route)."""
    out = np.zeros((K, values.shape[1]))
    if not case.size:
        return out
    order = np.argsort(case, kind="stable")
    ordered = case[order]
    starts = np.flatnonzero(np.concatenate([[True], ordered[1:] != ordered[:-1]]))
    # (C, R) contiguous along the panels, so that each case's sum is one pairwise reduction
    out[ordered[starts]] = np.add.reduceat(np.ascontiguousarray(values[order].T), starts, axis=1).T
    return out


# -- the rectangle driver (half-vector and dielectric routes) -------------------------------------------------

def _rule_on(integrand: RectangleIntegrand, panels: Panels, nodes: np.ndarray, sl: slice):
    """Integrand values times the panel's area factor on a tensor grid of ``nodes`` (R, n, n, C)."""
    ha = (panels.a1[sl] - panels.a0[sl]) / 2
    hb = (panels.b1[sl] - panels.b0[sl]) / 2
    a = ((panels.a0[sl] + panels.a1[sl]) / 2)[:, None] + ha[:, None] * nodes
    b = ((panels.b0[sl] + panels.b1[sl]) / 2)[:, None] + hb[:, None] * nodes
    # A node on a panel's upper edge (Lobatto's) takes the limit from inside: the integrands pick their piece
    # by floor(coordinate), and the last edge has no piece beyond it.
    a = np.minimum(a, np.nextafter(panels.a1[sl], -np.inf)[:, None])
    b = np.minimum(b, np.nextafter(panels.b1[sl], -np.inf)[:, None])
    piece = np.floor(panels.b0[sl]).astype(int)
    values = integrand(panels.case[sl], a[:, :, None], b[:, None, :], piece)
    return values * (ha * hb)[:, None, None, None]


def _evaluate(integrand: RectangleIntegrand, panels: Panels, chunk: int) -> None:
    R = panels.case.size
    value = err_a = err_b = None
    for start in range(0, R, chunk):
        sl = slice(start, start + chunk)
        kk, ea, eb, _ = kronrod_estimate(_rule_on(integrand, panels, NODES, sl))
        if value is None:
            C = kk.shape[-1]
            value, err_a, err_b = np.empty((R, C)), np.empty((R, C)), np.empty((R, C))
        value[sl], err_a[sl], err_b[sl] = kk, ea, eb
    panels.value, panels.err_a, panels.err_b = value, err_a, err_b
    panels.change = np.zeros_like(value)
    panels.checked = np.zeros(R, dtype=bool)
    panels.floor = np.zeros_like(value)


def _quarters(integrand: RectangleIntegrand, panels: Panels, chunk: int) -> np.ndarray:
    """The four quarters of every panel by Lobatto7 ⊗ Lobatto7, summed: (R, C). Lobatto's nodes on the quarters'
    edges see a kink or jump in the sliver next to a panel's edge, where no Gauss or Kronrod node lies
    (:mod:`brdfnorm.engine.machinery.kinks`); non-finite values there count as 0."""
    total = np.zeros_like(panels.value)
    for qa in (0, 1):
        for qb in (0, 1):
            ma, mb = (panels.a0 + panels.a1) / 2, (panels.b0 + panels.b1) / 2
            quarter = Panels(panels.case, np.where(qa, ma, panels.a0), np.where(qa, panels.a1, ma),
                             np.where(qb, mb, panels.b0), np.where(qb, panels.b1, mb))
            for start in range(0, quarter.case.size, chunk):
                sl = slice(start, start + chunk)
                with np.errstate(all="ignore"):
                    f = _rule_on(integrand, quarter, QUARTER_NODES, sl)
                f = np.where(np.isfinite(f), f, 0.0)
                total[sl] += np.einsum("rabc,a,b->rc", f, QUARTER_WEIGHTS, QUARTER_WEIGHTS)
    return total


def _confirm_quarters(pool: Panels, check: np.ndarray, *, integrand: RectangleIntegrand, chunk: int) -> None:
    """The confirmation of the panels ``pool[check]``: the difference to their quarters (:func:`_quarters`, new
    nodes) becomes the panel's ``change``, at least the rounding floor 50ε|value|. A confirmation far off the panel's
    own |K − G| (:func:`.kinks.surprised`): neither rule is in its asymptotic regime there, and the difference itself
    was found 3.2 times below the true error (modified Phong n = 1.735); the panel's estimate is then
    :data:`.kinks.SURPRISE` times the difference, and the driver's usual splitting refines it where that matters to
    its case. (Bisecting every surprised panel before its case may stop, as first tried, chased differences of
    1e-17…1e-28 against a tolerance of 1e-13 — GGX α = 1.9e-7 at μ = 6.1e-6 — down to panels 7e-12 wide, from 0.7 to
    29 million evaluations.)"""
    subset = pool.take(check)
    difference = np.maximum(np.abs(subset.value - _quarters(integrand, subset, chunk)),
                            50.0 * _EPS * np.abs(subset.value))
    surprise = kinks.surprised(difference, subset.err_a, subset.err_b)
    pool.change[check] = np.where(surprise[:, None], kinks.SURPRISE * difference, difference)


def _within_budget(split: np.ndarray, badness: np.ndarray, case: np.ndarray, allowed: np.ndarray) -> np.ndarray:
    """``split`` (R,) less, per case, all but its ``allowed[case]`` worst panels (by ``badness``): the splits its
    budget can still pay for, their halves evaluated and confirmed (a case that cannot pay for one has stopped)."""
    chosen = np.flatnonzero(split)
    order = chosen[np.lexsort((-badness[chosen], case[chosen]))]
    cases = case[order]
    rank = np.arange(order.size) - np.searchsorted(cases, cases, side="left")
    within = np.zeros_like(split)
    within[order[rank < allowed[cases]]] = True
    return within


def adaptive_rectangles(integrand: RectangleIntegrand, initial: Panels, K: int, *, rtol: float | np.ndarray,
                        atol: float | np.ndarray, max_evaluations: int,
                        chunk: int = PANELS_PER_CHUNK) -> RouteResult:
    """Integrate every case over the union of its initial panels, adaptively and all cases at once (``rtol`` and
    ``atol`` scalars or per case, (K, 1)). Before a case stops — meeting the tolerance or out of budget — every
    panel of it not yet checked is re-integrated on its four quarters (:func:`_confirm_quarters`, new nodes) and the
    difference joins its error (:func:`.confirmation.confirm_before_stop`, as the hemisphere route does; the budget
    keeps what that costs, :func:`.confirmation.out_of_budget`): an unconverged case's estimate must bound its error
    too (an edge ramp beyond every K15 node, 2e-8, was reported with an estimate of 1.9e-14 when the budget stopped
    it unconfirmed: tests/engine/test_rectangle_budget.py). The difference is kept as a sum (taking the smaller of
    the two instead halves the work but was found optimistic at μ ≲ 1e-6 in the half-vector route)."""
    value = error = None
    evaluations = np.zeros(K, dtype=np.int64)
    converged = np.zeros(K, dtype=bool)
    active = np.ones(K, dtype=bool)
    pool: Panels | None = None
    fresh = initial
    per_panel, per_check = NODES.size**2, 4 * QUARTER_NODES.size**2
    per_split = 2 * (per_panel + per_check)  # a split's two halves, evaluated and confirmed before their case stops
    confirm = partial(_confirm_quarters, integrand=integrand, chunk=chunk)
    parent_error = None  # |K − G| of the panels whose halves ``fresh`` holds
    while True:
        _evaluate(integrand, fresh, chunk)
        np.add.at(evaluations, fresh.case, per_panel)
        if parent_error is not None:
            # Where a split converged algebraically (a kink or a jump), the parent's estimate stays as a floor.
            fresh.floor = algebraic_floor(parent_error, fresh.err_a + fresh.err_b)
        pool = Panels.join(pool, fresh)
        if value is None:
            value = np.zeros((K, pool.value.shape[1]))
            error = np.zeros_like(value)
        total = per_case(K, pool.case, pool.value)
        tolerance = np.maximum(atol, rtol * np.abs(total))
        meets = np.all(per_case(K, pool.case, pool.error()) <= tolerance, axis=1) & active
        unchecked = np.bincount(pool.case[~pool.checked], minlength=K)
        stopping = out_of_budget(active & ~meets, evaluations, unchecked, per_check, per_split, max_evaluations)
        # Confirmation: the unchecked panels of the cases that meet the tolerance or stop, on new nodes.
        confirm_before_stop(pool, meets, stopping, confirm, evaluations, per_check)
        total_error = per_case(K, pool.case, pool.error())
        done = np.all(total_error <= tolerance, axis=1) & active
        # A case confirmed to stop stops (with what its confirmation found), unless it now meets its tolerance; one
        # whose confirmation took it back over the tolerance goes on while the budget allows (its panels are all
        # confirmed now, so it stops honestly whenever it does).
        unchecked = np.bincount(pool.case[~pool.checked], minlength=K)
        budget = active & ~done & (stopping | out_of_budget(active, evaluations, unchecked, per_check, per_split,
                                                            max_evaluations))
        finished = done | budget
        value[finished], error[finished] = total[finished], total_error[finished]
        converged[done] = True
        active &= ~finished
        pool = pool.take(active[pool.case])
        if not pool.case.size:
            break
        # Split the panels carrying more than their share of their case's tolerance, and each case's worst.
        badness = np.max(pool.error() / np.maximum(tolerance[pool.case], 1e-300), axis=1)
        count = np.bincount(pool.case, minlength=K)
        worst = np.zeros(K)
        np.maximum.at(worst, pool.case, badness)
        split = (badness > 1.0 / count[pool.case]) | (badness >= worst[pool.case])
        split = _within_budget(split, badness, pool.case, (max_evaluations - evaluations - unchecked * per_check)
                               // per_split)
        parents = pool.take(split)
        pool = pool.take(~split)
        parent_error = parents.err_a + parents.err_b
        fresh = parents.halves(np.max(parents.err_a, axis=1) >= np.max(parents.err_b, axis=1))
    return RouteResult(value, error, evaluations, converged)
