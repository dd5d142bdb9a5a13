"""Test helpers of the native (Numba) GLSL backend's differential tests: the direction pairs every backend is
compared on, the native kernel's values, and the comparison (moved from tests/glsl/test_native.py, issue 40
item 6)."""

from __future__ import annotations

import numpy as np


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def directions(rng: np.random.Generator, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Random pairs over the whole sphere (below the horizon too), then the special pairs: N, grazing, L = V,
    L = −V (0/0 in the half vector), the mirror pair (H = N), signed zeros and exact axes."""
    L, V = _unit(rng.normal(size=(count, 3))), _unit(rng.normal(size=(count, 3)))
    s = np.sqrt(0.5)
    special = [
        ([0, 0, 1], [0, 0, 1]), ([1, 0, 0], [0, 0, 1]), ([0, 0, 1], [1, 0, 0]), ([1, 0, 0], [-1, 0, 0]),
        ([s, 0, s], [s, 0, s]), ([s, 0, s], [-s, 0, -s]), ([s, 0, s], [-s, 0, s]), ([0, 0, -1], [0, 0, 1]),
        ([-0.0, -0.0, 1.0], [0.0, -0.0, 1.0]), ([0, 1, 0], [0, -1, 0]), ([0.6, 0.0, 0.8], [-0.6, 0.0, 0.8]),
        ([1e-300, 0, 1], [0, 1e-300, 1]), ([0, s, -s], [0, -s, s]),
    ]
    Ls, Vs = (np.array([p[k] for p in special], dtype=float) for k in (0, 1))
    return np.concatenate([L, _unit(Ls)]), np.concatenate([V, _unit(Vs)])


def native_values(kernel, L: np.ndarray, V: np.ndarray, params) -> np.ndarray:
    u = kernel.pack(params)
    return np.array([kernel.function(*l, *v, u) for l, v in zip(L, V, strict=True)])


def assert_same(native: np.ndarray, reference: np.ndarray, where: str) -> None:
    """Equal to 1e-13 of the value (or of the largest value, near a cancellation); NaN and ±inf where numpy."""
    assert np.array_equal(np.isnan(native), np.isnan(reference)), where
    infinite = np.isinf(reference)
    assert np.array_equal(native[infinite], reference[infinite]), where
    finite = np.isfinite(reference)
    scale = np.max(np.abs(reference[finite]), initial=0.0)
    np.testing.assert_allclose(native[finite], reference[finite], rtol=1e-13, atol=1e-13 * scale, err_msg=where)
