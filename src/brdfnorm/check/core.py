"""Results and budget of :func:`brdfnorm.check.check`: :class:`Budget`, :class:`CheckResult`, :class:`CheckReport`,
and the text that names parameter values and directions in their messages."""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from ..engine.compiled.drivers import compile_seconds
from ..errors import ArgumentError
from ..models.base import Over


@dataclass(frozen=True)
class Budget:
    """Bound on the work of one :func:`check`: wall-clock seconds and/or integrand evaluations (None: no bound).

    The final tight albedo of the best point found is always computed, so the energy verdict keeps its
    error bar; the search stages stop when the budget is spent and the coverage says so.
    """

    seconds: float | None = 20.0
    evaluations: int | None = None

    def __post_init__(self) -> None:
        if self.seconds is not None and not (np.isfinite(self.seconds) and self.seconds > 0):
            raise ArgumentError(f"budget seconds must be > 0, got {self.seconds!r}", where="budget")
        if self.evaluations is not None and self.evaluations < 1:
            raise ArgumentError(f"budget evaluations must be ≥ 1, got {self.evaluations!r}", where="budget")

    def describe(self) -> str:
        parts = ([f"{self.seconds:g} s"] if self.seconds is not None else []) + (
            [f"{self.evaluations:.3g} evaluations"] if self.evaluations is not None else [])
        return " and ".join(parts) or "unbounded"


class Meter:
    """Time and evaluations spent against a :class:`Budget`; ``share`` reserves part of it for a stage.
    ``spread``: where the albedo integrals run when not in this process (a :class:`~.cells.SpreadAlbedo`)."""

    def __init__(self, budget: Budget, spread=None) -> None:
        self.budget = budget
        self.spread = spread
        self.start = time.perf_counter()
        self.compiling = compile_seconds()
        self.evaluations = 0

    def elapsed(self) -> float:
        """Seconds spent, less those spent compiling kernels (a first run searches as far as a later one)."""
        return time.perf_counter() - self.start - (compile_seconds() - self.compiling)

    def allowance(self, cases: int, minimum_seconds: float = 0.0) -> float | None:
        """Evaluations per case that the rest of the budget (or at least ``minimum_seconds`` of work) pays for,
        at the rate measured so far; None while nothing bounds it. One albedo call cannot be interrupted, so
        its per-case evaluation cap is what keeps it within the budget (a capped integral keeps an honest error).
        """
        b, limits = self.budget, []
        if b.evaluations is not None:
            limits.append(b.evaluations - self.evaluations)
        if b.seconds is not None and self.evaluations > 0:
            rate = self.evaluations / max(self.elapsed(), 1e-3)
            limits.append(max(b.seconds - self.elapsed(), minimum_seconds) * rate)
        return None if not limits else max(min(limits), 0.0) / max(cases, 1)

    def spent(self, share: float = 1.0) -> bool:
        b = self.budget
        return ((b.seconds is not None and self.elapsed() >= share * b.seconds)
                or (b.evaluations is not None and self.evaluations >= share * b.evaluations))


@dataclass(frozen=True)
class CheckResult:
    """One check's verdict (``pass``, ``fail``, ``inconclusive``), its headline number and where it occurs.

    ``value``: the largest albedo (energy), relative asymmetry (reciprocity), most negative value relative to
    the lobe's scale (positivity), share of non-finite values (finiteness) or max |E − 1| (normalization);
    ``error``: its error estimate where it comes from an integral; ``params``, ``L``, ``V``, ``theta_deg``,
    ``phi_deg``: the worst case found; ``sampled``: what was looked at, in words and numbers.
    """

    name: str
    status: str
    value: float
    message: str
    error: float | None = None
    params: dict = field(default_factory=dict)
    L: tuple[float, float, float] | None = None
    V: tuple[float, float, float] | None = None
    theta_deg: float | None = None
    phi_deg: float | None = None
    channel: int | None = None
    share: float | None = None
    sampled: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return self.status != "fail"


@dataclass(frozen=True)
class CheckReport:
    """All checks of one model, with what was covered (see :func:`check`)."""

    model: str
    source: str | None
    tolerance: float
    over: Over
    results: dict[str, CheckResult]
    coverage: dict

    @property
    def status(self) -> str:
        statuses = [r.status for r in self.results.values()]
        return "fail" if "fail" in statuses else "inconclusive" if "inconclusive" in statuses else "pass"

    @property
    def failed(self) -> list[str]:
        return [name for name, r in self.results.items() if r.status == "fail"]

    @property
    def passed(self) -> bool:
        return not self.failed


def count_text(number: int, noun: str) -> str:
    """``3 points``, ``1 point``: a count with its noun, for the reports' messages."""
    return f"{number} {noun}" + ("" if number == 1 else "s")


def plain(value: object) -> bool | str | float | list[float]:
    """A parameter value as JSON data (a choice or bool as itself, numbers as floats or lists of them)."""
    if isinstance(value, (bool, np.bool_, str)):
        return value if isinstance(value, str) else bool(value)
    array = np.asarray(value, dtype=float)
    return float(array) if array.ndim == 0 else [float(v) for v in array.ravel()]


def value_text(value: object) -> str:
    """A parameter value as the reports print it (6 significant digits, channels joined by commas)."""
    if isinstance(value, str):  # a choice
        return value
    if isinstance(value, (bool, np.bool_)):
        return str(int(value))
    return ",".join(f"{v:.6g}" for v in np.atleast_1d(np.asarray(value, dtype=float)))


def params_text(params: dict) -> str:
    """Parameter values as ``name=value, ...`` (what a failed check names)."""
    return ", ".join(f"{k}={value_text(v)}" for k, v in params.items()) or "(no parameters)"


def direction_text(d: np.ndarray) -> str:
    """A unit direction as its polar and azimuthal angles in degrees."""
    theta = np.degrees(np.arccos(np.clip(d[2], -1.0, 1.0)))
    phi = np.degrees(np.arctan2(d[1], d[0])) % 360.0
    return f"(θ {theta:.6g}°, φ {phi:.6g}°)"


def values_text(values: np.ndarray) -> str:
    """One value, or the channels' values where they differ."""
    values = np.atleast_1d(values)
    return f"{values[0]:.6g}" if np.all(values == values[0]) or np.all(np.isnan(values)) else \
        "(" + ", ".join(f"{v:.6g}" for v in values) + ")"


def direction_tuple(d: np.ndarray) -> tuple[float, float, float]:
    """A direction as JSON data."""
    return (float(d[0]), float(d[1]), float(d[2]))


def fixed_name(over: Over) -> str:
    """The name of the direction held fixed while the other is integrated over."""
    return "V" if over == "light" else "L"
