"""The albedo searches of a check: the largest albedo (energy) and the distance from 1 (normalization).

Energy: a coarse grid of albedo integrals over parameter points × view directions in batches, then a compass
(pattern) search from the best grid points (Kolda, Lewis & Torczon 2003, "Optimization by direct search",
SIAM Review 45(3), §3), then the best point integrated at rtol 1e-8 (1e-11 if the error bar straddles the
limit). Work is bounded by the :class:`~brdfnorm.check.core.Budget` through :class:`~.core._Meter`.
"""

from __future__ import annotations

import warnings

import numpy as np

from ..engine.methods import albedo
from ..output.formats import format_error
from .core import CheckResult, fixed_name, params_text
from .space import Points, bind_case, case_values, params_at

THETA_MAX = np.radians(89.9)  # the integrand degenerates at exactly 90°
COARSE_RTOL = 1e-4
REFINE_RTOL = 1e-6
FINAL_RTOL = 1e-8
TIGHT_RTOL = 1e-11
#: Evaluations every integral may use whatever the budget says (about five rounds of panels).
MIN_EVALUATIONS = 20_000
#: The final integral of the best point may take this share of the budget even when the search spent it all.
FINAL_SHARE = 0.1
#: Polar angles of the coarse energy grid: uniform in cos θ, so that grazing views are well represented.
THETA_GRID = np.arccos(np.linspace(1.0, np.cos(THETA_MAX), 10))
PHI_GRID = np.linspace(0.0, 2 * np.pi, 8, endpoint=False)
AXES_PHI = np.array([0.0, np.pi / 2])


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
        if meter.spread is not None:  # through brdfnorm.parallel: the same values (check/cells.py)
            bools, per_case = case_values(space, points, combo, cases)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # a slider range is searched on purpose, never beyond it
                bound = model.with_params(**bools)
            value[cases], error[cases], bad[cases], spent = meter.spread.albedo(
                bound, theta[cases], phi[cases], per_case, over=over, rtol=rtol, max_evaluations=max_evaluations)
            meter.evaluations += spent
            continue
        bound = bind_case(model, space, points, combo, cases)
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


def _scan(model, space, points: Points, index: np.ndarray, directions, over, meter):
    """Coarse albedo (largest channel) of the parameter points ``index`` × ``directions``: (len(index), D)."""
    D = directions.shape[0]
    value, _, _ = _albedo(model, space, points.take(np.repeat(index, D)), np.tile(directions[:, 0], index.size),
                          np.tile(directions[:, 1], index.size), over, COARSE_RTOL, meter, 400_000, budgeted=False)
    return value.max(axis=1).reshape(index.size, D)


def search_energy(model, space, points: Points, over, tolerance, meter, isotropic) -> tuple[CheckResult, dict]:
    # Anisotropic lobes are scanned along the tangent axes (φ = 0°, 90°) at every parameter point, then over
    # the whole azimuth grid at the best few: parameter space gets the coverage, the refinement moves φ.
    directions = _directions(np.zeros(1) if isotropic else AXES_PHI)
    D = directions.shape[0]
    # Coarse stage: chunks of parameter points × directions, until the points or ~50 % of the budget end.
    best = np.full(len(points), -np.inf)
    best_theta, best_phi = np.zeros(len(points)), np.zeros(len(points))
    done, chunk, started, per_point = 0, 1, meter.elapsed(), 0.0
    while done < len(points) and not (done and meter.spent(0.5)):
        index = np.arange(done, min(done + chunk, len(points)))
        chunk_started = meter.elapsed()
        energy = _scan(model, space, points, index, directions, over, meter)
        k = energy.argmax(axis=1)
        best[index], best_theta[index], best_phi[index] = energy.max(axis=1), *directions[k].T
        done = index[-1] + 1
        # Size the next chunk from the slowest point cost seen so far (costs vary with the parameters: a shader
        # loop may run 100× longer at one corner): one batch is large, yet a small budget holds.
        per_point = max(per_point, (meter.elapsed() - chunk_started) / index.size)
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
    params = params_at(model, space, final, 0)
    theta_deg, phi_deg = float(np.degrees(y[c, 0] * THETA_MAX)), float(np.degrees(y[c, 1] * 2 * np.pi))
    where = f"at {params_text(params)}, {fixed_name(over)} θ={theta_deg:.4g}° φ={phi_deg:.4g}°"
    shown = format_error(err, 2)  # rounded up: the printed error is never below the estimate
    if status == "fail":
        message = f"gains energy: albedo {E:.10g} ± {shown} > 1 + {tolerance:g} (gained {E - 1:.4g}) {where}"
    elif status == "pass":
        message = f"largest albedo found {E:.10g} ± {shown} ≤ 1 + {tolerance:g} {where}"
    else:
        message = (f"inconclusive: largest albedo found {E:.10g} ± {shown} straddles 1 + {tolerance:g} {where}; "
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


def _with_x(points: Points, y: np.ndarray) -> Points:
    return Points(points.combo, points.discrete, y[:, 2:])


def _y_energy(model, space, points, y, over, meter) -> np.ndarray:
    """The refinement's score: the albedo's lower bound E − error (largest channel). An integral cut short by
    the budget keeps an honest but wide error bar; scoring its lower bound keeps it from steering the search."""
    value, error, _ = _albedo(model, space, _with_x(points, y), y[:, 0] * THETA_MAX, y[:, 1] * 2 * np.pi, over,
                              REFINE_RTOL, meter, 2_000_000)
    return (value - error).max(axis=1)


def search_normalization(model, space, points: Points, at, over, tolerance, meter, isotropic) -> CheckResult:
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
    params = params_at(model, space, points, int(p))
    dev = abs(E - 1.0)
    status = "fail" if dev - err > tolerance else "pass" if dev + err <= tolerance else "inconclusive"
    where = f"at {params_text(params)}, {fixed_name(over)} θ={np.degrees(theta):.4g}° φ={np.degrees(phi):.4g}°"
    verdict = {"fail": "not normalized", "pass": "normalized", "inconclusive": "inconclusive"}[status]
    message = (f"{verdict} (at {at}): largest |E − 1| {dev:.3g} ± {format_error(err, 2)} (tolerance {tolerance:g}), "
               f"E = {E:.10g} {where}")
    return CheckResult("normalization", status, dev, message, error=err, params=params,
                       theta_deg=float(np.degrees(theta)), phi_deg=float(np.degrees(phi)), channel=int(c),
                       sampled={"parameter_points": P, "directions": D, "at": at})
