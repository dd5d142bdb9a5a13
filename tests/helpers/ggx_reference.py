"""An independent reference for GGX's directional albedo (F = 1): plain Gauss–Legendre in the half-vector CDF.

Not brdfnorm's integrator. With h drawn by GGX's own CDF — u = tan²θ_h/(α² + tan²θ_h), φ_h — the measure
D(h)(N·h) dω_h is du dφ/(2π), and with L = reflect(V, h), dω_L = 4(V·h) dω_h:

    E(V) = ∫ D G2 / (4 (N·L)(N·V)) (N·L) dω_L = (1/2π) ∫∫ G2(L, V) (V·h) / ((N·V)(N·h)) du dφ   (N·L > 0).

For V at θ_v in the xz-plane, N·L > 0 ⇔ cos φ > −cos θ_v cos 2θ_h / (sin 2θ_h sin θ_v): all φ while
θ_h ≤ (π/2 − θ_v)/2, none past (π/2 + θ_v)/2, and |φ| < φ0(θ_h) between. Both pieces are integrated with
Gauss–Legendre in u (after a cosine map that flattens the square-root ends of φ0) and in φ over [0, φ0]
(the integrand is even in φ), so the only non-smooth point of the integrand is a panel end.
"""

from __future__ import annotations

import numpy as np


def _lambda(cos_theta: np.ndarray, alpha: float) -> np.ndarray:
    """Smith Λ of GGX: (−1 + √(1 + α² tan²θ))/2."""
    cos2 = np.maximum(cos_theta * cos_theta, 1e-300)  # N·L → 0: Λ → ∞ and G2 → 0, as it should
    tan2 = np.maximum(1.0 - cos2, 0.0) / cos2
    return 0.5 * (-1.0 + np.sqrt(1.0 + alpha * alpha * tan2))


_PHI_EDGES = np.array([0.0, *(1.0 - 0.25 ** k for k in range(1, 12)), 1.0])
PHI_LO, PHI_WIDTH = _PHI_EDGES[:-1], np.diff(_PHI_EDGES)


def ggx_albedo(mu: float, alpha: float, *, shadowing: str = "height-correlated", nodes: int = 48,
               schlick: str | None = None) -> float:
    """E(μ) of the GGX lobe with F = 1 (``shadowing``: ``height-correlated`` or ``separable``); with ``schlick``
    ``"f0"`` or ``"f90"`` times the split-sum weight 1 − (1 − V·h)⁵ or (1 − V·h)⁵ instead.

    u = sin²β with tan β = tan θ_h / α (so du = sin 2β dβ and 1 − u = cos²β never cancels); the piece where φ is
    cut is split into panels graded geometrically towards its lower end, where φ0 turns over on the scale μ.
    """
    sin_v = np.sqrt(max(0.0, 1.0 - mu * mu))
    theta_v = np.arctan2(sin_v, mu)
    x, w = np.polynomial.legendre.leggauss(nodes)
    s = 0.5 * (1.0 - np.cos(0.5 * np.pi * (x + 1.0)))  # cosine map of [-1, 1] onto [0, 1]: flattens both ends
    ds = 0.25 * np.pi * np.sin(0.5 * np.pi * (x + 1.0)) * w
    beta1 = np.arctan(np.tan(0.5 * (np.pi / 2 - theta_v)) / alpha)
    beta2 = np.arctan(np.tan(0.5 * (np.pi / 2 + theta_v)) / alpha) if theta_v > 0 else beta1
    grading = [0.0, *(0.25 ** k for k in range(14, -1, -1))]
    edges = [(0.0, beta1)] + [(beta1 + (beta2 - beta1) * lo, beta1 + (beta2 - beta1) * hi)
                              for lo, hi in zip(grading[:-1], grading[1:], strict=True)]
    total = 0.0
    for a, b in edges:
        if b <= a:
            continue
        beta = a + (b - a) * s
        dbeta = (b - a) * ds
        du = np.sin(2.0 * beta) * dbeta
        tan_h = alpha * np.tan(beta)
        cos_h = 1.0 / np.sqrt(1.0 + tan_h * tan_h)
        sin_h = tan_h * cos_h
        with np.errstate(divide="ignore", invalid="ignore"):
            c = -mu * (2 * cos_h * cos_h - 1.0) / (2.0 * sin_h * cos_h * sin_v)
        phi0 = np.where(sin_v * sin_h > 0, np.arccos(np.clip(c, -1.0, 1.0)), np.pi)
        # φ panels graded towards φ0, where N·L → 0 and G2 turns over on the scale 1/Λ(V) ~ μ/α
        phi = (phi0[:, None, None] * (PHI_LO[None, :, None] + PHI_WIDTH[None, :, None] * s[None, None, :]))
        phi = phi.reshape(len(beta), -1)
        dphi = (phi0[:, None, None] * PHI_WIDTH[None, :, None] * ds[None, None, :]).reshape(len(beta), -1)
        v_dot_h = sin_v * sin_h[:, None] * np.cos(phi) + mu * cos_h[:, None]
        n_dot_l = np.maximum(2.0 * v_dot_h * cos_h[:, None] - mu, 1e-300)
        lam_l, lam_v = _lambda(n_dot_l, alpha), _lambda(np.array(mu), alpha)
        if shadowing == "height-correlated":
            g2 = 1.0 / (1.0 + lam_l + lam_v)
        else:
            g2 = 1.0 / ((1.0 + lam_l) * (1.0 + lam_v))
        g = g2 * v_dot_h / (mu * cos_h[:, None])
        if schlick is not None:
            tail = (1.0 - np.clip(v_dot_h, 0.0, 1.0)) ** 5
            g = g * (1.0 - tail if schlick == "f0" else tail)
        total += float(np.sum(du[:, None] * dphi * g))
    return total / np.pi  # (1/2π)·2 for the even φ integral over [0, φ0]
