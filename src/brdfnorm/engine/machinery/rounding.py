"""Float64 rounding noise of an integrand near its peak, and what it can do to an integral.

A lobe written in terms of the cosine of the angle from its peak — cos^n (Phong 1975), (N·H)^n (Blinn 1977),
the 1 − (N·H)² of a GGX shader (Walter et al. 2007) — sees that cosine only to within ε = 2.2e-16. Near the
peak the rounded cosine is a staircase; once the lobe is narrow enough (n ≳ 1e7, α ≲ 1e-4) that staircase is
a visible share of the lobe, and no quadrature can recover the albedo of the exact BRDF from the float64
one. :func:`rounding_noise` measures the noise before integrating, :func:`noise_bound` turns it into a term
of the error estimate (:mod:`brdfnorm.engine.routes.hemisphere` stops a case whose noise exceeds its tolerance, with the
reason "rounding-limited").

The probe costs 576 evaluations per case; :func:`surveyed_noise` evaluates 96 of them first (the first 12 points of
its fine step on the rays nearest the peak) and the rest only where the noise could matter against the tolerance,
or the lobe is anisotropic — elsewhere four times the survey's amplitude stands for the probe's, which has measured
at most 2.1 times it (docs/performance.md, seventh session).

A model that evaluates in lower precision declares its unit roundoff as ``epsilon`` (Mitsuba's float32 variants:
2⁻²⁴, :mod:`brdfnorm.models.mitsuba`). Its noise is then also at least :data:`EVALUATION_ULPS` units of it — a
float32 evaluation's error is partly a bias (the rounded inputs, a fixed direction rounded for the whole integral)
that no difference along a ray sees — and the plateau charge below scales with it.

A bias no difference sees either (:func:`cosine_bias`): the fixed direction and the integrator's lobe frame are
float64 vectors whose norms are off by up to half an ulp, the same for every node of a case. A lobe c^n whose
cosine c is a dot product of such vectors is then off by n·δ relative everywhere ((1 + δ)^n ≈ 1 + n·δ), δ the
norms' relative error: the same sign over the whole lobe, so no averaging over nodes removes it (modified Phong
n = 7 006 at 3.9…4.3°: the relative error of the albedo is n·(δ_V + δ_P) to three digits, up to 1.0 ε/w²,
where the fourth differences see 0.36–0.41 ε/w²). :func:`cosine_bias` measures the lobe's exponent in each
input's norm instead of assuming one from its width in ω (which a half-vector lobe at a grazing view squeezes
while its cosine stays as wide) and takes the norms' errors exactly.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

_EPS = np.finfo(float).eps


# Rounding-noise probe: along rays from each case's peak at these azimuths, starting at these radii (in
# widths), the integrand at _PROBE_POINTS points spaced by each of _PROBE_STEPS (in widths); fourth differences.
_PROBE_RADII = np.array([1e-2, 0.3, 1.0])
_PROBE_AZIMUTHS = np.arange(4) * (np.pi / 2)
_PROBE_POINTS = 24
_PROBE_STEPS = np.array([1e-4, 1e-4 / 16])
PROBE_EVALUATIONS = _PROBE_RADII.size * _PROBE_AZIMUTHS.size * _PROBE_STEPS.size * _PROBE_POINTS
#: Fourth differences of independent noise of standard deviation σ have standard deviation √70·σ.
_FOURTH_DIFFERENCE_GAIN = np.sqrt(70.0)
#: Lobes narrower than this (rad) may be plateaus of float64 rounding at their core.
_PLATEAU_WIDTH = 1e-5
#: The survey (:func:`surveyed_noise`): the first points of the fine step on the rays at 1e-2 and 0.3 widths, and
#: what its amplitude is multiplied by where it stands for the probe's (which has measured at most 2.1 times it).
_SURVEY_RADII = np.array([0, 1])
_SURVEY_STEPS = np.array([1])
_SURVEY_POINTS = 12
SURVEY_EVALUATIONS = _PROBE_AZIMUTHS.size * _SURVEY_RADII.size * _SURVEY_STEPS.size * _SURVEY_POINTS
SURVEY_MARGIN = 4.0
#: The survey stands for the probe where its noise bound is below rtol over this.
SURVEY_QUIET = 64.0
#: Evaluations of :func:`cosine_bias` per probed case: 12 nodes, each at ω, ω(1 + h) and with F(1 + h).
BIAS_EVALUATIONS = 3 * _PROBE_RADII.size * _PROBE_AZIMUTHS.size
#: Veltkamp's splitting constant for float64, 2^27 + 1.
_SPLIT = 134217729.0


def _probe_rays(frame, widths: np.ndarray, supports: np.ndarray) -> np.ndarray:
    """The probe's directions (K, azimuths, radii, steps, points, 3) (:func:`rounding_noise`)."""
    return _rays(frame[0], *_probe_angles(frame, widths, supports))


def _rays(P: np.ndarray, alpha: np.ndarray, radial: np.ndarray) -> np.ndarray:
    """The directions at angles ``alpha`` (K, azimuths, ...) from the poles ``P`` (K, 3) towards ``radial``
    (K, azimuths, 3): (K, azimuths, ..., 3), each from its own angle alone (so any subset of a probe's angles gives
    the same bits as the whole probe's)."""
    extra = (None,) * (alpha.ndim - 2)
    pole = P[(slice(None), None) + extra]
    towards = radial[(slice(None), slice(None)) + extra]
    return np.cos(alpha)[..., None] * pole + np.sin(alpha)[..., None] * towards


def _probe_angles(frame, widths: np.ndarray, supports: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The probe's angles from the pole (K, azimuths, radii, steps, points) and its radial directions
    (K, azimuths, 3) (:func:`_probe_rays`)."""
    P, T, B = frame
    pz = P[:, 2:3]
    s = np.sqrt(np.maximum(1.0 - pz * pz, 0.0))
    cos_b, sin_b = np.cos(_PROBE_AZIMUTHS), np.sin(_PROBE_AZIMUTHS)
    alpha_max = np.minimum(np.arctan2(pz, -s * cos_b), supports[:, None])  # (K, azimuths)
    # Each ray stays within half the horizon's distance, unclipped (a clipped ray would have a kink).
    scale = np.minimum(widths[:, None], alpha_max)  # (K, az)
    step = scale[:, :, None] * _PROBE_STEPS  # (K, az, steps)
    reach = _PROBE_POINTS * step.max(axis=2, keepdims=True)
    start = np.minimum(widths[:, None, None] * _PROBE_RADII, 0.5 * alpha_max[:, :, None] - reach)  # (K, az, radii)
    alpha = (start[:, :, :, None, None]
             + step[:, :, None, :, None] * np.arange(_PROBE_POINTS))  # (K, az, radii, steps, points)
    radial = cos_b[None, :, None] * T[:, None, :] + sin_b[None, :, None] * B[:, None, :]  # (K, az, 3)
    return alpha, radial


def _sample(integrand, omega: np.ndarray, cases: np.ndarray, max_nodes_per_call: int) -> np.ndarray:
    """The integrand on the directions ``omega`` (k, ..., 3) of the cases ``cases`` (k,): (k, ..., C)."""
    shape = omega.shape[:-1]
    per_case = int(np.prod(shape[1:]))
    per_call = max(1, max_nodes_per_call // per_case)
    values = []
    with np.errstate(all="ignore"):
        for first in range(0, cases.size, per_call):
            part = slice(first, first + per_call)
            case = np.repeat(cases[part], per_case)
            values.append(np.asarray(integrand(omega[part].reshape(-1, 3), case), dtype=float)
                          .reshape(omega[part].shape[:-1] + (-1,)))
    return np.concatenate(values) if values else np.zeros(shape + (1,))


def _relative_noise(g: np.ndarray) -> np.ndarray:
    """The RMS over the rays of each ray's smaller RMS fourth difference over its steps, over √70 and relative to
    the largest sample, (k, C), of samples ``g`` (k, azimuths, radii, steps, points, C)."""
    # A ray with a non-finite sample is left out: the integrator raises there or zeroes it (``nonfinite``).
    usable = np.isfinite(g).all(axis=(3, 4))  # (K, az, radii, C)
    g = np.where(np.isfinite(g), g, 0.0)
    # A smooth lobe's fourth differences shrink 16⁴-fold from the coarse step to the fine one, noise's do not:
    # the smaller of the two is the noise (or a smooth part far below it, on a ray where the lobe is steep).
    rms = np.sqrt(np.mean(np.diff(g, n=4, axis=4) ** 2, axis=4)).min(axis=3) / _FOURTH_DIFFERENCE_GAIN
    peak = np.where(usable, np.abs(g).max(axis=(3, 4)), 0.0).max(axis=(1, 2))  # (K, C): relative to the peak,
    with np.errstate(invalid="ignore", divide="ignore"):  # so a ray along a fast-decaying sliver does not count
        mean_square = (np.where(usable, rms**2, 0.0).sum(axis=(1, 2)) / np.maximum(usable.sum(axis=(1, 2)), 1))
        return np.where(peak > 0, np.sqrt(mean_square) / peak, 0.0)


def _floored(relative: np.ndarray, widths: np.ndarray, epsilon: float | None) -> np.ndarray:
    """``relative`` (K, C) with the plateau charge and a lower-precision model's floor (:func:`rounding_noise`)."""
    if epsilon is None or epsilon <= _EPS:
        plateau = _EPS / widths[:, None] ** 2 * (_PLATEAU_WIDTH / widths[:, None]) ** 2
        return np.minimum(1.0, np.maximum(relative, plateau))
    plateau_width = _PLATEAU_WIDTH * np.sqrt(epsilon / _EPS)
    plateau = epsilon / widths[:, None] ** 2 * (plateau_width / widths[:, None]) ** 2
    return np.minimum(1.0, np.maximum(np.maximum(relative, plateau), EVALUATION_ULPS * epsilon))


def rounding_noise(integrand: Callable[[np.ndarray, np.ndarray], np.ndarray], frame, widths: np.ndarray,
                   supports: np.ndarray, max_nodes_per_call: int = 1_500_000,
                   epsilon: float | None = None) -> np.ndarray:
    """Relative amplitude (K, C) of each case's float64 evaluation noise around its peak.

    Along rays from the peak, at 1e-2, 0.3 and 1 widths w (or closer, to stay within half the horizon's
    distance α_h), the integrand is sampled 1e-4·min(w, α_h) apart, and 16 times closer. A smooth lobe's
    fourth differences are ~1e-16 of it there (16⁴ times less at the fine step), while float64 rounding of
    the cosine the lobe is written in (cos^n, (N·H)^n, 1 − (N·H)²) is a staircase with narrower steps:
    noise, independent from sample to sample. (Perturbing directions by a few ulps would not show it: near a
    peak the steps are wider than any ulp.) The noise estimate is the RMS over the rays of the smaller RMS
    fourth difference of the two steps, over √70 and relative to the largest sample.

    A lobe narrower than 1e-5 rad is also charged ε/w²·(1e-5/w)²: its core may be a plateau of rounding, the
    cosine 1 across it, which no difference sees (Phong at n = 1e20), or a staircase coarser than the fine
    step (GGX at α = 1e-6). Rays with a non-finite sample are left out (the integrator raises or zeroes).

    ``epsilon``: the unit roundoff of a model evaluated in lower precision than float64 (None: float64). The
    plateau charge then uses it, over a width scaled by √(epsilon/ε) (where a cosine near 1 has as few values
    across the lobe as float64's has across 1e-5 rad), and the noise is at least :data:`EVALUATION_ULPS` × epsilon.
    """
    omega = _probe_rays(frame, widths, supports)
    g = _sample(integrand, omega, np.arange(omega.shape[0]), max_nodes_per_call)
    return _floored(_relative_noise(g), widths, epsilon)


def surveyed_noise(integrand: Callable[[np.ndarray, np.ndarray], np.ndarray], frame, widths: np.ndarray,
                   supports: np.ndarray, rtol: float, max_nodes_per_call: int = 1_500_000,
                   epsilon: float | None = None,
                   anisotropic: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`rounding_noise` where it can matter, a cheaper survey of it elsewhere: (amplitude (K, C),
    evaluations (K,)).

    The survey is the first 12 of the 24 points of the probe's fine step on its rays at 1e-2 and 0.3 widths
    (:data:`SURVEY_EVALUATIONS` = 96 per case), a subset of the probe's nodes; its amplitude times
    :data:`SURVEY_MARGIN` stands for the probe's where even
    that keeps the noise bound (:func:`noise_bound` of the |g|-integral) below rtol/:data:`SURVEY_QUIET` — far from
    where the noise decides anything (a case is "quiet" below rtol/16) and then a term of the estimate well under
    its tolerance (the estimate's rounding floor, 50 ε, is most of it for lobes wider than ~0.1 rad). Elsewhere
    — for every case when ``rtol`` is 0, and for the ``anisotropic`` ones (K,) (a lobe narrow across one axis,
    where the rays at 1 width see up to 9.5 times what the survey does: Ashikhmin-Shirley) — the rest of the
    probe's nodes are evaluated and the amplitude is the probe's, exactly. The fine step alone, on all 24 points,
    sees at least what the probe's smaller of two steps does on the same ray; the rays at 1 width, left out, are
    where a lobe's noise is smallest relative to its peak; 12 points give 8 fourth differences per ray, 64 in all,
    a noisier RMS, which the margin covers (measured: the
    probe's amplitude is at most 2.1 times the survey's over Blinn-Phong, Phong, modified Phong n = 1…1e8, the
    Beckmann, GGX, naive GGX, Oren-Nayar and two-lobe shaders at random views, docs/performance.md).
    """
    # (the survey's directions alone, then the probe's of the cases that need it: most cases need only the survey)
    alpha, radial = _probe_angles(frame, widths, supports)
    K = alpha.shape[0]
    evaluations = np.full(K, SURVEY_EVALUATIONS, dtype=np.int64)
    survey = _rays(frame[0], alpha[:, :, _SURVEY_RADII][:, :, :, _SURVEY_STEPS][:, :, :, :, :_SURVEY_POINTS], radial)
    g_survey = _sample(integrand, survey, np.arange(K), max_nodes_per_call)
    amplitude = _floored(SURVEY_MARGIN * _relative_noise(g_survey), widths, epsilon)
    stands = np.all(noise_bound(amplitude, 1.0) < rtol / SURVEY_QUIET, axis=-1)
    if anisotropic is not None:
        stands &= ~np.asarray(anisotropic, dtype=bool)
    full = np.flatnonzero(~stands)
    if full.size:
        # The rest of the probe's nodes for those cases (the survey's are reused).
        omega = _rays(frame[0][full], alpha[full], radial[full])
        surveyed = np.zeros(omega.shape[1:5], dtype=bool)  # (azimuths, radii, steps, points)
        surveyed[np.ix_(np.arange(_PROBE_AZIMUTHS.size), _SURVEY_RADII, _SURVEY_STEPS,
                        np.arange(_SURVEY_POINTS))] = True
        g = np.full(omega.shape[:-1] + (g_survey.shape[-1],), np.nan)
        g[:, surveyed] = g_survey[full].reshape(full.size, -1, g_survey.shape[-1])
        g[:, ~surveyed] = _sample(integrand, omega[:, ~surveyed], full, max_nodes_per_call)
        amplitude[full] = _floored(_relative_noise(g), widths[full], epsilon)
        evaluations[full] = PROBE_EVALUATIONS
    return amplitude, evaluations


def norm_error(vectors: np.ndarray) -> np.ndarray:
    """|v| − 1 of float64 vectors (..., 3) to first order, (Σ v_i² − 1)/2, with each square and the sum carried
    in double-double (Dekker's product by Veltkamp's split, Knuth's two-sum): a unit vector's few-ulp excess,
    which float64 arithmetic rounds away."""
    v = np.asarray(vectors, dtype=float)
    hi = _SPLIT * v - (_SPLIT * v - v)
    lo = v - hi
    square = v * v
    square_error = ((hi * hi - square) + 2.0 * hi * lo) + lo * lo  # v² = square + square_error exactly
    total, carry = np.full(v.shape[:-1], -1.0), np.zeros(v.shape[:-1])
    for part in (square[..., 0], square[..., 1], square[..., 2]):
        added = total + part
        carry += (total - (added - (added - total))) + (part - (added - total))
        total = added
    return (total + (carry + square_error.sum(axis=-1))) / 2.0


def cosine_bias(rescaled: Callable[[np.ndarray], Callable[[np.ndarray, np.ndarray], np.ndarray]],
                frame, fixed: np.ndarray, widths: np.ndarray, supports: np.ndarray, error: np.ndarray,
                magnitude: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Relative bias bound (K, C) of each case's integrand from the rounded norms of its inputs, and which cases
    were probed (K,) (:data:`BIAS_EVALUATIONS` each).

    A lobe whose cosine is a dot product of the free direction ω (a node, |ω| − 1 = δ_P of the lobe frame's pole
    P near the peak) and of the fixed direction F (|F| − 1 = δ_F) is off by S_ω·δ_P + S_F·δ_F relative, where
    S = d ln g / d ln|·| is the lobe's exponent in that input's norm: n for (R·V)^n, ~0 for a lobe of a
    normalized half vector ((N·H)^n, a GGX shader), whatever the lobe's width in ω. S is measured at 12 nodes
    around the peak (0.01, 0.3 and 1 width out, 4 azimuths) from g at ω, at ω(1 + h) and at F(1 + h),
    h ≈ 1e-3 w², all through ``rescaled(factor)`` (the integrand with each case's F scaled by ``factor`` (K,), by
    one evaluator, so that the ratios compare like with like): ln of the ratio over ln(1 + h), exact for a power.
    The bound per node is |S_ω δ_P + S_F δ_F| + |S_ω|·max(|δ_T|, |δ_B|)·sin²α (the frame's other axes weigh in
    off the peak), its largest over the nodes where g ≠ 0; the δ are exact (:func:`norm_error`). A systematic
    rounding inside the model itself (a shader's normalize(V)) is not seen.

    Probed are the cases where the bias could matter against their error estimate ``error`` (K, C) of an integral
    of |g|-integral ``magnitude`` (K, C): where :func:`noise_bound` of 8/w²·(|δ_F| + max |δ_frame|) exceeds a
    quarter of the estimate in some channel (a lobe c^n of ω-width w has n ≈ 2/w²; 4× for a lobe wider in ω than
    in its cosine, Blinn-Phong's (N·H)^n); elsewhere the bound is 0 and nothing is evaluated.
    """
    P, T, B = frame
    K = P.shape[0]
    delta_p, delta_f = norm_error(P), norm_error(fixed)
    delta_side = np.maximum(np.abs(norm_error(T)), np.abs(norm_error(B)))
    potential = 8.0 / widths**2 * (np.abs(delta_f) + np.maximum(np.abs(delta_p), delta_side))
    probed = np.any(noise_bound(potential[:, None], magnitude) > error / 4, axis=1)
    cases = np.flatnonzero(probed)
    bias = np.zeros((K, 1))
    if not cases.size:
        return bias, probed
    pz = P[cases, 2:3]
    s = np.sqrt(np.maximum(1.0 - pz * pz, 0.0))
    cos_b, sin_b = np.cos(_PROBE_AZIMUTHS), np.sin(_PROBE_AZIMUTHS)
    alpha_max = np.minimum(np.arctan2(pz, -s * cos_b), supports[cases, None])  # (k, az), as rounding_noise's rays
    alpha = np.minimum(widths[cases, None, None] * _PROBE_RADII, 0.5 * alpha_max[:, :, None])  # (k, az, radii)
    radial = cos_b[None, :, None] * T[cases, None, :] + sin_b[None, :, None] * B[cases, None, :]  # (k, az, 3)
    omega = (np.cos(alpha)[..., None] * P[cases, None, None, :]
             + np.sin(alpha)[..., None] * radial[:, :, None, :]).reshape(-1, 3)
    case = np.repeat(cases, _PROBE_AZIMUTHS.size * _PROBE_RADII.size)
    h = np.clip(1e-3 * widths[cases] ** 2, 2.0**-40, 2.0**-20)
    h_node = np.repeat(h, _PROBE_AZIMUTHS.size * _PROBE_RADII.size)[:, None]
    integrand = rescaled(np.ones(K))
    moved = rescaled(np.where(probed, 1.0 + np.clip(1e-3 * widths**2, 2.0**-40, 2.0**-20), 1.0))
    with np.errstate(all="ignore"):
        g = np.asarray(integrand(omega, case), dtype=float)
        s_omega = np.log(np.asarray(integrand(omega * (1.0 + h_node), case), dtype=float) / g) / np.log1p(h_node)
        s_fixed = np.log(np.asarray(moved(omega, case), dtype=float) / g) / np.log1p(h_node)
        off_peak = np.sin(alpha).reshape(-1, 1) ** 2
        node = (np.abs(s_omega * delta_p[case, None] + s_fixed * delta_f[case, None])
                + np.abs(s_omega) * delta_side[case, None] * off_peak)
    node = np.where((g != 0) & np.isfinite(node), node, 0.0).reshape(cases.size, -1, g.shape[-1])
    bias = np.zeros((K, g.shape[-1]))
    bias[cases] = node.max(axis=1)
    return bias, probed


def noise_bound(amplitude: np.ndarray, magnitude: np.ndarray) -> np.ndarray:
    """_NOISE_MARGIN × the relative float64 noise ``amplitude`` of the integrand × its |g|-integral
    ``magnitude``. No credit is taken for averaging over nodes: the error can be a bias (Blinn-Phong's
    half vector at n = 1e6…1e10 is off by 0.7–1.1 noise amplitudes)."""
    return _NOISE_MARGIN * amplitude * magnitude


#: Bias allowed per unit of noise amplitude — a calibration, and a tight one: at Blinn-Phong n = 1e9 the
#: true error is 0.87 of the estimate, while a margin above ~1.3 would charge (N·H)^1e4 at 86° more than
#: the rtol 1e-12 it honours (tests/engine/test_series.py). The tests' probe cases stay within 0.8 of it.
_NOISE_MARGIN = 1.25

#: Least relative noise charged to a model evaluated in lower precision, in units of its declared epsilon: a
#: calibration on Mitsuba's float32 BSDFs (tests/models/test_mitsuba.py), whose values differ from a float64
#: evaluation of the same formulas by up to ~60 units at grazing directions and whose albedos by a few units.
EVALUATION_ULPS = 16.0
