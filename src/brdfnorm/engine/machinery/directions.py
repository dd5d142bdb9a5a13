"""Directions on the hemisphere the engine samples: uniform random directions (the isotropy and reciprocity
tests, the furnace's and the checks' samples), rotations about the normal N = +z (the isotropy tests), and the angle
between directions (the lobe search and the partition about its peaks), with the vector products it is made of."""

from __future__ import annotations

import numpy as np


def random_hemisphere(rng: np.random.Generator, count: int) -> np.ndarray:
    """Directions uniform in solid angle over the open upper hemisphere (z > 0), shape (count, 3)."""
    z = 1.0 - rng.random(count)  # (0, 1]
    phi = 2.0 * np.pi * rng.random(count)
    r = np.sqrt(1.0 - z * z)
    return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)


def rotation_about_normal(angle: float) -> np.ndarray:
    """The (3, 3) rotation by ``angle`` about N = +z (rows act on column vectors: d @ R.T turns directions d)."""
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angles between unit directions ``a`` and ``b`` (…, 3), broadcast: atan2(|a × b|, a·b), since arccos would not
    resolve angles below √ε (a narrow lobe's core). (The cross product and its length written out component by
    component: the same operations in the same order as ``np.cross`` and ``np.linalg.norm``, so the same bits, at a
    third of their cost — the lobe search takes ~10⁵ angles per batch.)"""
    return np.arctan2(np.sqrt(squared_norm(cross(a, b))), np.einsum("...i,...i->...", *np.broadcast_arrays(a, b)))


def cross(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The components of a × b (…, 3), broadcast, as ``np.cross`` computes them (a₁b₂ − a₂b₁, …)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0


def squared_norm(components) -> np.ndarray:
    """x² + y² + z² summed in that order, as ``np.linalg.norm(v, axis=-1)`` sums them before its square root, of
    the components (x, y, z) (a tuple, or a (…, 3) array)."""
    if isinstance(components, np.ndarray):
        components = components[..., 0], components[..., 1], components[..., 2]
    x, y, z = components
    return x * x + y * y + z * z


def norm(v: np.ndarray) -> np.ndarray:
    """``np.linalg.norm(v, axis=-1)`` of directions v (…, 3), the same bits, without its generic reduction over an
    axis of three."""
    return np.sqrt(squared_norm(v))
