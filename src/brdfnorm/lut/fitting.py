"""Fits of a two-axis lookup table, E(μ, α) say, by :func:`brdfnorm.fit.fit`, with the Pareto front.

The table's direction axis (``mu``, or ``theta`` as μ = cos θ) is the fit's first variable x and the other axis
its second variable t, on which every coefficient depends polynomially (:mod:`brdfnorm.fit`'s ``P/Q@D`` forms):
rationals in √x, and — when the second axis is ``alpha`` — the ``smith:P/Q@D`` forms in the Smith variable
μ/√(μ² + α²(1 − μ²)) with E(0, α) = 1 and the horizon's ln term built in (issue 12 item 5: GGX's E(μ, α) over
μ ∈ [0, 1], α ∈ [0.02, 1] to 7.5·10⁻³ with 9 coefficients, 4.2·10⁻³ with 11, 2.0·10⁻³ with 14, where
rationals in √μ stall at 0.049 with 16). Every candidate form up to ``max_coefficients`` is fitted (minimax in
absolute error by default); the front lists, for each coefficient count, the smallest maximum absolute error
reached on the table's cells when it is at least 1 % below that of every form with fewer coefficients
(:data:`FRONT_STEP`). Candidates proved unable to enter the front are listed in ``tried`` but not fitted
(:data:`PRUNE_MARGIN`): a linear program bounds the max error of a whole rational family from below. The
chosen fit is the one with the fewest coefficients meeting ``target`` (an absolute error), or the most accurate
one when none does.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import ArgumentError
from ..fit import FitResult, auto_candidates, fit, parse_form, smith_candidates
from ..fit.families import SmithForm
from .table import Lut


@dataclass
class TableFit:
    """The chosen fit, the Pareto front and every candidate (form, coefficients, max abs/rel error, pole)."""

    best: FitResult
    front: list[dict]
    tried: list[dict] = field(default_factory=list)
    variables: tuple[str, str] = ("mu", "alpha")
    table: str = "E"


#: A front entry must lower the max abs error of every fit with fewer coefficients by at least this fraction:
#: more coefficients for less than 1 % is not worth it, and the same fit reached by two forms (``smith:1/1@1/2``
#: and ``smith:2/1@1/2`` agree to 10⁻¹⁵) would otherwise enter or not by rounding.
FRONT_STEP = 0.01
#: Errors of one coefficient count within this relative difference are a tie, broken by candidate order (smith
#: forms, then rationals in √μ, each fewest operations first): the fits' last bits vary with the BLAS kernel.
TIE = 1e-9


def table_samples(lut: Lut, table: str = "E") -> tuple[np.ndarray, np.ndarray, np.ndarray, tuple[str, str]]:
    """(x, t, y) over the cells of a two-axis table: x the direction axis as μ, t the other axis."""
    if table not in lut:
        raise ArgumentError(f"no table {table!r} in the lut (tables: {', '.join(lut)})", where="table")
    axes = lut.table_axes[table]
    if len(axes) != 2:
        raise ArgumentError(f"table {table} has {len(axes)} axes ({', '.join(axes) or 'none'}); a fit takes two",
                            where="lut")
    values = np.asarray(lut[table], dtype=float)  # a .h/.exr table is float32; the fit runs in float64
    first, second = axes
    if second in ("mu", "theta") and first not in ("mu", "theta"):
        first, second, values = second, first, values.T
    x = lut.axes[first]
    if first == "theta":  # radians from the API, degrees in a file the command line wrote (meta["units"])
        degrees = lut.meta.get("units", {}).get("theta") == "degrees"
        x, first = np.cos(np.radians(x) if degrees else x), "mu"
    X, T = np.meshgrid(x, lut.axes[second], indexing="ij")
    return X.ravel(), T.ravel(), values.ravel(), (first, second)


def fit_table(lut: Lut, *, table: str = "E", form: str = "auto", metric: str = "minimax-abs",
              target: float = 5e-3, max_coefficients: int = 16, prune: bool = True) -> TableFit:
    """Fit ``table`` over its two axes; ``form="auto"`` tries every candidate up to ``max_coefficients``
    (with ``prune``, those proved unable to enter the front are listed in ``tried`` unfitted: :data:`PRUNE_MARGIN`)."""
    x, t, y, names = table_samples(lut, table)
    if np.any(x < 0):
        raise ArgumentError("the direction axis must be μ ≥ 0 (rationals in √μ)", where="lut")
    limit = min(max_coefficients, x.size)
    if form.strip() != "auto":
        candidates = [parse_form(form, two_d=True)]
    else:
        candidates = auto_candidates(True, limit)
        if names[1] == "alpha":
            candidates = smith_candidates(limit) + candidates
    if any(isinstance(c, SmithForm) for c in candidates) and (names[1] != "alpha" or np.any(x > 1)):
        raise ArgumentError(f"form {form!r} fits E(μ, α): the table's axes must be mu (or theta) and alpha, "
                            f"not {names[0]} and {names[1]}", where="form")
    tried, results = _fit_candidates(candidates, x, t, y, metric, names, prune=prune and form.strip() == "auto")
    if not results:
        raise ArgumentError("every candidate form has a pole over the table", where="form")
    front, best_so_far = [], np.inf
    for count in sorted({len(r.coefficients) for r in results}):
        at_count = [r for r in results if len(r.coefficients) == count]  # in candidate order (TIE)
        smallest = min(r.max_abs_error for r in at_count)
        level = next(r for r in at_count if r.max_abs_error <= smallest * (1 + TIE))
        if level.max_abs_error < (1 - FRONT_STEP) * best_so_far:
            best_so_far = level.max_abs_error
            front.append({"coefficients": count, "form": level.form, "max_abs_error": level.max_abs_error,
                          "max_rel_error": level.max_rel_error, "_result": level})
    meeting = [entry for entry in front if entry["max_abs_error"] <= target]
    chosen = (meeting[0] if meeting else front[-1])["_result"]
    if not meeting:
        chosen.warnings.append(f"no form with ≤ {max_coefficients} coefficients reached the target {target:g} "
                               f"(absolute); this is the most accurate one")
    for entry in front:
        del entry["_result"]
    return TableFit(chosen, front, tried, names, table)


#: A candidate is left unfitted when it is proved that its max abs error exceeds this factor times the smallest
#: one already reached with fewer coefficients: it cannot enter the front (an entry must be strictly smaller),
#: nor change it. The 1 % keeps the proof away from the linear program's feasibility tolerance.
PRUNE_MARGIN = 1.01


def _fit_candidates(candidates: list, x: np.ndarray, t: np.ndarray, y: np.ndarray, metric: str,
                    names: tuple[str, str], prune: bool) -> tuple[list[dict], list[FitResult]]:
    """Fit the candidates in order of coefficient count; ``tried`` in the candidates' order, and the fits
    without a pole. With ``prune``, a candidate whose family provably stays above ``PRUNE_MARGIN`` × the best
    pole-free error of fewer coefficients (:meth:`brdfnorm.fit.families.Form.error_exceeds`) is not fitted: that best
    error is ≥ (1 − FRONT_STEP) × the front's last, so the candidate could neither enter the front nor tie with
    a count's entry; the front and the chosen fit are those of fitting it (tested against ``prune=False``)."""
    tried: list[dict | None] = [None] * len(candidates)
    results: list[FitResult] = []
    best_fewer = np.inf
    for count in sorted({c.n_coefficients for c in candidates}):
        level = [i for i, c in enumerate(candidates) if c.n_coefficients == count]
        bound = PRUNE_MARGIN * best_fewer
        for i in level:
            candidate = candidates[i]
            if prune and np.isfinite(bound) and candidate.error_exceeds(x, t, y, bound):
                tried[i] = {"form": candidate.spec, "coefficients": count, "max_abs_error": None,
                            "max_rel_error": None, "pole": None, "skipped": True, "max_abs_error_above": bound}
                continue
            result = fit(x, y, t, form=candidate, metric=metric, names=names)
            pole = bool(result.warnings)
            tried[i] = {"form": result.form, "coefficients": count, "max_abs_error": result.max_abs_error,
                        "max_rel_error": result.max_rel_error, "pole": pole, "skipped": False}
            if not pole:
                results.append(result)
        best_fewer = min([best_fewer] + [r.max_abs_error for r in results if len(r.coefficients) == count])
    return [entry for entry in tried if entry is not None], results
