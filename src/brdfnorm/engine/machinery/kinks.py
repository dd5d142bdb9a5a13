"""What the adaptive panels of :mod:`brdfnorm.engine.routes.hemisphere` and :mod:`brdfnorm.engine.routes.halfvector`
do about integrands with kinks or jumps (FON's max(N·L, N·V) and the sign of L·V − N·L N·V, Oren-Nayar's
max(0, cos Δφ), Burley's, a shader's clamp): the Gauss-Lobatto rule their confirmation uses, and the floor kept
under a panel that converges algebraically. docs/kinks.md has the measurements.

An embedded Gauss-Kronrod pair is an honest estimate where the integrand is smooth on the panel: |K − G| is then
the error of the lower-order rule, far above the reported rule's. Across a kink both rules' errors are J h² times
coefficients set by where the kink falls between their nodes; they can agree by accident, and a kink in the sliver
next to an edge, beyond the outermost node, is seen by neither (nor by a G7 check of the halves, nor by the
children, which keep the edge). Two remedies, both general:

- the confirmation of a panel uses Gauss-Lobatto rules (Abramowitz & Stegun 25.4.32) on its halves or quarters,
  whose nodes include the edges (:data:`LOBATTO_NODES`, :data:`QUARTER_NODES`);
- a panel whose bisection reduced |K − G| by less than :data:`SLOW` keeps half its parent's estimate as a floor
  (:func:`algebraic_floor`);
- a panel whose confirmation differs from it by more than :data:`SURPRISE` times its own |K − G| is not yet in
  its rules' asymptotic regime: its estimate is :data:`SURPRISE` times that difference, and the usual splitting
  refines it where that matters to its case (:func:`surprised`).
"""

from __future__ import annotations

import numpy as np

_EPS = np.finfo(float).eps

#: Points of the Gauss-Lobatto rule in the split direction of the hemisphere route's check of halves (9: degree 15,
#: above the G7 it replaces there), and in both directions of the half-vector route's check of quarters (7: degree
#: 11 on panels half as wide, which left the smooth lobes' evaluation counts as they were with G7).
LOBATTO_POINTS = 9
QUARTER_POINTS = 7


def lobatto(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The n-point Gauss-Lobatto rule on [−1, 1] (Abramowitz & Stegun 25.4.32): the ends and the zeros of
    P'_{n−1}, weights 2/(n(n − 1) P_{n−1}(x)²)."""
    legendre = np.polynomial.legendre
    degree = np.zeros(n)
    degree[-1] = 1.0  # P_{n-1}
    inner = np.sort(legendre.legroots(legendre.legder(degree)).real)
    nodes = np.concatenate([[-1.0], (inner - inner[::-1]) / 2, [1.0]])  # symmetric to the last bit
    weights = 2.0 / (n * (n - 1) * legendre.legval(nodes, degree) ** 2)
    return nodes, (weights + weights[::-1]) / 2


#: Nodes on both ends of the interval, where no Gauss or Kronrod node lies
#: (brdfnorm.engine.machinery.confirmation.check_by_halves).
LOBATTO_NODES, LOBATTO_WEIGHTS = lobatto(LOBATTO_POINTS)
QUARTER_NODES, QUARTER_WEIGHTS = lobatto(QUARTER_POINTS)

#: A bisection that reduces a panel's summed |K − G| by less than this factor marks it non-smooth
#: (:func:`algebraic_floor`).
SLOW = 64.0


def algebraic_floor(parent_error: np.ndarray, children_error: np.ndarray) -> np.ndarray:
    """The error floor (2R, C) of the halves (first halves, then second halves) of R bisected panels.

    Where the halves' embedded estimates |K − G| together are more than 1/:data:`SLOW` of their parent's, the
    panel converges algebraically — a kink or a jump inside, whose error shrinks like h² where a smooth
    integrand's drops by orders of magnitude per bisection — and there |K − G| is no estimate: both rules' errors
    are J h² times a coefficient that depends on where the kink falls between their nodes, and the two can agree
    by accident (FON at θ_V = 71.2°, rtol 1e-8: a panel 0.002 wide across the kink θ_L = θ_V, |K − G| = 3.1e-10,
    error 1.7e-9; the ratios of successive |K − G| along its lineage were 2.6, 25, 0.34, 4.7, 4, 6.6, 10, 23).
    Each half then keeps half its parent's estimate as a floor, one level behind: an error that shrinks like h²
    is then overestimated about 4 times, and one lucky |K − G| alone cannot end the refinement. (A floor that
    also remembered older ancestors, scaled by h², covered every FON case but multiplied the evaluations tenfold
    and left 88% of them unconverged at rtol 1e-8; see docs/kinks.md.) A split that converges fast clears it."""
    half = parent_error.shape[0]
    slow = (children_error[:half] + children_error[half:]) > parent_error / SLOW
    floor = np.where(slow, parent_error / 2, 0.0)
    return np.concatenate([floor, floor])


#: A confirmation that differs from a panel by more than this many times the panel's |K − G| shows the pair's
#: estimate did not hold there (:func:`surprised`).
SURPRISE = 4.0


def surprised(change: np.ndarray, err_a: np.ndarray, err_b: np.ndarray) -> np.ndarray:
    """(R,) where a confirmed panel's difference to its quarters, ``change`` (R, C), exceeds :data:`SURPRISE`
    times its |K − G| in some channel. On a smooth panel the K15 ⊗ K15 value is far more accurate than the
    embedded G7 rules and the quarters' Lobatto7 rules on panels half as wide, so their difference is below
    |K − G|; where it is several times above, neither is an estimate. Near a weak algebraic singularity
    d^p (modified Phong's max(cos α, 0)^n at the support edge, n = 1.735, crossing a half-vector panel
    obliquely) every rule's error is C h^{p+1} with C set by where the edge falls between its nodes: at
    θ_o = 18.95°, rtol 1e-8, a panel with |K − G| = 4.0e-10 had a quarters' difference of 3.8e-9 and a true
    error of 1.2e-8 (2.1× outside the case's estimate). The kink floor does not see it (the bisection that
    made the panel had reduced |K − G| 64-fold by chance), so the panel's estimate becomes SURPRISE times the
    difference (the true error was 3.2× it there) and the driver's share-of-tolerance splitting refines it."""
    return np.any(change > SURPRISE * (err_a + err_b), axis=1)


def refinement_change(whole: np.ndarray, first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """|whole − (first + second)| for a panel and its two halves, less rounding-level noise (which each
    panel's own floor already covers)."""
    noise = 8.0 * _EPS * (np.abs(whole) + np.abs(first) + np.abs(second))
    return np.maximum(np.abs(whole - first - second) - noise, 0.0)
