"""The error a renderer sees: bilinear (trilinear) interpolation of a table against exact values, and the same
for exact tables of 8 … 128 samples per axis (error against resolution).

A GPU fetches a table by linear interpolation between its samples in each axis's unit coordinate t, clamped at
the ends (clamp-to-edge: below the first texel centre it returns the first texel). Here each axis's samples sit
where the audited convention puts them (:func:`.conventions.unit_positions`), and the interpolant is compared with the
exact quantity at dense points: the texel centres (j + ½)/(8N) of a grid 8× finer than the table on every axis,
all of them when there are at most ``max_points``, else a seeded random subset of them of that size (stated in
the result). The exact values come from :class:`.reference.Reference` (shared cache), so the dense points are
computed once for the table and for every size of the sweep.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from .conventions import Convention, axis_roles, fresnel_of, role_value, unit_positions
from .reference import Reference

SWEEP_SIZES = (8, 16, 32, 64, 128)
#: Dense points and sweep cells for cheap meanings and for those needing F90 (~3 ms a cell).
MAX_POINTS = {"cheap": 16384, "f90": 768}
MAX_SWEEP_CELLS = {"cheap": 20000, "f90": 1200}
DENSITY = 8


@dataclass
class DenseError:
    """Interpolation error of a table at dense points."""

    max: float
    rms: float
    worst: dict  # coordinates (mu, alpha, f0) of the worst point
    points: int
    of_grid: int  # size of the 8× grid the points were taken from


def dense_points(c: Convention, shape: tuple[int, ...], max_points: int, seed: int = 7) -> tuple[list[np.ndarray],
                                                                                                  int]:
    """Unit coordinates t (one array per axis, each of P points) on the 8× texel-centre grid."""
    fine = [DENSITY * n for n in shape]
    total = int(np.prod(fine))
    rng = np.random.default_rng(seed)
    if total <= max_points:
        cells = [g.ravel() for g in np.meshgrid(*[np.arange(f) for f in fine], indexing="ij")]
    else:
        cells = [rng.integers(0, f, max_points) for f in fine]
    # one point at a random place in each chosen cell of the fine grid: never on the samples of a swept table
    return [(c + rng.random(c.size)) / f for c, f in zip(cells, fine, strict=True)], total


def physical(c: Convention, t: list[np.ndarray]) -> dict[str, np.ndarray]:
    """μ, α, f0 at unit coordinates ``t`` (floors applied)."""
    out = {}
    for axis, role in axis_roles(c).items():
        floor = {"mu": c.mu_floor, "alpha": c.alpha_floor}.get(role, -np.inf)
        out[role] = np.maximum(role_value(c, role, t[axis]), floor)
    return out


def interpolate(table: np.ndarray, c: Convention, t: list[np.ndarray]) -> np.ndarray:
    """Multilinear interpolation of ``table`` (stored order, flips included) at unit coordinates ``t``."""
    roles = axis_roles(c)
    index = [slice(None, None, -1) if c.flips[a] else slice(None) for a in range(table.ndim)]
    table = table[tuple(index)]  # increasing t along every axis
    lows, weights = [], []
    for axis in range(table.ndim):
        n = table.shape[axis]
        p = unit_positions(c, roles[axis], n, np.arange(n), False)
        x = np.clip(t[axis], p[0], p[-1])
        i = np.clip(np.searchsorted(p, x, side="right") - 1, 0, max(n - 2, 0))
        span = p[np.minimum(i + 1, n - 1)] - p[i]
        w = np.where(span > 0, (x - p[i]) / np.where(span > 0, span, 1.0), 0.0)
        lows.append(i)
        weights.append(w)
    out = np.zeros_like(t[0])
    for corner in range(2 ** table.ndim):
        weight = np.ones_like(t[0])
        idx = []
        for axis in range(table.ndim):
            up = (corner >> axis) & 1
            n = table.shape[axis]
            idx.append(np.minimum(lows[axis] + up, n - 1))
            weight = weight * (weights[axis] if up else 1.0 - weights[axis])
        out = out + weight * table[tuple(idx)]
    return out


def _exact_at(reference: Reference, c: Convention, meaning: str, coords: dict) -> np.ndarray:
    return reference.meaning(meaning, c.shadowing, coords.get("mu"), coords["alpha"], coords.get("f0"),
                             axis_eta=coords.get("eta"),
                             **fresnel_of(c))[0]


def dense_error(table: np.ndarray, c: Convention, meaning: str, reference: Reference,
                points: tuple[list[np.ndarray], int]) -> DenseError:
    t, of_grid = points
    coords = physical(c, t)
    exact = _exact_at(reference, c, meaning, coords)
    error = interpolate(table, c, t) - exact
    magnitude = np.where(np.isfinite(error), np.abs(error), np.inf)
    k = int(np.argmax(magnitude))
    return DenseError(float(magnitude[k]), float(np.sqrt(np.mean(np.where(np.isfinite(error), error, 0.0) ** 2))),
                      {name: float(v[k]) for name, v in coords.items()}, int(t[0].size), of_grid)


def exact_table(c: Convention, meaning: str, reference: Reference, shape: tuple[int, ...]) -> np.ndarray:
    """The exact table of ``shape`` in convention ``c`` (stored order)."""
    from .conventions import coordinates

    mesh = list(np.meshgrid(*[np.arange(n) for n in shape], indexing="ij"))
    coords = coordinates(c, shape, mesh)
    return _exact_at(reference, c, meaning, coords)


def sweep(c: Convention, meaning: str, reference: Reference, points: tuple[list[np.ndarray], int],
          ndim: int, sizes=SWEEP_SIZES) -> list[dict]:
    """Interpolation error of exact tables of each size (per axis) in convention ``c`` (unflipped)."""
    plain = replace(c, flips=(False,) * ndim)
    budget = MAX_SWEEP_CELLS["f90" if Reference.expensive(meaning) else "cheap"]
    out = []
    # an f0 axis adds no new reference cells (E_f0 is linear in f0); an η axis does, and so does f0 under the exact
    # dielectric factor (a quadrature at each f0's η)
    pairs_axes = ndim - (c.f0_axis is not None and not c.f0.startswith("eta") and meaning != "E_f0_dielectric")
    for size in sizes:
        if size ** pairs_axes > budget:
            out.append({"size": size, "skipped": f"more than {budget} exact cells"})
            continue
        # explicit axes (--axis) become `size` nodes over the same range
        sized = replace(plain, explicit=tuple((name, tuple(np.linspace(v[0], v[-1], size)))
                                              for name, v in plain.explicit))
        table = exact_table(sized, meaning, reference, (size,) * ndim)
        e = dense_error(table, sized, meaning, reference, points)
        out.append({"size": size, "max": e.max, "rms": e.rms})
    return out


def budget_points(meaning: str) -> int:
    return MAX_POINTS["f90" if Reference.expensive(meaning) else "cheap"]
