"""Globally adaptive bisection of [0, 1] for many integrals at once (as QUADPACK's QAG): the μ integrals of the
tables' E_avg (:mod:`brdfnorm.lut.table`, and the fallback of :mod:`brdfnorm.lut.glass`), whose panel rules and error
estimates the callers supply."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np


def adaptive_unit_interval(evaluate: Callable, count: int, *, rtol: float, max_panels: int
                           ) -> tuple[np.ndarray, np.ndarray]:
    """``count`` integrals over [0, 1] at once, globally adaptive (as QUADPACK): ``evaluate(owner, left, width)``
    returns each panel's (value, error); while an integral's summed errors exceed rtol·|value| and it has fewer
    than ``max_panels`` panels, its worst panels (error ≥ ¼ of its largest) are halved. Returns (value, error)."""
    owner = np.repeat(np.arange(count), 2)
    left, width = np.tile([0.0, 0.5], count), np.full(2 * count, 0.5)
    value, error = evaluate(owner, left, width)
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
        children_owner = np.repeat(owner[split], 2)
        children_left = np.stack([left[split], left[split] + 0.5 * width[split]], axis=1).ravel()
        children_width = np.repeat(0.5 * width[split], 2)
        children_value, children_error = evaluate(children_owner, children_left, children_width)
        owner = np.concatenate([owner[keep], children_owner])
        left, width = np.concatenate([left[keep], children_left]), np.concatenate([width[keep], children_width])
        value, error = np.concatenate([value[keep], children_value]), np.concatenate([error[keep], children_error])
    return total, total_error
