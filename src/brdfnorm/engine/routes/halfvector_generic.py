"""The generic engine's half-vector route: any specular lobe integrated in the slope coordinates of
:mod:`brdfnorm.engine.routes.halfvector`, tried before the lobe-aligned coordinates of
:mod:`brdfnorm.engine.routes.hemisphere`.

What it computes
----------------
E(F) = ∫ g(ω) dω over the free direction ω, g the cosine-weighted BRDF with the fixed direction F. The reflection
map ω = 2(F·H)H − F (dω = 4 (F·H) dω_H, Walter et al. 2007 eq. 14) turns it into an integral over the half vector
H, which is written against the GGX slope distribution D_α of a width α chosen from the lobe's:

    E = ∫ w · D_α(H) H_z dω_H = (1/2π) ∫∫ w du dφ,
    w = g(ω) 4 (F·H) / (D_α(H) H_z) = g(ω) 4 (F·H) · π α² (1 + s²)² / (1 + α² s²)^{3/2},          (G1)

s the standardized slope radius (H ∝ (x, y, 1), |x| = α s) and u(s) = s²/(1 + s²) GGX's radial measure. The
rectangle (φ, v), its horizon in closed form, its pieces, and its cubature (a global tensor rule, then adaptive
G7/K15 panels confirmed on their quarters) are those of :mod:`brdfnorm.engine.routes.halfvector`; only w differs (for
the GGX
lobe itself, w is (H1) exactly: ``examples/ggx.brdf`` settles with the same evaluation counts as the built-in
GGX lobe).

Why
---
A lobe centred on the mirror direction (Blinn-Phong, Phong, every microfacet lobe) is centred on H = N for every
view: in H its width does not change with the view, and the horizon, which cuts the lobe off-centre in ω at
grazing views, is the closed-form boundary s_h(φ) of the rectangle. In the lobe-aligned coordinates of
:mod:`brdfnorm.engine.routes.hemisphere` the same lobe is stretched by the reflection and cut by a horizon that turns
within
c_P of its pole, where the trapezoid rule needs hundreds of azimuths (benchmarks/README.md, issue 13, rounds 1–5).

Where it is tried, and when its answer is kept
----------------------------------------------
- Only for isotropic lobes (:func:`brdfnorm.engine.routes.quadrature.rotation_invariant`, at each case's
  parameters), for cases whose rounding noise is below half the tolerance (:data:`HOPEFUL`), whose fixed direction
  is at least :data:`MU_MIN` above the horizon (:data:`MU_MIN_NARROW` for some lobes, :data:`MU_MIN_LOOSE`
  for narrow ones at tolerances of :data:`LOOSE` and above), and either
  whose lobe is broad (:data:`BROAD`: a spike at the mirror direction over it is at this route's pole), or
  whose peak's half vector lies within the lobe's core of N (:func:`specular`) and whose tail is a power law
  (:func:`heavy_tailed`): narrow Gaussian lobes cost both routes about the same evaluations, each cheaper in
  the lobe-aligned coordinates.
- The half azimuth range counted twice only where a sample of directions and their mirror images in the plane
  of N and F agree to rtol/64 (:func:`mirror_symmetric`); otherwise the full range.
- A case is kept only if its cubature converged, every value was finite, and the estimate plus the
  rounding-noise bound (:func:`brdfnorm.engine.machinery.rounding.noise_bound` of the |g|-integral, integrated
  alongside as
  one more channel) is within max(atol, rtol·|E|). Any other case goes on to the lobe-aligned routes as if this
  one had not been tried (its evaluations are counted).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...models.microfacet import GGXDistribution
from ..compiled import drivers as native
from ..machinery.lobe_search import fibonacci_hemisphere
from ..machinery.result import RouteResult
from ..machinery.rounding import noise_bound
from . import halfvector_global as global_rule
from .halfvector import SlopeGeometry, SlopeNodes, integrate_slopes, slope_map

#: Fixed directions closer to the horizon than this are left to the lobe-aligned routes (whose grazing honesty
#: was established down to μ = 1e-7 on random sweeps; this route's sweeps cover μ ≥ 1e-3).
MU_MIN = 1e-3
#: Below MU_MIN the route is tried down to this μ (1e-4, the tables' clamp, less the rounding of cos(arccos 1e-4))
#: for narrow heavy-tailed lobes and for broad lobes peaked near the horizon (:data:`LOW_PEAK`), whose grazing views
#: the route's graded azimuth map (:mod:`brdfnorm.engine.routes.halfvector_global`) settles far cheaper than the
#: lobe-aligned panels: examples/ggx.brdf at μ ∈ [1e-4, 1e-3], random roughness 0.05…1, rtol 1e-9 / 1e-10:
#: 206 000 / 274 000 evaluations per albedo → 31 000 / 97 000 (the true error at most 0.22 of the estimate,
#: tests/test_halfvector_generic_grazing.py); charlie.brdf 219 000 → 85 000 and multi_lobe.brdf 105 000 → 73 000
#: at rtol 1e-9. Where the shader is not finite at a node (examples/ggx.brdf at μ = 1e-4 for some roughnesses) or
#: the route fails (cook_torrance.brdf at rtol ≤ 1e-9), its evaluations are lost: up to 1.5× more there. Below
#: 1e-4 the route rarely settles at tighter tolerances than LOOSE.
MU_MIN_NARROW = 0.99e-4
#: At tolerances of LOOSE and above, narrow lobes are tried down to this μ. Where the route does settle below 1e-4 it
#: is at such tolerances: E_avg's grazing nodes (μ = 9.2e-5, 2.9e-5, 5.8e-6 of its Clenshaw–Curtis rule in √μ,
#: asked for 2.5e-6 … 1e-4 by their weights, brdfnorm.lut.table), where the lobe-aligned panels took 47 000–120 000
#: evaluations per albedo: examples/ggx.brdf's 32 × 32 E_avg, 2.6 M → 1.0 M, 1.5 M → 0.67 M and 0.61 M → 0.20 M
#: evaluations on those nodes (tests/engine/test_halfvector_generic_loose.py: estimates cover the errors there).
MU_MIN_LOOSE = 1e-6
LOOSE = 1e-7
#: Below MU_MIN a broad lobe is taken only where its peak's cos θ is below this: the horizon cuts a broad lobe
#: peaked near N (diffuse lobes: lambert, disney_diffuse, oren_nayar, eon.brdf, peaks at cos θ ≥ 0.9) far from its
#: core, which the lobe-aligned panels resolve in a few thousand evaluations (lambert.brdf at μ = 5e-4, rtol 1e-9:
#: 1 344 against 32 000 by this route), and through the core of one peaked near the horizon (charlie.brdf's sheen,
#: multi_lobe.brdf: cos θ ≤ 0.52).
LOW_PEAK = 0.7
#: A lobe whose (ω-space) width is at least this is broad: taken wherever its peak lies, since a narrow feature at
#: the mirror direction over it (a clear coat's spike over a diffuse base) lies at this route's pole, where the
#: lobe-aligned coordinates about the base's peak can miss it entirely (examples/layered_series.brdf).
BROAD = 0.5
#: The heavy-tail test: |g| at standardized slope radius FAR against the pole (:func:`heavy_tailed`).
FAR = 8.0
HEAVY = 1e-6
#: Sampled directions per case for the mirror-symmetry test: a Fibonacci lattice and a polar grid in H (also the
#: heavy-tail test's azimuths).
LATTICE = 96
RINGS = (0.125, 0.5, 1.0, 2.0, 8.0)
AZIMUTHS = 12
#: The route takes cases whose rounding-noise bound is below rtol/HOPEFUL — not only the quiet ones (below rtol/16)
#: that the global rule of the lobe-aligned coordinates takes: it adds the bound to its estimate before it keeps a
#: case, so a noisier case costs it evaluations, never honesty. examples/ggx.brdf at roughness 0.05 (noise ~6e-11
#: of the albedo): E_avg at rtol 1e-10 of roughness 0.05 and 0.1, 3.16 → 2.19 CPU s (at rtol/16); 30 random views
#: of roughness 0.03…0.12 at rtol 2.5e-11…1e-9, 18–45 % fewer evaluations, true errors ≤ 0.21 of the estimates
#: (tests/test_halfvector_generic_grazing.py).
HOPEFUL = 2.0
#: Evaluations this route may spend on a case before the lobe-aligned routes take it, and the least budget (what
#: the engine passes: a quarter of its own) for which it is tried at all.
BUDGET = 200_000
MIN_BUDGET = 20_000

_GGX = GGXDistribution()


def specular(fixed: np.ndarray, poles: np.ndarray, widths: np.ndarray,
             loose: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(eligible (K,), α (K,), broad (K,)): the lobe's half vector H_p = (P + F)/|P + F| is within its width of
    N, or the lobe is broad, and the GGX width α = tan(width/2) (the reflection doubles angles at H = N); a narrow
    lobe from :data:`MU_MIN_LOOSE` on where ``loose`` (a tolerance of :data:`LOOSE` or above)."""
    half = poles + fixed
    tilt = np.arctan2(np.hypot(half[:, 0], half[:, 1]), half[:, 2])
    width = np.asarray(widths, dtype=float)
    broad = width >= BROAD
    floor = np.where(~broad & loose, MU_MIN_LOOSE, MU_MIN_NARROW)
    eligible = (fixed[:, 2] >= floor) & ((tilt <= width) | broad)
    eligible &= (fixed[:, 2] >= MU_MIN) | ~broad | (poles[:, 2] < LOW_PEAK)
    alpha = np.tan(np.clip(0.5 * width, 1e-8, np.pi / 4))
    return eligible, alpha, broad


def _ring(integrand: Callable, fixed: np.ndarray, alpha: np.ndarray, cases: np.ndarray, slopes: tuple,
          extra: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(ω (k, m, 3), g (k, m, C) with 0 below the horizon): ω = 2(F·H)H − F for H at standardized
    slope radii ``slopes`` (slowest) × :data:`AZIMUTHS` azimuths, then the directions ``extra`` (m', 3)."""
    F = fixed[cases]
    ring, phi = np.meshgrid(np.asarray(slopes), np.arange(AZIMUTHS) * (2 * np.pi / AZIMUTHS) + 0.1, indexing="ij")
    slope = alpha[cases][:, None] * ring.ravel()  # |x| = α s
    H = np.stack([slope * np.cos(phi.ravel()), slope * np.sin(phi.ravel()), np.ones_like(slope)], axis=-1)
    H /= np.linalg.norm(H, axis=-1, keepdims=True)
    omega = reflect(F[:, None, :], H)
    if extra is not None:
        omega = np.concatenate([omega, np.broadcast_to(extra, (cases.size,) + extra.shape)], axis=1)
    return omega, _values(integrand, omega, cases)


def _values(integrand: Callable, omega: np.ndarray, cases: np.ndarray) -> np.ndarray:
    index = np.broadcast_to(cases[:, None], omega.shape[:2]).ravel()
    with np.errstate(all="ignore"):
        g = np.asarray(integrand(omega.reshape(-1, 3), index), dtype=float).reshape(omega.shape[:2] + (-1,))
    return np.where((omega[..., 2] > 0)[..., None], g, 0.0)


def heavy_tailed(integrand: Callable, fixed: np.ndarray, alpha: np.ndarray, cases: np.ndarray) -> np.ndarray:
    """Per case of ``cases``: |g| at slope radius s = :data:`FAR` (α s from N in H) exceeds :data:`HEAVY` of |g| at
    the pole. A power-law tail (GGX: (1 + s²)⁻² = 2.4e-4 there) is where the lobe-aligned coordinates need many
    nodes near the horizon and this route does not; a Gaussian one (Blinn-Phong, Phong, Beckmann: below 1e-20)
    costs both routes about the same evaluations, each cheaper in the lobe-aligned ones."""
    _, g = _ring(integrand, fixed, alpha, cases, (0.0, FAR))
    pole, far = np.abs(g[:, :AZIMUTHS]).max(axis=(1, 2)), np.abs(g[:, AZIMUTHS:]).max(axis=(1, 2))
    with np.errstate(invalid="ignore", divide="ignore"):
        return far > HEAVY * pole


def reflect(fixed: np.ndarray, H: np.ndarray) -> np.ndarray:
    """ω = 2 (F·H) H − F."""
    return 2.0 * np.einsum("...i,...i->...", fixed, H)[..., None] * H - fixed


def mirror_symmetric(integrand: Callable, fixed: np.ndarray, alpha: np.ndarray, cases: np.ndarray,
                     rtol: float) -> np.ndarray:
    """Per case of ``cases``: g(ω) = g(ω') to rtol/64 of max |g| on a sample, ω' the mirror image of ω in the
    plane of N and F (the plane :func:`brdfnorm.engine.routes.halfvector.integrate_slopes` folds the azimuth about)."""
    omega, g = _ring(integrand, fixed, alpha, cases, RINGS, fibonacci_hemisphere(LATTICE))
    azimuth = np.arctan2(fixed[cases, 1], fixed[cases, 0])
    across = np.stack([-np.sin(azimuth), np.cos(azimuth), np.zeros_like(azimuth)], axis=-1)  # normal of the plane
    image = omega - 2.0 * np.einsum("kmi,ki->km", omega, across)[..., None] * across[:, None, :]
    g_image = _values(integrand, image, cases)  # the image keeps ω_z: the plane is vertical
    scale = np.max(np.abs(g), axis=(1, 2))
    difference = np.max(np.abs(g - g_image), axis=(1, 2))
    return np.isfinite(scale) & np.isfinite(difference) & (difference <= rtol / 64 * scale)


def route(fixed: np.ndarray, isotropic: np.ndarray, integrand: Callable, poles: np.ndarray, widths: np.ndarray,
          quiet: np.ndarray, noise_amplitude: np.ndarray, *, rtol: float, atol: float,
          max_evaluations: int) -> RouteResult:
    """(G1) for the cases ``quiet`` whose noise is below rtol/:data:`HOPEFUL`, whose lobe is ``isotropic`` (K,) and
    :func:`specular` (module docstring), as
    :func:`brdfnorm.engine.routes.hemisphere.integrate_hemisphere` tries it first: ``converged`` says which cases it
    keeps (the
    other rows are to be ignored; their evaluations are counted)."""
    K = fixed.shape[0]
    quiet = quiet[np.all(noise_bound(noise_amplitude[quiet], 1.0) < rtol / HOPEFUL, axis=-1)]
    eligible, alpha, broad = specular(fixed, poles, widths, loose=rtol >= LOOSE)
    eligible &= isotropic
    cases = quiet[eligible[quiet]] if max_evaluations >= MIN_BUDGET else quiet[:0]
    budget = min(max_evaluations, BUDGET)
    evaluations = np.zeros(K, dtype=np.int64)
    kept = np.zeros(K, dtype=bool)
    narrow = cases[~broad[cases]]
    if narrow.size:
        evaluations[narrow] += 2 * AZIMUTHS
        cases = np.union1d(cases[broad[cases]], narrow[heavy_tailed(integrand, fixed, alpha, narrow)])
    if not cases.size:
        return RouteResult(np.zeros((K, 1)), np.zeros((K, 1)), evaluations, kept)
    symmetric = mirror_symmetric(integrand, fixed, alpha, cases, rtol)
    evaluations[cases] += 2 * (LATTICE + len(RINGS) * AZIMUTHS)
    F = fixed[cases]
    g = SlopeGeometry(_GGX, "", F, alpha[cases], alpha[cases], np.zeros(cases.size))
    failed = np.zeros(cases.size, dtype=bool)
    fused = hasattr(integrand, "kernels")  # the compiled backend: the rectangle integrand is one kernel

    def weight_of(n: SlopeNodes) -> np.ndarray:
        root = np.sqrt(n.n2)
        cos_fh = F[n.k, 2] * n.one_sp / root  # F·H
        hx, hy = n.s * n.dx / root, n.s * n.dy / root
        shape = np.broadcast_shapes(n.s.shape, n.Lz.shape, hx.shape)
        omega = np.empty(shape + (3,))
        omega[..., 0] = 2.0 * cos_fh * hx - F[n.k, 0]
        omega[..., 1] = 2.0 * cos_fh * hy - F[n.k, 1]
        omega[..., 2] = n.Lz  # N·ω with its relative accuracy at the horizon (halfvector's product form)
        local = np.broadcast_to(n.k, shape)
        values = np.asarray(integrand(omega.reshape(-1, 3), cases[local.ravel()]), dtype=float)
        values = values.reshape(shape + (-1,))
        a = g.ax[n.k]
        jacobian = 4.0 * cos_fh * np.pi * a * a * (1.0 + n.s * n.s) ** 2 / (n.n2 * root) * n.weight_t * n.azimuth
        inside = n.Lz > 0
        finite = np.isfinite(values).all(axis=-1) | ~inside
        if not finite.all():
            failed[np.unique(np.broadcast_to(n.k, shape)[~finite])] = True
        weighted = np.where((inside & finite)[..., None], values * jacobian[..., None], 0.0)
        # g, and the largest |g| of its channels: the magnitude the noise bound scales with (one channel more).
        return np.concatenate([weighted, np.abs(weighted).max(axis=-1, keepdims=True)], axis=-1)

    with np.errstate(all="ignore"):
        # Half the budget for the global rule (three radial pieces), the rest for the panels.
        result = integrate_slopes(g, weight_of, symmetric, rtol=rtol, atol=atol, max_evaluations=budget,
                                  max_nodes=min(global_rule.MAX_NODES, budget // (2 * global_rule.PIECES)),
                                  rectangle=None if not fused else (
                                      lambda linear: native.slope_rectangle(
                                          integrand, slope_map(g), F, cases, failed, linear,
                                          linear and _GGX.name in global_rule.GRADED)))
    value, error, magnitude = result.value[:, :-1], result.error[:, :-1], result.value[:, -1:]
    error = error + noise_bound(np.broadcast_to(noise_amplitude[cases], value.shape), magnitude)
    within = np.all(error <= np.maximum(atol, rtol * np.abs(value)), axis=1)
    ok = result.converged & ~failed & within & np.all(np.isfinite(value) & np.isfinite(error), axis=1)
    out_value, out_error = np.zeros((K, value.shape[1])), np.zeros((K, value.shape[1]))
    out_value[cases], out_error[cases] = value, error
    evaluations[cases] += result.evaluations
    kept[cases] = ok
    return RouteResult(out_value, out_error, evaluations, kept)
