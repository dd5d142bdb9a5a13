"""Hemispherical average of a rough dielectric's albedo, E_avg = 2∫₀¹ E(μ) μ dμ, as one 3-D integral over the
facet normal and the view about it — no albedo is computed on the way.

With the BSDF in its energy form (:mod:`brdfnorm.models.dielectric`; Walter et al. 2007), E(V) = ∫ w(V, m) D(m)
(V·m)/V_z dm, w = F G2_r on the reflecting side and (1 − F) G2_t on the refracting one, so

    E_avg = (1/π) ∫_H E(V) V_z dV = (1/π) ∫ du / m_z ∫_{V·m > 0} w(V, m) (V·m) dV,                          (A1)

u the facets' slope CDF (D(m) m_z dm = du dφ_m/2π; the lobe is isotropic, so φ_m drops out). The view is written
about its facet, V = cos θ' m + sin θ' (cos φ' t₁ + sin φ' t₂) with t₁ in the plane of m and N, so that

- V·m = cos θ' is a coordinate, and total internal reflection (η < 1: V·m < c* = √(1 − η²)) is the line θ' = θ_c;
- V_z = cos θ' m_z + sin θ' sin β cos φ' (β the facet's polar angle) is linear in cos φ', and so are both scattered
  L_z: the reflected L is above the surface for |cos φ'| < cot θ' cot β, the refracted one below for cos φ' >
  −η cos θ_t cot β / sin θ' (and V above for cos φ' > −cot θ' cot β) — each inner range in closed form.

Each range's ends are square-root points of the next integral out (the φ'-range opens at θ' = π/2 − β, and for T at
cos θ' = √(1 − η² m_z²); 1 − F has a square root at θ_c), so θ' is cut there — and where the shadowing's boundary
layers begin (cos θ' = 4α for the views near the horizon, cos θ_t = 4α for the refracted L next to θ_c) — and every
range is mapped by y = (1 − cos πx)/2, which makes square roots at both ends analytic; in the facet slope the
collision of θ_c with π/2 − β is a kink (at s = √(1 − η²)/(ηα)), also a cut. The slope radius s runs over panels cut
at 1 and 1/α — in the pole coordinate on [0, 1], log s up to 1/α, and cot β = 1/(αs) beyond (analytic to the
horizontal facet) — so that every panel's integrand is analytic. Gauss–Legendre rules of order n per panel and
dimension, for n in :data:`ORDERS`, give Q_n; the error of Q_n is |Q_n − Q_n'| + |Q_n' − Q_n''| (the two previous
orders: each difference is the error of the coarser, pessimistic for Q_n while the rules converge geometrically),
and the first Q_n within tolerance is kept. Combinations not settled by the last order are reported so (the tables
then fall back to the μ-average of albedos, :mod:`brdfnorm.lut.glass`).

Measured against that μ-average (rtol 1e-10): GGX α = 0.3, η = 1/1.5 to 1.4e-14 in 0.5 s where the μ-average took
454 albedos and 23.5 s (tests/engine/test_dielectric_average.py); the 256 (α, η) of a 16³ glass table at rtol
1e-9 in 20 s on two cores (benchmarks/results/glass.md).
"""

from __future__ import annotations

import functools

import numpy as np

from ...models.dielectric import refraction_kind, refraction_shadowing
from ...models.microfacet import Distribution, fresnel_dielectric, shadowing_masking
from ...validate import DEFAULT_RTOL
from ..machinery.result import RouteResult
from ..machinery.slope_coordinates import slope_coordinates

#: Gauss–Legendre orders per panel and dimension, tried in turn.
ORDERS = (16, 20, 24, 28, 32, 40, 48, 56, 64, 80, 96)
#: The horizon's boundary layer (Λ turns on) spans directions with |ω_z| ≲ LAYER·α.
_LAYER = 4.0
#: Slope-radius nodes per array pass (memory: this times the θ' and φ' nodes of one order).
_CHUNK = 16


@functools.cache
def _legendre(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss–Legendre nodes and weights on [0, 1] (cached: numpy's eigenvalue solve was 15% of the run)."""
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1.0) / 2.0, w / 2.0


@functools.cache
def _graded(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Nodes and weights on [0, 1] of y = (1 − cos πx)/2: a square root at either end becomes analytic."""
    x, w = _legendre(n)
    return (1.0 - np.cos(np.pi * x)) / 2.0, w * (np.pi / 2.0) * np.sin(np.pi * x)


def _slope_nodes(distribution: Distribution, alpha: float, n: int, cuts: list[float]):
    """Slope radii s and weights du over panels between ``cuts`` (0, 1, 1/α, the cap and any kink): the pole
    coordinate on [0, min(1, 1/α)], log s up to 1/α, c = 1/(αs) beyond."""
    x, w = _legendre(n)
    coords = slope_coordinates(distribution)
    cap = float(coords.cap(np.array(np.inf)))
    knee, far = min(1.0, 1.0 / alpha), 1.0 / alpha
    edges = sorted({0.0, knee, far, cap, *(c for c in cuts if 0.0 < c < cap)})
    edges = [e for e in edges if e <= cap]
    radii, weights = [], []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        if hi <= knee:
            t0, t1 = coords.pole_coordinate(np.array(lo)), coords.pole_coordinate(np.array(hi))
            s, density = coords.pole(t0 + (t1 - t0) * x)
            weights.append(w * (t1 - t0) * density)
        elif hi <= far:
            l0, l1 = np.log(lo), np.log(hi)
            s = np.exp(l0 + (l1 - l0) * x)
            weights.append(w * (l1 - l0) * s * distribution.slope_density(s))
        else:
            c0, c1 = 1.0 / (alpha * hi), 1.0 / (alpha * lo)
            c = c0 + (c1 - c0) * x
            s = 1.0 / (alpha * c)
            weights.append(w * (c1 - c0) * distribution.slope_density(s) / (alpha * c * c))
        radii.append(s)
    return np.concatenate(radii), np.concatenate(weights)


def _inner(part: str, distribution: Distribution, alpha: float, eta: float, shadowing: str, s: np.ndarray,
           n: int, refraction: str = "auto") -> tuple[np.ndarray, int]:
    """∫ w (V·m) dV over the views about each facet of slope radius s (the inner two integrals of (A1)), and the
    number of integrand nodes it took."""
    mz = 1.0 / np.sqrt(1.0 + (alpha * s) ** 2)
    sin_b = alpha * s * mz
    cot_b = 1.0 / (alpha * s)
    critical = np.sqrt(max(1.0 - eta * eta, 0.0))
    top = np.arccos(critical) if (part == "T" and eta < 1.0) else np.pi / 2
    # The horizon's boundary layer for facets near the mean normal: V_z (and the reflected L_z) ≲ LAYER·α.
    cuts = [np.zeros_like(s), np.full_like(s, top), np.pi / 2 - np.arctan(alpha * s),
            np.full_like(s, np.arccos(min(_LAYER * alpha, 1.0)))]
    if critical > 0.0:
        cuts.append(np.full_like(s, np.arccos(critical)))
        if part == "T":  # the refracted L's layer next to the critical angle: cos θ_t ≲ LAYER·α
            layer = np.sqrt(max(1.0 - eta * eta * (1.0 - (_LAYER * alpha) ** 2), 0.0))
            cuts.append(np.full_like(s, np.arccos(min(layer, 1.0))))
    if part == "T":
        opening = 1.0 - (eta * mz) ** 2
        cuts.append(np.where(opening > 0.0, np.arccos(np.sqrt(np.clip(opening, 0.0, 1.0))), 0.0))
    cuts = np.sort(np.clip(np.stack(cuts, axis=1), 0.0, top), axis=1)
    y, wy = _graded(n)
    a, b = cuts[:, :-1, None], cuts[:, 1:, None]
    used = np.any(b > a, axis=(0, 2))  # segments empty for every facet (cuts that coincide or lie past the top)
    a, b = a[:, used], b[:, used]
    theta, w_theta = a + (b - a) * y, (b - a) * wy  # (S, segments, n)
    ct, st = np.cos(theta), np.sin(theta)
    F = fresnel_dielectric(ct, eta)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        cb = cot_b[:, None, None]
        if part == "R":
            reach = np.minimum(np.where(st > 0.0, ct / st * cb, np.inf), 1.0)  # |cos φ'| < cot θ' cot β
            p0, p1, weight = np.arccos(reach), np.pi - np.arccos(reach), F
        else:
            cos_t = np.sqrt(np.maximum(1.0 - (1.0 - ct * ct) / (eta * eta), 0.0))
            lower = np.where(st > 0.0, np.maximum(-ct / st * cb, -eta * cos_t * cb / st), -np.inf)
            p0, p1, weight = np.zeros_like(ct), np.arccos(np.clip(lower, -1.0, 1.0)), 1.0 - F
        phi = p0[..., None] + (p1 - p0)[..., None] * y
        w_phi = (p1 - p0)[..., None] * wy
        m_z, s_b, c, s_ = mz[:, None, None, None], sin_b[:, None, None, None], ct[..., None], st[..., None]
        vz = c * m_z + s_ * np.cos(phi) * s_b
        if part == "R":
            lz = 2.0 * c * m_z - vz
            side = lz > 0.0
        else:
            lz = -vz / eta + (ct / eta - cos_t)[..., None] * m_z
            side = lz < 0.0
        lam = distribution.smith_lambda
        lambda_v, lambda_l = lam(alpha**2 * (1.0 - vz * vz) / (vz * vz)), lam(alpha**2 * (1.0 - lz * lz) / (lz * lz))
        if part == "R":
            G2 = shadowing_masking(shadowing, lambda_l, lambda_v)
        else:
            G2 = refraction_shadowing(refraction_kind(shadowing, refraction), lambda_l, lambda_v)
        g = np.where(side & (vz > 0.0) & np.isfinite(G2), G2, 0.0)
    # φ' over [0, π] counted twice (the views mirror about the plane of m and N).
    return 2.0 * np.einsum("skij,skij,ski,ski->s", g, w_phi, weight * st * ct, w_theta), g.size


def _quadrature(distribution: Distribution, alpha: float, eta: float, shadowing: str, n: int,
                refraction: str = "auto") -> tuple[float, float, int]:
    """(R̄, T̄) of (A1) by the order-n rules, and the integrand nodes they took."""
    kink = [np.sqrt(1.0 - eta * eta) / (eta * alpha)] if eta < 1.0 else []
    s, du = _slope_nodes(distribution, alpha, n, kink)
    mz = 1.0 / np.sqrt(1.0 + (alpha * s) ** 2)
    parts, nodes = [], 0
    for part in ("R", "T"):
        chunks = [_inner(part, distribution, alpha, eta, shadowing, s[i:i + _CHUNK], n, refraction)
                  for i in range(0, s.size, _CHUNK)]
        inner = np.concatenate([values for values, _ in chunks])
        nodes += sum(count for _, count in chunks)
        parts.append(float(np.sum(du / mz * inner)) / np.pi)
    return parts[0], parts[1], nodes


def average_albedo(distribution: Distribution, alpha, eta, shadowing: str = "height-correlated",
                   refraction: str = "auto", *, rtol: float = DEFAULT_RTOL, atol: float = 0.0) -> RouteResult:
    """E_avg = R̄ + T̄ of the rough dielectric for each (α, η) (arrays broadcast to (M,)); ``refraction`` the
    refraction's G2 (the model's ``refraction_shadowing``). The result's arrays are (M,), its extras
    ``reflected`` and ``transmitted`` the R̄ and T̄ parts."""
    alpha, eta = (np.atleast_1d(np.asarray(q, dtype=float)) for q in (alpha, eta))
    alpha, eta = np.broadcast_arrays(alpha, eta)
    M = alpha.size
    value, error = np.zeros(M), np.full(M, np.inf)
    reflected, transmitted = np.zeros(M), np.zeros(M)
    converged = np.zeros(M, dtype=bool)
    evaluations = np.zeros(M, dtype=np.int64)
    # Beckmann's truncation: the dropped facets carry ≤ ∫ du/m_z = ∫ √(1 + α²s²) dP ≤ mass + α·moment (the inner
    # integral of (A1) is at most π).
    mass, moment = slope_coordinates(distribution).truncated_moments()
    for k in range(M):
        history = []
        for n in ORDERS:
            r, t, nodes = _quadrature(distribution, float(alpha.flat[k]), float(eta.flat[k]), shadowing, n,
                                      refraction)
            evaluations[k] += nodes
            history.append(r + t)
            if len(history) >= 3:
                estimate = abs(history[-1] - history[-2]) + abs(history[-2] - history[-3])
                estimate += mass + float(alpha.flat[k]) * moment
                value[k], error[k], reflected[k], transmitted[k] = r + t, estimate, r, t
                if not np.isfinite(estimate):
                    error[k] = np.inf
                    break
                if estimate <= max(atol, rtol * abs(r + t)):
                    converged[k] = True
                    break
    return RouteResult(value, error, evaluations, converged,
                       extras={"reflected": reflected, "transmitted": transmitted})
