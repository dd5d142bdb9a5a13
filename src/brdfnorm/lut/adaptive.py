"""Globally adaptive bisection of [0, 1] for many integrals at once (as QUADPACK's QAG): the μ integrals of the
tables' E_avg (:mod:`brdfnorm.lut.table`, and the fallback of :mod:`brdfnorm.lut.glass`), whose panel rules and error
estimates the callers supply.

A panel rule's own estimate (|K15 − G7| for the callers' Gauss–Kronrod pair) measures the coarser rule's error, and
is pessimistic for the finer one only while the integrand is smooth on the panel. At a point where it is not, both
rules can share one error: a rough dielectric's E(μ) (Beckmann, α = 1, η = 1/1.5) has a jump in its second derivative
at μ ≈ 0.992, and on the panel x = √μ ∈ [0.96875, 1] the K15 value was 5.9e-9 off with |K15 − G7| plus the albedo
errors at 1.9e-9, so E_avg at rtol 1e-8 settled 1.8 times outside its estimate. Every panel therefore also carries
the discrepancy of its parent, |Q_parent − (Q_left + Q_right)|: the parent's error, which bounds each child's while
bisection converges (it gains a factor 2^(p+1) per halving on a panel holding a singularity of order p; p > 0 for
the kinks and square-root onsets these integrands have). On smooth panels that discrepancy is the finer rule's error
on the parent, far below |K15 − G7|, so it costs evaluations only next to such points. The whole interval is
evaluated once as the parent of the first two halves.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def adaptive_unit_interval(evaluate: Callable, count: int, *, rtol: float, max_panels: int
                           ) -> tuple[np.ndarray, np.ndarray]:
    """``count`` integrals over [0, 1] at once, globally adaptive (as QUADPACK): ``evaluate(owner, left, width)``
    returns each panel's (value, error). A panel's error is the larger of that error and its parent's bisection
    discrepancy (module docstring). While an integral's summed errors exceed rtol·|value| and it has fewer than
    ``max_panels`` panels, its worst panels (error ≥ ¼ of its largest) are halved. Returns (value, error)."""
    owner, left, width = np.arange(count), np.zeros(count), np.ones(count)
    whole, _ = evaluate(owner, left, width)
    owner, left, width, value, error = _halves(evaluate, owner, left, width, whole)
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
        children = _halves(evaluate, owner[split], left[split], width[split], value[split])
        owner, left, width, value, error = (np.concatenate([kept[keep], new]) for kept, new in
                                            zip((owner, left, width, value, error), children, strict=True))
    return total, total_error


def _halves(evaluate: Callable, owner: np.ndarray, left: np.ndarray, width: np.ndarray, parent: np.ndarray
            ) -> tuple[np.ndarray, ...]:
    """The two halves of each panel (owner, left, width; its value ``parent``), interleaved: (owner, left, width,
    value, error), each half's error at least the parent's bisection discrepancy |parent − (left + right half)|."""
    owner, width = np.repeat(owner, 2), np.repeat(0.5 * width, 2)
    left = np.stack([left, left + width[::2]], axis=1).ravel()
    value, error = evaluate(owner, left, width)
    discrepancy = np.abs(parent - value.reshape(-1, 2).sum(axis=1))
    return owner, left, width, value, np.maximum(error, np.repeat(discrepancy, 2))
