"""The parameter space a check searches: continuous ranges, swept values, bool combinations, held values.

Floats with a finite declared range are searched through x ∈ [0, 1] (a log1p scale where the range spans more
than two decades), sampled at the centre, the corners and a scrambled Halton sequence; ranges open above are
capped at min + :data:`UNBOUNDED_SPAN`; ``int`` parameters (table sizes) at whole numbers only; bools take both
values; per-channel numbers (colours, spectra), choices and held names keep the bound value.
"""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from ..models.base import Model
from .core import plain, value_text

#: An open parameter range [min, ∞) is searched over [min, min + UNBOUNDED_SPAN] (exponents: README, ≤ 1e5).
UNBOUNDED_SPAN = 1e4


@dataclass(frozen=True)
class _Range:
    """A float parameter searched continuously over [low, high] through x ∈ [0, 1]."""

    name: str
    low: float
    high: float
    capped: bool
    integer: bool = False  # an int parameter (a table size): searched at whole numbers only

    @property
    def log(self) -> bool:
        return self.high - self.low > 100.0 and self.low >= 0.0

    def value(self, x: np.ndarray) -> np.ndarray:
        x = np.clip(x, 0.0, 1.0)
        if self.log:  # log1p scale: n = 1, 10, 100, … get equal room (and a minimum of 0 is allowed)
            value = self.low + np.expm1(x * np.log1p(self.high - self.low))
        else:
            value = self.low + x * (self.high - self.low)
        if self.integer:
            value = np.clip(np.rint(value), np.ceil(self.low), np.floor(self.high))
        return np.clip(value, self.low, self.high)  # rounding must not step outside a hard range

    def describe(self) -> str:
        scale = ", log1p scale" if self.log else ""
        cap = f" (declared [{self.low:g}, ∞), capped)" if self.capped else ""
        whole = ", whole numbers" if self.integer else ""
        return f"{self.name} ∈ [{self.low:g}, {self.high:g}]{scale}{whole}{cap}"


@dataclass(frozen=True)
class ParameterSpace:
    """How each parameter varies: continuous ranges, discrete value lists (sweeps), bool combinations."""

    ranges: tuple[_Range, ...]
    discrete: tuple[tuple[str, np.ndarray], ...]
    bools: tuple[dict, ...]  # every combination of the bool parameters (one dict per combination)
    held: dict  # name -> value kept as bound
    described: tuple[str, ...]


def parameter_space(model: Model, sweep: Mapping[str, object] | None, fixed: Iterable[str]) -> ParameterSpace:
    sweep = dict(sweep or {})
    fixed = set(fixed)
    for name in [*sweep, *fixed]:
        model.parameter(name)  # an unknown name fails before any work
    ranges, discrete, bool_names, held, described = [], [], [], {}, []
    bound = model.params
    narrowed = model.search_space()  # ranges that depend on other parameters, or settings to hold
    for p in model.parameters:
        if p.name in sweep:
            if p.kind != "float":
                raise ArgumentError(f"only float parameters can be swept; {p.name} is {p.kind}", where="sweep")
            values = np.asarray(sweep[p.name], dtype=float).ravel()
            if values.size == 0:
                raise ArgumentError(f"the sweep over {p.name} is empty", where="sweep")
            model.with_params(**{p.name: values})  # validates the values (hard ranges)
            discrete.append((p.name, values))
            described.append(f"{p.name}: {values.size} given values")
        elif (p.name in fixed or p.per_channel or p.kind == "choice"
              or (p.name in narrowed and narrowed[p.name] is None)
              or np.ndim(bound[p.name]) > (1 if p.per_channel else 0)):
            held[p.name] = bound[p.name]
            described.append(f"{p.name} = {value_text(bound[p.name])} (held)")
        elif p.kind == "bool":
            bool_names.append(p.name)
            described.append(f"{p.name} ∈ {{0, 1}}")
        elif p.name in narrowed:
            low, high = narrowed[p.name]
            ranges.append(_Range(p.name, low, high, False, p.kind == "int"))
            described.append(ranges[-1].describe() + f" (declared {p.describe_range()}; narrowed by the model)")
        elif p.minimum is None or (p.maximum is not None and p.maximum == p.minimum):
            held[p.name] = bound[p.name]
            described.append(f"{p.name} = {value_text(bound[p.name])} (no finite range declared; held)")
        else:
            capped = p.maximum is None
            ranges.append(_Range(p.name, p.minimum, p.minimum + UNBOUNDED_SPAN if capped else p.maximum, capped,
                                 p.kind == "int"))
            described.append(ranges[-1].describe())
    bools = tuple(dict(zip(bool_names, combo, strict=True))
                  for combo in itertools.product((False, True), repeat=len(bool_names)))
    return ParameterSpace(tuple(ranges), tuple(discrete), bools, held, tuple(described))


def _unit_samples(dimensions: int, count: int, seed: int) -> np.ndarray:
    """Points of [0, 1]^d: the centre, the corners (up to 32), then a scrambled Halton sequence — an order in
    which every prefix is spread over the whole box, so a search cut short by its budget still covers it."""
    if dimensions == 0:
        return np.zeros((1, 0))
    # Imported here: scipy.stats costs ~0.5 s to import, which every CLI command would pay at start-up.
    from scipy.stats import qmc

    corners = np.array(list(itertools.product((0.0, 1.0), repeat=dimensions)))[:32]
    halton = qmc.Halton(dimensions, scramble=True, seed=seed).random(max(count - corners.shape[0] - 1, 0))
    return np.vstack([np.full((1, dimensions), 0.5), corners, halton])


@dataclass(frozen=True)
class Points:
    """Parameter points: per point, a bool combination index, the discrete values and x in [0, 1]^d."""

    combo: np.ndarray  # (P,) int
    discrete: np.ndarray  # (P, D) values
    x: np.ndarray  # (P, d)

    def __len__(self) -> int:
        return self.combo.size

    def take(self, index) -> Points:
        return Points(self.combo[index], self.discrete[index], self.x[index])


def sample_points(space: ParameterSpace, count: int, seed: int) -> Points:
    """``count`` points of the space (every bool combination and discrete value interleaved), reproducibly."""
    unit = _unit_samples(len(space.ranges), count, seed)
    lists = [values for _, values in space.discrete]
    combos = list(itertools.product(*lists))
    discrete = np.array(combos, dtype=float) if lists else np.zeros((1, 0))
    # Interleave so that a budget cut short still covers every bool combination and every discrete value.
    rows = [(c, i, j) for j in range(unit.shape[0]) for i in range(discrete.shape[0]) for c in range(len(space.bools))]
    c, i, j = (np.array(a, dtype=int) for a in zip(*rows, strict=True))
    return Points(c, discrete[i], unit[j])


def case_values(space: ParameterSpace, points: Points, combo: int, cases: np.ndarray) -> tuple[dict, dict]:
    """The bool values of combination ``combo`` and the per-case float values of the cases (indices into
    ``points``) that belong to it."""
    per_case = {name: points.discrete[cases, k] for k, (name, _) in enumerate(space.discrete)}
    per_case.update({r.name: r.value(points.x[cases, k]) for k, r in enumerate(space.ranges)})
    return dict(space.bools[combo]), per_case


def bind_case(model: Model, space: ParameterSpace, points: Points, combo: int, cases: np.ndarray) -> Model:
    """The model with per-case parameter arrays for the cases (indices into ``points``) of one bool combination."""
    bools, per_case = case_values(space, points, combo, cases)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a slider range is searched on purpose, never beyond it
        return model.with_params(**bools, **per_case)


def params_at(model: Model, space: ParameterSpace, points: Points, index: int) -> dict:
    """Every parameter's value at point ``index``, as JSON data (what a failed check reports)."""
    params = {name: plain(value) for name, value in model.params.items() if name in space.held}
    params.update(space.bools[points.combo[index]])
    for k, (name, _) in enumerate(space.discrete):
        params[name] = float(points.discrete[index, k])
    for k, r in enumerate(space.ranges):
        params[r.name] = float(r.value(points.x[index, k]))
    return {p.name: params[p.name] for p in model.parameters}
