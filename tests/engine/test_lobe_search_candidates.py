"""The lobe search's free test comes before its cap on candidates (engine/machinery/lobe_search._candidates): a noisy
plateau's many strict local maxima must not crowd out a lone sample of a narrow lobe, and lone maxima beyond the cap
are charged, never dropped."""

from __future__ import annotations

import numpy as np

from brdfnorm.engine.machinery import lobe_search


def _strict(g: np.ndarray, nearest: np.ndarray) -> np.ndarray:
    return (g > g[:, nearest].max(axis=-1)) & (g > 0)


def _lattice() -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    omega = lobe_search.fibonacci_hemisphere(lobe_search.SAMPLES)
    nearest, symmetric = lobe_search.lattice_neighbours(lobe_search.SAMPLES)
    return omega, nearest, symmetric, float(np.sqrt(2.0 * np.pi / lobe_search.SAMPLES))


def _isolated(omega: np.ndarray, nearest: np.ndarray, where: np.ndarray, count: int) -> np.ndarray:
    """Up to ``count`` lattice indices among ``where`` no two of which are neighbours."""
    chosen: list[int] = []
    blocked = np.zeros(omega.shape[0], dtype=bool)
    for i in np.flatnonzero(where):
        if not blocked[i] and len(chosen) < count:
            chosen.append(int(i))
            blocked[i] = True
            blocked[nearest[i]] = True
            blocked[np.flatnonzero(np.any(nearest == i, axis=1))] = True
    return np.array(chosen)


def test_a_noisy_plateau_does_not_crowd_out_a_lone_narrow_lobe():
    omega, nearest, symmetric, spacing = _lattice()
    rng = np.random.default_rng(3)
    g = np.where(omega[:, 2] > 0.5, 1.0 + 1e-6 * rng.random(omega.shape[0]), 0.0)
    lone = _isolated(omega, nearest, omega[:, 2] < 0.2, 1)[0]
    g[lone] = 1e-6  # a narrow lobe's tail at one sample, far below every plateau maximum
    g = g[None]
    strict = _strict(g, nearest)
    assert strict.sum() > 2 * lobe_search.MAX_CANDIDATES  # the plateau's noise: many strict maxima
    case, direction, level, width, spacing_of, over_case, over_charge = lobe_search._candidates(
        np.zeros(1, dtype=np.intp), omega[None], g, g, strict, symmetric, np.full(1, spacing))
    assert np.any(np.all(direction == omega[lone], axis=1))  # the lone sample is a candidate
    assert over_case.size == 0


def test_lone_maxima_beyond_the_cap_are_charged():
    omega, nearest, symmetric, spacing = _lattice()
    extra = 5
    lone = _isolated(omega, nearest, omega[:, 2] < 0.9, lobe_search.MAX_CANDIDATES + extra)
    g = np.zeros((1, omega.shape[0]))
    g[0, lone] = np.linspace(2.0, 1.0, lone.size)
    strict = _strict(g, nearest)
    case, direction, level, width, spacing_of, over_case, over_charge = lobe_search._candidates(
        np.zeros(1, dtype=np.intp), omega[None], g, g, strict, symmetric, np.full(1, spacing))
    assert level.size == lobe_search.MAX_CANDIDATES and np.all(level >= g[0, lone][lobe_search.MAX_CANDIDATES - 1])
    assert over_case.size == extra
    smallest = np.sort(g[0, lone])[:extra]
    np.testing.assert_allclose(np.sort(over_charge), lobe_search.CHARGE * 2 * np.pi * smallest * spacing**2)
