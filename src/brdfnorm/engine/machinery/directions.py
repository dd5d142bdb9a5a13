"""Directions on the hemisphere the engine samples: uniform random directions (the isotropy and reciprocity
tests, the furnace's and the checks' samples), rotations about the normal N = +z (the isotropy tests), and the angle
between directions (the lobe search and the partition about its peaks)."""

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
    resolve angles below √ε (a narrow lobe's core)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.einsum("...i,...i->...", *np.broadcast_arrays(a, b)))
