"""The engine's one one-dimensional adaptive integrator: bisection of panels for many integrals at once (no Python
loop per integral), as scipy.integrate.quad_vec and mpmath's ``QuadratureRule``: the rule is a small class
(:class:`PanelRule`, override :meth:`PanelRule.apply`), the driver is one function, :func:`adaptive_interval`.

Callers: the 1-D routes (:mod:`brdfnorm.engine.routes.series`, :mod:`~brdfnorm.engine.routes.azimuthal`,
:mod:`~brdfnorm.engine.routes.microfacet`'s E_avg) and the claims' seed integrals with :class:`GaussLegendre`; the
tables' μ-average E_avg (:mod:`brdfnorm.lut.table`) with :class:`GaussKronrod` on albedos.

The error of a panel. Every panel is evaluated once, as a whole, by the rule; splitting it evaluates the rule on
its two halves, and the halves replace it. Each half's error is the larger of the rule's own estimate on it (0 for
a lone Gauss rule, |K15 − G7| plus the node errors for the Gauss–Kronrod pair) and half the parent's bisection
discrepancy |Q_parent − (Q_left + Q_right)|. That discrepancy is the parent's error seen from the finer value
(the check of a rule on its halves, Piessens et al. 1983 §2.2): while bisection converges on a panel holding a
point where the integrand is not smooth (a kink, a square-root onset: a singularity of order p > 0, each halving
gains 2^(p+1)), it bounds the pair's error. It is needed even with a Gauss–Kronrod pair, whose |K15 − G7|
measures the coarser rule's error and is pessimistic for the finer one only while the integrand is smooth on the
panel: a rough dielectric's E(μ) (Beckmann, α = 1, η = 1/1.5) has a jump in its second derivative at μ ≈ 0.992, and
on the panel x = √μ ∈ [0.96875, 1] the K15 value was 5.9e-9 off with |K15 − G7| plus the albedo errors at 1.9e-9
(tests/lut/test_adaptive.py). On smooth panels the discrepancy is far below the rule's own estimate and costs
nothing. The two halves share the discrepancy, half each, so a pair carries it once in the sum (as the former
local driver did); the former QAG driver gave each half all of it, which took 375 albedos instead of 195 for
examples/ggx.brdf's E_avg at roughness 0.05 (rtol 1e-10; the values 1.6e-14 apart, the estimate 8.2e-12), while
the kink test above holds either way.

Acceptance, ``policy=``:

- ``"local"`` (the 1-D routes): a panel whose error is within its share of its case's tolerance (the tolerance
  over the case's live panels), or at rounding level, is accepted and leaves the pool; the others are halved.
- ``"global"`` (QUADPACK's QAG, the μ-average): every panel stays in the pool; while a case's summed errors exceed
  its tolerance, its worst panels (error ≥ ¼ of its largest) are halved, up to ``max_panels`` panels.

In both, a case is done when its summed errors are within max(rtol·|value|, atol), and is reported converged
exactly then; it stops short of that when no panel is worth halving (each at rounding level, or narrower than
1e-12) or a budget (``max_rounds`` halvings, ``max_panels``) is spent. The estimate covers the rules' truncation;
the rounding of the integrand and of the sums is the caller's to add (each 1-D route adds its floor).

A lone Gauss–Legendre rule has no estimate but the discrepancy, and across a kink inside a panel that can fall
short (the kink's place in the panel moves with each halving, so the error does not shrink by a steady factor:
|x − 0.3141| on [0, 1] at rtol 1e-10 ends 3.7 times outside; tests/engine/test_interval.py): its callers start
with panel edges at their integrands' kinks, and an integrand with kinks at unknown places takes the
Gauss–Kronrod pair.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Literal

import numpy as np
from scipy.special import roots_legendre

from .kronrod import GAUSS, KRONROD, NODES
from .result import RouteResult

_EPS = np.finfo(float).eps
#: Panels are evaluated in blocks of this many, to bound the size of temporaries (panels × nodes × the
#: integrand's own intermediates).
_BLOCK = 4096
#: A panel whose error is at most this many ulps of its value is at rounding level: halving cannot improve it.
_ROUNDING_ULPS = 64.0
#: Panels narrower than this are not halved.
_MIN_WIDTH = 1e-12

#: A batch integrand: (case indices (P,), abscissae (P, N)) -> values (P, N).
Integrand = Callable[[np.ndarray, np.ndarray], np.ndarray]


class PanelRule:
    """A quadrature rule on panels. Subclasses set :attr:`cost` and override :meth:`apply`."""

    #: Integrand evaluations one panel costs (what :func:`adaptive_interval` counts as ``evaluations``).
    cost: int = 1

    def apply(self, case: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(value, error estimate), each (P,), of the rule on the panels [a, b] of cases ``case`` (each (P,))."""
        raise NotImplementedError


class _NodeRule(PanelRule):
    """A rule with fixed nodes on [−1, 1]: ``func(case, x)`` on panels in blocks, the sums as row sums."""

    nodes: np.ndarray

    def __init__(self, func: Callable) -> None:
        self.func = func
        self.cost = self.nodes.size

    def apply(self, case: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        value, error = np.empty(a.shape), np.empty(a.shape)
        for start in range(0, a.size, _BLOCK):
            sl = slice(start, start + _BLOCK)
            half = 0.5 * (b[sl] - a[sl])
            x = 0.5 * (a[sl] + b[sl])[:, None] + half[:, None] * self.nodes
            value[sl], error[sl] = self.sums(self.func(case[sl], x), half)
        return value, error

    def sums(self, values: object, half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(value, error) of the panels from the integrand's output at the nodes; ``half`` is each half-width.
        Sums are row sums, not matrix-vector products: BLAS's gemv rounds a row differently with the number of
        rows (measured: 524 of 1 003 rows differ from the same rows one at a time), which made a cell's value
        depend on which other cells shared its call (tests/lut/test_parallel.py)."""
        raise NotImplementedError


class GaussLegendre(_NodeRule):
    """``order``-point Gauss–Legendre (default 15) of ``func(case, x) -> values``; no error of its own (the
    driver's bisection discrepancy is the estimate)."""

    def __init__(self, func: Integrand, order: int = 15) -> None:
        self.nodes, self.weights = roots_legendre(order)
        super().__init__(func)

    def sums(self, values: object, half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return half * (np.asarray(values) * self.weights).sum(axis=1), np.zeros(half.shape)


class GaussKronrod(_NodeRule):
    """The G7/K15 pair (:mod:`.kronrod`) of ``func(case, x)``, which returns the values (P, 15) or (values, their
    error estimates): the K15 value, with error |K15 − G7| plus the node errors through |K15 weights|."""

    nodes = NODES

    def sums(self, values: object, half: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        g, g_error = values if isinstance(values, tuple) else (values, None)
        kronrod = half * (g * KRONROD).sum(axis=1)
        error = np.abs(kronrod - half * (g * GAUSS).sum(axis=1))
        if g_error is not None:
            error = error + half * (g_error * np.abs(KRONROD)).sum(axis=1)
        return kronrod, error


def adaptive_interval(rule: PanelRule, a: np.ndarray, b: np.ndarray, case: np.ndarray, cases: int, *, rtol: float,
                      atol: float | np.ndarray = 0.0, policy: Literal["local", "global"] = "local",
                      max_panels: int | None = None, max_rounds: int = 60) -> RouteResult:
    """Integrate ``cases`` one-dimensional integrals at once by adaptive bisection (module docstring).

    Case ``k`` is the sum of the integrals over its initial panels [a[i], b[i]] with case[i] = k, each evaluated
    by ``rule`` and halved once; then, per ``policy``, panels are halved until the case's summed error estimate is
    at most max(rtol·|value|, atol) (``atol`` a scalar or (cases,)), for at most ``max_rounds`` rounds and (global
    policy) ``max_panels`` live panels a case. The result's arrays are (cases,); ``evaluations`` counts
    ``rule.cost`` per panel evaluated.
    """
    if policy not in ("local", "global"):
        raise ValueError(f"policy must be 'local' or 'global', not {policy!r}")
    a, b, case = (np.asarray(v) for v in (a, b, case))
    atol = np.broadcast_to(np.asarray(atol, dtype=float), (cases,))
    max_panels = np.inf if max_panels is None else max_panels
    parent, _ = rule.apply(case, a, b)
    evaluations = np.bincount(case, minlength=cases).astype(np.int64) * rule.cost
    done_value, done_error = np.zeros(cases), np.zeros(cases)
    # The panels to halve (pa, pb, pc: owner, pv: their value), and the pool of live panels (a, b, case, value,
    # error) that stay as they are (the global policy's; the local policy's pool is only the new halves).
    pa, pb, pc, pv = a, b, case, parent
    a, b, value, error = np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0)
    case = np.zeros(0, dtype=pc.dtype)
    for round_ in range(max_rounds + 1):
        # Halve: the halves replace their parent, each with at least half the parent's discrepancy.
        evaluations += 2 * rule.cost * np.bincount(pc, minlength=cases)
        mid = 0.5 * (pa + pb)
        ha, hb, owners = np.concatenate([pa, mid]), np.concatenate([mid, pb]), np.concatenate([pc, pc])
        h_value, h_error = rule.apply(owners, ha, hb)
        discrepancy = 0.5 * np.abs(pv - (h_value[:mid.size] + h_value[mid.size:]))
        h_error = np.maximum(h_error, np.concatenate([discrepancy, discrepancy]))
        a, b, case = np.concatenate([a, ha]), np.concatenate([b, hb]), np.concatenate([case, owners])
        value, error = np.concatenate([value, h_value]), np.concatenate([error, h_error])

        total = done_value + np.bincount(case, weights=value, minlength=cases)
        total_error = done_error + np.bincount(case, weights=error, minlength=cases)
        target = np.maximum(rtol * np.abs(total), atol)
        open_ = total_error > target
        count = np.bincount(case, minlength=cases)
        improvable = (error > _ROUNDING_ULPS * _EPS * np.abs(value)) & (b - a > _MIN_WIDTH)
        if policy == "local":
            split = open_[case] & (error > target[case] / np.maximum(count[case], 1)) & improvable
        else:
            worst = np.zeros(cases)
            np.maximum.at(worst, case, error)
            split = open_[case] & (error >= 0.25 * worst[case]) & improvable & (count < max_panels)[case]
        if round_ == max_rounds or not split.any():
            break
        pa, pb, pc, pv = a[split], b[split], case[split], value[split]
        keep = ~split
        if policy == "local":
            # Accepted panels leave the pool.
            done_value += np.bincount(case[keep], weights=value[keep], minlength=cases)
            done_error += np.bincount(case[keep], weights=error[keep], minlength=cases)
            a, b, value, error, case = a[:0], b[:0], value[:0], error[:0], case[:0]
        else:
            a, b, case, value, error = a[keep], b[keep], case[keep], value[keep], error[keep]
    total = done_value + np.bincount(case, weights=value, minlength=cases)
    total_error = done_error + np.bincount(case, weights=error, minlength=cases)
    return RouteResult(total, total_error, evaluations, total_error <= np.maximum(rtol * np.abs(total), atol))
