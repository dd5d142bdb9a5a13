"""The adaptive panels' starting grid at grazing views (:func:`starting_panels`, used by
:func:`brdfnorm.engine.routes.hemisphere.integrate_hemisphere`): the plain β × u grid, cut further at the two scales of
a peak
c_P ≪ 1 above the horizon that no node of the plain grid sees — the lobe's neck next to the pole
(:func:`brdfnorm.engine.machinery.tensor_rule.neck_u`) and the band next to the horizon's turn at β = ±π/2."""

from __future__ import annotations

import numpy as np

#: Initial edges next to the pole and to β = ±π/2 are graded by these factors (:func:`starting_panels`).
NECK_GRADING = 4.0
BAND_GRADING = 8.0


def ladder(start: np.ndarray, stop: float, factor: float = NECK_GRADING) -> tuple[np.ndarray, np.ndarray]:
    """Per case (R,), the rungs start·factor^k (R, 64) and which of them lie below ``stop``: geometrically graded
    panel edges (also :func:`brdfnorm.engine.routes.dielectric._azimuth_edges`)."""
    rungs = start[:, None] * factor ** np.arange(64)  # far past any stop for start ≥ 1e-38
    return rungs, rungs < stop


def starting_panels(cases: np.ndarray, edges_b: np.ndarray, edges_u: np.ndarray, u_neck: np.ndarray,
                    height: np.ndarray, widths: np.ndarray, supports: np.ndarray) -> tuple[np.ndarray, ...]:
    """The starting panels of ``cases`` as arrays (case, β₀, β₁, u₀, u₁), sorted by case: the tensor grid of
    ``edges_b`` × ``edges_u``, cut further where the peak lies a height c_P = ``height`` ≪ 1 above the horizon, at
    two scales of c_P the plain grid's nodes do not see.

    * In u, at u_neck·4^k (k = 0, 1, … up to a quarter of the first regular edge): the lobe's neck
      (:func:`brdfnorm.engine.machinery.tensor_rule.neck_u`: the lobe of a half-vector BRDF covers every azimuth within
      c_P·w of
      its peak). Without these cuts no node of the first panel, nor of its halves in the confirmation, lies in
      the neck, and panels away from β = 0, π report ~0 there with a ~0 error (Beckmann α = 0.0176 at
      μ = 1.26e-4: 1.3e-6 missed, the estimate 5.4e-10).
    * In β, at ±π/2 ± s·8^k (k = 0, 1, … up to a quarter of a regular panel; both sides of both): the horizon
      passes c_P below the peak, so at a distance α from it the band of directions less than c_P above the
      horizon lies within |β ∓ π/2| ≈ c_P/tan α of ±π/2 (α_h(β) falls from π − c_P through π/2 to c_P there, and
      the radial map follows it). A tail that reaches the band (GGX) holds mass all along it, in a sliver of β the
      nodes of a panel [π/2, π] (the nearest 6.7e-3 from π/2) miss (GGX α = 0.27 at μ = 1e-5: 2.2e-7 missed, the
      estimate 9e-8; α = 0.86 at μ = 1.8e-7, the far side β < π/2: 1.3e-6, the estimate 4.7e-7). The first step
      s = c_P/min(1, tan α_top) per row of panels, α_top its largest radius at β = π/2 (:func:`_band_start`):
      rows near the pole need no step below c_P/α_top. (A ladder from c_P in every row cost 158 000 evaluations
      per albedo on a random sweep of 1 200 grazing GGX/Beckmann cases, μ = 1e-7…1e-2, rtol 1e-5…1e-9; per row
      with steps of 4, 107 000; of 8 (:data:`BAND_GRADING`), 96 500; of 16, 92 500 — all with no estimate below
      its error. Restricting the ladder to the tails the global rule's start grid calls heavy left narrow GGX
      lobes, α ≈ 0.003–0.03 at μ ≈ 1e-5 and rtol 1e-9, up to 26 times outside their estimates.)"""
    u_rungs, u_kept = ladder(u_neck, edges_u[1] / NECK_GRADING)
    n_extra = u_kept.sum(axis=1)
    regular_b = np.union1d(edges_b, [np.pi / 2, 3 * np.pi / 2])
    stop_b = (edges_b[1] - edges_b[0]) / NECK_GRADING
    parts = []
    for count in np.unique(n_extra):
        pick = n_extra == count
        r = pick.sum()
        u = np.concatenate([np.zeros((r, 1)), u_rungs[pick, :count],
                            np.broadcast_to(edges_u[1:], (r, edges_u.size - 1))], axis=1)
        for j in range(u.shape[1] - 1):
            start = _band_start(height[pick], u[:, j + 1], widths[pick], supports[pick])
            b_rungs, b_kept = ladder(start, stop_b, BAND_GRADING)
            b_count = b_kept.sum(axis=1)
            for n_b_extra in np.unique(b_count):
                sub = b_count == n_b_extra
                steps = b_rungs[sub, :n_b_extra]
                beta = np.sort(np.concatenate([np.broadcast_to(regular_b, (sub.sum(), regular_b.size)),
                                               np.pi / 2 + steps, np.pi / 2 - steps, 1.5 * np.pi + steps,
                                               1.5 * np.pi - steps], axis=1), axis=1)
                n_b = beta.shape[1] - 1
                parts.append((np.repeat(cases[pick][sub], n_b), beta[:, :-1].ravel(), beta[:, 1:].ravel(),
                              np.repeat(u[sub, j], n_b), np.repeat(u[sub, j + 1], n_b)))
    if not parts:
        return (cases[:0],) + tuple(np.zeros(0) for _ in range(4))
    joined = [np.concatenate(field) for field in zip(*parts, strict=True)]
    order = np.argsort(joined[0], kind="stable")
    return tuple(field[order] for field in joined)


def _band_start(height, u_top, widths, supports):
    """The first β step of a row of panels reaching up to ``u_top`` (:func:`starting_panels`): c_P/tan α_top,
    at most c_P, α_top the row's largest radius on the panels' map at β = π/2."""
    alpha_max = np.minimum(np.pi / 2, supports)
    v = 1.0 - (1.0 - u_top) ** 2
    top = widths * np.tan(v * np.arctan(alpha_max / widths))
    return height / np.minimum(1.0, np.tan(np.minimum(top, 1.5)))
