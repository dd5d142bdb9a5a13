"""The generic albedo route, method ``"quadrature"``, for any model: the lobe's hint (or a search for it), then the
adaptive hemisphere quadrature of :mod:`.hemisphere` with the half-vector route of :mod:`.halfvector_generic` tried
first for isotropic lobes centred on the mirror direction; a BSDF's lower hemisphere as a second, mirrored
hemisphere integral about the refraction direction. A BRDF whose values are finite but near float64's limit (2e307)
is integrated divided by a power of two, so that the sums do not overflow; a BRDF that is NaN or infinite is
reported at a real (L, V) pair.

``problem`` is the front door's batch (:class:`brdfnorm.engine.methods.Problem`: ``model``, ``fixed`` directions,
``integrand``, per-case parameters, ``over``; the compiled integrand ``native`` where there is one).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from functools import partial

import numpy as np

from ...errors import EvaluationError
from ...models.base import Lobe, mirror
from ..machinery import partition
from ..machinery.directions import random_hemisphere, rotation_about_normal
from ..machinery.lobe_search import Peaks, fibonacci_hemisphere, search_lobes
from ..machinery.result import RouteResult
from . import halfvector_generic
from .hemisphere import NonFiniteIntegrand, NonFinitePolicy, integrate_hemisphere

#: An integrand whose sampled values exceed this is integrated divided by a power of two (the sums of values near
#: float64's limit, such as a BRDF of 2e307, overflow although the albedo itself is finite).
LARGE_VALUE = 1e150
#: Directions per case sampled to find that power of two (only after an overflow), as many as the lobe search.
SCALE_SAMPLES = 1024


def albedo_method(problem, *, rtol: float, atol: float, nonfinite: NonFinitePolicy,
                  max_evaluations: int, **_: object) -> RouteResult:
    """Method ``"quadrature"``: the albedo of a :class:`brdfnorm.engine.methods.Problem`'s batch over the upper
    hemisphere, and for a BSDF also over the lower one (both parts in the extras ``reflected``, ``transmitted``)."""
    options = dict(rtol=rtol, atol=atol, nonfinite=nonfinite, max_evaluations=max_evaluations)
    upper = _quadrature_hemisphere(problem, False, options)
    if not getattr(problem.model, "transmits", False):
        return upper
    # A BSDF: the lower hemisphere as a second hemisphere integral, mirrored into the upper one (ω_z → −ω_z),
    # about its own peak, the refraction direction.
    lower = _quadrature_hemisphere(problem, True, options)
    return RouteResult(upper.value + lower.value, upper.error + lower.error, upper.evaluations + lower.evaluations,
                       upper.converged & lower.converged, np.where(upper.reason != "", upper.reason, lower.reason),
                       {"nonfinite_fraction": upper.nonfinite_fraction + lower.nonfinite_fraction,
                        "reflected": upper.value, "transmitted": lower.value})


#: ω_z → −ω_z: the lower hemisphere of a BSDF integrated as an upper one.
FLIP = np.array([1.0, 1.0, -1.0])


def _quadrature_hemisphere(problem, lower: bool, options: dict) -> RouteResult:
    where = problem.model.source_path or problem.model.name
    # Overflow in the lobe search or the sums is handled here, never shown as numpy's warning.
    with np.errstate(all="ignore"):
        try:
            outcome = _integrate(problem, None, lower, **options)
            overflowed = not (np.all(np.isfinite(outcome.value)) and np.all(np.isfinite(outcome.error)))
        except NonFiniteIntegrand as bad:
            if np.all(np.isfinite(bad.direction)):  # the BRDF itself is NaN or infinite there
                raise EvaluationError(_nonfinite_message(problem, bad), where=where) from None
            overflowed = True
        if overflowed:
            try:
                scale = _scales(problem, options["nonfinite"])  # raises where the BRDF is not finite
                if not np.any(scale > 1.0):
                    raise EvaluationError("the integration overflowed, yet no sampled BRDF value is large",
                                          where=where)
                outcome = _integrate(problem, scale, lower, **options)
            except NonFiniteIntegrand as bad:
                raise EvaluationError(_nonfinite_message(problem, bad), where=where) from None
            if not (np.all(np.isfinite(outcome.value)) and np.all(np.isfinite(outcome.error))):
                raise EvaluationError("the albedo or its error estimate exceeds float64's range", where=where)
    return outcome


def _integrate(problem, scale: np.ndarray | None, lower: bool = False, *, rtol: float, atol: float,
               nonfinite: NonFinitePolicy, max_evaluations: int) -> RouteResult:
    """The lobe hint (or search) and the adaptive cubature, of the integrand divided by ``scale`` per case; with
    ``lower``, of the lower hemisphere mirrored into the upper one. A case where the search finds separated peaks
    is integrated as one sub-case per peak (brdfnorm.engine.machinery.partition), the others as before."""
    K = problem.fixed.shape[0]
    options = dict(rtol=rtol, atol=atol / (1.0 if scale is None else scale.max()), nonfinite=nonfinite,
                   max_evaluations=max_evaluations)
    if lower:
        refracted = problem.model.transmission_lobe(problem.fixed, problem.case_params(np.arange(K)))
        lobe = Lobe(refracted.direction * FLIP, refracted.width, refracted.support)
    else:
        lobe = problem.model.lobe(problem.fixed, problem.case_params(np.arange(K)), problem.over)
    # Isotropy decides the half-vector route, the global rule's azimuth estimate, and which cases have no separated
    # peaks: an isotropic lobe at a fixed direction along N is rotation-invariant about N (its maxima off N are rings).
    isotropic = _isotropic_cases(problem, rtol)
    if lobe is not None:
        poles = np.broadcast_to(lobe.direction, (K, 3))
        widths, supports = np.broadcast_to(lobe.width, (K,)), np.broadcast_to(lobe.support, (K,))
        return _cubature(problem, scale, lower, isotropic, poles, widths, supports, **options)
    normal = np.broadcast_to([0.0, 0.0, 1.0], problem.fixed.shape)
    candidates = np.stack([mirror(problem.fixed), problem.fixed, normal], axis=1)
    axial = isotropic & (np.hypot(problem.fixed[:, 0], problem.fixed[:, 1]) <= AXIAL)
    # (a bump whose contribution is below rtol/64 of the main peak's is charged, not integrated about its own pole)
    poles, widths, supports, peaks = search_lobes(_integrand(problem, scale, lower), K, candidates=candidates,
                                                  negligible=rtol / 64, axial=axial)
    count = peaks.count(K)
    if np.all(count == 1):  # (the whole batch as it is, compiled kernels and all)
        result = _cubature(problem, scale, lower, isotropic, poles, widths, supports, **options)
        return _joined([(np.arange(K), result)], K, peaks, scale, rtol, atol)

    def part(cases: np.ndarray, *args, **changes) -> RouteResult:
        """The cubature of ``problem`` restricted to ``cases`` (its non-finite values reported at their own case)."""
        try:
            return _cubature(_take(problem, cases), None if scale is None else scale[cases], lower, isotropic[cases],
                             *args, **{**options, **changes})
        except NonFiniteIntegrand as bad:
            case = int(cases[bad.case])
            value = _integrand(problem, scale, lower)(bad.direction[None], np.array([case]))[0]
            raise NonFiniteIntegrand(case, bad.direction, value) from None

    single = np.flatnonzero(count == 1)
    parts = [(single, part(single, poles[single], widths[single], supports[single]))] if single.size else []
    for m in np.unique(count[count > 1]):
        # each peak's sub-case with its share of the case's budget and absolute tolerance, both tolerances divided by
        # the margin fold charges
        cases = np.flatnonzero(count == m)
        sub = partition.expand(poles, widths, supports, peaks, cases)
        result = part(cases[sub.owner], sub.poles, sub.widths, sub.supports, sub, rtol=rtol / partition.MARGIN,
                      atol=options["atol"] / (m * partition.MARGIN), max_evaluations=max_evaluations // m)
        folded = partition.fold(result, sub, cases.size)  # (the isotropy test ran on every case: charged here too)
        parts.append((cases, folded.with_(evaluations=folded.evaluations + 3 * ISOTROPY_PAIRS)))
    return _joined(parts, K, peaks, scale, rtol, atol)


def _joined(parts: list, K: int, peaks: Peaks, scale: np.ndarray | None, rtol: float, atol: float) -> RouteResult:
    """The parts' results (cases, result) as one of the K cases, with the search's evaluations and the charge of the
    separated peaks no sub-case integrated (times ``scale``, the search's integrand having been divided by it). A
    case with a charge or several peaks that is past its tolerance is not converged: "budget", the cap on peaks per
    case (the others keep their route's verdict)."""
    channels = parts[0][1].value.shape[1:]
    value, error = np.zeros((K,) + channels), np.zeros((K,) + channels)
    evaluations, converged = peaks.evaluations.copy(), np.zeros(K, dtype=bool)
    reason, nonfinite = np.full(K, "", dtype=object), np.zeros(K)
    for cases, result in parts:
        value[cases], error[cases] = result.value, result.error
        evaluations[cases] += result.evaluations
        converged[cases], reason[cases] = result.converged, result.reasons()
        nonfinite[cases] = result.nonfinite_fraction
    error += (peaks.charge * (1.0 if scale is None else scale))[:, None]
    checked = (peaks.charge > 0) | (peaks.count(K) > 1)
    over = checked & converged & np.any(error > np.maximum(atol, rtol * np.abs(value)), axis=1)
    converged &= ~over
    reason[over] = "budget"
    return RouteResult(value, error, evaluations, converged, reason.astype(str), {"nonfinite_fraction": nonfinite})


def _integrand(problem, scale: np.ndarray | None, lower: bool):
    """The integrand of ``problem``'s cases divided by ``scale`` (None: 1, and the compiled integrand itself where
    there is one: the routes then run their fused kernels on it); with ``lower``, mirrored (ω_z → −ω_z)."""
    side = (lambda omega, case: problem.integrand(omega * FLIP, case)) if lower else problem.integrand
    if scale is None:
        return problem.native if problem.native is not None and not lower else side

    def integrand(omega: np.ndarray, case: np.ndarray) -> np.ndarray:
        return side(omega, case) / scale[case, None]

    return integrand


def _take(problem, cases: np.ndarray):
    """``problem`` restricted to ``cases`` (repeats allowed): its case i is case ``cases[i]``."""
    params = {name: np.asarray(value)[cases] if name in problem.per_case else value
              for name, value in problem.params.items()}
    native = None if problem.native is None else problem.native.take(cases)
    return replace(problem, fixed=problem.fixed[cases], params=params, native=native)


def _cubature(problem, scale: np.ndarray | None, lower: bool, isotropic: np.ndarray, poles: np.ndarray,
              widths: np.ndarray, supports: np.ndarray, sub: partition.SubCases | None = None, *, rtol: float,
              atol: float, nonfinite: NonFinitePolicy, max_evaluations: int) -> RouteResult:
    """The adaptive cubature of :mod:`.hemisphere` about ``poles``, of ``problem``'s integrand (divided by
    ``scale``, mirrored with ``lower``; ``isotropic`` (K,) its cases rotation-invariant, :func:`_isotropic_cases`)
    — or, with ``sub``, of its sub-cases' g·ψ (no half-vector route: it assumes a lobe centred on the mirror
    direction; every sub-case anisotropic: ψ breaks any symmetry about its pole)."""
    K = problem.fixed.shape[0]
    integrand = _integrand(problem, scale, lower)
    factor = np.ones(K) if scale is None else scale

    def rescaled(change: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
        """The integrand (by numpy) with each case's fixed direction scaled by ``change`` (K,), for the bias of the
        lobe's cosine (brdfnorm.engine.machinery.rounding.cosine_bias)."""
        moved = replace(problem, fixed=problem.fixed * change[:, None], native=None)
        def plain(omega: np.ndarray, case: np.ndarray) -> np.ndarray:
            return moved.integrand(omega * FLIP if lower else omega, case) / factor[case, None]

        return plain if sub is None else sub.wrap(plain)

    if sub is None:
        # The half-vector route first, on the upper hemisphere (brdfnorm.engine.routes.halfvector_generic says which
        # lobes it takes); isotropy decides that and the global rule's azimuth estimate.
        first = None if lower else partial(halfvector_generic.route, problem.fixed, isotropic)
        anisotropic, tested = ~isotropic, 3 * ISOTROPY_PAIRS
    else:
        integrand, first, anisotropic, tested = sub.wrap(integrand), None, np.ones(K, dtype=bool), 0
    result = integrate_hemisphere(integrand, poles, widths, supports, rtol=rtol, atol=atol, nonfinite=nonfinite,
                                  max_evaluations=max_evaluations, first_route=first, anisotropic=anisotropic,
                                  epsilon=getattr(problem.model, "epsilon", None), fixed=problem.fixed,
                                  rescaled=rescaled)
    # Each case is charged the isotropy test as if it had run alone: counts do not depend on how cases are batched.
    return result.with_(value=result.value * factor[:, None], error=result.error * factor[:, None],
                        evaluations=result.evaluations + tested)


#: A fixed direction within this of N (in sin θ) counts as along N for an isotropic lobe: rotation-invariant about N.
AXIAL = 1e-12
#: Random direction pairs per parameter set for the isotropy test.
ISOTROPY_PAIRS = 48


def _isotropic_cases(problem, rtol: float) -> np.ndarray:
    """Per case (K,): :func:`rotation_invariant` at its parameter values, tested once per distinct set."""
    K = problem.fixed.shape[0]
    if problem.per_case:
        values = np.column_stack([np.asarray(problem.params[name], dtype=float).reshape(K, -1)
                                  for name in sorted(problem.per_case)])
        _, first, label = np.unique(values, axis=0, return_index=True, return_inverse=True)
    else:
        first, label = np.zeros(1, dtype=np.intp), np.zeros(K, dtype=np.intp)

    def brdf(L: np.ndarray, V: np.ndarray, case: np.ndarray) -> np.ndarray:
        return problem.model.evaluate(L, V, problem.case_params(case))

    return rotation_invariant(brdf, first, rtol)[label.reshape(K)]


def rotation_invariant(brdf: Callable, cases: np.ndarray, rtol: float) -> np.ndarray:
    """Per case of ``cases``: f(R L, R V) = f(L, V) to rtol/64 of max |f| on random pairs, R rotations about N.
    ``brdf(L, V, case)`` evaluates f for (M, 3) directions and the case index (M,) of each.

    An anisotropic lobe is an ellipse, a wedge thinner than the azimuths of either route's polar coordinates
    where it is long (Ashikhmin-Shirley, n_u = 1.6, n_v = 5112: 1.37 times the estimate at rtol 1e-9 over the half
    vector; n_u = 1407, n_v = 2.3: 1.42 times at rtol 1e-5 in the lobe-aligned global rule). Such lobes skip the
    half-vector route, and the global rule bounds its azimuthal Fourier tail for them."""
    rng = np.random.default_rng(7)
    L, V = random_hemisphere(rng, ISOTROPY_PAIRS), random_hemisphere(rng, ISOTROPY_PAIRS)
    index = np.repeat(cases, ISOTROPY_PAIRS)
    with np.errstate(all="ignore"):
        reference = np.asarray(brdf(np.tile(L, (cases.size, 1)), np.tile(V, (cases.size, 1)), index), dtype=float)
        scale = np.abs(reference).reshape(cases.size, -1).max(axis=1)
        change = np.zeros(cases.size)
        for angle in (0.7, 2.1):
            rotation = rotation_about_normal(angle)
            turned = [np.tile(d @ rotation.T, (cases.size, 1)) for d in (L, V)]
            rotated = np.asarray(brdf(*turned, index), dtype=float)
            change = np.maximum(change, np.abs(rotated - reference).reshape(cases.size, -1).max(axis=1))
    return np.isfinite(scale) & np.isfinite(change) & (change <= rtol / 64 * scale)


def _scales(problem, nonfinite: NonFinitePolicy) -> np.ndarray:
    """Per case, 2^k ≥ the largest |integrand| on a Fibonacci lattice where that exceeds :data:`LARGE_VALUE`,
    else 1 (a power of two: dividing by it is exact). With ``nonfinite="raise"``, a lattice direction where the
    integrand is not finite raises :class:`NonFiniteIntegrand` there."""
    K = problem.fixed.shape[0]
    probe = fibonacci_hemisphere(SCALE_SAMPLES)
    peak = np.zeros(K)
    step = max(1, 1_000_000 // SCALE_SAMPLES)  # bounded memory whatever the number of cases
    for start in range(0, K, step):
        cases = np.repeat(np.arange(start, min(K, start + step)), SCALE_SAMPLES)
        omega = np.tile(probe, (cases.size // SCALE_SAMPLES, 1))
        values = problem.integrand(omega, cases)
        finite = np.all(np.isfinite(values), axis=-1)
        if nonfinite == "raise" and not finite.all():
            first = int(np.argmin(finite))
            raise NonFiniteIntegrand(int(cases[first]), omega[first], values[first])
        magnitude = np.where(finite, np.abs(values).max(axis=-1), 0.0).reshape(-1, SCALE_SAMPLES)
        peak[start:start + magnitude.shape[0]] = magnitude.max(axis=1)
    return np.where(peak > LARGE_VALUE, np.exp2(np.ceil(np.log2(np.maximum(peak, 1.0)))), 1.0)


def _nonfinite_message(problem, bad: NonFiniteIntegrand) -> str:
    """Where the BRDF was not finite: its value and the (L, V) pair — or, where the direction itself is not (the
    lobe search's sums overflowed even after scaling), that the values are too large to integrate."""
    fixed = problem.fixed[bad.case]
    hint = "pass nonfinite='zero' (--nonfinite zero) to count such values as 0"
    if not np.all(np.isfinite(bad.direction)):
        return f"BRDF values at V={_fmt(fixed)} are too large to integrate in float64 (their sums overflow)"
    L, V = (bad.direction, fixed) if problem.over == "light" else (fixed, bad.direction)
    # Python's formatting, not numpy's: numpy pads a NaN whose sign bit is set ("[ nan]"), as compiled code makes it.
    value = "[" + " ".join(f"{v:.6g}" for v in np.ravel(bad.value)) + "]"
    return f"BRDF is not finite (value {value}) at L={_fmt(L)}, V={_fmt(V)}; {hint}"


def _fmt(direction: np.ndarray) -> str:
    return "(" + ", ".join(f"{c:.9g}" for c in direction) + ")"
