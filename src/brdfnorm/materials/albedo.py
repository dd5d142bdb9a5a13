"""The albedos a layering rule needs inside the integrand: E_top(μ) of a layer's top lobe at any μ, and E_avg.

Three sources, chosen by the material's ``albedo_source``:

* **exact** — at the fixed direction of an albedo integral (a few distinct μ per batch: at most
  :data:`EXACT_LIMIT`) each E(μ) is the engine's own integral of the component (cached); at the free direction
  (thousands of μ), a piecewise Chebyshev interpolant of those exact values (:class:`AlbedoCurve`): degree-16 panels
  bisected until the interpolant meets the exact E at the 16 points between its nodes within
  :data:`CURVE_TOLERANCE` (or 4 times the nodes' own quadrature errors where those are larger: the sheen's); its
  error estimate is twice the largest such miss plus the nodes' own errors (on the GGX lobes of the tests the true
  error at random μ was 1e-13 to 1.3e-12 against estimates of 9e-12 to 1.8e-11). Below μ = :data:`MU_LOW` the
  curve holds E(MU_LOW) (the integrand there carries the weight μ ≤ 1e-6).
* **table** — an engine's table: E on an N × N grid over (μ, roughness) ∈ [0, 1]² (the μ = 0 row at μ = 1e-4, as
  renderers clamp it), read bilinearly, with E_avg the table's own 2∫E μ dμ (exact for the table read linearly in μ);
  so that a table-driven layering can be compared with the exact one.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np

from .components import Component

#: At most this many distinct μ are integrated one by one (the fixed directions of a batch); more use the curve.
EXACT_LIMIT = 64
CURVE_TOLERANCE = 1e-11
CURVE_DEGREE = 16
MU_LOW = 1e-6
_START = (MU_LOW, 1e-3, 0.02, 0.1, 0.3, 0.6, 1.0)
_MAX_PANELS = 256
#: Table rows at μ = 0 are evaluated here (a renderer clamps μ there too).
TABLE_MU_CLAMP = 1e-4


def _chebyshev_nodes(a: float, b: float, n: int) -> np.ndarray:
    k = np.arange(n)
    return (a + b) / 2 + (b - a) / 2 * np.cos(np.pi * (2 * k + 1) / (2 * n))[::-1]


@dataclass(frozen=True)
class AlbedoCurve:
    """E(μ) of one component as piecewise Chebyshev interpolants on ``edges``, with an error estimate."""

    edges: np.ndarray  # (P + 1,)
    coefficients: list  # P arrays (degree + 1, 3) in the panel's variable t ∈ [−1, 1]
    error: float
    low: np.ndarray  # (3,) E(MU_LOW), held below it

    def __call__(self, mu: np.ndarray) -> np.ndarray:
        mu = np.asarray(mu, dtype=float)
        flat = np.clip(mu.ravel(), MU_LOW, 1.0)
        panel = np.clip(np.searchsorted(self.edges, flat, side="right") - 1, 0, len(self.coefficients) - 1)
        out = np.empty(flat.shape + (3,))
        for p in np.unique(panel):
            where = panel == p
            a, b = self.edges[p], self.edges[p + 1]
            out[where] = np.polynomial.chebyshev.chebval((2 * flat[where] - a - b) / (b - a),
                                                         self.coefficients[p]).T
        return out.reshape(mu.shape + (3,))

    def average(self) -> tuple[np.ndarray, float]:
        """(2∫₀¹ E(μ) μ dμ of the interpolant (exact: Gauss–Legendre of enough points per panel), its error)."""
        x, w = np.polynomial.legendre.leggauss(CURVE_DEGREE + 2)
        total = self.low * MU_LOW**2
        for p, coefficients in enumerate(self.coefficients):
            a, b = self.edges[p], self.edges[p + 1]
            mu = (a + b) / 2 + (b - a) / 2 * x
            values = np.polynomial.chebyshev.chebval(x, coefficients).T
            total = total + np.sum(2.0 * mu[:, None] * values * (w * (b - a) / 2)[:, None], axis=0)
        return total, self.error + MU_LOW**2


def build_curve(component: Component) -> AlbedoCurve:
    """Bisect panels from :data:`_START` until each panel's interpolant meets the exact E between its nodes."""
    pending = list(zip(_START[:-1], _START[1:], strict=True))
    done: list[tuple[float, float, np.ndarray]] = []
    error = 0.0
    n = CURVE_DEGREE + 1
    while pending:
        if len(done) + len(pending) > _MAX_PANELS:
            raise RuntimeError(f"the albedo of {component.label} does not settle into {_MAX_PANELS} panels")
        nodes = np.concatenate([_chebyshev_nodes(a, b, n) for a, b in pending])
        checks = np.concatenate([(lambda x: (x[1:] + x[:-1]) / 2)(_chebyshev_nodes(a, b, n)) for a, b in pending])
        values, node_errors = component.albedo(np.concatenate([nodes, checks]))
        # a lobe whose own albedos are looser than the tolerance (the sheen's quadrature) is held to 4 times theirs
        tolerance = max(CURVE_TOLERANCE, 4.0 * float(node_errors.max()))
        split = []
        for i, (a, b) in enumerate(pending):
            at = values[i * n:(i + 1) * n]
            exact = values[nodes.size + i * (n - 1):nodes.size + (i + 1) * (n - 1)]
            t_nodes = (2 * nodes[i * n:(i + 1) * n] - a - b) / (b - a)
            t_checks = (2 * checks[i * (n - 1):(i + 1) * (n - 1)] - a - b) / (b - a)
            coefficients = np.polynomial.chebyshev.chebfit(t_nodes, at, n - 1)
            miss = float(np.max(np.abs(np.polynomial.chebyshev.chebval(t_checks, coefficients).T - exact)))
            if miss <= tolerance:
                done.append((a, b, coefficients))
                error = max(error, 2.0 * miss)
            else:
                split += [(a, (a + b) / 2), ((a + b) / 2, b)]
        error = max(error, float(node_errors.max()))
        pending = split
    done.sort(key=lambda panel: panel[0])
    edges = np.array([panel[0] for panel in done] + [1.0])
    low = component.albedo(np.array([MU_LOW]))[0][0]
    return AlbedoCurve(edges, [panel[2] for panel in done], error + 2 * float(np.finfo(float).eps), low)


@dataclass(frozen=True)
class AlbedoTable:
    """An engine's table: E on an N × N grid over (μ, roughness), read bilinearly at the component's roughness."""

    mu: np.ndarray
    roughness: np.ndarray
    table: np.ndarray  # (N, N, 3)
    at: float  # the component's roughness

    def __call__(self, mu: np.ndarray) -> np.ndarray:
        mu = np.clip(np.asarray(mu, dtype=float), self.mu[0], self.mu[-1])
        i = np.clip(np.searchsorted(self.mu, mu, side="right") - 1, 0, self.mu.size - 2)
        fu = ((mu - self.mu[i]) / (self.mu[i + 1] - self.mu[i]))[..., None]
        r = float(np.clip(self.at, self.roughness[0], self.roughness[-1]))
        j = int(np.clip(np.searchsorted(self.roughness, r, side="right") - 1, 0, self.roughness.size - 2))
        fr = (r - self.roughness[j]) / (self.roughness[j + 1] - self.roughness[j])
        column = (1 - fr) * self.table[:, j] + fr * self.table[:, j + 1]  # (N, 3)
        return (1 - fu) * column[i] + fu * column[i + 1]

    def average(self) -> tuple[np.ndarray, float]:
        # Linear in μ between nodes: two Gauss–Legendre points per segment integrate 2μE exactly.
        lo, hi = self.mu[:-1], self.mu[1:]
        x = np.array([-1.0, 1.0]) / np.sqrt(3.0)
        nodes = ((lo + hi)[:, None] + (hi - lo)[:, None] * x) / 2
        values = self(nodes)
        return np.sum(((hi - lo) / 2)[:, None, None] * 2 * nodes[..., None] * values, axis=(0, 1)), 0.0


def build_table(component: Component, size: int) -> AlbedoTable:
    nodes = np.linspace(0.0, 1.0, size)
    variants = [component.with_roughness(float(r)) for r in nodes]
    columns = [variant.albedo(np.maximum(nodes, TABLE_MU_CLAMP))[0] for variant in variants]
    return AlbedoTable(nodes, nodes, np.stack(columns, axis=1), float(component.roughness or 0.0))


class AlbedoCache:
    """Exact values, curves and tables per component (by its key), least recently used ones dropped."""

    def __init__(self, size: int = 64) -> None:
        self.size = size
        self._exact: OrderedDict = OrderedDict()
        self._curves: OrderedDict = OrderedDict()
        self._tables: OrderedDict = OrderedDict()

    def _remember(self, store: OrderedDict, key, make):
        if key in store:
            store.move_to_end(key)
            return store[key]
        value = store[key] = make()
        if len(store) > self.size:
            store.popitem(last=False)
        return value

    def curve(self, component: Component) -> AlbedoCurve:
        return self._remember(self._curves, component.key, lambda: build_curve(component))

    def table(self, component: Component, size: int) -> AlbedoTable:
        return self._remember(self._tables, (component.table_key, size, component.roughness),
                              lambda: build_table(component, size))

    def exact(self, component: Component, mu: np.ndarray) -> np.ndarray:
        """E at each μ (…,), each distinct value integrated once and remembered: (…, 3)."""
        known: dict = self._remember(self._exact, component.key, dict)
        mu = np.asarray(mu, dtype=float)
        unique, inverse = np.unique(mu.ravel(), return_inverse=True)
        missing = np.array([m for m in unique if m not in known])
        if missing.size:
            values, _ = component.albedo(missing)
            known.update(zip(missing.tolist(), values, strict=True))
        return np.stack([known[m] for m in unique.tolist()])[inverse].reshape(mu.shape + (3,))


CACHE = AlbedoCache()


def top_albedo(component: Component, mu: np.ndarray, source: str, size: int) -> np.ndarray:
    """E_top(μ) (…, 3) as the material's ``albedo_source`` reads it (see the module docstring); a closed form
    (:attr:`Component.closed_form`) is read exactly whatever the source."""
    if component.closed_form:
        mu = np.asarray(mu, dtype=float)
        return component.albedo(mu.ravel())[0].reshape(mu.shape + (3,))
    if source == "table":
        return CACHE.table(component, size)(mu)
    mu = np.asarray(mu, dtype=float)
    if np.unique(mu).size <= EXACT_LIMIT:
        return CACHE.exact(component, np.maximum(mu, 0.0))
    return CACHE.curve(component)(mu)


def top_average(component: Component, source: str, size: int) -> np.ndarray:
    """E_avg = 2∫E μ dμ of the top lobe as the source reads it: (3,)."""
    if source == "table":
        return CACHE.table(component, size).average()[0]
    return CACHE.curve(component).average()[0]
