"""A white-furnace and physics audit of any BRDF: energy, reciprocity, positivity, finiteness, normalization.

Renderers test energy conservation with a furnace and a few thousand samples; this module answers it with the
exact integrator, over the model's declared parameter ranges and every direction, and says where a lobe fails.

* **energy** — the largest directional albedo E = ∫ f(L, V)(N·L) dL (seed 002's integral, ``over="light"``)
  over parameters and the fixed direction (θ ∈ [0°, 89.9°], and φ for anisotropic lobes): a coarse grid of
  albedo integrals in one batch, then a compass (pattern) search from the best grid points
  (Kolda, Lewis & Torczon 2003, "Optimization by direct search", SIAM Review 45(3), §3), then the best point
  integrated at rtol 1e-10. Verdict with the error bar: *fail* if E − err > 1 + tolerance (the energy gained
  is E − 1), *pass* if E + err ≤ 1 + tolerance, *inconclusive* when the bar straddles the limit. A pass is the
  verdict of a search, not a proof: the coverage says what was searched.
* **reciprocity** — the largest |f(L, V) − f(V, L)| relative to the lobe's scale (the largest |f| sampled at
  the same parameters), on uniform, grazing and structured direction pairs (Helmholtz reciprocity).
* **positivity** / **finiteness** — negative, NaN or ±Inf values on the same pairs, with a pair and the share
  of the domain (the fraction of the pairs drawn uniformly in solid angle) that is affected.
* **normalization** — for lobes meant to be normalized, max |E − 1| at the direction of the convention
  (``at="normal"``: the fixed direction at N; ``"view"``: every grid direction; ``"max"``: the grid maximum).

Parameters: floats with a finite declared range are sampled over it (corners, centre and a scrambled Halton
sequence; on a log1p scale where the range spans more than two decades) and refined continuously; ranges open
above are capped at min + :data:`UNBOUNDED_SPAN`; bools take both values; colours and the names in ``fixed``
keep the bound value; ``sweep`` gives explicit values. Work is bounded by a :class:`Budget` (seconds and/or
integrand evaluations); what was covered is reported.
"""

from __future__ import annotations

import itertools
import time
import warnings
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.stats import qmc

from .albedo import albedo
from .brdffile import random_hemisphere
from .errors import ArgumentError
from .models.base import Model, Over

CHECKS = ("energy", "reciprocity", "positivity", "finiteness", "normalization")
#: What :func:`check` runs when ``checks`` is not given (normalization only for lobes meant to be normalized).
DEFAULT_CHECKS = CHECKS[:4]
AT = ("normal", "max", "view")
THETA_MAX = np.radians(89.9)  # the integrand degenerates at exactly 90°
#: An open parameter range [min, ∞) is searched over [min, min + UNBOUNDED_SPAN] (exponents: README, ≤ 1e5).
UNBOUNDED_SPAN = 1e4
COARSE_RTOL = 1e-4
REFINE_RTOL = 1e-6
FINAL_RTOL = 1e-8
TIGHT_RTOL = 1e-11
#: Most parameter points one check plans (memory and time stay bounded whatever the arguments).
MAX_POINTS = 100_000
#: Evaluations every integral may use whatever the budget says (about five rounds of panels).
MIN_EVALUATIONS = 20_000
#: The final integral of the best point may take this share of the budget even when the search spent it all.
FINAL_SHARE = 0.1
#: Polar angles of the coarse energy grid: uniform in cos θ, so that grazing views are well represented.
THETA_GRID = np.arccos(np.linspace(1.0, np.cos(THETA_MAX), 10))
PHI_GRID = np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
AXES_PHI = np.array([0.0, np.pi / 2])


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


class _Meter:
    """Time and evaluations spent against a :class:`Budget`; ``share`` reserves part of it for a stage."""

    def __init__(self, budget: Budget) -> None:
        self.budget = budget
        self.start = time.perf_counter()
        self.evaluations = 0

    def elapsed(self) -> float:
        return time.perf_counter() - self.start

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


# -- the parameter space ------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Range:
    """A float parameter searched continuously over [low, high] through x ∈ [0, 1]."""

    name: str
    low: float
    high: float
    capped: bool

    @property
    def log(self) -> bool:
        return self.high - self.low > 100.0 and self.low >= 0.0

    def value(self, x: np.ndarray) -> np.ndarray:
        x = np.clip(x, 0.0, 1.0)
        if self.log:  # log1p scale: n = 1, 10, 100, … get equal room (and a minimum of 0 is allowed)
            return self.low + np.expm1(x * np.log1p(self.high - self.low))
        return self.low + x * (self.high - self.low)

    def describe(self) -> str:
        scale = ", log1p scale" if self.log else ""
        cap = f" (declared [{self.low:g}, ∞), capped)" if self.capped else ""
        return f"{self.name} ∈ [{self.low:g}, {self.high:g}]{scale}{cap}"


@dataclass(frozen=True)
class _Space:
    """How each parameter varies: continuous ranges, discrete value lists (sweeps), bool combinations."""

    ranges: tuple[_Range, ...]
    discrete: tuple[tuple[str, np.ndarray], ...]
    bools: tuple[dict, ...]  # every combination of the bool parameters (one dict per combination)
    held: dict  # name -> value kept as bound
    described: tuple[str, ...]


def _space(model: Model, sweep: Mapping[str, object] | None, fixed: Iterable[str]) -> _Space:
    sweep = dict(sweep or {})
    fixed = set(fixed)
    for name in [*sweep, *fixed]:
        model.parameter(name)  # an unknown name fails before any work
    ranges, discrete, bool_names, held, described = [], [], [], {}, []
    bound = model.params
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
        elif p.name in fixed or p.kind == "color" or np.ndim(bound[p.name]) > (1 if p.kind == "color" else 0):
            held[p.name] = bound[p.name]
            described.append(f"{p.name} = {_text(bound[p.name])} (held)")
        elif p.kind == "bool":
            bool_names.append(p.name)
            described.append(f"{p.name} ∈ {{0, 1}}")
        elif p.minimum is None or (p.maximum is not None and p.maximum == p.minimum):
            held[p.name] = bound[p.name]
            described.append(f"{p.name} = {_text(bound[p.name])} (no finite range declared; held)")
        else:
            capped = p.maximum is None
            ranges.append(_Range(p.name, p.minimum, p.minimum + UNBOUNDED_SPAN if capped else p.maximum, capped))
            described.append(ranges[-1].describe())
    bools = tuple(dict(zip(bool_names, combo, strict=True))
                  for combo in itertools.product((False, True), repeat=len(bool_names)))
    return _Space(tuple(ranges), tuple(discrete), bools, held, tuple(described))


def _unit_samples(dimensions: int, count: int, seed: int) -> np.ndarray:
    """Points of [0, 1]^d: the centre, the corners (up to 32), then a scrambled Halton sequence."""
    if dimensions == 0:
        return np.zeros((1, 0))
    if dimensions == 1:
        return np.linspace(0.0, 1.0, max(count, 2))[:, None]
    corners = np.array(list(itertools.product((0.0, 1.0), repeat=dimensions)))[:32]
    halton = qmc.Halton(dimensions, scramble=True, seed=seed).random(max(count - corners.shape[0] - 1, 0))
    return np.vstack([np.full((1, dimensions), 0.5), corners, halton])


@dataclass(frozen=True)
class _Points:
    """Parameter points: per point, a bool combination index, the discrete values and x in [0, 1]^d."""

    combo: np.ndarray  # (P,) int
    discrete: np.ndarray  # (P, D) values
    x: np.ndarray  # (P, d)

    def __len__(self) -> int:
        return self.combo.size

    def take(self, index) -> _Points:
        return _Points(self.combo[index], self.discrete[index], self.x[index])


def _points(space: _Space, count: int, seed: int) -> _Points:
    unit = _unit_samples(len(space.ranges), count, seed)
    lists = [values for _, values in space.discrete]
    combos = list(itertools.product(*lists))
    discrete = np.array(combos, dtype=float) if lists else np.zeros((1, 0))
    # Interleave so that a budget cut short still covers every bool combination and every discrete value.
    rows = [(c, i, j) for j in range(unit.shape[0]) for i in range(discrete.shape[0]) for c in range(len(space.bools))]
    c, i, j = (np.array(a, dtype=int) for a in zip(*rows, strict=True))
    return _Points(c, discrete[i], unit[j])


def _bind(model: Model, space: _Space, points: _Points, combo: int, cases: np.ndarray) -> Model:
    """The model with per-case parameter arrays for the cases (indices into ``points``) of one bool combination."""
    values = dict(space.bools[combo])
    for k, (name, _) in enumerate(space.discrete):
        values[name] = points.discrete[cases, k]
    for k, r in enumerate(space.ranges):
        values[r.name] = r.value(points.x[cases, k])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a slider range is searched on purpose, never beyond it
        return model.with_params(**values)


def _params_at(model: Model, space: _Space, points: _Points, index: int) -> dict:
    params = {name: _plain(value) for name, value in model.params.items() if name in space.held}
    params.update(space.bools[points.combo[index]])
    for k, (name, _) in enumerate(space.discrete):
        params[name] = float(points.discrete[index, k])
    for k, r in enumerate(space.ranges):
        params[r.name] = float(r.value(points.x[index, k]))
    return {p.name: params[p.name] for p in model.parameters}


# -- the energy search --------------------------------------------------------------------------------------

def _albedo(model, space, points, theta, phi, over, rtol, meter, max_evaluations=2_000_000, minimum_seconds=0.0,
            budgeted=True):
    """Albedo (K, C), error (K, C), non-finite share (K,) at points × directions given case by case.

    ``budgeted``: cap each integral's evaluations by what the rest of the budget pays for (the coarse grid is
    bounded by its chunk size instead: a starved narrow-lobe integral there would mislead the ranking).
    """
    K = len(points)
    allowed = meter.allowance(K, minimum_seconds) if budgeted else None
    if allowed is not None:  # at least a few rounds of panels per integral, so that every value has an estimate
        max_evaluations = int(np.clip(allowed, MIN_EVALUATIONS, max_evaluations))
    value, error, bad = np.zeros((K, model.channels)), np.zeros((K, model.channels)), np.zeros(K)
    for combo in np.unique(points.combo):
        cases = np.flatnonzero(points.combo == combo)
        bound = _bind(model, space, points, combo, cases)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # non-convergence and zeroed NaNs are reported from the arrays
            r = albedo(bound, theta[cases], phi[cases], over=over, rtol=rtol, nonfinite="zero",
                       max_evaluations=max_evaluations)
        value[cases], error[cases] = r.value, r.error
        bad[cases] = 0.0 if r.nonfinite_fraction is None else r.nonfinite_fraction
        meter.evaluations += int(r.evaluations.sum())
    return value, error, bad


def _directions(phis: np.ndarray) -> np.ndarray:
    """(θ, φ) pairs of the coarse grid: :data:`THETA_GRID` × ``phis`` (one direction at θ = 0)."""
    return np.array([(t, p) for t in THETA_GRID for p in (phis if t > 0 else [0.0])])


def _scan(model, space, points: _Points, index: np.ndarray, directions, over, meter):
    """Coarse albedo (largest channel) of the parameter points ``index`` × ``directions``: (len(index), D)."""
    D = directions.shape[0]
    value, _, _ = _albedo(model, space, points.take(np.repeat(index, D)), np.tile(directions[:, 0], index.size),
                          np.tile(directions[:, 1], index.size), over, COARSE_RTOL, meter, 400_000, budgeted=False)
    return value.max(axis=1).reshape(index.size, D)


def _energy(model, space, points: _Points, over, tolerance, meter, isotropic) -> tuple[CheckResult, dict]:
    # Anisotropic lobes are scanned along the tangent axes (φ = 0°, 90°) at every parameter point, then over
    # the whole azimuth grid at the best few: parameter space gets the coverage, the refinement moves φ.
    directions = _directions(np.zeros(1) if isotropic else AXES_PHI)
    D = directions.shape[0]
    # Coarse stage: chunks of parameter points × directions, until the points or ~50 % of the budget end.
    best = np.full(len(points), -np.inf)
    best_theta, best_phi = np.zeros(len(points)), np.zeros(len(points))
    done, chunk, started = 0, 1, meter.elapsed()
    while done < len(points) and not (done and meter.spent(0.5)):
        index = np.arange(done, min(done + chunk, len(points)))
        energy = _scan(model, space, points, index, directions, over, meter)
        k = energy.argmax(axis=1)
        best[index], best_theta[index], best_phi[index] = energy.max(axis=1), *directions[k].T
        done = index[-1] + 1
        # Size the next chunk from the time per point so far: one batch is large, yet a small budget holds.
        per_point = (meter.elapsed() - started) / done
        left = None if meter.budget.seconds is None else 0.5 * meter.budget.seconds - meter.elapsed()
        chunk = max(1, min(max(1, 400 // D), int(0.15 * left / per_point) if left is not None and per_point > 0
                            else 400))
    full = 0
    if not isotropic and not meter.spent(0.6):
        index = np.argsort(-best[:done], kind="stable")[:4]
        azimuths = _directions(PHI_GRID)
        energy = _scan(model, space, points, index, azimuths, over, meter)
        k = energy.argmax(axis=1)
        better = energy.max(axis=1) > best[index]
        best[index] = np.maximum(best[index], energy.max(axis=1))
        best_theta[index] = np.where(better, azimuths[k, 0], best_theta[index])
        best_phi[index] = np.where(better, azimuths[k, 1], best_phi[index])
        full = index.size
    coarse_seconds = meter.elapsed() - started
    # Refinement from the best grid points: a compass search over (θ, φ, continuous parameters) in [0, 1]^n.
    order = np.argsort(-best[:done], kind="stable")[:3]
    start = points.take(order)
    theta0, phi0 = best_theta[order], best_phi[order]
    y = np.column_stack([theta0 / THETA_MAX, phi0 / (2 * np.pi), start.x])
    free = np.array([True, not isotropic] + [True] * len(space.ranges))
    step = np.where(np.arange(y.shape[1]) < 2, 0.5 / len(THETA_GRID),
                    0.5 / max(done, 2) ** (1 / max(len(space.ranges), 1)))
    steps = np.tile(step, (y.shape[0], 1))
    current = _y_energy(model, space, start, y, over, meter)
    rounds, finished = 0, False
    while not meter.spent():
        active = steps[:, free].max(axis=1) > 1e-4
        if not active.any():
            finished = True
            break
        rounds += 1
        trials, owners = [], []
        for c in np.flatnonzero(active):
            for k in np.flatnonzero(free):
                for sign in (1.0, -1.0):
                    trial = y[c].copy()
                    trial[k] += sign * steps[c, k]
                    trial[0] = np.clip(trial[0], 0.0, 1.0)
                    trial[1] %= 1.0
                    trial[2:] = np.clip(trial[2:], 0.0, 1.0)
                    if not np.array_equal(trial, y[c]):  # a step out of the box is clipped back onto it
                        trials.append(trial)
                        owners.append(c)
        if not trials:
            steps[active] /= 2.0
            continue
        trials, owners = np.array(trials), np.array(owners)
        energy = _y_energy(model, space, start.take(owners), trials, over, meter)
        for c in np.flatnonzero(active):
            mine = np.flatnonzero(owners == c)
            k = mine[np.argmax(energy[mine])] if mine.size else None
            if k is not None and energy[k] > current[c] * (1.0 + REFINE_RTOL):  # smaller gains are noise
                y[c], current[c] = trials[k], energy[k]
            else:
                steps[c] /= 2.0
    refine_seconds = meter.elapsed() - started - coarse_seconds
    # The best point, integrated tightly: its value and error bar decide. A bar that straddles the limit at
    # rtol 1e-8 is tightened once more (the integrator's estimate is honest, so a verdict never rests on luck).
    c = int(np.argmax(current))
    final = _with_x(start.take([c]), y[[c]])
    limit = 1.0 + tolerance
    for rtol, cap in ((FINAL_RTOL, 4_000_000), (TIGHT_RTOL, 40_000_000)):
        value, error, bad = _albedo(model, space, final, y[[c], 0] * THETA_MAX, y[[c], 1] * 2 * np.pi, over,
                                    rtol, meter, cap, minimum_seconds=FINAL_SHARE * (meter.budget.seconds or 0))
        channel = int(np.argmax(value[0]))
        E, err = float(value[0, channel]), float(error[0, channel])
        status = "fail" if E - err > limit else "pass" if E + err <= limit else "inconclusive"
        if status != "inconclusive":
            break
    params = _params_at(model, space, final, 0)
    theta_deg, phi_deg = float(np.degrees(y[c, 0] * THETA_MAX)), float(np.degrees(y[c, 1] * 2 * np.pi))
    where = f"at {_params_text(params)}, {_fixed_name(over)} θ={theta_deg:.4g}° φ={phi_deg:.4g}°"
    if status == "fail":
        message = f"gains energy: albedo {E:.10g} ± {err:.2g} > 1 + {tolerance:g} (gained {E - 1:.4g}) {where}"
    elif status == "pass":
        message = f"largest albedo found {E:.10g} ± {err:.2g} ≤ 1 + {tolerance:g} {where}"
    else:
        message = (f"inconclusive: largest albedo found {E:.10g} ± {err:.2g} straddles 1 + {tolerance:g} {where}; "
                   "tighten the tolerance or check the integrand")
    if bad[0] > 0:
        message += f"; non-finite values counted as 0 on {100 * bad[0]:.3g}% of the hemisphere there"
    if status != "fail" and (done < len(points) or not finished):
        message += (f"; search cut short by the budget ({done} of {len(points)} parameter points, refinement "
                    f"{'finished' if finished else 'unfinished'})")
    coverage = {"parameter_points": int(done), "parameter_points_planned": len(points), "directions": D,
                "full_azimuth_points": full,
                "refinement_rounds": rounds, "refinement_finished": finished,
                "coarse_seconds": coarse_seconds, "refinement_seconds": refine_seconds}
    sampled = dict(coverage, theta_deg=[0.0, float(np.degrees(THETA_MAX))], phi_swept=not isotropic)
    return CheckResult("energy", status, E, message, error=err, params=params, theta_deg=theta_deg, phi_deg=phi_deg,
                  channel=int(channel), sampled=sampled), coverage


def _with_x(points: _Points, y: np.ndarray) -> _Points:
    return _Points(points.combo, points.discrete, y[:, 2:])


def _y_energy(model, space, points, y, over, meter) -> np.ndarray:
    """The refinement's score: the albedo's lower bound E − error (largest channel). An integral cut short by
    the budget keeps an honest but wide error bar; scoring its lower bound keeps it from steering the search."""
    value, error, _ = _albedo(model, space, _with_x(points, y), y[:, 0] * THETA_MAX, y[:, 1] * 2 * np.pi, over,
                              REFINE_RTOL, meter, 2_000_000)
    return (value - error).max(axis=1)


# -- pointwise checks ---------------------------------------------------------------------------------------

def _pairs(count: int, seed: int) -> tuple[np.ndarray, np.ndarray, int]:
    """Direction pairs: ``count`` uniform in solid angle (the share is measured on these), as many with
    log-uniform N·ω down to 1e-7 (grazing), and a structured grid (normal, mirror, retro, horizon)."""
    rng = np.random.default_rng(seed)
    L, V = random_hemisphere(rng, count), random_hemisphere(rng, count)

    def grazing(n: int) -> np.ndarray:
        z = 10.0 ** rng.uniform(-7.0, 0.0, n)
        phi = rng.uniform(0.0, 2 * np.pi, n)
        r = np.sqrt(1.0 - z * z)
        return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)

    theta = np.radians([0.0, 30.0, 60.0, 85.0, 89.99])
    phi = np.radians([0.0, 90.0, 180.0, 270.0])
    grid = np.array([[np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)] for t in theta
                     for p in (phi if t > 0 else [0.0])])
    gL, gV = np.meshgrid(np.arange(len(grid)), np.arange(len(grid)), indexing="ij")
    L = np.vstack([L, grazing(count), rng.permutation(random_hemisphere(rng, count)), grid[gL.ravel()]])
    V = np.vstack([V, random_hemisphere(rng, count), grazing(count), grid[gV.ravel()]])
    return L, V, count


def _pointwise(model, space, points: _Points, checks, tolerance, pairs, seed, meter) -> tuple[dict, dict]:
    L, V, uniform = _pairs(pairs, seed)
    M = L.shape[0]
    worst = {"reciprocity": (-1.0, None), "positivity": (0.0, None), "finiteness": (0.0, None)}
    bad_counts = {"positivity": [0, 0], "finiteness": [0, 0]}  # [all pairs, uniform pairs]
    done = 0
    for p in range(len(points)):
        if done and meter.spent(0.15):
            break
        bound = _bind(model, space, points, points.combo[p], np.array([p]))
        with np.errstate(all="ignore"):
            forward = bound.eval(L, V)
            backward = bound.eval(V, L) if "reciprocity" in checks else forward
        meter.evaluations += (2 if "reciprocity" in checks else 1) * M
        done += 1
        finite = np.isfinite(forward) & np.isfinite(backward)
        # The lobe's scale per channel: the largest |f| sampled at these parameters, either way round.
        scale = np.max(np.abs(np.where(finite, np.maximum(np.abs(forward), np.abs(backward)), 0.0)), axis=0)
        scale = np.where(scale > 0, scale, 1.0)
        nonfinite = ~np.all(np.isfinite(forward), axis=1)
        negative = np.any(forward < 0, axis=1)
        for name, mask in (("finiteness", nonfinite), ("positivity", negative)):
            bad_counts[name][0] += int(mask.sum())
            bad_counts[name][1] += int(mask[:uniform].sum())
        if nonfinite.any() and worst["finiteness"][1] is None:
            i = int(np.flatnonzero(nonfinite)[0])
            worst["finiteness"] = (1.0, (p, i, forward[i]))
        relative_negative = np.max(np.where(finite, -forward / scale, 0.0), axis=1)
        i = int(np.argmax(relative_negative))
        if relative_negative[i] > max(worst["positivity"][0], 0.0):
            worst["positivity"] = (float(relative_negative[i]), (p, i, forward[i]))
        asymmetry = np.max(np.where(finite, np.abs(forward - backward) / scale, 0.0), axis=1)
        i = int(np.argmax(asymmetry))
        if asymmetry[i] > worst["reciprocity"][0]:
            worst["reciprocity"] = (float(asymmetry[i]), (p, i, forward[i], backward[i]))
    sampled = {"parameter_points": done, "pairs_per_point": M, "uniform_pairs_per_point": uniform,
               "evaluations": done * M * (2 if "reciprocity" in checks else 1)}
    results = {}
    for name in ("reciprocity", "positivity", "finiteness"):
        if name not in checks:
            continue
        amount, at = worst[name]
        share_all, share_uniform = bad_counts.get(name, (0, 0))
        share = share_uniform / max(done * uniform, 1) if name != "reciprocity" else None
        if at is None:
            what = {"reciprocity": "reciprocal", "positivity": "no negative value",
                    "finiteness": "every value finite"}[name]
            results[name] = CheckResult(name, "pass", max(amount, 0.0), f"{what} on {done * M} direction pairs at "
                                        f"{_count(done, 'parameter point')}", share=share, sampled=sampled)
            continue
        p, i = at[0], at[1]
        params = _params_at(model, space, points, p)
        where = f"at {_params_text(params)}, L={_direction_text(L[i])} V={_direction_text(V[i])}"
        if name == "reciprocity":
            status = "fail" if amount > tolerance else "pass"
            message = (f"{'not reciprocal' if status == 'fail' else 'reciprocal'}: largest |f(L,V) − f(V,L)| "
                       f"{amount:.3g} of the lobe's scale (tolerance {tolerance:g}) {where}: f(L,V)="
                       f"{_values_text(at[2])}, f(V,L)={_values_text(at[3])}")
        elif name == "positivity":
            status = "fail"
            message = (f"negative: f = {_values_text(at[2])} ({amount:.3g} of the lobe's scale) {where}; "
                       f"{share_all} of {done * M} pairs negative, {100 * share:.3g}% of the domain")
        else:
            status = "fail"
            amount = share
            message = (f"not finite: f = {_values_text(at[2])} {where}; {share_all} of {done * M} pairs, "
                       f"{100 * share:.3g}% of the domain")
        results[name] = CheckResult(name, status, float(amount), message, params=params, L=_tuple(L[i]),
                                    V=_tuple(V[i]), share=share, sampled=sampled)
    return results, sampled


def _normalization(model, space, points: _Points, at, over, tolerance, meter, isotropic) -> CheckResult:
    directions = np.zeros((1, 2)) if at == "normal" else _directions(np.zeros(1) if isotropic else PHI_GRID)
    D = directions.shape[0]
    P = len(points)
    cases = points.take(np.repeat(np.arange(P), D))
    rtol = FINAL_RTOL if D == 1 else REFINE_RTOL
    value, error, _ = _albedo(model, space, cases, np.tile(directions[:, 0], P), np.tile(directions[:, 1], P),
                              over, rtol, meter)
    value, error = value.reshape(P, D, -1), error.reshape(P, D, -1)
    if at == "max":  # the largest E over directions, per parameter point and channel
        k = value.argmax(axis=1)[:, None, :]
        value, error = np.take_along_axis(value, k, 1), np.take_along_axis(error, k, 1)
        directions_at = directions[k[:, 0, :]]  # (P, C, 2)
    deviation = np.abs(value - 1.0)
    p, d, c = np.unravel_index(np.argmax(deviation), deviation.shape)
    E, err = float(value[p, d, c]), float(error[p, d, c])
    theta, phi = directions_at[p, c] if at == "max" else directions[d]
    params = _params_at(model, space, points, int(p))
    dev = abs(E - 1.0)
    status = "fail" if dev - err > tolerance else "pass" if dev + err <= tolerance else "inconclusive"
    where = f"at {_params_text(params)}, {_fixed_name(over)} θ={np.degrees(theta):.4g}° φ={np.degrees(phi):.4g}°"
    verdict = {"fail": "not normalized", "pass": "normalized", "inconclusive": "inconclusive"}[status]
    message = (f"{verdict} (at {at}): largest |E − 1| {dev:.3g} ± {err:.2g} (tolerance {tolerance:g}), "
               f"E = {E:.10g} {where}")
    return CheckResult("normalization", status, dev, message, error=err, params=params,
                       theta_deg=float(np.degrees(theta)), phi_deg=float(np.degrees(phi)), channel=int(c),
                       sampled={"parameter_points": P, "directions": D, "at": at})


# -- the entry point ----------------------------------------------------------------------------------------

def check(
    model: Model | str | Path,
    *,
    checks: Iterable[str] = DEFAULT_CHECKS,
    sweep: Mapping[str, object] | None = None,
    fixed: Iterable[str] | str = (),
    tolerance: float = 1e-6,
    at: str = "normal",
    over: Over = "light",
    budget: Budget | float | None = None,
    points: int = 48,
    pairs: int = 2048,
    seed: int = 0,
) -> CheckReport:
    """Audit ``model`` (a :class:`Model`, a built-in name or a ``.brdf`` path); see the module docstring.

    ``checks``: names from :data:`CHECKS`; ``sweep``: explicit values per float parameter; ``fixed``: names
    kept at the model's bound values, or ``"all"`` for all of them (the lobe as bound: only directions are
    searched, e.g. for an interactive view); ``tolerance``: on the albedo (energy, normalization) and on the relative
    asymmetry (reciprocity); ``at``: the normalization convention; ``budget``: a :class:`Budget` or seconds
    (default 20 s); ``points``: parameter points of the coarse grid; ``pairs``: uniform direction pairs per
    parameter point (as many grazing ones and a structured grid are added).
    """
    if not isinstance(model, Model):
        from . import load

        model = load(model)
    checks = tuple(dict.fromkeys(checks))
    unknown = [c for c in checks if c not in CHECKS]
    if unknown or not checks:
        raise ArgumentError(f"unknown check {unknown[0]!r} (known: {', '.join(CHECKS)})" if unknown
                            else "no check selected", where="checks")
    if not (np.isfinite(tolerance) and tolerance >= 0):
        raise ArgumentError(f"tolerance must be finite and ≥ 0, got {tolerance!r}", where="tolerance")
    if at not in AT:
        raise ArgumentError(f"unknown convention {at!r} (known: {', '.join(AT)})", where="at")
    if over not in ("light", "view"):
        raise ArgumentError(f"over must be 'light' or 'view', got {over!r}", where="over")
    if points < 1 or pairs < 1:
        raise ArgumentError("points and pairs must be ≥ 1", where="points" if points < 1 else "pairs")
    budget = Budget() if budget is None else budget if isinstance(budget, Budget) else Budget(seconds=budget)
    meter = _Meter(budget)
    if isinstance(fixed, str):
        if fixed != "all":
            raise ArgumentError(f"fixed must be parameter names or 'all', got {fixed!r}", where="fixed")
        fixed = [p.name for p in model.parameters]
    space = _space(model, sweep, fixed)
    planned = len(space.bools) * max(points, 2) * int(np.prod([v.size for _, v in space.discrete]))
    if planned > MAX_POINTS:
        raise ArgumentError(f"{planned} parameter points (bool combinations × swept values × points) exceed "
                            f"{MAX_POINTS}; sweep fewer values or hold parameters fixed",
                            where="sweep" if space.discrete else "points")
    grid = _points(space, points, seed)
    isotropic = bool(model.isotropic)
    results: dict[str, CheckResult] = {}
    pointwise = [c for c in checks if c in ("reciprocity", "positivity", "finiteness")]
    coverage: dict = {"parameters": list(space.described), "parameter_points_planned": len(grid),
                      "isotropic": isotropic, "budget": budget.describe()}
    if pointwise:
        found, coverage["pairs"] = _pointwise(model, space, grid, pointwise, tolerance, pairs, seed, meter)
        results.update(found)
    if "normalization" in checks:  # before the energy search, which takes what is left of the budget
        results["normalization"] = _normalization(model, space, grid, at, over, tolerance, meter, isotropic)
    if "energy" in checks:
        results["energy"], coverage["energy"] = _energy(model, space, grid, over, tolerance, meter, isotropic)
    coverage.update(evaluations=meter.evaluations, elapsed_s=meter.elapsed(), budget_spent=meter.spent())
    ordered = {name: results[name] for name in CHECKS if name in results}
    source = getattr(model, "source_path", None)
    return CheckReport(model.name, source, tolerance, over, ordered, coverage)


# -- text ---------------------------------------------------------------------------------------------------

def _count(number: int, noun: str) -> str:
    return f"{number} {noun}" + ("" if number == 1 else "s")


def _plain(value):
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    array = np.asarray(value, dtype=float)
    return float(array) if array.ndim == 0 else [float(v) for v in array.ravel()]


def _text(value) -> str:
    if isinstance(value, (bool, np.bool_)):
        return str(int(value))
    return ",".join(f"{v:.6g}" for v in np.atleast_1d(np.asarray(value, dtype=float)))


def _params_text(params: dict) -> str:
    return ", ".join(f"{k}={_text(v)}" for k, v in params.items()) or "(no parameters)"


def _direction_text(d: np.ndarray) -> str:
    theta = np.degrees(np.arccos(np.clip(d[2], -1.0, 1.0)))
    phi = np.degrees(np.arctan2(d[1], d[0])) % 360.0
    return f"(θ {theta:.6g}°, φ {phi:.6g}°)"


def _values_text(values: np.ndarray) -> str:
    values = np.atleast_1d(values)
    return f"{values[0]:.6g}" if np.all(values == values[0]) or np.all(np.isnan(values)) else \
        "(" + ", ".join(f"{v:.6g}" for v in values) + ")"


def _tuple(d: np.ndarray) -> tuple[float, float, float]:
    return (float(d[0]), float(d[1]), float(d[2]))


def _fixed_name(over: Over) -> str:
    return "V" if over == "light" else "L"
