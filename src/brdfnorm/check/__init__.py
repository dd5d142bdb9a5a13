"""A white-furnace and physics audit of any BRDF: energy, reciprocity, positivity, finiteness, normalization.

Renderers test energy conservation with a furnace and a few thousand samples; this module answers it with the
exact integrator, over the model's declared parameter ranges and every direction, and says where a lobe fails.

* **energy** — the largest directional albedo E = ∫ f(L, V)(N·L) dL (seed 002's integral, ``over="light"``)
  over parameters and the fixed direction (θ ∈ [0°, 89.9°], and φ for anisotropic lobes): a coarse grid of
  albedo integrals in batches, then a compass (pattern) search from the best grid points (Kolda, Lewis &
  Torczon 2003, "Optimization by direct search", SIAM Review 45(3), §3), then the best point integrated at
  rtol 1e-8 (1e-11 if that bar straddles the limit). Verdict with the error bar: *fail* if
  E − err > 1 + tolerance (the energy gained is E − 1), *pass* if E + err ≤ 1 + tolerance, *inconclusive*
  when the bar straddles the limit. A pass is the verdict of a search, not a proof: the coverage says what
  was searched.
* **reciprocity** — the largest |f(L, V) − f(V, L)| relative to the lobe's scale (the largest |f| sampled at
  the same parameters), on uniform, grazing and structured direction pairs (Helmholtz reciprocity).
* **positivity** / **finiteness** — negative, NaN or ±Inf values on the same pairs, with a pair and the share
  of the domain (the fraction of the pairs drawn uniformly in solid angle) that is affected.
* **normalization** — for lobes meant to be normalized, max |E − 1| at the direction of the convention
  (``at="normal"``: the fixed direction at N; ``"view"``: every grid direction; ``"max"``: the grid maximum).

Parameters: floats with a finite declared range are sampled over it (corners, centre and a scrambled Halton
sequence; on a log1p scale where the range spans more than two decades) and refined continuously; ranges open
above are capped at min + :data:`UNBOUNDED_SPAN`; bools take both values; colours, choices and the names in ``fixed``
keep the bound value; ``sweep`` gives explicit values. Work is bounded by a :class:`Budget` (seconds and/or
integrand evaluations); what was covered is reported.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterable, Mapping
from pathlib import Path

import numpy as np

from .. import validate
from ..errors import ArgumentError
from ..models.base import Model, Over
from ..normalization import AT
from .cells import SpreadAlbedo
from .core import Budget, CheckReport, CheckResult, Meter
from .pointwise import check_pointwise
from .search import THETA_MAX, search_energy, search_normalization
from .space import UNBOUNDED_SPAN, parameter_space, sample_points

__all__ = ["AT", "CHECKS", "DEFAULT_CHECKS", "MAX_POINTS", "THETA_MAX", "UNBOUNDED_SPAN", "Budget", "CheckReport",
           "CheckResult", "check"]

CHECKS = ("energy", "reciprocity", "positivity", "finiteness", "normalization")
#: What :func:`check` runs when ``checks`` is not given (normalization only for lobes meant to be normalized).
DEFAULT_CHECKS = CHECKS[:4]
#: Most parameter points one check plans (memory and time stay bounded whatever the arguments).
MAX_POINTS = 100_000


def check(
    model: Model | str | Path,
    *,
    checks: Iterable[str] = DEFAULT_CHECKS,
    sweep: Mapping[str, object] | None = None,
    fixed: Iterable[str] | str = (),
    tolerance: float | None = None,
    at: str = "normal",
    over: Over = "light",
    budget: Budget | float | None = None,
    points: int = 48,
    pairs: int = 2048,
    seed: int = 0,
    workers: int | None = 1,
    scheduler: str | None = None,
    checkpoint: str | Path | None = None,
    chunk_cells: int | None = None,
) -> CheckReport:
    """Audit ``model`` (a :class:`Model`, a built-in name or a ``.brdf`` path); see the module docstring.

    ``checks``: names from :data:`CHECKS`; ``sweep``: explicit values per float parameter; ``fixed``: names
    kept at the model's bound values, or ``"all"`` for all of them (the lobe as bound: only directions are
    searched, e.g. for an interactive view); ``tolerance``: on the albedo (energy, normalization) and on the relative
    asymmetry (reciprocity), by default :func:`default_tolerance`; ``at``: the normalization convention;
    ``budget``: a :class:`Budget` or seconds
    (default 20 s); ``points``: parameter points of the coarse grid; ``pairs``: uniform direction pairs per
    parameter point (as many grazing ones and a structured grid are added).

    ``workers`` (None: all cores; default 1, this process), ``scheduler`` (a Dask address, with
    ``workers=None``), ``checkpoint`` (a directory; needs a budget of evaluations) and ``chunk_cells`` send the
    albedo integrals through :mod:`brdfnorm.parallel` as :func:`brdfnorm.lut.compute` takes them
    (:mod:`.cells`): the report is the same bit for bit under a budget of evaluations.
    """
    if not isinstance(model, Model):
        from .. import load

        model = load(model)
    if isinstance(checks, str):
        checks = (checks,)
    checks = tuple(dict.fromkeys(validate.choice(c, CHECKS, "checks") for c in checks))
    if not checks:
        raise ArgumentError("no check selected", where="checks")
    tolerance = default_tolerance(model) if tolerance is None else validate.real_number(tolerance, "tolerance")
    if tolerance < 0:
        raise ArgumentError(f"must be ≥ 0, got {tolerance:g}", where="tolerance")
    at = validate.choice(at, AT, "at")
    over = validate.choice(over, ("light", "view"), "over")
    points = validate.count(points, "points", maximum=MAX_POINTS)
    pairs = validate.count(pairs, "pairs", maximum=1_000_000)
    if budget is not None and not isinstance(budget, Budget):
        budget = Budget(seconds=validate.real_number(budget, "budget"))
    budget = Budget() if budget is None else budget
    if isinstance(fixed, str):
        if fixed != "all":
            raise ArgumentError(f"fixed must be parameter names or 'all', got {fixed!r}", where="fixed")
        fixed = [p.name for p in model.parameters]
    space = parameter_space(model, sweep, fixed)
    planned = len(space.bools) * max(points, 2) * int(np.prod([v.size for _, v in space.discrete]))
    if planned > MAX_POINTS:
        raise ArgumentError(f"{planned} parameter points (bool combinations × swept values × points) exceed "
                            f"{MAX_POINTS}; sweep fewer values or hold parameters fixed",
                            where="sweep" if space.discrete else "points")
    grid = sample_points(space, points, seed)
    definition = {"checks": checks, "sweep": {k: list(v) for k, v in space.discrete}, "held": sorted(space.held),
                  "tolerance": tolerance, "at": at, "over": over, "points": points, "pairs": pairs, "seed": seed,
                  "budget": {"seconds": budget.seconds, "evaluations": budget.evaluations}, "chunk_cells": chunk_cells}
    spread = SpreadAlbedo(model, definition, budget, workers=workers, scheduler=scheduler, checkpoint=checkpoint,
                          chunk_cells=chunk_cells) \
        if (workers, scheduler, checkpoint, chunk_cells) != (1, None, None, None) else None
    with spread or contextlib.nullcontext():
        return _run(model, checks, space, grid, tolerance, at, over, pairs, seed, Meter(budget, spread))


#: The energy and reciprocity tolerance of a float64 model.
DEFAULT_TOLERANCE = 1e-6
#: A model evaluated in lower precision (its ``epsilon``, Mitsuba's float32: 2⁻²⁴) is checked to this many units of
#: it: float32 albedos carry error bars of ~1.5e-6 (brdfnorm.engine.machinery.rounding.EVALUATION_ULPS), which
#: straddle 1 + 1e-6 for every lobe that keeps all its energy; 256 units (1.5e-5) is ten of those bars.
RESOLVED_ULPS = 256


def default_tolerance(model: Model) -> float:
    """1e-6, or :data:`RESOLVED_ULPS` units of the model's evaluation epsilon where that is coarser."""
    epsilon = getattr(model, "epsilon", None)
    return DEFAULT_TOLERANCE if epsilon is None else max(DEFAULT_TOLERANCE, RESOLVED_ULPS * float(epsilon))


def _run(model: Model, checks: tuple[str, ...], space, grid, tolerance: float, at: str, over: Over, pairs: int,
         seed: int, meter: Meter) -> CheckReport:
    """The selected checks, in order, with what they covered."""
    budget = meter.budget
    isotropic = bool(model.isotropic)
    results: dict[str, CheckResult] = {}
    pointwise = [c for c in checks if c in ("reciprocity", "positivity", "finiteness")]
    coverage: dict = {"parameters": list(space.described), "parameter_points_planned": len(grid),
                      "isotropic": isotropic, "budget": budget.describe()}
    if pointwise:
        found, coverage["pairs"] = check_pointwise(model, space, grid, pointwise, tolerance, pairs, seed, meter)
        results.update(found)
    if "normalization" in checks:  # before the energy search, which takes what is left of the budget
        results["normalization"] = search_normalization(model, space, grid, at, over, tolerance, meter, isotropic)
    if "energy" in checks:
        results["energy"], coverage["energy"] = search_energy(model, space, grid, over, tolerance, meter, isotropic)
    coverage.update(evaluations=meter.evaluations, elapsed_s=meter.elapsed(), budget_spent=meter.spent())
    if meter.spread is not None:
        coverage["parallel"] = meter.spread.coverage()
    ordered = {name: results[name] for name in CHECKS if name in results}
    source = getattr(model, "source_path", None)
    return CheckReport(model.name, source, tolerance, over, ordered, coverage)
