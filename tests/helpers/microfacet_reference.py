"""An independent reference for the albedo of the ggx and beckmann lobes (F = 1), written for the tests.

Plain fixed-order Gauss–Legendre in the half-vector CDF coordinates — not brdfnorm's adaptive cubature, not its
coordinates (it shares only the slope-space statement of the integral, (H1) in brdfnorm.engine.routes.halfvector):

    E(V) = (1/π) ∫₀^π dφ ∫₀^{u_h(φ)} G2(L, V) (V·H)/(N·V N·H) du,

with φ the azimuth of H, u the radial CDF of the standardized slope s (GGX s²/(1+s²), Beckmann 1 − e^{−s²}),
V in the xz-plane (hence the symmetric φ range), u_h where the reflected L meets the horizon, found here by
bisection on N·L (not from a formula). The radial integral is split at u = ½: below it u = y² (the slope is
analytic in y), above it the complement z = 1 − u on panels graded geometrically towards the horizon
(z_h(1 + 2^j)); φ panels are graded geometrically towards φ = π/2, where the horizon moves fastest at grazing
views. Every panel gets an n-point rule; the tests compare n and a higher order to show the reference converged.
"""

from __future__ import annotations

import numpy as np
from scipy.special import erf, roots_legendre

#: Anisotropic and Fresnel lobes the honesty tests check against the generic hemisphere engine (which this
#: reference does not cover: it is isotropic with F = 1), each by its own route.
FRESNEL_LOBES = [
    ("ggx", {"alpha_x": 0.08, "alpha_y": 0.5, "fresnel": "schlick", "f0": 0.04}),
    ("ggx", {"alpha_x": 0.7, "alpha_y": 0.15, "fresnel": "conductor", "eta": (0.2, 0.9, 1.1), "k": (3.0, 2.5, 2.2)}),
    ("beckmann", {"alpha_x": 0.3, "alpha_y": 0.1, "shadowing": "separable", "fresnel": "dielectric", "eta": 1.5}),
    ("ggx", {"alpha": 0.2, "fresnel": "dielectric", "eta": 1.33}),
]

def _lambda(name: str, a2: np.ndarray) -> np.ndarray:
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if name == "ggx":
            return (np.sqrt(1.0 + a2) - 1.0) / 2.0
        b = 1.0 / np.sqrt(a2)
        value = (erf(b) - 1.0) / 2.0 + np.exp(-b * b) / (2.0 * b * np.sqrt(np.pi))
        return np.where(a2 == 0, 0.0, value)


def _slope(name: str, u: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Standardized slope radius from the CDF u (and its complement z = 1 − u, for accuracy)."""
    if name == "ggx":
        return np.sqrt(u / z)
    return np.sqrt(-np.log(z))


def _panels(edges: np.ndarray, order: int) -> tuple[np.ndarray, np.ndarray]:
    x, w = roots_legendre(order)
    lo, hi = edges[:-1, None], edges[1:, None]
    return ((lo + hi) / 2 + (hi - lo) / 2 * x).ravel(), ((hi - lo) / 2 * w).ravel()


def reference_albedo(name: str, mu: float, alpha: float, shadowing: str = "height-correlated", *,
                     order: int = 10, phi_depth: int | None = None, radial_depth: int = 40) -> float:
    V = np.array([np.sqrt(1.0 - mu * mu), 0.0, mu])
    if phi_depth is None:  # the horizon's azimuthal features are ~μ wide at grazing views
        phi_depth = int(np.log2(1.0 / mu)) + 16

    def nl_and_w(phi, s):
        x, y = alpha * s * np.cos(phi), alpha * s * np.sin(phi)  # real slopes of H = (x, y, 1)/n
        n2 = 1.0 + x * x + y * y
        vh = (V[0] * x + V[2]) / np.sqrt(n2)
        H = np.stack([x, y, np.ones_like(x)]) / np.sqrt(n2)
        L = 2.0 * vh * H - V[:, None, None] if np.ndim(x) == 2 else 2.0 * vh * H - V.reshape(3, *([1] * np.ndim(x)))
        with np.errstate(divide="ignore", invalid="ignore"):
            lam_l = _lambda(name, alpha**2 * (L[0] ** 2 + L[1] ** 2) / L[2] ** 2)
        lam_v = _lambda(name, alpha**2 * (V[0] ** 2) / V[2] ** 2)
        G2 = 1.0 / (1.0 + lam_l + lam_v) if shadowing == "height-correlated" else 1.0 / ((1 + lam_l) * (1 + lam_v))
        w = np.where(L[2] > 0, G2 * vh / (V[2] * H[2]), 0.0)
        return L[2], w

    def u_of_s(s):
        return s * s / (1 + s * s) if name == "ggx" else -np.expm1(-s * s)

    # φ nodes, graded towards π/2 from both sides.
    steps = np.pi / 2 * 2.0 ** -np.arange(phi_depth + 1)
    edges_phi = np.unique(np.concatenate([[0.0, np.pi], np.pi / 2 - steps, np.pi / 2 + steps]))
    phi, w_phi = _panels(edges_phi, order)
    # Horizon radius along each φ by bisection on N·L in log s (N·L > 0 at s = 0).
    lo = np.full(phi.shape, -40.0)
    hi = np.full(phi.shape, 80.0)
    for _ in range(200):
        mid = (lo + hi) / 2
        nl, _ = nl_and_w(phi, np.exp(mid))
        inside = nl > 0
        lo, hi = np.where(inside, mid, lo), np.where(inside, hi, mid)
    s_h = np.exp(lo)
    if name == "beckmann":
        s_h = np.minimum(s_h, 7.0)  # mass e^{-49} beyond, times (1 + c·x) ≤ 1e5 here: nothing
    u_h = u_of_s(s_h)
    z_h = 1.0 / (1.0 + s_h * s_h) if name == "ggx" else np.exp(-s_h * s_h)
    total = 0.0
    # Pole part: u = y², y ∈ [0, √min(u_h, ½)].
    y, wy = _panels(np.linspace(0.0, 1.0, 5), order)
    top = np.sqrt(np.minimum(u_h, 0.5))[:, None]
    uu = (y[None, :] * top) ** 2
    s = _slope(name, uu, 1.0 - uu)
    _, w = nl_and_w(phi[:, None], s)
    total += np.sum(w_phi[:, None] * wy[None, :] * top * 2.0 * y[None, :] * top * w)
    # Tail part: z = 1 − u from z_h (graded) to ½, where u_h > ½.
    top_power = int(np.ceil(np.log2(0.5 / z_h.min()))) + 1
    fractions = np.concatenate([[0.0], 2.0 ** np.arange(-radial_depth, top_power)])
    zz_edges = z_h[:, None] * (1.0 + fractions[None, :])  # (P, E)
    zz_edges = np.minimum(zz_edges, 0.5)
    zx, zw = roots_legendre(order)
    lo_e, hi_e = zz_edges[:, :-1, None], zz_edges[:, 1:, None]
    zz = ((lo_e + hi_e) / 2 + (hi_e - lo_e) / 2 * zx).reshape(phi.size, -1)
    wz = ((hi_e - lo_e) / 2 * zw).reshape(phi.size, -1)
    s = _slope(name, 1.0 - zz, zz)
    _, w = nl_and_w(phi[:, None], s)
    total += np.sum(w_phi[:, None] * wz * np.where(u_h[:, None] > 0.5, w, 0.0))
    return total / np.pi
