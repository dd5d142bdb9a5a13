"""The engine's one-dimensional adaptive integration: bisection of panels for many integrals at once (no Python
loop per integral), in two acceptance policies.

:func:`adaptive_gauss_legendre` — the 1-D routes' integrator (:mod:`brdfnorm.engine.routes.series`,
:mod:`~brdfnorm.engine.routes.azimuthal`, :mod:`~brdfnorm.engine.routes.microfacet`'s E_avg, the claims' seed
integrals): 15-point Gauss–Legendre panels; a panel's error is the difference between the rule on it and on its two
halves (the finer value is kept), and a panel whose error is below its share of its case's tolerance, or at
rounding level, is accepted and leaves the pool (locally adaptive).

:func:`adaptive_unit_interval` — the tables' μ-average of E_avg (:mod:`brdfnorm.lut.table`, and the fallback of
:mod:`brdfnorm.lut.glass`), whose panel rule and its error estimate the caller supplies (a Gauss–Kronrod pair on
albedos): globally adaptive as QUADPACK's QAG, every panel stays in the pool and the worst are halved.

In :func:`adaptive_unit_interval`, a panel rule's own estimate (|K15 − G7| for the callers' Gauss–Kronrod pair)
measures the coarser rule's error, and is pessimistic for the finer one only while the integrand is smooth on the
panel. At a point where it is not, both rules can share one error: a rough dielectric's E(μ) (Beckmann, α = 1, η =
1/1.5) has a jump in its second derivative at μ ≈ 0.992, and on the panel x = √μ ∈ [0.96875, 1] the K15 value was
5.9e-9 off with |K15 − G7| plus the albedo errors at 1.9e-9, so E_avg at rtol 1e-8 settled 1.8 times outside its
estimate. Every panel therefore also carries the discrepancy of its parent, |Q_parent − (Q_left + Q_right)|: the
parent's error, which bounds each child's while bisection converges (it gains a factor 2^(p+1) per halving on a
panel holding a singularity of order p; p > 0 for the kinks and square-root onsets these integrands have). On smooth
panels that discrepancy is the finer rule's error on the parent, far below |K15 − G7|, so it costs evaluations only
next to such points. The whole interval is evaluated once as the parent of the first two halves.

The two policies are not merged: each keeps its callers' recorded results bit for bit (tests/test_engine_grid.py),
and one acceptance rule for both would change them.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.special import roots_legendre

from .result import RouteResult

_EPS = np.finfo(float).eps
#: Gauss–Legendre order of one panel of :func:`adaptive_gauss_legendre`.
_ORDER = 15
_NODES, _WEIGHTS = roots_legendre(_ORDER)
#: Panels are evaluated in blocks of this many, to bound the size of temporaries (panels × 30 × 24 floats).
_BLOCK = 4096
_MAX_ROUNDS = 60

#: A batch integrand: (case indices (P,), abscissae (P, N)) -> values (P, N).
Integrand = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _panel_values(func: Integrand, case: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """15-point Gauss–Legendre of ``func`` on each panel [a, b]; blocks of panels bound the temporaries."""
    out = np.empty(a.shape)
    for start in range(0, a.size, _BLOCK):
        sl = slice(start, start + _BLOCK)
        half = 0.5 * (b[sl] - a[sl])
        x = 0.5 * (a[sl] + b[sl])[:, None] + half[:, None] * _NODES
        # A row sum, not a matrix-vector product: BLAS's gemv rounds a row differently with the number of rows
        # (measured: 524 of 1 003 rows differ from the same rows one at a time), which made a cell's value depend
        # on which other cells shared its call, and tables differ in the last bits between one process and
        # several (tests/test_lut_parallel.py).
        out[sl] = half * (func(case[sl], x) * _WEIGHTS).sum(axis=1)
    return out


def adaptive_gauss_legendre(
    func: Integrand, a: np.ndarray, b: np.ndarray, case: np.ndarray, cases: int, *, rtol: float, atol: float = 0.0
) -> RouteResult:
    """Integrate many one-dimensional integrals at once by adaptive bisection of Gauss–Legendre panels.

    Case ``k`` is the sum of ∫ func over its initial panels [a[i], b[i]] with case[i] = k; ``func(case, x)``
    takes case indices (P,) and abscissae (P, N) and returns (P, N). A panel's error estimate is the difference
    between the 15-point rule on it and on its two halves (the finer value is kept); a case is done when its
    summed estimate is at most max(rtol·|value|, atol). The result's arrays are (cases,); ``evaluations`` counts
    calls of ``func`` per abscissa.
    """
    coarse = _panel_values(func, case, a, b)
    done_value = np.zeros(cases)
    done_error = np.zeros(cases)
    evaluations = np.bincount(case, minlength=cases) * _ORDER
    converged = np.ones(cases, dtype=bool)
    for round_ in range(_MAX_ROUNDS + 1):
        mid = 0.5 * (a + b)
        left = _panel_values(func, case, a, mid)
        right = _panel_values(func, case, mid, b)
        count = np.bincount(case, minlength=cases)
        evaluations += 2 * _ORDER * count
        fine = left + right
        err = np.abs(fine - coarse)
        # Current estimate and error per case: accepted panels plus the live ones at their finer value.
        total = done_value + np.bincount(case, weights=fine, minlength=cases)
        total_err = done_error + np.bincount(case, weights=err, minlength=cases)
        target = np.maximum(rtol * np.abs(total), atol)
        unsettled = total_err > target
        # Split a live panel only while its case misses the target and the panel carries more than its share
        # of the error and more than rounding (a panel at rounding level cannot get better by splitting).
        share = target[case] / np.maximum(count[case], 1)
        split = unsettled[case] & (err > share) & (err > 64.0 * _EPS * np.abs(fine)) & (b - a > 1e-12)
        if round_ == _MAX_ROUNDS:
            converged &= np.bincount(case, weights=split, minlength=cases) == 0
            split[:] = False
        keep = ~split
        done_value += np.bincount(case[keep], weights=fine[keep], minlength=cases)
        done_error += np.bincount(case[keep], weights=err[keep], minlength=cases)
        if not split.any():
            break
        a = np.concatenate([a[split], mid[split]])
        b = np.concatenate([mid[split], b[split]])
        coarse = np.concatenate([left[split], right[split]])
        case = np.concatenate([case[split], case[split]])
    return RouteResult(done_value, done_error, evaluations, converged)


def adaptive_unit_interval(evaluate: Callable, count: int, *, rtol: float, max_panels: int) -> RouteResult:
    """``count`` integrals over [0, 1] at once, globally adaptive (as QUADPACK): ``evaluate(owner, left, width)``
    returns each panel's (value, error). A panel's error is the larger of that error and its parent's bisection
    discrepancy (module docstring). While an integral's summed errors exceed rtol·|value| and it has fewer than
    ``max_panels`` panels, its worst panels (error ≥ ¼ of its largest) are halved. The result's arrays are
    (count,); ``evaluations`` counts the panels ``evaluate`` was given per integral."""
    owner, left, width = np.arange(count), np.zeros(count), np.ones(count)
    whole, _ = evaluate(owner, left, width)
    owner, left, width, value, error = _halves(evaluate, owner, left, width, whole)
    evaluations = np.full(count, 3, dtype=np.int64)  # the whole interval and its halves
    while True:
        total, total_error = np.bincount(owner, value, count), np.bincount(owner, error, count)
        open_ = (total_error > rtol * np.abs(total)) & (np.bincount(owner, minlength=count) < max_panels)
        if not open_.any():
            break
        worst = np.zeros(count)
        np.maximum.at(worst, owner, error)
        split = open_[owner] & (error >= 0.25 * worst[owner]) & (width > 1e-12)
        if not split.any():
            break
        keep = ~split
        evaluations += 2 * np.bincount(owner[split], minlength=count)
        children = _halves(evaluate, owner[split], left[split], width[split], value[split])
        owner, left, width, value, error = (np.concatenate([kept[keep], new]) for kept, new in
                                            zip((owner, left, width, value, error), children, strict=True))
    return RouteResult(total, total_error, evaluations, total_error <= rtol * np.abs(total))


def _halves(evaluate: Callable, owner: np.ndarray, left: np.ndarray, width: np.ndarray, parent: np.ndarray
            ) -> tuple[np.ndarray, ...]:
    """The two halves of each panel (owner, left, width; its value ``parent``), interleaved: (owner, left, width,
    value, error), each half's error at least the parent's bisection discrepancy |parent − (left + right half)|."""
    owner, width = np.repeat(owner, 2), np.repeat(0.5 * width, 2)
    left = np.stack([left, left + width[::2]], axis=1).ravel()
    value, error = evaluate(owner, left, width)
    discrepancy = np.abs(parent - value.reshape(-1, 2).sum(axis=1))
    return owner, left, width, value, np.maximum(error, np.repeat(discrepancy, 2))
