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
    g = np.where(omega[:, 2] > 0.2, 1.0 + 1e-6 * rng.random(omega.shape[0]), 0.0)
    lone = _isolated(omega, nearest, omega[:, 2] < 0.02, 1)[0]
    g[lone] = 1e-6  # a narrow lobe's tail at one sample, far below every plateau maximum
    g = g[None]
    strict = _strict(g, nearest)
    assert strict.sum() > lobe_search.MAX_CANDIDATES  # the plateau's noise: more strict maxima than the cap
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


def _sheen_at_normal_incidence(roughness: float) -> float:
    """The sheen lobe's albedo at V = N as the 1-D integral it is there (rotation-invariant about N): 2π ∫ f cos θ
    sin θ dθ, by scipy's adaptive quadrature with the ring's polar angle as a breakpoint."""
    import warnings

    from scipy import integrate

    import brdfnorm as bn

    model = bn.load("charlie", roughness=roughness)
    V = np.array([[0.0, 0.0, 1.0]])

    def g(theta: float) -> float:
        L = np.array([[np.sin(theta), 0.0, np.cos(theta)]])
        return float(model.eval(L, V)[0, 0]) * np.cos(theta) * np.sin(theta)

    ring = np.pi / 2 - np.array([0.02, 0.006, 0.003, 0.001])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        value, _ = integrate.quad(g, 0.0, np.pi / 2, points=ring, epsabs=0.0, epsrel=1e-13, limit=500)
    return 2.0 * np.pi * value


def test_a_ring_about_n_is_not_taken_for_separated_peaks():
    """The sheen lobe near normal incidence peaks on a ring 0.003 rad thick above the horizon: its samples are strict
    maxima whose great-circle arcs dip, so they were taken for up to eight peaks (at V = N a charge of half the albedo,
    unconverged at 7.2 M evaluations; at θ_o = 0.01 rad the same at 1.5 M)."""
    import warnings

    import brdfnorm as bn

    model = bn.load("charlie", roughness=0.04)
    theta = np.array([0.0, 0.0014, 0.014, 0.0447])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        result = bn.albedo(model, theta, rtol=1e-10)
    assert result.converged.all() and np.all(result.evaluations < 700_000)
    assert abs(result.value[0, 0] - _sheen_at_normal_incidence(0.04)) <= result.error[0, 0]

    V = np.stack([np.sin(theta), np.zeros_like(theta), np.cos(theta)], axis=1)

    def g(omega: np.ndarray, case: np.ndarray) -> np.ndarray:
        return model.eval(omega, V[case]) * omega[:, 2:3]

    with np.errstate(all="ignore"):
        peaks = lobe_search.search_lobes(g, theta.size, negligible=1e-10 / 64)[3]
    assert peaks.count(theta.size).tolist() == [1] * theta.size and np.all(peaks.charge == 0)
