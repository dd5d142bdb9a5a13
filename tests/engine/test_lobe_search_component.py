"""The lobe search's joined samples (engine/machinery/lobe_search._component, one pass of connected components)
equal the flood it replaced (grown through the mask's neighbours until nothing changes), and its neighbour lists
(lobe_search._neighbour_lists: all pairs' distances, numpy's unique pairs) equal the sorted set of pairs of a
scipy k-d tree's neighbours they replaced."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from brdfnorm.engine.machinery import lobe_search


def _flood(mask: np.ndarray, start: np.ndarray, symmetric: np.ndarray) -> np.ndarray:
    """The reference: reach grows by the samples of ``mask`` next to a reached one until it stops growing."""
    reach = start.copy()
    while True:
        grown = reach | (mask & reach[:, symmetric].any(axis=-1))
        if np.array_equal(grown, reach):
            return reach
        reach = grown


def _pairs(tree: cKDTree) -> tuple[np.ndarray, np.ndarray]:
    """The reference neighbour lists: a Python set of pairs, sorted, padded with i itself."""
    count = tree.data.shape[0]
    nearest = tree.query(tree.data, lobe_search.NEIGHBOURS + 1)[1][:, 1:]
    pairs = {(int(i), int(j)) for i, row in enumerate(nearest) for j in row}
    pairs |= {(j, i) for i, j in pairs}
    lists: list[list[int]] = [[] for _ in range(count)]
    for i, j in sorted(pairs):
        lists[i].append(j)
    width = max(len(row) for row in lists)
    return nearest, np.array([row + [i] * (width - len(row)) for i, row in enumerate(lists)], dtype=np.intp)


@pytest.mark.parametrize("points", ["lattice", "cap", "random"])
def test_neighbour_lists_equal_the_sorted_pairs(points):
    rng = np.random.default_rng(5)
    data = {"lattice": lobe_search.fibonacci_hemisphere(lobe_search.SAMPLES),
            "cap": np.stack([lobe_search._cap()[0] * np.cos(lobe_search._cap()[1]),
                             lobe_search._cap()[0] * np.sin(lobe_search._cap()[1])], axis=-1),
            "random": rng.random((300, 2))}[points]
    nearest, symmetric = lobe_search._neighbour_lists(data)
    reference_nearest, reference = _pairs(cKDTree(data))
    # the same neighbours as scipy's k-d tree, nearest first (the order of exact ties aside: none here)
    assert np.array_equal(nearest, reference_nearest)
    assert symmetric.shape == reference.shape and np.array_equal(symmetric, reference)


@pytest.mark.parametrize("lattice", ["lattice", "cap"])
def test_component_equals_the_flood(lattice):
    symmetric = (lobe_search.lattice_neighbours(lobe_search.SAMPLES) if lattice == "lattice"
                 else lobe_search._cap_neighbours())[1]
    m = symmetric.shape[0]
    rng = np.random.default_rng(11)
    for density in (0.0, 0.05, 0.3, 0.5, 0.7, 1.0):
        mask = rng.random((24, m)) < density
        # starts inside the mask, outside it (the flood passes a start sample on either way), several or none a row
        start = rng.random((24, m)) < rng.choice([0.0, 0.002, 0.02], size=(24, 1))
        start[0] = False
        got = lobe_search._component(mask, start, symmetric)
        assert got.dtype == bool and got.shape == mask.shape
        assert np.array_equal(got, _flood(mask, start, symmetric))
    # smooth masks (superlevel sets of a bumpy function: large components, long paths) as the search sees them
    omega = lobe_search.fibonacci_hemisphere(m) if lattice == "lattice" else None
    if omega is not None:
        centres = rng.normal(size=(24, 5, 3))
        centres /= np.linalg.norm(centres, axis=-1, keepdims=True)
        g = np.exp(8.0 * np.einsum("kcj,mj->kcm", centres, omega)).sum(axis=1)
        top = np.argmax(g, axis=1)
        start = np.zeros_like(g, dtype=bool)
        start[np.arange(24), top] = True
        for level in (0.1, 0.5, 0.9):
            mask = g >= level * g.max(axis=1, keepdims=True)
            assert np.array_equal(lobe_search._component(mask, start, symmetric), _flood(mask, start, symmetric))


def test_component_of_nothing():
    symmetric = lobe_search._cap_neighbours()[1]
    empty = np.zeros((3, symmetric.shape[0]), dtype=bool)
    assert not lobe_search._component(empty, empty, symmetric).any()
    assert lobe_search._component(empty[:0], empty[:0], symmetric).shape == (0, symmetric.shape[0])


def test_within_equals_the_angles_compared():
    """lobe_search._within (angles only where the dot product allows them below the radius) equals the angles of
    every sample compared with it, for radii from below the lattice's spacing to past the hemisphere."""
    rng = np.random.default_rng(13)
    omega = np.broadcast_to(lobe_search.fibonacci_hemisphere(lobe_search.SAMPLES), (6, lobe_search.SAMPLES, 3))
    centre = rng.normal(size=(6, 3))
    centre[:, 2] = np.abs(centre[:, 2])
    centre /= np.linalg.norm(centre, axis=-1, keepdims=True)
    centre[0] = omega[0, 17]  # a centre on the lattice: its own sample at angle 0
    for radius in (1e-9, 0.01, 0.078, 0.5, 2.0, 4.0):
        radii = np.full(6, radius)
        expected = lobe_search._angles(omega, centre) < radii[:, None]
        got = lobe_search._within(omega, centre, radii)
        assert np.array_equal(got, expected)
        assert radius < 0.5 or got.any()


def test_above_neighbours_is_the_maximum_compared():
    """lobe_search._above_neighbours (each neighbour compared with the survivors of the ones before) equals the
    comparison with the neighbours' maximum, on smooth lobes, noise, plateaus (ties are not strict) and zeros."""
    nearest = lobe_search.lattice_neighbours(lobe_search.SAMPLES)[0]
    omega = lobe_search.fibonacci_hemisphere(lobe_search.SAMPLES)
    rng = np.random.default_rng(29)
    centre = rng.normal(size=(40, 3))
    centre /= np.linalg.norm(centre, axis=-1, keepdims=True)
    g = np.exp(20.0 * centre @ omega.T)
    g[:10] = rng.random((10, omega.shape[0]))
    g[10:15] = np.round(g[10:15], 1)  # plateaus: equal neighbours
    g[15] = 0.0
    got = lobe_search._above_neighbours(g, nearest)
    assert np.array_equal(got, g > g[:, nearest].max(axis=-1))
    assert got[:10].sum() > 10 and not got[15].any()
    cap = lobe_search._cap_neighbours()[0]
    h = rng.random((5, cap.shape[0]))
    assert np.array_equal(lobe_search._above_neighbours(h, cap), h > h[:, cap].max(axis=-1))
