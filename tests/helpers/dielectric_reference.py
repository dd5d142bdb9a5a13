"""An independent reference for the rough dielectric's R and T: the facet normal m in spherical coordinates about
the view V (θ' = ∠(m, V), φ' about V), nested ``scipy.integrate.quad``. Shares no code with brdfnorm.

In these coordinates V·m = cos θ' is the outer variable, so total internal reflection (V·m = c*) is a breakpoint
of the outer integral, and each side condition — the reflected L above the surface, the refracted L below it, the
facet above — is an interval of cos φ' in closed form (m_z is linear in cos φ'). The energy form of the BSDF
(Walter et al. 2007, with the facet's sampling density D(m) m_z) gives

    R = ∫ F(V·m) G2(L_r, V) D(m) (V·m)/V_z dm,      T = ∫ (1 − F(V·m)) G2(L_t, V) D(m) (V·m)/V_z dm,

with Smith's height-correlated G2: 1/(1 + Λ_V + Λ_L) for reflection, Heitz's B(1 + Λ_V, 1 + Λ_L) for refraction.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.integrate import IntegrationWarning, quad
from scipy.optimize import brentq
from scipy.special import betaln


def _distribution(name: str, alpha: float):
    """(D(m_z), Λ(tan² θ)) of GGX or Beckmann."""
    if name == "ggx":
        def D(mz):
            return alpha * alpha / (math.pi * (mz * mz * (alpha * alpha - 1.0) + 1.0) ** 2)

        def lam(tan2):
            return (-1.0 + math.sqrt(1.0 + alpha * alpha * tan2)) / 2.0
        return D, lam

    def D(mz):
        tan2 = (1.0 - mz * mz) / (mz * mz)
        return math.exp(-tan2 / (alpha * alpha)) / (math.pi * alpha * alpha * mz**4)

    def lam(tan2):
        if tan2 == 0.0:
            return 0.0
        a = 1.0 / (alpha * math.sqrt(tan2))
        return (math.erf(a) - 1.0) / 2.0 + math.exp(-a * a) / (2.0 * a * math.sqrt(math.pi)) if a < 30 else 0.0
    return D, lam


def _fresnel(c: float, eta: float) -> float:
    s2t = (1.0 - c * c) / (eta * eta)
    if s2t >= 1.0:
        return 1.0
    ct = math.sqrt(1.0 - s2t)
    rs, rp = (c - eta * ct) / (c + eta * ct), (eta * c - ct) / (eta * c + ct)
    return 0.5 * (rs * rs + rp * rp)


def albedo_part(distribution: str, mu: float, alpha: float, eta: float, part: str,
                refraction: str = "correlated-beta") -> float:
    """R (``part="R"``) or T (``"T"``) of the rough dielectric at cos θ_V = ``mu``, to ~1e-13; ``refraction`` the
    refraction's G2: Heitz's B(1 + Λ_V, 1 + Λ_L) (``correlated-beta``), 1/(1 + Λ_V + Λ_L) (``reflection-form``) or
    1/((1 + Λ_V)(1 + Λ_L)) (``separable``)."""
    D, lam = _distribution(distribution, alpha)
    vz, sin_v = mu, math.sqrt(1.0 - mu * mu)
    lambda_v = lam(sin_v * sin_v / (vz * vz))

    def mz_range(tp):
        """Facet heights m_z allowed at θ' (the side condition on L, and m_z > 0)."""
        c = math.cos(tp)
        if part == "R":
            return vz / (2.0 * c), math.inf  # L_z = 2 c m_z − V_z > 0
        s2t = (1.0 - c * c) / (eta * eta)
        if s2t >= 1.0:
            return None
        slope = c / eta - math.sqrt(1.0 - s2t)  # L_z = −V_z/η + slope·m_z < 0
        return 0.0, (math.inf if slope <= 0 else vz / eta / slope)

    def cos_range(tp):
        """The interval of cos φ' (m_z = cos θ' V_z + sin θ' sin θ_V cos φ'), unclipped."""
        r = mz_range(tp)
        if r is None:
            return None
        k = math.sin(tp) * sin_v
        base = math.cos(tp) * vz
        if k == 0.0:
            return (-math.inf, math.inf) if r[0] < base < r[1] else (math.inf, -math.inf)
        return (r[0] - base) / k, (r[1] - base) / k

    def inner(tp):
        r = cos_range(tp)
        if r is None:
            return 0.0
        lo, hi = max(r[0], -1.0), min(r[1], 1.0)
        if lo >= hi:
            return 0.0
        c, s = math.cos(tp), math.sin(tp)
        weight = _fresnel(c, eta) if part == "R" else 1.0 - _fresnel(c, eta)
        if part == "T":
            slope = c / eta - math.sqrt(max(1.0 - (1.0 - c * c) / (eta * eta), 0.0))

        def g(p):
            mz = c * vz + s * math.cos(p) * sin_v
            if mz <= 0.0:
                return 0.0
            lz = 2.0 * c * mz - vz if part == "R" else -vz / eta + slope * mz
            if (lz <= 0.0) if part == "R" else (lz >= 0.0):
                return 0.0
            lambda_l = lam((1.0 - lz * lz) / (lz * lz))
            if part == "R":
                g2 = 1.0 / (1.0 + lambda_v + lambda_l)
            elif refraction == "correlated-beta":
                g2 = math.exp(betaln(1.0 + lambda_v, 1.0 + lambda_l))
            elif refraction == "reflection-form":
                g2 = 1.0 / (1.0 + lambda_v + lambda_l)
            else:
                g2 = 1.0 / ((1.0 + lambda_v) * (1.0 + lambda_l))
            return weight * g2 * D(mz) * c / vz

        return 2.0 * s * quad(g, math.acos(hi), math.acos(lo), epsabs=1e-15, epsrel=1e-14, limit=200)[0]

    # Breakpoints of the outer integral: the critical angle, and where the cos φ' interval's ends cross ±1.
    critical = math.sqrt(max(1.0 - eta * eta, 0.0))
    top = math.acos(critical) if (part == "T" and eta < 1.0) else math.pi / 2
    points = [math.acos(critical)] if critical > 0 else []
    grid = np.linspace(1e-9, top - 1e-9, 4001)

    def end(tp, which):
        r = cos_range(tp)
        return np.nan if r is None else float(np.clip(r[which], -1e300, 1e300))

    for which in (0, 1):
        values = np.array([end(t, which) for t in grid])
        for target in (-1.0, 1.0):
            sign = np.sign(values - target)
            for i in np.flatnonzero(sign[:-1] * sign[1:] < 0):
                points.append(brentq(lambda t, w=which, y=target: end(t, w) - y, grid[i], grid[i + 1], xtol=1e-16))
    edges = sorted({0.0, top, *(p for p in points if 0.0 < p < top)})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", IntegrationWarning)
        pieces = zip(edges[:-1], edges[1:], strict=True)
        return sum(quad(inner, a, b, epsabs=1e-14, epsrel=1e-13, limit=400)[0] for a, b in pieces)

