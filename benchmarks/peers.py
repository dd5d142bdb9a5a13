"""What a user would reach for instead of brdfnorm, written the way they would write it — and the references.

Peers (each computes the directional albedo E(V) = ∫_H f(L, V)(N·L) dL of seed 002 at a view angle θ_o,
V = (sin θ_o, 0, cos θ_o)):

* :func:`dblquad_albedo` — ``scipy.integrate.dblquad`` in spherical coordinates about N, θ_i outer on
  [0, π/2], φ_i inner on [0, 2π], integrand f·cos θ_i·sin θ_i written with the ``math`` module, one call per
  albedo, ``epsrel`` = the requested rtol and ``epsabs=0`` (scipy's default epsabs 1.5e-8 would silently loosen
  the request to ~1e-6 relative for albedos of ~1e-2).
* :func:`cubature_albedo` / :func:`cubature_albedo_batched` — ``scipy.integrate.cubature`` (scipy ≥ 1.15,
  Genz–Malik/Gauss–Kronrod adaptive cubature) over the same (θ_i, φ_i) rectangle with a vectorized integrand,
  one call per albedo, or one call for a whole table with an array-valued integrand (cubature supports it).
* :func:`mc_albedo` — BRDF Explorer's estimator: Hammersley points (i/N, radical inverse of i in base 2)
  mapped to cosine-weighted directions, E ≈ (π/N) Σ f(L_j, V), in float32 (as on a GPU) or float64.

References (the "accuracy" column of every benchmark is measured against these):

* :func:`blinn_phong_reference` — mpmath at 30 significant digits on seed 002's one-dimensional form
  E(θ_o) = 2π·2^(−n/2) ∫₀^{π/2} ((c_o+c_i)/√(c_o c_i+1))^n c_i s_i ₂F₁(n/4, n/4+½; 1; (s_o s_i/(c_o c_i+1))²) dφ_i
  (seed 002, "Spherical Coordinates: Integrating Δθ"), with ``mpmath.hyp2f1`` and ``mpmath.quad`` split at the
  mirror peak φ_i = θ_o and at multiples of the lobe width around it; at θ_o = 0 seed 000's closed form
  8π(2^(−n/2)+n)/((n+2)(n+4)). mpmath's unbounded exponent range absorbs the 2^(n/2)·0 products that break the
  formula in floating point.

The lobes are hand-written twice — scalar (``math``, for dblquad) and vectorized (numpy, any dtype) — exactly as
the built-in models and the ``.brdf`` examples define them, so the peers do not depend on brdfnorm at all.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import mpmath
import numpy as np
from scipy.integrate import IntegrationWarning, cubature, dblquad

# -- lobes, by hand -------------------------------------------------------------------------------------------

#: Scalar lobe: f(lx, ly, lz, vx, vy, vz) -> float.
Scalar = Callable[[float, float, float, float, float, float], float]
#: Vectorized lobe: f(L (M, 3), V (3,) or (M, 3)) -> (M,), computed in L's dtype.
Vector = Callable[[np.ndarray, np.ndarray], np.ndarray]


@dataclass(frozen=True)
class PeerLobe:
    """One BRDF written by hand for the peers: a scalar and a vectorized version of the same formula."""

    name: str
    scalar: Scalar
    vector: Vector


def blinn_phong(n: float) -> PeerLobe:
    """max(0, N·H)^n, H = normalize(L + V) (seed 000/002; examples/blinn_phong.brdf)."""

    def scalar(lx, ly, lz, vx, vy, vz):
        hx, hy, hz = lx + vx, ly + vy, lz + vz
        nh = hz / math.sqrt(hx * hx + hy * hy + hz * hz)
        return nh**n if nh > 0.0 else 0.0

    def vector(L, V):
        S = L + V
        nh = np.clip(S[..., 2] / np.sqrt(np.einsum("...i,...i->...", S, S)), 0, 1)
        return nh ** L.dtype.type(n)

    return PeerLobe(f"blinn-phong n={n:g}", scalar, vector)


def blinn_phong_gaussian(n: float) -> PeerLobe:
    """Seed 003's exp(−((N·H − 1)/(c − 1))²), c = 0.04^(1/n), unnormalized."""
    c = 0.04 ** (1.0 / n)

    def scalar(lx, ly, lz, vx, vy, vz):
        hx, hy, hz = lx + vx, ly + vy, lz + vz
        nh = min(max(hz / math.sqrt(hx * hx + hy * hy + hz * hz), 0.0), 1.0)
        a = (nh - 1.0) / (c - 1.0)
        return math.exp(-a * a)

    def vector(L, V):
        S = L + V
        nh = np.clip(S[..., 2] / np.sqrt(np.einsum("...i,...i->...", S, S)), 0, 1)
        a = (nh - 1) / L.dtype.type(c - 1.0)
        return np.exp(-a * a)

    return PeerLobe(f"blinn-phong-gaussian n={n:g}", scalar, vector)


def ggx(roughness: float, f0: float = 0.04) -> PeerLobe:
    """examples/ggx.brdf by hand: D_GGX·G1(L)G1(V)·Schlick F / (4 N·L N·V), α = roughness²."""
    alpha = roughness * roughness
    a2 = alpha * alpha

    def scalar(lx, ly, lz, vx, vy, vz):
        if lz <= 0.0 or vz <= 0.0:
            return 0.0
        hx, hy, hz = lx + vx, ly + vy, lz + vz
        norm = math.sqrt(hx * hx + hy * hy + hz * hz)
        nh, lh = hz / norm, (lx * hx + ly * hy + lz * hz) / norm
        d = nh * nh * (a2 - 1.0) + 1.0
        D = a2 / (math.pi * d * d)
        G = (2.0 * lz / (lz + math.sqrt(a2 + (1.0 - a2) * lz * lz))) * (
            2.0 * vz / (vz + math.sqrt(a2 + (1.0 - a2) * vz * vz)))
        F = f0 + (1.0 - f0) * (1.0 - lh) ** 5
        return D * G * F / (4.0 * lz * vz)

    def vector(L, V):
        t = L.dtype.type
        V = np.broadcast_to(V, L.shape)
        S = L + V
        norm = np.sqrt(np.einsum("...i,...i->...", S, S))
        nh = S[..., 2] / norm
        lh = np.einsum("...i,...i->...", L, S) / norm
        lz, vz = L[..., 2], V[..., 2]
        d = nh * nh * t(a2 - 1.0) + 1
        D = t(a2) / (t(math.pi) * d * d)
        G = (2 * lz / (lz + np.sqrt(t(a2) + t(1.0 - a2) * lz * lz))) * (
            2 * vz / (vz + np.sqrt(t(a2) + t(1.0 - a2) * vz * vz)))
        F = t(f0) + t(1.0 - f0) * (1 - lh) ** 5
        with np.errstate(divide="ignore", invalid="ignore"):
            f = D * G * F / (4 * lz * vz)
        return np.where((lz > 0) & (vz > 0), f, 0)

    return PeerLobe(f"ggx roughness={roughness:g}", scalar, vector)


# -- peers ----------------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PeerResult:
    value: float
    error: float  # the peer's own error estimate (NaN for Monte Carlo)
    warnings: int  # IntegrationWarnings raised (dblquad) or not-converged status (cubature)


def _view(theta_o: float) -> tuple[float, float, float]:
    return math.sin(theta_o), 0.0, math.cos(theta_o)


def dblquad_albedo(lobe: PeerLobe, theta_o: float, rtol: float) -> PeerResult:
    """E(θ_o) with ``scipy.integrate.dblquad``, θ_i outer and φ_i inner, as people write it by hand."""
    vx, vy, vz = _view(theta_o)
    f = lobe.scalar

    def integrand(phi, theta):
        st, ct = math.sin(theta), math.cos(theta)
        return f(st * math.cos(phi), st * math.sin(phi), ct, vx, vy, vz) * ct * st

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", IntegrationWarning)
        value, error = dblquad(integrand, 0.0, math.pi / 2, 0.0, 2.0 * math.pi, epsabs=0.0, epsrel=rtol)
    return PeerResult(value, error, sum(issubclass(w.category, IntegrationWarning) for w in caught))


def _spherical(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Directions L (M, 3) and the Jacobian cos θ sin θ of points x = (θ, φ) (M, 2)."""
    st, ct = np.sin(x[:, 0]), np.cos(x[:, 0])
    L = np.stack([st * np.cos(x[:, 1]), st * np.sin(x[:, 1]), ct], axis=-1)
    return L, ct * st


def cubature_albedo(lobe: PeerLobe, theta_o: float, rtol: float) -> PeerResult:
    """E(θ_o) with ``scipy.integrate.cubature`` over (θ_i, φ_i) ∈ [0, π/2] × [0, 2π], vectorized integrand."""
    V = np.array(_view(theta_o))

    def integrand(x):
        L, jacobian = _spherical(x)
        return lobe.vector(L, V) * jacobian

    r = cubature(integrand, [0.0, 0.0], [math.pi / 2, 2.0 * math.pi], rtol=rtol, atol=0.0)
    return PeerResult(float(r.estimate), float(r.error), int(r.status != "converged"))


def cubature_albedo_batched(lobe: PeerLobe, thetas: np.ndarray, rtol: float) -> list[PeerResult]:
    """A whole table in one ``cubature`` call: the integrand returns one value per view angle."""
    V = np.stack([np.sin(thetas), np.zeros_like(thetas), np.cos(thetas)], axis=-1)  # (T, 3)

    def integrand(x):
        L, jacobian = _spherical(x)
        M, T = L.shape[0], V.shape[0]
        values = lobe.vector(np.repeat(L, T, axis=0), np.tile(V, (M, 1))).reshape(M, T)
        return values * jacobian[:, None]

    r = cubature(integrand, [0.0, 0.0], [math.pi / 2, 2.0 * math.pi], rtol=rtol, atol=0.0)
    bad = int(r.status != "converged")
    return [PeerResult(float(v), float(e), bad) for v, e in zip(r.estimate, r.error, strict=True)]


def radical_inverse_base2(i: np.ndarray) -> np.ndarray:
    """Van der Corput radical inverse of 32-bit integers (bit reversal / 2^32), as in BRDF Explorer's shaders."""
    bits = np.asarray(i, dtype=np.uint32)
    bits = ((bits << 16) | (bits >> 16)).astype(np.uint32)
    bits = (((bits & 0x55555555) << 1) | ((bits & 0xAAAAAAAA) >> 1)).astype(np.uint32)
    bits = (((bits & 0x33333333) << 2) | ((bits & 0xCCCCCCCC) >> 2)).astype(np.uint32)
    bits = (((bits & 0x0F0F0F0F) << 4) | ((bits & 0xF0F0F0F0) >> 4)).astype(np.uint32)
    bits = (((bits & 0x00FF00FF) << 8) | ((bits & 0xFF00FF00) >> 8)).astype(np.uint32)
    return bits.astype(np.float64) * 2.0**-32


def hammersley_cosine(samples: int, dtype=np.float64) -> np.ndarray:
    """``samples`` cosine-weighted directions (pdf cos θ/π) from the 2-D Hammersley set, shape (samples, 3)."""
    i = np.arange(samples)
    u1, u2 = i / samples, radical_inverse_base2(i)
    r, phi = np.sqrt(u1), 2.0 * np.pi * u2
    L = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1.0 - u1)], axis=-1)
    return L.astype(dtype)


def mc_albedo(lobe: PeerLobe, theta_o: float, directions: np.ndarray) -> PeerResult:
    """BRDF Explorer-style estimate (π/N) Σ f(L_j, V) over cosine-weighted ``directions``, in their dtype."""
    dtype = directions.dtype
    V = np.array(_view(theta_o), dtype=dtype)
    f = lobe.vector(directions, V)
    value = dtype.type(np.pi) * f.sum(dtype=dtype) / dtype.type(directions.shape[0])
    return PeerResult(float(value), math.nan, 0)


# -- references ------------------------------------------------------------------------------------------------

def blinn_phong_closed_form(n: float) -> float:
    """Seed 000: E(0) = 8π(2^(−n/2)+n)/((n+2)(n+4)), evaluated in mpmath (exact to double precision)."""
    n = mpmath.mpf(n)
    return float(8 * mpmath.pi * (mpmath.power(2, -n / 2) + n) / ((n + 2) * (n + 4)))


def blinn_phong_reference(n: float, theta_o: float, dps: int = 30) -> float:
    """Blinn-Phong albedo at view angle θ_o (radians) from seed 002's ₂F₁ form in mpmath at ``dps`` digits."""
    if theta_o == 0.0:
        return blinn_phong_closed_form(n)
    with mpmath.workdps(dps):
        n_, to = mpmath.mpf(n), mpmath.mpf(theta_o)
        co, so = mpmath.cos(to), mpmath.sin(to)
        a, b = n_ / 4, n_ / 4 + mpmath.mpf(1) / 2

        def g(p):
            ci, si = mpmath.cos(p), mpmath.sin(p)
            B = co * ci + 1
            return ((co + ci) / mpmath.sqrt(B)) ** n_ * ci * si * mpmath.hyp2f1(a, b, 1, (so * si / B) ** 2)

        # Split at the mirror peak φ_i = θ_o and at multiples of the lobe width 2√2/√(n+1) around it, so that
        # tanh-sinh sees a smooth integrand on each piece.
        width = 2 * mpmath.sqrt(2) / mpmath.sqrt(n_ + 1)
        points = [mpmath.mpf(0)]
        for k in (-8, -3, -1, 0, 1, 3, 8):
            x = to + k * width
            if points[-1] < x < mpmath.pi / 2:
                points.append(x)
        points.append(mpmath.pi / 2)
        return float(2 * mpmath.pi * mpmath.power(2, -n_ / 2) * mpmath.quad(g, points))


# -- energy tables by Monte Carlo, as engines make them ------------------------------------------------------

def _ggx_lambda(cos_theta: np.ndarray, alpha: float) -> np.ndarray:
    cos2 = np.clip(cos_theta * cos_theta, 1e-300, 1.0)
    return 0.5 * (-1.0 + np.sqrt(1.0 + alpha * alpha * (1.0 - cos2) / cos2))


def ggx_vndf_albedo(mu: float, alpha: float, samples: int, rng: np.random.Generator) -> tuple[float, float]:
    """E(μ) of GGX (height-correlated Smith, F = 1) by visible-normal sampling (Heitz 2018, "Sampling the GGX
    distribution of visible normals", JCGT 7(4)): h ~ D_V(h), L = reflect(V, h), weight G2(L, V)/G1(V).
    Returns (estimate, standard error of the mean)."""
    V = np.array([math.sqrt(max(0.0, 1.0 - mu * mu)), 0.0, mu])
    u1, u2 = rng.random(samples), rng.random(samples)
    # Section 3 of Heitz 2018: stretch V, sample the projected hemisphere disk, unstretch.
    vh = np.array([alpha * V[0], alpha * V[1], V[2]])
    vh /= np.linalg.norm(vh)
    lensq = vh[0] ** 2 + vh[1] ** 2
    t1_axis = np.array([-vh[1], vh[0], 0.0]) / math.sqrt(lensq) if lensq > 0 else np.array([1.0, 0.0, 0.0])
    t2_axis = np.cross(vh, t1_axis)
    r, phi = np.sqrt(u1), 2.0 * math.pi * u2
    t1, t2 = r * np.cos(phi), r * np.sin(phi)
    s = 0.5 * (1.0 + vh[2])
    t2 = (1.0 - s) * np.sqrt(np.maximum(0.0, 1.0 - t1 * t1)) + s * t2
    nh = (t1[:, None] * t1_axis + t2[:, None] * t2_axis
          + np.sqrt(np.maximum(0.0, 1.0 - t1 * t1 - t2 * t2))[:, None] * vh)
    h = np.stack([alpha * nh[:, 0], alpha * nh[:, 1], np.maximum(0.0, nh[:, 2])], axis=1)
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    v_dot_h = h @ V
    L = 2.0 * v_dot_h[:, None] * h - V
    lam_v = _ggx_lambda(np.array(mu), alpha)
    weight = np.where(L[:, 2] > 0, (1.0 + lam_v) / (1.0 + lam_v + _ggx_lambda(L[:, 2], alpha)), 0.0)
    return float(weight.mean()), float(weight.std(ddof=1) / math.sqrt(samples))


def ggx_vndf_table(mus: np.ndarray, alphas: np.ndarray, samples: int, seed: int = 2018) -> tuple[np.ndarray,
                                                                                                   np.ndarray]:
    """E(μ, α) over a grid by :func:`ggx_vndf_albedo`, ``samples`` a cell: (estimates, standard errors)."""
    rng = np.random.default_rng(seed)
    values, errors = np.empty((len(mus), len(alphas))), np.empty((len(mus), len(alphas)))
    for i, mu in enumerate(mus):
        for j, alpha in enumerate(alphas):
            values[i, j], errors[i, j] = ggx_vndf_albedo(float(mu), float(alpha), samples, rng)
    return values, errors
