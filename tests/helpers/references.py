"""Reference integrals the tests compare brdfnorm with: plain functions of numpy/scipy that share no code with
brdfnorm's quadrature (moved here from conftest.py, issue 40 item 6)."""

from __future__ import annotations

import numpy as np
from scipy import integrate


def phong_like_reference(n: float, theta: float, *, original: bool) -> float:
    """E(θ_o) of max(0,R·V)^n (N·L) (modified) or max(0,R·V)^n (original) by a 1-D integral.

    In polar coordinates (α, β) about P = mirror(V), R·V = cos α and N·L = a + b cos β with a = cos θ_o cos α,
    b = sin θ_o sin α; the β integral over {N·L > 0} is elementary:
    ∫ max(0, a + b cos β) dβ = 2(a·β0 + √(b² − a²)), and the measure of {a + b cos β > 0} is 2β0,
    β0 = arccos(−a/b) (clipped to [0, π]). The remaining α integral runs over [0, π/2] (R·V ≥ 0).
    """

    def beta_integral(alpha: float) -> float:
        a = np.cos(theta) * np.cos(alpha)
        b = np.sin(theta) * np.sin(alpha)
        if b <= abs(a):
            full = a > 0
            return (2 * np.pi * a if not original else 2 * np.pi) if full else 0.0
        beta0 = np.arccos(np.clip(-a / b, -1.0, 1.0))
        return 2.0 * beta0 if original else 2.0 * (a * beta0 + np.sqrt(b * b - a * a))

    def integrand(alpha: float) -> float:
        return np.cos(alpha) ** n * np.sin(alpha) * beta_integral(alpha)

    horizon = np.pi / 2 - theta  # where the cone of half-angle α first touches the horizon
    width = min(1.0, np.sqrt(2.0 / (n + 1.0)))
    points = sorted({p for p in (horizon, width, 3 * width, 10 * width) if 0 < p < np.pi / 2})
    edges = [0.0, *points, np.pi / 2]
    total = 0.0
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        value, _ = integrate.quad(integrand, lo, hi, epsabs=0.0, epsrel=2e-14, limit=500)
        total += value
    return total


def nquad_albedo(model, theta_o: float, theta_points, *, epsabs: float = 0.0, limit: int = 400) -> float:
    """E(θ_o) (view in the xz-plane) by scipy nquad in spherical coordinates about N — not lobe-aligned —
    with breakpoints at the mirror azimuth (φ = π) and at ``theta_points``, epsrel 1e-12."""
    V = np.array([np.sin(theta_o), 0.0, np.cos(theta_o)])

    def g(phi, theta):
        L = np.array([np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)])
        return model.eval(L, V)[0] * L[2] * np.sin(theta)

    options = {"epsabs": epsabs, "epsrel": 1e-12, "limit": limit}
    value, _ = integrate.nquad(g, [[0, 2 * np.pi], [0, np.pi / 2]],
                               opts=[{**options, "points": [np.pi]}, {**options, "points": list(theta_points)}])
    return value


def ggx_albedo_reference(alpha: float, mu: float, order: int = 24) -> float:
    """E(μ) of GGX with height-correlated Smith G2 (Heitz 2014, eq. 99) and F = 1, by Gauss–Legendre in
    half-vector coordinates — never forming 1 − (N·H)², so exact in float64 at any α.

    With tan²θ_h = α²t, D(H)(N·H) dω_h = dt/(1+t)² dφ/(2π) and dL = 4(V·H) dω_h, so
    E = ∫∫ G2(L, V)(V·H)/(μ (N·H)) dt/(1+t)² dφ/(2π) over the half vectors whose mirror L = 2(V·H)H − V lies
    above the horizon. For each φ node the horizon's t is found by bisection; u = ln t runs from ln 1e-40 to
    it on 60 panels and 30 more graded geometrically towards the horizon (where G2's masking layer is ~α wide
    in u), φ on 8 panels over [0, π] (the integrand is even in φ).
    """
    x, w = np.polynomial.legendre.leggauss(order)
    sin_o = np.sqrt(1.0 - mu * mu)
    a2 = alpha * alpha

    def smith_lambda(c):
        return 0.5 * (-1.0 + np.sqrt(1.0 + a2 * (1.0 - c * c) / (c * c)))

    def panels(edges):
        lo, hi = edges[:-1, None], edges[1:, None]
        return (lo + (hi - lo) * (x + 1) / 2).ravel(), (w * (hi - lo) / 2).ravel()

    phi, w_phi = panels(np.linspace(0.0, np.pi, 9))

    def light_z(theta_h):
        v_dot_h = sin_o * np.sin(theta_h) * np.cos(phi) + mu * np.cos(theta_h)
        return 2.0 * v_dot_h * np.cos(theta_h) - mu

    lo, hi = np.zeros_like(phi), np.full_like(phi, np.pi / 2)
    for _ in range(200):
        mid = (lo + hi) / 2
        above = light_z(mid) > 0
        lo, hi = np.where(above, mid, lo), np.where(above, hi, mid)
    t_horizon = np.tan(lo) ** 2 / a2
    total = 0.0
    for k in range(phi.size):
        # Panels graded towards the horizon, where the masking layer (μ_L ≲ α) is ~α wide in u.
        top = np.log(t_horizon[k])
        edges = np.concatenate([np.linspace(np.log(1e-40), top - 1.0, 60), top - np.geomspace(0.5, 1e-9, 30), [top]])
        u, w_u = panels(edges)
        t = np.exp(u)
        tan_h = alpha * np.sqrt(t)
        cos_h = 1.0 / np.sqrt(1.0 + tan_h**2)
        v_dot_h = sin_o * tan_h * cos_h * np.cos(phi[k]) + mu * cos_h
        mu_l = 2.0 * v_dot_h * cos_h - mu
        above = mu_l > 0
        g2 = 1.0 / (1.0 + smith_lambda(np.where(above, mu_l, 1.0)) + smith_lambda(mu))
        f = np.where(above, g2 * v_dot_h / (mu * cos_h), 0.0) * t / (1.0 + t) ** 2 / (2.0 * np.pi)
        total += 2.0 * w_phi[k] * np.dot(f, w_u)
    return float(total)


def half_vector_gauss_legendre(model, V, order, panels):
    """E(V) = ∫ f(L, V)(N·L) 4(V·H) dω_H by composite Gauss-Legendre in polar coordinates (θ_H, φ_H) of the half
    vector about N: N·L > 0 is θ_H < (π/2 + atan2(sin θ_V cos(φ_H − φ_V), cos θ_V))/2 in closed form, so each
    φ_H node integrates θ_H over [0, θ_max] (panels graded towards θ_H = 0, where the lobe peaks). Shares no code
    with brdfnorm's integrators."""
    x, w = np.polynomial.legendre.leggauss(order)

    def nodes(edges):
        half, mid = np.diff(edges)[:, None] / 2, (edges[:-1] + edges[1:])[:, None] / 2
        return (mid + half * x).ravel(), (half * w).ravel()

    # The lobe (N·H)^(n_u cos²φ_H + n_v sin²φ_H) narrows to a wedge about φ_H = ±π/2 away from the pole.
    graded = np.concatenate([-0.002 * 2.0 ** np.arange(10)[::-1], [0.0], 0.002 * 2.0 ** np.arange(10)])
    edges = np.mod(np.concatenate([np.pi / 2 + graded, 3 * np.pi / 2 + graded, np.linspace(0.0, 2 * np.pi, panels)]),
                   2 * np.pi)
    phi, w_phi = nodes(np.append(np.unique(edges), 2 * np.pi))
    y, w_y = nodes(np.concatenate([[0.0], 0.002 * 2.0 ** np.arange(9), [1.0]]))
    theta_v, phi_v = np.arccos(V[2]), np.arctan2(V[1], V[0])
    top = (np.pi / 2 + np.arctan2(np.sin(theta_v) * np.cos(phi - phi_v), np.cos(theta_v))) / 2  # (nφ,)
    t = top[:, None] * y[None, :]
    H = np.stack([np.sin(t) * np.cos(phi)[:, None], np.sin(t) * np.sin(phi)[:, None], np.cos(t)], axis=-1)
    vh = H @ V
    L = 2.0 * vh[..., None] * H - V
    f = model.eval(L.reshape(-1, 3), np.broadcast_to(V, (L.size // 3, 3)))[:, 0].reshape(t.shape)
    g = f * np.maximum(L[..., 2], 0.0) * 4.0 * vh * np.sin(t) * top[:, None]
    return w_phi @ g @ w_y


def dblquad_albedo(model, mu: float, *, even: bool = False, epsabs: float = 1e-12, epsrel: float = 1e-10) -> float:
    """E(V) = ∫∫ f(L, V)(N·L) sin θ_L dθ_L dφ_L, channel 0, at V = (√(1 − μ²), 0, μ) by scipy's dblquad in
    spherical coordinates about N (no lobe-aligned coordinates: for broad lobes). ``even``: the lobe is even in
    φ_L, so φ_L runs over [0, π] and the result is doubled."""
    V = np.array([[np.sqrt(1.0 - mu * mu), 0.0, mu]])

    def g(phi, theta):
        L = np.array([[np.sin(theta) * np.cos(phi), np.sin(theta) * np.sin(phi), np.cos(theta)]])
        return float(np.asarray(model.eval(L, V))[0, 0]) * np.cos(theta) * np.sin(theta)

    top = np.pi if even else 2 * np.pi
    value, _ = integrate.dblquad(g, 0.0, np.pi / 2, 0.0, top, epsabs=epsabs, epsrel=epsrel)
    return 2.0 * value if even else value


def oren_nayar_reference(theta: float, sigma: float, rho: float) -> float:
    """examples/oren_nayar.brdf's albedo: the azimuth in closed form (∫ max(cos Δφ, 0) dφ = 2), θ_L by quad, split
    at the kink θ_L = θ_o."""
    s2 = sigma * sigma
    A, B = 1.0 - 0.5 * s2 / (s2 + 0.33), 0.45 * s2 / (s2 + 0.09)

    def polar(t):
        return 2.0 * np.sin(t) ** 2 * np.cos(t) / max(np.cos(t), np.cos(theta))

    kinked = integrate.quad(polar, 0.0, theta, epsrel=1e-13, limit=200)[0] + integrate.quad(
        polar, theta, np.pi / 2, epsrel=1e-13, limit=200)[0]
    return rho / np.pi * (A * np.pi + B * np.sin(theta) * kinked)
