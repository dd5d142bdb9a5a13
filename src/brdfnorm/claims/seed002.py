"""Seed 002 ("Energy-Normalizing Blinn–Phong Specular"): the spherical form of the albedo, its ₂F₁ and
hypergeometric-series forms, the Weierstrass substitution, and the Stokes/divergence steps."""

from __future__ import annotations

from collections.abc import Callable

import mpmath as mp
import numpy as np
from scipy.special import gammaln, roots_legendre

from ..engine.machinery.interval import adaptive_gauss_legendre
from . import SOURCES, TWO_PI, Claim, parametric, quadrature_albedo, rel_error


def half_vector_length(_: np.ndarray) -> Claim:
    rng = np.random.default_rng(2)
    v = rng.normal(size=(2, 4096, 3))
    v /= np.linalg.norm(v, axis=-1, keepdims=True)
    v[..., 2] = np.abs(v[..., 2])  # both in the upper hemisphere, as in the albedo integral
    wi, wo = v
    formula = np.sqrt(2.0) * np.sqrt(np.einsum("ij,ij->i", wi, wo) + 1.0)
    numeric = np.linalg.norm(wi + wo, axis=-1)
    errors = rel_error(formula, numeric)
    worst = int(np.argmax(errors))
    return Claim(
        "bp-half-vector-length", SOURCES["002"], "‖ω_i + ω_o‖ = √2·√(ω_i·ω_o + 1)",
        float(formula[worst]), float(numeric[worst]), float(errors[worst]), bool(errors.max() <= 1e-13),
        f"{wi.shape[0]} random pairs of upper-hemisphere directions; numeric: the norm of the vector sum",
        criterion="|A − B| / |B| ≤ 1e-13 for every pair",
    )  # fmt: skip


def _equation_1(n: np.ndarray, theta: float, rtol: float = 1e-12) -> np.ndarray:
    """2^(−n/2) × seed 002's Equation 1: the 2-D integral in (Δθ, φ_i), nested adaptive Gauss–Legendre.

    The power is taken in log space; the 2^(−n/2) keeps it finite (Equation 1 itself reaches 2^(n/2)).
    """
    n = np.asarray(n, dtype=float)
    co, so = np.cos(theta), np.sin(theta)

    def inner(index_n: np.ndarray, phi: np.ndarray) -> np.ndarray:
        # ∫₀^{2π} dΔθ for each (case, φ_i) node, as a batch of 1-D adaptive integrals (symmetric: 2∫₀^π).
        nn, pp = np.broadcast_arrays(n[index_n][:, None], phi)
        nn, pp = nn.ravel(), pp.ravel()
        width = np.minimum(np.pi, 3.0 / np.sqrt(nn + 1.0))
        points = np.stack([np.zeros_like(pp), np.pi - 4 * width, np.pi - width, np.full_like(pp, np.pi)], axis=1)
        points = np.clip(np.sort(points, axis=1), 0.0, np.pi)
        a, b = points[:, :-1].ravel(), points[:, 1:].ravel()
        case = np.repeat(np.arange(pp.size), 3)
        keep = b > a

        def f(index: np.ndarray, d: np.ndarray) -> np.ndarray:
            ci, si = np.cos(pp[index, None]), np.sin(pp[index, None])
            base = np.log(co + ci) - 0.5 * np.log(2.0 * (so * si * np.cos(d) + co * ci + 1.0))
            return np.exp(nn[index, None] * base)

        value = adaptive_gauss_legendre(f, a[keep], b[keep], case[keep], pp.size, rtol=rtol * 0.1).value
        return 2.0 * value.reshape(phi.shape) * np.cos(phi) * np.sin(phi)

    width = np.minimum(np.pi / 2, 3.0 / np.sqrt(n + 1.0))
    points = np.clip(theta + width[:, None] * np.array([-4.0, -1.0, 0.0, 1.0, 4.0]), 0.0, np.pi / 2)
    points = np.sort(np.concatenate([np.zeros((n.size, 1)), points, np.full((n.size, 1), np.pi / 2)], axis=1), axis=1)
    a, b = points[:, :-1].ravel(), points[:, 1:].ravel()
    case = np.repeat(np.arange(n.size), points.shape[1] - 1)
    keep = b > a
    value = adaptive_gauss_legendre(inner, a[keep], b[keep], case[keep], n.size, rtol=rtol).value
    return value


def spherical_form(n: np.ndarray) -> Claim:
    theta = np.radians(60.0)
    return parametric(
        "bp-spherical-form", "002", "Equation 1 (spherical coordinates, ×2^(−n/2)) equals the hemisphere albedo", n,
        _equation_1(n, theta), quadrature_albedo("blinn-phong", n, theta), 1e-10,
        "θ_o = 60°; formula: Equation 1 by nested adaptive Gauss–Legendre; numeric: adaptive hemisphere cubature",
    )  # fmt: skip


def periodic_trapezoid(f: Callable, tol: float = mp.mpf(10) ** -26, start: int = 64, limit: int = 2**17) -> mp.mpf:
    """∫₀^{2π} f by the trapezoidal rule, doubled until two estimates agree to ``tol`` (mpmath precision).

    For a periodic analytic integrand the rule converges geometrically (Trefethen & Weideman, SIAM Rev. 2014);
    mpmath's tanh-sinh quad, by contrast, returns (A + cos)^(−256) at A = 4 only to 4e-10.
    """
    count = start
    total = mp.fsum(f(2 * mp.pi * k / count) for k in range(count))
    estimate = 2 * mp.pi * total / count
    while count < limit:
        total += mp.fsum(f(2 * mp.pi * (2 * k + 1) / (2 * count)) for k in range(count))
        count *= 2
        previous, estimate = estimate, 2 * mp.pi * total / count
        if abs(estimate - previous) <= tol * abs(estimate):
            break
    return estimate


def delta_theta_2f1(n: np.ndarray) -> Claim:
    """∫₀^{2π} dΔθ/(A + cos Δθ)^m = (2π/A^m) ₂F₁(m/2, (m+1)/2; 1; 1/A²), m = n/2, by mpmath at 30 digits."""
    rows = []
    with mp.workdps(30):
        for k in n:
            m = mp.mpf(float(k)) / 2
            for A in (mp.mpf("1.01"), mp.mpf("1.5"), mp.mpf(4)):
                # Both sides ×(A − 1)^m, the integrand's maximum, so that the values shown stay finite.
                scale = (A - 1) ** m
                formula = scale * 2 * mp.pi / A**m * mp.hyp2f1(m / 2, (m + 1) / 2, 1, 1 / A**2)
                numeric = periodic_trapezoid(lambda d, A=A, m=m: ((A - 1) / (A + mp.cos(d))) ** m)
                rows.append((float(k), float(A), formula, numeric, float(abs(formula / numeric - 1))))
    worst = max(rows, key=lambda r: r[4])
    return Claim(
        "bp-delta-theta-2f1", SOURCES["002"], "∫₀^{2π} dΔθ/(A+cos Δθ)^(n/2) = (2π/A^(n/2))·₂F₁(n/4, n/4+½; 1; 1/A²)",
        float(worst[2]), float(worst[3]), worst[4], all(r[4] <= 1e-20 for r in rows),
        f"values ×(A−1)^(n/2); A ∈ {{1.01, 1.5, 4}} × n = {', '.join(f'{k:g}' for k in n)}; mpmath.hyp2f1 "
        f"against the periodic trapezoidal rule at 30 digits; worst at n = {worst[0]:g}, A = {worst[1]:g}; "
        "tolerance 1e-20",
        [{"n": r[0], "A": r[1], "formula_value": float(r[2]), "numeric_value": float(r[3]), "rel_error": r[4]}
         for r in rows],
        criterion="|A − B| / |B| ≤ 1e-20 at every (n, A)",
    )  # fmt: skip


_GL_NODES, _GL_WEIGHTS = roots_legendre(40)


def _hypergeometric_series(n: float, theta: float) -> tuple[float, int]:
    """2^(−n/2) × the last equation of seed 002's Δθ section: Σ_k coefficient_k s_o^{2k} ∫ (…) dφ_i.

    Every term's integral uses one composite 40-point Gauss–Legendre rule (60 panels graded toward the mirror
    peak); terms are summed in log-space blocks until they fall below 1e-18 of the sum. Returns (sum, terms).
    """
    co, so = np.cos(theta), np.sin(theta)
    width = min(np.pi / 2, 3.0 / np.sqrt(n + 1.0))
    edges = np.unique(np.clip(theta + width * np.linspace(-8.0, 8.0, 61), 0.0, np.pi / 2))
    edges = np.unique(np.concatenate([np.linspace(0.0, np.pi / 2, 21), edges]))
    half = 0.5 * np.diff(edges)
    phi = (0.5 * (edges[:-1] + edges[1:])[:, None] + half[:, None] * _GL_NODES).ravel()
    weight = (half[:, None] * _GL_WEIGHTS).ravel()
    ci, si = np.cos(phi), np.sin(phi)
    a = n / 4.0
    base = n * np.log(co + ci) + np.log(si) + np.log(ci) - (n / 2.0) * np.log(co * ci + 1.0) - (n / 2.0) * np.log(2.0)
    growth = 2.0 * np.log(si) - 2.0 * np.log(co * ci + 1.0)  # per k: s_i^{2k}/(c_o c_i + 1)^{2k}
    total, k0 = 0.0, 0
    while True:
        k = np.arange(k0, k0 + 512, dtype=float)
        coefficient = gammaln(a + k) + gammaln(a + 0.5 + k) - gammaln(a) - gammaln(a + 0.5) - 2.0 * gammaln(1.0 + k)
        logs = (coefficient + 2.0 * k * np.log(so))[:, None] + base[None, :] + k[:, None] * growth[None, :]
        block = TWO_PI * np.exp(logs) @ weight
        total += block.sum()
        k0 += 512
        if block[-1] <= 1e-18 * total and block[-1] <= block[0]:
            return total, k0


def hypergeometric_series(n: np.ndarray) -> Claim:
    theta = np.radians(45.0)
    values = np.array([_hypergeometric_series(float(k), theta)[0] for k in n])
    return parametric(
        "bp-hypergeometric-series", "002", "the Γ-series over k (the Δθ section's last equation) equals Equation 1",
        n, values, _equation_1(n, theta), 1e-10,
        "θ_o = 45°; formula: the series summed until its terms are < 1e-18 of the sum, ×2^(−n/2); numeric: "
        "Equation 1 by nested adaptive Gauss–Legendre",
    )  # fmt: skip


def weierstrass(n: np.ndarray) -> Claim:
    """The x = tan(φ_i/2) form of Equation 1's inner integral, against the φ_i form, both ×2^(−n/2)."""
    theta = np.radians(60.0)
    co, so = np.cos(theta), np.sin(theta)
    deltas = np.array([np.pi, 2.0, 0.5])
    nn, dd = (g.ravel() for g in np.meshgrid(np.asarray(n, dtype=float), deltas, indexing="ij"))

    def integrate(integrand, upper, peak):
        width = np.minimum(upper, 3.0 / np.sqrt(nn + 1.0))
        points = np.clip(peak + width[:, None] * np.array([-4.0, -1.0, 0.0, 1.0, 4.0]), 0.0, upper)
        points = np.sort(np.concatenate([np.zeros((nn.size, 1)), points, np.full((nn.size, 1), upper)], 1), 1)
        a, b = points[:, :-1].ravel(), points[:, 1:].ravel()
        case = np.repeat(np.arange(nn.size), points.shape[1] - 1)
        keep = b > a
        return adaptive_gauss_legendre(integrand, a[keep], b[keep], case[keep], nn.size, rtol=1e-13).value

    def polar_log(p, d):
        ci, si = np.cos(p), np.sin(p)
        return np.log(co + ci) - 0.5 * np.log(2.0 * (so * si * np.cos(d) + co * ci + 1.0))

    # Both forms are divided by the same per-case constant, the integrand's largest value on a fine φ grid, so
    # that Δθ far from the mirror side does not underflow at large n (the identity is unchanged).
    grid = np.linspace(0.0, np.pi / 2, 2001)
    shift = nn * np.max(polar_log(grid[None, :], dd[:, None]), axis=1)

    def polar(index, p):
        ci, si = np.cos(p), np.sin(p)
        return np.exp(nn[index, None] * polar_log(p, dd[index, None]) - shift[index, None]) * ci * si

    def tangent(index, x):
        cd = so * np.cos(dd[index, None])
        num = (co - 1.0) ** 2 * x**4 + 2.0 * (co**2 - 1.0) * x**2 + (co + 1.0) ** 2
        den = (1.0 - co) * x**4 + 2.0 * cd * x**3 + 2.0 * x**2 + 2.0 * cd * x + (co + 1.0)
        ratio = 0.5 * (np.log(num) - np.log(den)) - 0.5 * np.log(2.0)
        return 4.0 * x * (1.0 - x**2) / (1.0 + x**2) ** 3 * np.exp(nn[index, None] * ratio - shift[index, None])

    formula = integrate(tangent, 1.0, np.tan(theta / 2))
    numeric = integrate(polar, np.pi / 2, theta)
    errors = rel_error(formula, numeric)
    worst = int(np.argmax(errors))
    return Claim(
        "bp-weierstrass", SOURCES["002"], "x = tan(φ_i/2) turns the inner φ_i integral into the rational form in x",
        float(formula[worst]), float(numeric[worst]), float(errors[worst]), bool(errors.max() <= 1e-11),
        f"θ_o = 60°, Δθ ∈ {{π, 2, 0.5}} × n = {', '.join(f'{k:g}' for k in n)} (both divided by the integrand's "
        "maximum); both forms by "
        f"adaptive Gauss–Legendre; worst at n = {nn[worst]:g}, Δθ = {dd[worst]:.3g}; tolerance 1e-11",
        criterion="|A − B| / |B| ≤ 1e-11 at every (n, Δθ)",
    )  # fmt: skip


# Vector-calculus checks: fields, the Poincaré-lemma potential, line / surface / volume integrals.

_T_NODES, _T_WEIGHTS = roots_legendre(24)


def cosine_field(r: np.ndarray) -> np.ndarray:
    """G = N = (0, 0, 1): G·ω is the cosine (seed 002's first test)."""
    return np.broadcast_to(np.array([0.0, 0.0, 1.0]), r.shape)


def z_cubed_field(r: np.ndarray) -> np.ndarray:
    """G = (0, 0, z³): G·ω = z⁴ (seed 002's second test)."""
    out = np.zeros(r.shape)
    out[..., 2] = r[..., 2] ** 3
    return out


def poincare_potential(G: Callable[[np.ndarray], np.ndarray], r: np.ndarray) -> np.ndarray:
    """F̄(r) = ∫₀¹ t G(t r) × r dt (seed 002's component formulas), by 24-point Gauss–Legendre in t."""
    t = (0.5 * (_T_NODES + 1.0)).reshape((-1,) + (1,) * r.ndim)
    integrand = t * np.cross(G(t * r), r)  # (T, ..., 3)
    return 0.5 * np.tensordot(_T_WEIGHTS, integrand, axes=1)


def _curl(F: Callable[[np.ndarray], np.ndarray], r: np.ndarray, h: float = 1e-5) -> np.ndarray:
    """∇×F by central differences (error O(h²) ≈ 1e-10 for these smooth fields)."""
    J = np.empty(r.shape + (3,))  # J[..., i, j] = ∂F_i/∂x_j
    for j in range(3):
        step = np.zeros(3)
        step[j] = h
        J[..., :, j] = (F(r + step) - F(r - step)) / (2.0 * h)
    return np.stack([J[..., 2, 1] - J[..., 1, 2], J[..., 0, 2] - J[..., 2, 0], J[..., 1, 0] - J[..., 0, 1]], axis=-1)


def _hemisphere(f: Callable[[np.ndarray], np.ndarray], order: int = 48) -> float:
    """∫ f(ω) dω over the upper hemisphere: Gauss–Legendre in cos θ × trapezoid in φ (exact for polynomials)."""
    x, w = roots_legendre(order)
    mu = 0.5 * (x + 1.0)
    phi = np.linspace(0.0, TWO_PI, 2 * order, endpoint=False)
    s = np.sqrt(1.0 - mu**2)
    omega = np.stack(np.broadcast_arrays(s[:, None] * np.cos(phi), s[:, None] * np.sin(phi), mu[:, None]), -1)
    return float(0.5 * w @ f(omega) @ np.full(phi.size, TWO_PI / phi.size))


def _circle_integral(F: Callable[[np.ndarray], np.ndarray], order: int = 64) -> float:
    """∮ F·dl around the unit circle z = 0 (counter-clockwise, the boundary of the upper hemisphere)."""
    t = np.linspace(0.0, TWO_PI, order, endpoint=False)
    r = np.stack([np.cos(t), np.sin(t), np.zeros_like(t)], -1)
    tangent = np.stack([-np.sin(t), np.cos(t), np.zeros_like(t)], -1)
    return float(np.sum(np.einsum("mi,mi->m", F(r), tangent)) * TWO_PI / order)


def _curl_mismatch(G) -> float:
    """max |∇×F̄ − G| over sample points of the unit ball: 0 exactly when G is divergence-free."""
    rng = np.random.default_rng(3)
    r = rng.uniform(-0.7, 0.7, size=(64, 3))
    return float(np.max(np.abs(_curl(lambda p: poincare_potential(G, p), r) - G(r))))


def stokes_cosine(_: np.ndarray) -> Claim:
    circle = _circle_integral(lambda r: poincare_potential(cosine_field, r))
    surface = _hemisphere(lambda w: np.einsum("...i,...i->...", cosine_field(w), w))
    mismatch = _curl_mismatch(cosine_field)
    error = float(rel_error(circle, surface))
    return Claim(
        "stokes-cosine", SOURCES["002"], "Stokes with G = N: ∮ F̄·dl over the base circle = ∫ N·ω dω = π",
        circle, surface, error, error <= 1e-12 and mismatch <= 1e-8 and abs(surface - np.pi) <= 1e-12,
        f"F̄ by the Poincaré-lemma integral = (−y/2, x/2, 0); max |∇×F̄ − G| = {mismatch:.1g} (finite differences); "
        "formula: the line integral; numeric: the hemisphere integral of the cosine",
        criterion="|A − B| / |B| ≤ 1e-12",
    )  # fmt: skip


def stokes_z_cubed(_: np.ndarray) -> Claim:
    potential = lambda r: poincare_potential(z_cubed_field, r)  # noqa: E731
    circle = _circle_integral(potential)
    surface = _hemisphere(lambda w: np.einsum("...i,...i->...", z_cubed_field(w), w))
    curl_flux = _hemisphere(lambda w: np.einsum("...i,...i->...", _curl(potential, w), w))
    mismatch = _curl_mismatch(z_cubed_field)
    error = float(rel_error(circle, surface))
    failure = error > 0.5 and mismatch > 0.1 and abs(surface - TWO_PI / 5) <= 1e-12 and abs(curl_flux - circle) <= 1e-8
    return Claim(
        "stokes-z-cubed-fails", SOURCES["002"],
        "Stokes with G = (0,0,z³) fails: ∮ F̄·dl ≠ ∫ z⁴ dω = 2π/5, because ∇×F̄ ≠ G",
        circle, surface, error, failure,
        f"∮ F̄·dl = {circle:.3g} = ∫(∇×F̄)·ω dω = {curl_flux:.2g} (Stokes holds for F̄), but ∫ G·ω dω = 2π/5 = "
        f"{surface:.6f}: ∇×F̄ = (−3xz²/5, −3yz²/5, 2z³/5) ≠ G, max |∇×F̄ − G| = {mismatch:.3g}, as ∇·G = 3z² ≠ 0; "
        "ok means the failure is reproduced",
        relation="differ", criterion="|A − B| / |B| > 0.5, with Stokes confirmed for F̄",
    )  # fmt: skip


def divergence_cosine(_: np.ndarray) -> Claim:
    """I = ∭_V ∇·F dV + ∬_disk F_z dA with F = N, against the hemisphere integral of N·ω."""
    x, w = roots_legendre(32)
    r = 0.5 * (x + 1.0)
    # Volume: spherical coordinates (radius, cos θ, φ) over the half ball; divergence by central differences.
    mu = 0.5 * (x + 1.0)
    phi = np.linspace(0.0, TWO_PI, 32, endpoint=False)
    R, M, P = np.meshgrid(r, mu, phi, indexing="ij")
    S = np.sqrt(1.0 - M**2)
    points = np.stack([R * S * np.cos(P), R * S * np.sin(P), R * M], -1)
    h = 1e-5
    div = sum(
        (cosine_field(points + h * e)[..., i] - cosine_field(points - h * e)[..., i]) / (2 * h)
        for i, e in enumerate(np.eye(3))
    )
    volume = float(np.einsum("i,j,ijk->", 0.5 * w, 0.5 * w, div * R**2) * TWO_PI / phi.size)
    # Disk: polar coordinates; F·(0,0,−1) outward on the base, so the base flux is subtracted (+∬ F_z dA).
    disk_points = np.stack(np.broadcast_arrays(r[:, None] * np.cos(phi), r[:, None] * np.sin(phi), 0.0 * phi), -1)
    disk = float(0.5 * w @ (cosine_field(disk_points)[..., 2] * r[:, None]) @ np.full(phi.size, TWO_PI / phi.size))
    formula = volume + disk
    surface = _hemisphere(lambda om: np.einsum("...i,...i->...", cosine_field(om), om))
    error = float(rel_error(formula, surface))
    return Claim(
        "divergence-cosine", SOURCES["002"], "divergence theorem with F = N: ∭∇·N dV + ∬_disk N_z dA = π",
        formula, surface, error, error <= 1e-12 and abs(surface - np.pi) <= 1e-12,
        f"volume term {volume:.1g}, disk term {disk:.15g}; numeric: the hemisphere integral of N·ω",
        criterion="|A − B| / |B| ≤ 1e-12",
    )  # fmt: skip
