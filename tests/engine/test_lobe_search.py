"""The lobe search of the generic route (brdfnorm.engine.machinery.lobe_search): the main peak as before, the
separated peaks besides it (strict local maxima of the lattice and of the main peak's zoom caps, their half-level
components, the arc to the main peak, the zoom, the merge and the cap on peaks per case with its charge), and a
single lobe of every kind giving exactly one peak at no extra evaluation."""

from __future__ import annotations

import numpy as np
import pytest

import brdfnorm as bn
from brdfnorm.engine.machinery import lobe_search
from brdfnorm.engine.machinery.lobe_search import (
    MAX_PEAKS,
    estimate_lobe,
    fibonacci_hemisphere,
    lattice_neighbours,
    search_lobes,
)
from brdfnorm.engine.methods import make_problem
from brdfnorm.models.base import mirror


def _direction(theta: float, phi: float) -> np.ndarray:
    return np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])


def _gaussians(centres, widths, heights, base: float = 0.0):
    """g(ω) = base + Σ h_j exp(−|ω − P_j|²/(2 w_j²)), one case (every case index the same)."""
    centres = np.asarray(centres, dtype=float)

    def integrand(omega: np.ndarray, case: np.ndarray) -> np.ndarray:
        total = np.full(omega.shape[0], base)
        for P, w, h in zip(centres, widths, heights, strict=True):
            total += h * np.exp(-((omega - P)**2).sum(axis=1) / (2 * w * w))
        return total[:, None]

    return integrand


def _angle(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), a @ b))


def _search(integrand, cases: int = 1, candidates=None):
    return search_lobes(integrand, cases, candidates=candidates)


def test_the_neighbour_table_is_the_nearest_directions_and_symmetric():
    nearest, symmetric = lattice_neighbours(1024)
    grid = fibonacci_hemisphere(1024)
    distance = np.linalg.norm(grid[:, None] - grid[None], axis=-1)
    np.fill_diagonal(distance, np.inf)
    assert np.array_equal(np.sort(nearest, axis=1), np.sort(np.argsort(distance, axis=1)[:, :8], axis=1))
    for i in (0, 17, 500, 1023):
        for j in symmetric[i]:
            assert j == i or i in symmetric[j]
    assert lattice_neighbours(1024) is lattice_neighbours(1024)  # computed once


def test_two_separated_narrow_lobes_give_two_peaks_at_their_centres_and_widths():
    main, second = _direction(0.5, 0.0), _direction(0.9, 2.0)
    integrand = _gaussians([main, second], [0.02, 0.004], [1.0, 1e-3])
    poles, widths, _, peaks = _search(integrand)
    assert _angle(poles[0], main) < 0.5 * 0.02
    assert peaks.case.tolist() == [0] and peaks.count(1).tolist() == [2]
    assert _angle(peaks.direction[0], second) < 0.5 * 0.004
    assert 0.5 * 0.004 < peaks.width[0] < 2 * 0.004
    assert peaks.evaluations[0] > 0 and peaks.charge[0] == 0.0


def test_a_bump_on_a_slope_or_a_broad_base_is_not_separated():
    """A second maximum whose valley to the main peak stays above half its value lies on that peak's slope."""
    main = _direction(0.3, 0.0)
    on_slope = _gaussians([main, _direction(0.55, 0.0)], [0.3, 0.05], [1.0, 0.2])
    on_base = _gaussians([main, _direction(1.0, 2.5)], [0.05, 0.08], [1.0, 0.1], base=0.2)
    for integrand in (on_slope, on_base):
        assert _search(integrand)[3].count(1).tolist() == [1]


def test_a_noisy_plateau_has_many_local_maxima_and_no_peak_and_costs_nothing():
    rng = np.random.default_rng(3)
    noise = {}

    def integrand(omega: np.ndarray, case: np.ndarray) -> np.ndarray:
        key = omega.tobytes()
        noise.setdefault(key, 1.0 + 1e-13 * rng.standard_normal(omega.shape[0]))
        return noise[key][:, None]

    nearest, _ = lattice_neighbours(1024)
    g = integrand(fibonacci_hemisphere(1024), np.zeros(1024, dtype=int))[:, 0]
    assert np.count_nonzero(g > g[nearest].max(axis=1)) > 20  # the plateau's strict local maxima
    peaks = _search(integrand)[3]
    assert peaks.case.size == 0 and peaks.evaluations.tolist() == [0]


def test_nan_regions_are_zero_to_the_search():
    main, second = _direction(0.4, 0.0), _direction(1.0, -2.0)
    clean = _gaussians([main, second], [0.03, 0.01], [1.0, 0.01])

    def integrand(omega: np.ndarray, case: np.ndarray) -> np.ndarray:
        return np.where(omega[:, 1:2] > 0.5, np.nan, clean(omega, case))

    peaks = _search(integrand)[3]
    assert peaks.count(1).tolist() == [2]
    assert _angle(peaks.direction[0], second) < 0.5 * 0.01


def test_more_separated_peaks_than_the_cap_are_charged_their_contribution():
    directions = [_direction(0.15 + 0.12 * j, 0.8 * j) for j in range(MAX_PEAKS + 3)]
    widths = [0.01] * len(directions)
    heights = [1.0] + [10.0 ** -j for j in range(1, len(directions))]
    peaks = _search(_gaussians(directions, widths, heights))[3]
    assert peaks.count(1).tolist() == [MAX_PEAKS]
    dropped = sum(h * 2 * np.pi * 0.01**2 for h in heights[MAX_PEAKS:])
    assert dropped < peaks.charge[0] < 10 * lobe_search.CHARGE * dropped
    # the kept ones are the largest contributions
    kept = sorted(int(np.argmin([np.linalg.norm(d - p) for p in directions])) for d in peaks.direction)
    assert kept == list(range(1, MAX_PEAKS))


def test_candidates_converging_to_one_peak_are_merged(monkeypatch):
    """Two lattice candidates that zoom onto the same lobe (a lobe seen as two maxima, the lattice's and a cap's)
    are one peak."""
    main, second = _direction(0.2, 0.0), _direction(1.1, 1.0)
    integrand = _gaussians([main, second], [0.02, 0.005], [1.0, 1e-2])
    once = _search(integrand)[3]
    found = lobe_search._candidates

    def twice(*args):
        *tested, untested, charge = found(*args)
        return (*(np.concatenate([part, part]) for part in tested), untested, charge)

    monkeypatch.setattr(lobe_search, "_candidates", twice)
    merged = _search(integrand)[3]
    assert merged.count(1).tolist() == once.count(1).tolist() == [2]
    assert merged.evaluations[0] > once.evaluations[0]


def test_a_lobe_narrower_than_the_lattice_near_the_main_peak_is_found_on_its_zoom_caps():
    main = _direction(0.3, 0.0)
    second = _direction(0.3, 0.12)  # 0.036 rad away: half a lattice spacing, no lattice maximum of its own
    integrand = _gaussians([main, second], [0.01, 0.004], [1.0, 0.5])
    peaks = _search(integrand)[3]
    assert peaks.count(1).tolist() == [2]
    assert _angle(peaks.direction[0], second) < 0.5 * 0.004


@pytest.mark.parametrize(("name", "params"), [
    ("blinn-phong", {"n": 100.0}), ("blinn-phong", {"n": 1e4}), ("ggx", {"alpha": 0.3}), ("ggx", {"alpha": 0.01}),
    ("lambert", {}), ("beckmann", {"alpha": 0.2})])
def test_a_single_lobe_gives_one_peak_and_no_extra_evaluation(name, params):
    """Every view, down to a grazing lobe cut by the horizon, of built-in lobes evaluated by numpy with no hint; at
    grazing views a narrow lobe's sliver, thinner than the zoom caps' spacing across it, shows the caps a few strict
    local maxima, each rejected by its arc (ARC_POINTS evaluations; a few hundred at most, where the albedo
    costs tens of thousands)."""
    theta = np.radians([0.0, 20.0, 45.0, 70.0, 85.0, 89.5])
    problem = make_problem(bn.load(name).with_params(**params), theta, 0.7)
    K = theta.size
    normal = np.broadcast_to([0.0, 0.0, 1.0], problem.fixed.shape)
    candidates = np.stack([mirror(problem.fixed), problem.fixed, normal], axis=1)
    poles, widths, supports, peaks = _search(problem.integrand, K, candidates)
    assert peaks.count(K).tolist() == [1] * K
    grazing = theta > np.radians(80.0)
    assert peaks.evaluations[~grazing].tolist() == [0] * np.count_nonzero(~grazing)
    assert peaks.evaluations[grazing].max() <= 400
    same = estimate_lobe(problem.integrand, K, candidates=candidates)
    for a, b in zip((poles, widths, supports), same, strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("shader", ["ward_anisotropic.brdf", "ashikhmin_shirley.brdf", "oren_nayar.brdf"])
def test_anisotropic_ridges_and_rough_diffuse_shaders_stay_single_peaked(shader, request):
    """Ridges (stretched lobes) and the horizon-cut lobes of the examples have one separated peak."""
    examples = request.config.rootpath / "examples"
    theta = np.radians([0.0, 30.0, 60.0, 80.0, 88.0])
    problem = make_problem(bn.load(str(examples / shader)), theta, 0.7)
    normal = np.broadcast_to([0.0, 0.0, 1.0], problem.fixed.shape)
    candidates = np.stack([mirror(problem.fixed), problem.fixed, normal], axis=1)
    peaks = _search(problem.integrand, theta.size, candidates)[3]
    assert peaks.count(theta.size).tolist() == [1] * theta.size
