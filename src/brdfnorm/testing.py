"""Assertions for users' own test suites: energy conservation, reciprocity and normalization of a BRDF.

Each runs :func:`brdfnorm.check.check` with one check and raises :class:`AssertionError` naming the offending
parameter values and directions; on success it returns the :class:`~brdfnorm.check.CheckReport`, whose
coverage says what was searched. Usable from pytest without brdfnorm's command line::

    from brdfnorm.testing import assert_energy_conserving

    def test_my_lobe_conserves_energy():
        assert_energy_conserving("shaders/my_lobe.brdf", sweep={"roughness": [0.05, 0.3, 1.0]})

An inconclusive energy or normalization verdict (the error bar straddles the limit) fails too: an assertion
holds only when it is shown to hold.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from pathlib import Path

from .check import Budget, CheckReport, check
from .models.base import Model, Over

__all__ = ["assert_energy_conserving", "assert_material_furnace", "assert_normalized", "assert_reciprocal"]


def _assert(report: CheckReport, name: str, claim: str) -> CheckReport:
    result = report.results[name]
    if result.status != "pass":
        covered = report.coverage.get("energy") or report.coverage.get("pairs") or {}
        where = ", ".join(f"{k}={v}" for k, v in covered.items() if k in ("parameter_points", "directions",
                                                                         "pairs_per_point"))
        raise AssertionError(f"{report.source or report.model} {claim}: {result.message}"
                             + (f" [searched {where}]" if where else ""))
    return report


def assert_energy_conserving(model: Model | str | Path, sweep: Mapping[str, object] | None = None,
                             tolerance: float = 1e-6, *, fixed: Iterable[str] = (), over: Over = "light",
                             budget: Budget | float | None = None, points: int = 48) -> CheckReport:
    """Assert that the largest albedo over the parameters and directions is at most 1 + ``tolerance``."""
    report = check(model, checks=("energy",), sweep=sweep, fixed=fixed, tolerance=tolerance, over=over,
                   budget=budget, points=points)
    return _assert(report, "energy", "is not shown to conserve energy")


def assert_reciprocal(model: Model | str | Path, sweep: Mapping[str, object] | None = None,
                      tolerance: float = 1e-6, *, fixed: Iterable[str] = (), budget: Budget | float | None = None,
                      points: int = 48, pairs: int = 2048) -> CheckReport:
    """Assert |f(L, V) − f(V, L)| ≤ ``tolerance`` × the lobe's scale on the sampled pairs and parameters."""
    report = check(model, checks=("reciprocity",), sweep=sweep, fixed=fixed, tolerance=tolerance, budget=budget,
                   points=points, pairs=pairs)
    return _assert(report, "reciprocity", "is not reciprocal")


def assert_normalized(model: Model | str | Path, sweep: Mapping[str, object] | None = None,
                      tolerance: float = 1e-6, *, at: str = "normal", fixed: Iterable[str] = (),
                      over: Over = "light", budget: Budget | float | None = None, points: int = 48) -> CheckReport:
    """Assert |E − 1| ≤ ``tolerance`` at the direction of the convention ``at`` for every parameter point."""
    report = check(model, checks=("normalization",), sweep=sweep, fixed=fixed, tolerance=tolerance, at=at,
                   over=over, budget=budget, points=points)
    return _assert(report, "normalization", f"is not normalized (at {at})")


def assert_material_furnace(model: Model | str | Path, tolerance: float = 1e-9, *, theta: Iterable[float] | None = None,
                            **params: object):
    """Assert that a material (``openpbr``, a material file, or any model) reflects 1 ± ``tolerance`` at every view
    of its white furnace (:func:`brdfnorm.materials.furnace.furnace`; ``theta`` in radians, default 30 views to
    89.9°), counting each albedo's error estimate against it; returns the :class:`~brdfnorm.materials.furnace.
    Furnace`. ``params`` are bound first (e.g. ``layering="symmetric"``)."""
    import numpy as np

    from . import load
    from .materials.furnace import furnace

    if not isinstance(model, Model):
        model = load(model, **params)
    elif params:
        model = model.with_params(**params)
    result = furnace(model, None if theta is None else np.asarray(list(theta), dtype=float))
    worst = np.abs(result.value - 1.0) + result.error
    if worst.max() > tolerance:
        i = int(np.unravel_index(np.argmax(worst), worst.shape)[0])
        raise AssertionError(f"{model.source_path or model.name} fails the white furnace: E = "
                             f"{result.value[i].max():.12g} (residual {result.max_residual:.3e}) at θ = "
                             f"{np.degrees(result.theta[i]):g}°, tolerance {tolerance:g}")
    return result
