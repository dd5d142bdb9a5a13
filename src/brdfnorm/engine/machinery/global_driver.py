"""The one driver of the global tensor rules (issue 39): the levels loop every coordinate system of the rule shares.

A global tensor rule integrates a case over one rectangle (t, u) ∈ [0, 2π) × [0, 1] at a time: the periodic
trapezoid rule in t × Fejér's second rule in u, both nested under doubling, each doubling evaluating only the new
nodes (:mod:`brdfnorm.engine.machinery.tensor_rule` gives the rule, its sums and estimates, and the reasons for
each step below). This module runs it, level by level, for many cases at once:

1. the start grid (2^3 azimuths × 2^4 − 1 radial nodes) of every (case, piece) — a case may be cut into radial
   pieces that share its tolerance;
2. per level and per group of units at the same levels: the sums and deviations of the embedded coarser rules
   (:func:`~brdfnorm.engine.machinery.tensor_rule.sums`), the estimate — raised where 16 azimuths suddenly agree
   with 8 (:func:`~brdfnorm.engine.machinery.grid_estimate.sudden`) — and the units that settle, never on the
   start azimuths: their embedded 4- and 2-azimuth rules are blind to a feature the 8 alias, and agree on the miss
   (the randomized sweep on main: a naive GGX shader, α = 0.14 at μ = 0.0146, rtol 1e-3, settled its half-vector
   pole piece on 8 × 15 nodes 74 times outside its estimate; Blinn-Phong n = 1 611 at 78.8°, 6.7 times on 8 × 63).
   A unit within its tolerance there is confirmed along β;
3. the direction(s) to double (those whose estimate exceeds half the tolerance, else the larger one; a single
   one where the grid allows it), the doublings still needed if each squares the last reduction
   (:func:`~brdfnorm.engine.machinery.tensor_rule.doublings`), and the units predicted hopeless within the node
   cap — those, and the non-finite ones, are left unsettled for the caller's adaptive panels;
4. the doublings (:func:`schedule_doublings`), the refined units merged into one group per pair of levels, and
   batches of cases bounded in memory. Where both directions would be doubled and one more doubling of u is
   predicted to settle the unit, a lobe-aligned grid doubles β alone and measures u on the azimuths it already has
   (:func:`_refine_half`, the *half-azimuth check*): the unit's estimate at (2M, N) is then its β estimate plus
   the error of the N-node radial rule measured on M azimuths, |Q(M, 2N) − Q(M, N)| with its margin, and Q(2M, N)
   the value (Blinn-Phong n = 100, θ_o = 0…89°, rtol 1e-9: 7 013 → 5 921 evaluations per albedo; the randomized
   sweeps are in docs/performance.md, sixth session). Since the seventh session u is measured on a quarter of the
   refined grid's azimuths, M/2 of 2M (:data:`HALF_AZIMUTH_DEPTH`), its estimate raised by its own β error (the
   change measured on every other of those azimuths): 5 440 → 4 906 with the rounding-noise survey.

What differs between coordinate systems is a grid,
:class:`~brdfnorm.engine.machinery.tensor_rule.GlobalGrid` (the style of mpmath's quadrature classes: a class with
a few methods to override): the weighted integrand at (cases, azimuth indices, radial nodes), the count of
evaluations, the radial pieces, the sums' implementation, extra estimate terms, the minimum radial level, when the
prediction may give a case up, and what happens once the start grid is in (a restart on another map). Two exist:
:class:`brdfnorm.engine.machinery.tensor_rule.LobeAlignedGrid` (the hemisphere's lobe-aligned coordinates) and
:class:`brdfnorm.engine.routes.halfvector_global.HalfVectorGrid` (the half-vector rectangle, three pieces).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import grid_estimate
from .result import RouteResult
from .tensor_rule import BATCH_NODES, MAX_LEVEL_B, START_LEVELS, GlobalGrid, doublings, fejer, normalized

#: The half-azimuth check of u (:func:`_refine_half`) measures u on 2^-HALF_AZIMUTH_DEPTH of the refined grid's
#: azimuths: 1, the M of 2M (the sixth session); 2, a quarter (M/2 of 2M; Blinn-Phong n = 100, rtol 1e-9, with
#: the rounding-noise survey: 5 440.2 → 4 905.5 evaluations per albedo, every estimate above its true error on
#: the sweeps of docs/performance.md, seventh session) ...
HALF_AZIMUTH_DEPTH = 2
#: ... on grids whose check has at least 2^HALF_AZIMUTH_FROM azimuths (where the grid allows it,
#: :attr:`~brdfnorm.engine.machinery.tensor_rule.GlobalGrid.half_azimuth`): u is never measured on the 8 start
#: azimuths alone, whose embedded rules the driver does not trust either (module docstring, step 2; 3, 4 and 5
#: cost the same on Blinn-Phong n = 100 at rtol 1e-9 with the check on half the azimuths) ...
HALF_AZIMUTH_FROM = 4
#: ... where at most this many more doublings of u are predicted to settle the unit
#: (:func:`~brdfnorm.engine.machinery.tensor_rule.doublings`; 2 saves 34 per albedo at rtol 1e-9, the view at
#: 77°, but costs 16 % at rtol 1e-11: 74–87° then double u twice).
HALF_AZIMUTH_NEEDED = 1


@dataclass
class Group:
    """Units (case, piece) at the same levels: their grids of weighted integrand values F (n, M, N − 1, C), per
    unit the deviations e_β, e_u (relative to their share of the tolerance) before the last doubling along each
    direction (inf where there was none), and what the grid keeps of earlier levels (``earlier``; for
    :func:`brdfnorm.engine.machinery.tensor_rule._stalled`, the values Q of the last three levels)."""

    case: np.ndarray  # (n,)
    piece: np.ndarray  # (n,)
    level_b: int
    level_u: int
    grid: np.ndarray
    last_b: np.ndarray  # (n,)
    last_u: np.ndarray  # (n,)
    earlier: np.ndarray | None = None
    #: The half-azimuth check of u (:func:`_refine_half`): the grid's radial rule one level up, (n, 2^check_b,
    #: 2N − 1, C), on every (M / 2^check_b)-th azimuth; None where there is none.
    check: np.ndarray | None = None
    check_b: int = -1
    #: :func:`brdfnorm.engine.machinery.grid_estimate.deviations` of ``grid``, where the driver computed them.
    deviations: tuple | None = None

    def take(self, keep: np.ndarray) -> Group:
        return Group(self.case[keep], self.piece[keep], self.level_b, self.level_u, self.grid[keep],
                     self.last_b[keep], self.last_u[keep], None if self.earlier is None else self.earlier[keep],
                     None if self.check is None else self.check[keep], self.check_b)

    @property
    def checked(self) -> bool:
        """Whether the half-azimuth check measures u on 2^-:data:`HALF_AZIMUTH_DEPTH` of the grid's azimuths (then
        it takes part in the estimate; after a further doubling of β alone it is kept for its nodes only)."""
        return self.check is not None and self.check_b == self.level_b - HALF_AZIMUTH_DEPTH


def integrate_global(grid: GlobalGrid, K: int, cases: np.ndarray, *, rtol, atol, max_nodes: int) -> RouteResult:
    """The global rule on ``grid`` for ``cases`` (indices < K) as a :class:`RouteResult` (value and error (K, C),
    evaluations and converged (K,)): ``converged`` marks the cases it settled; the others keep their evaluation
    count and are left to the caller."""
    atol = np.broadcast_to(np.asarray(atol, dtype=float).reshape(-1), (K,))
    evaluations = np.zeros(K, dtype=np.int64)
    value = error = None
    settled = np.zeros(K, dtype=bool)
    batch = max(1, BATCH_NODES // grid.batch_nodes(max_nodes))
    for start in range(0, cases.size, batch):
        part = cases[start:start + batch]
        v, e, ok = _integrate_batch(grid, K, part, rtol, atol, max_nodes, evaluations)
        if value is None:
            value, error = np.zeros((K, v.shape[1])), np.zeros((K, v.shape[1]))
        value[part], error[part], settled[part] = v[part], e[part], ok[part]
    if value is None:
        value, error = np.zeros((K, 1)), np.zeros((K, 1))
    return RouteResult(value, error, evaluations, settled)


def _integrate_batch(grid: GlobalGrid, K, cases, rtol, atol, max_nodes, evaluations):
    """:func:`integrate_global` for one batch: fills ``evaluations`` in place, returns value, error (K, C) and
    settled (K,)."""
    P = grid.pieces
    level_b, level_u = START_LEVELS
    case, piece = np.repeat(cases, P), np.tile(np.arange(P), cases.size)
    M, u = 2**level_b, fejer(level_u)[0]
    F = grid.evaluate(case, piece, np.arange(M), M, u)
    np.add.at(evaluations, case, grid.count(case, np.arange(M), M) * F.shape[2])
    inf = np.full(case.size, np.inf)
    start = Group(case, piece, level_b, level_u, F, inf, inf.copy())
    again = grid.start(start)
    if again is not None and again.any():
        F[again] = grid.evaluate(case[again], piece[again], np.arange(M), M, u)
        np.add.at(evaluations, case[again], grid.count(case[again], np.arange(M), M) * F.shape[2])
    C = F.shape[-1]
    latest = np.zeros((K, P, C))
    value, error = np.zeros((K, P, C)), np.zeros((K, P, C))
    done_piece = np.zeros((K, P), dtype=bool)
    failed = np.zeros(K, dtype=bool)
    groups = [start]
    while groups:
        rules = []
        for group in groups:
            finite = np.isfinite(group.grid).all(axis=(1, 2, 3))
            if group.check is not None:
                finite &= np.isfinite(group.check).all(axis=(1, 2, 3))
            with np.errstate(invalid="ignore", over="ignore"):
                F = group.grid if finite.all() else np.where(finite[:, None, None, None], group.grid, 0.0)
                q, e_b, e_u, magnitude = grid.sums(F, group.level_u)
                trend = q  # (the value whose level-to-level changes grid.may_settle watches)
                if group.checked:
                    # u of the grid's own radial rule, measured on half its azimuths (_refine_half); the trend
                    # is Q(2M, N) + Q(M, 2N) − Q(M, N), the combination technique's Q(2M, 2N), as if u had been
                    # doubled with β (a level that doubled β alone would otherwise look like a stall)
                    check = group.check if finite.all() else np.where(finite[:, None, None, None], group.check, 0.0)
                    q_check, _, e_check, _ = grid.sums(check, group.level_u + 1)
                    change = q_check - grid.sums(check[:, :, 1::2], group.level_u)[0]
                    # The check's own β error: the same change measured on every other of its azimuths. Where
                    # the radial rule's error varies along β faster than the check's azimuths follow, the two
                    # differ (Blinn-Phong n = 1 307.5 at 74.85°, rtol 1e-6, u checked on 16 azimuths: changes
                    # 3.6e-16 and 2.6e-14 on 8, the grid 1.3e-14 off against an estimate of 5.9e-15).
                    coarser = (grid.sums(check[:, ::2], group.level_u + 1)[0]
                               - grid.sums(check[:, ::2, 1::2], group.level_u)[0])
                    e_u = np.minimum(e_u, e_check + np.abs(change - coarser))
                    trend = q + change
                weights = [fejer(group.level_u - k)[1] for k in range(4)]
                # (the deviations at 16 azimuths, where grid_estimate.sudden needs them, computed once)
                group.deviations = grid_estimate.deviations(F, weights) if F.shape[1] == 16 else None
                e_b, e_u, floor, noise, estimate = grid.estimate(group, F, q, e_b, e_u, magnitude)
                # A sudden agreement is no evidence of convergence (grid_estimate.sudden): on every grid.
                raised_b, raised_u = grid_estimate.sudden(F, weights, e_b, e_u, magnitude, group.deviations)
                estimate = estimate + (raised_b - e_b) + (raised_u - e_u)
                e_b, e_u = raised_b, raised_u
            latest[group.case, group.piece] = q
            failed[group.case[~finite]] = True
            rules.append((finite, q, e_b, e_u, floor, noise, estimate, trend))
        # A case's tolerance, shared by its pieces, is on its value: the settled pieces' and the others' latest.
        total = np.where(done_piece[..., None], value, latest).sum(axis=1)
        case_tolerance = np.maximum(atol[:, None], rtol * np.abs(total)) / P
        refined: dict[tuple[int, int], list[Group]] = {}
        for group, (finite, q, e_b, e_u, floor, noise, estimate, trend) in zip(groups, rules, strict=True):
            tolerance = case_tolerance[group.case]
            short = grid.short(group)  # (the neck lies below the coarse rules' nodes: tensor_rule.neck_u)
            # Never on the start azimuths: their embedded 4- and 2-azimuth rules are blind to a feature the 8
            # azimuths alias, and agree on the miss (module docstring, step 2).
            done = (np.all(estimate <= tolerance, axis=1) & finite & grid.may_settle(group, trend) & ~short
                    & (group.level_b > START_LEVELS[0]))
            value[group.case[done], group.piece[done]] = q[done]
            error[group.case[done], group.piece[done]] = estimate[done]
            done_piece[group.case[done], group.piece[done]] = True
            share = np.maximum(tolerance - floor - noise, 0.0) / 2
            more_b, more_u, ratio_b, ratio_u, needed_b, needed_u = _directions(grid, group, short, e_b, e_u, share)
            size = 2 ** (group.level_b + more_b) * (2 ** (group.level_u + more_u) - 1)
            # Give up early where geometric convergence, extrapolated from the last doubling, would not settle
            # the unit within max_nodes (a kink, a feature the coordinates do not follow): the panels will.
            hopeless = ((needed_b + group.level_b) > MAX_LEVEL_B) | (
                2 ** (group.level_b + needed_b) * (2 ** (group.level_u + needed_u) - 1) > max_nodes)
            hopeless &= grid.may_predict(group)
            go_on = finite & ~done & (size <= max_nodes) & ~hopeless & ~failed[group.case]
            failed[group.case[finite & ~done & ~go_on]] = True
            half = _halves(grid, group, more_b, more_u, short, needed_u)
            schedule_doublings(group, go_on, more_b, more_u, ratio_b, ratio_u, refined,
                               lambda g, pick, b, u: _refine(grid, g, pick, b, u, evaluations),
                               half, lambda g, pick: _refine_half(grid, g, pick, evaluations))
        groups = [_merge(parts) for parts in refined.values()]
        groups = [g if keep.all() else g.take(keep) for g in groups if (keep := ~failed[g.case]).any()]
    # A case is settled when all its pieces are and their summed estimate meets the final tolerance.
    value, error = value.sum(axis=1), error.sum(axis=1)
    settled = done_piece.all(axis=1) & ~failed
    settled &= np.all(error <= np.maximum(atol[:, None], rtol * np.abs(value)), axis=1)
    return value, error, settled


def _directions(grid: GlobalGrid, group: Group, short, e_b, e_u, share):
    """The directions to double (more_b, more_u), the estimates over their shares (ratio_b, ratio_u) and the
    doublings each still needs (needed_b, needed_u; :func:`brdfnorm.engine.machinery.tensor_rule.doublings`)."""
    # Double the direction(s) whose deviation exceeds its share of the tolerance, else the larger one (a unit
    # within tolerance is confirmed at the next level); a unit short of its radial level doubles u.
    more_b = np.any(e_b > share, axis=1)
    more_u = np.any(e_u > share, axis=1)
    neither = ~(more_b | more_u | short)
    # (on the start azimuths, where no unit settles, the confirmation is along β)
    larger_b = np.any(e_b >= e_u, axis=1) | (group.level_b == START_LEVELS[0])
    more_b |= neither & larger_b
    more_u |= neither & ~larger_b
    ratio_b = normalized(e_b, share).max(axis=1)
    ratio_u = normalized(e_u, share).max(axis=1)
    lone_b = lone_u = np.zeros(group.case.size, dtype=bool)
    if grid.lone:
        # Where both exceed their shares but one direction's estimate is within the whole tolerance on its
        # own (ratio < 2), double only the other: it then has the rest of the tolerance to reach, at half the
        # cost (examples/ggx.brdf, roughness 0.107, θ_o = 60°, rtol 1e-9: e_u at 1.1 shares after 64 × 127
        # nodes; doubling both passed the cap of 16 384 and sent the case to the panels, 55 248 evaluations;
        # 128 × 127 settles it).
        both = more_b & more_u
        lone_b = both & (ratio_u < 2.0) & (ratio_b >= ratio_u)
        lone_u = both & (ratio_b < 2.0) & ~lone_b
    more_u = (more_u & ~lone_b) | short
    more_b &= ~lone_u
    needed_b = np.where(lone_u, 0, doublings(ratio_b, group.last_b))
    needed_u = np.maximum(np.where(lone_b & ~short, 0, doublings(ratio_u, group.last_u)),
                          grid.min_level_u(group) - group.level_u)
    return more_b, more_u, ratio_b, ratio_u, needed_b, needed_u


def _halves(grid: GlobalGrid, group: Group, more_b, more_u, short, needed_u) -> np.ndarray | None:
    """The units to refine by :func:`_refine_half` (β doubled, u measured on the azimuths already there), or None:
    where both directions would be doubled and one more doubling of u is predicted to settle the unit (from the
    second doubling of u on, :func:`~brdfnorm.engine.machinery.tensor_rule.doublings`), on a grid that allows it
    (:attr:`~brdfnorm.engine.machinery.tensor_rule.GlobalGrid.half_azimuth`). Where u was measured so at this
    radial level already, u is doubled (:func:`_refine`, on the check's nodes), and a doubling of β alone takes
    the check along to the new half of the azimuths (else the next level's u estimate would fall back to the
    coarser rule's, and its value move along u alone, which the stall check reads as a stall)."""
    if group.checked:
        return more_b & ~more_u
    if (grid.half_azimuth and group.level_b >= HALF_AZIMUTH_FROM + HALF_AZIMUTH_DEPTH - 1
            and group.level_u > START_LEVELS[1]):
        return more_b & more_u & ~short & (needed_u <= HALF_AZIMUTH_NEEDED) & np.isfinite(group.last_u)
    return None


def schedule_doublings(group: Group, go_on, more_b, more_u, ratio_b, ratio_u, refined: dict, refine,
                       half=None, refine_half=None) -> None:
    """Double the units ``go_on`` of ``group`` along β (``more_b``), u (``more_u``) or both:
    ``refine(group, pick, b, u)`` makes the finer group of the picked units, filed in ``refined`` by its levels
    with the ratios it was doubled on (the extrapolation of
    :func:`~brdfnorm.engine.machinery.tensor_rule.doublings`); the units ``half`` (of those doubled along β)
    are refined by ``refine_half(group, pick)`` instead (β doubled, u checked on half the azimuths: its next
    estimate is that of one radial level up, so its ratio counts as a doubling of u)."""
    half = np.zeros(group.case.size, dtype=bool) if half is None else half & go_on
    for b in (False, True):
        for u in (False, True):
            for by_half in ((False, True) if b else (False,)):
                pick = go_on & (more_b == b) & (more_u == u) & (half == by_half)
                if not pick.any():
                    continue
                new = refine_half(group, pick) if by_half else refine(group, pick, b, u)
                # The first doubling from the start is often pre-asymptotic: extrapolate from the second on.
                if b and group.level_b > START_LEVELS[0]:
                    new.last_b = ratio_b[pick]
                # (a unit whose u was checked on half the azimuths had its estimate of the next radial level
                # already: the ratio it was doubled on is that of the level before)
                if u and group.level_u > START_LEVELS[1] and not group.checked:
                    new.last_u = ratio_u[pick]
                refined.setdefault((new.level_b, new.level_u, new.check_b), []).append(new)


def _refine(grid: GlobalGrid, group: Group, pick, along_b: bool, along_u: bool, evaluations) -> Group:
    """The picked units of ``group`` with their grid doubled along β and/or u (only the new nodes evaluated; along
    u, not those the half-azimuth check holds)."""
    every = pick.all()  # (all picked: the group's arrays as they are, no copy of its grid)
    case, piece = (group.case, group.piece) if every else (group.case[pick], group.piece[pick])
    F = group.grid if every else group.grid[pick]
    level_b, level_u = group.level_b, group.level_u
    check = None if group.check is None else (group.check if every else group.check[pick])
    if along_u and check is not None:
        # u first, from the check's nodes where it has them; the check is then spent
        new = _new_radial(grid, case, piece, level_b, level_u, check, group.check_b, evaluations)
        refined = np.empty(F.shape[:2] + (2 * F.shape[2] + 1, F.shape[3]))
        refined[:, :, 1::2], refined[:, :, 0::2] = F, new
        F, level_u, check, along_u = refined, level_u + 1, None, False
    if along_b:
        M = 2**level_b
        index = 2 * np.arange(M) + 1
        new = grid.evaluate(case, piece, index, 2 * M, fejer(level_u)[0])
        refined = np.empty((case.size, 2 * M) + F.shape[2:])
        refined[:, 0::2], refined[:, 1::2] = F, new
        F, level_b = refined, level_b + 1
        np.add.at(evaluations, case, grid.count(case, index, 2 * M) * new.shape[2])
    if along_u:
        M = 2**level_b
        new = grid.evaluate(case, piece, np.arange(M), M, fejer(level_u + 1)[0][0::2])
        refined = np.empty(F.shape[:2] + (2 * F.shape[2] + 1, F.shape[3]))
        refined[:, :, 1::2], refined[:, :, 0::2] = F, new
        F, level_u = refined, level_u + 1
        np.add.at(evaluations, case, grid.count(case, np.arange(M), M) * new.shape[2])
    return Group(case, piece, level_b, level_u, F, group.last_b[pick], group.last_u[pick],
                 None if group.earlier is None else group.earlier[pick], check,
                 group.check_b if check is not None else -1)


def _new_radial(grid: GlobalGrid, case, piece, level_b: int, level_u: int, check, check_b: int,
                evaluations) -> np.ndarray:
    """The weighted integrand (n, M, N, C) at the radial nodes one level up that the grid (M = 2^level_b
    azimuths, radial level ``level_u``) lacks, on all its azimuths: from ``check`` (the half-azimuth check, on
    every (M / 2^check_b)-th azimuth) where it holds them, evaluated elsewhere."""
    M, u = 2**level_b, fejer(level_u + 1)[0][0::2]
    every = M if check is None else M >> check_b
    index = np.arange(M) if check is None else np.flatnonzero(np.arange(M) % every)
    values = grid.evaluate(case, piece, index, M, u) if index.size else None
    if values is not None:
        np.add.at(evaluations, case, grid.count(case, index, M) * values.shape[2])
    if check is None:
        return values
    out = np.empty((case.size, M, u.size, check.shape[3]))
    out[:, ::every] = check[:, :, 0::2]
    if values is not None:
        out[:, index] = values
    return out


def _refine_half(grid: GlobalGrid, group: Group, pick, evaluations) -> Group:
    """The half-azimuth check of u (issue 39, item 5): for the picked units of ``group`` at (M, N), where the
    driver would double both directions, β is doubled to (2M, N) and u measured on m = M/2^(depth − 1) of the
    azimuths already there (:data:`HALF_AZIMUTH_DEPTH`: every other one of the M at depth 2), (m, 2N) — m·N new
    nodes instead of 2M·N. The unit's estimate at (2M, N) is then its plain β estimate plus the u estimate of the
    N-node rule itself, |Q(m, 2N) − Q(m, N)| with its margin (the driver's loop): both bound errors of the
    reported Q(2M, N) — the error of its β rule, and that of its radial rule, which the m azimuths measure as the
    2M would unless a feature along β that only the finer azimuths resolve changes how the radial rule converges
    (the mixed term of the combination technique, Griebel, Schneider & Zenger 1992; the randomized sweeps of
    tests/engine/test_half_azimuth_check.py look for one)."""
    every = pick.all()
    case, piece = (group.case, group.piece) if every else (group.case[pick], group.piece[pick])
    F = group.grid if every else group.grid[pick]
    old = None if group.check is None else (group.check if every else group.check[pick])
    check_b = group.level_b + 1 - HALF_AZIMUTH_DEPTH  # (the check's azimuths: every 2^(depth-1)-th of the M)
    new = _new_radial(grid, case, piece, check_b, group.level_u, old, group.check_b, evaluations)
    sub = F[:, ::2 ** (group.level_b - check_b)]
    check = np.empty(sub.shape[:2] + (2 * F.shape[2] + 1, F.shape[3]))
    check[:, :, 1::2], check[:, :, 0::2] = sub, new
    halved = Group(case, piece, group.level_b, group.level_u, F, group.last_b[pick], group.last_u[pick],
                   None if group.earlier is None else group.earlier[pick])
    refined = _refine(grid, halved, np.ones(case.size, dtype=bool), True, False, evaluations)
    refined.check, refined.check_b = check, check_b
    return refined


def _merge(parts: list[Group]) -> Group:
    if len(parts) == 1:
        return parts[0]
    first = parts[0]
    return Group(np.concatenate([p.case for p in parts]), np.concatenate([p.piece for p in parts]), first.level_b,
                 first.level_u, np.concatenate([p.grid for p in parts]), np.concatenate([p.last_b for p in parts]),
                 np.concatenate([p.last_u for p in parts]),
                 None if first.earlier is None else np.concatenate([p.earlier for p in parts]),
                 None if first.check is None else np.concatenate([p.check for p in parts]), first.check_b)
