"""Honesty of the generic engine's error estimate on lobes with kinks (brdfnorm.engine.machinery.kinks): FON
(max(N·L, N·V) and the sign of L·V − N·L N·V), Oren-Nayar built in and as examples/oren_nayar.brdf
(max(0, cos Δφ) and max/min(θ_L, θ_V)), and Burley, at random views and tolerances 1e-6..1e-10.

The references are independent of the engine: FON's closed form, and for the others a tensor Gauss-Legendre rule
in (θ_L, φ_L) about N with the domain cut at every kink (θ_L = θ_V, Δφ = ±π/2), where each piece is smooth and the
rule converges geometrically. That reference is itself checked against FON's closed form here."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.paths import EXAMPLES

import brdfnorm as bn
from brdfnorm.models.fon import fon_albedo_exact

_X, _W = np.polynomial.legendre.leggauss(48)


def _pieces(a: float, b: float, cuts: list[float], parts: int = 2) -> list[tuple[float, float]]:
    edges = sorted({a, b, *(c for c in cuts if a < c < b)})
    out = []
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sub = np.linspace(lo, hi, parts + 1)
        out.extend(zip(sub[:-1], sub[1:], strict=True))
    return out


def reference_albedo(model, theta_v: float) -> float:
    """E(V) = ∫ f(L, V) cos θ_L dL by Gauss-Legendre (48 × 48 nodes) on each smooth piece of θ_L ∈ [0, π/2] cut at
    θ_V and φ_L ∈ [0, π] cut at π/2 (V in the xz-plane: the integrand is even in φ_L)."""
    V = np.array([np.sin(theta_v), 0.0, np.cos(theta_v)])
    total = 0.0
    for t0, t1 in _pieces(0.0, np.pi / 2, [theta_v]):
        for p0, p1 in _pieces(0.0, np.pi, [np.pi / 2]):
            t = (t0 + t1) / 2 + (t1 - t0) / 2 * _X
            p = (p0 + p1) / 2 + (p1 - p0) / 2 * _X
            T, P = np.meshgrid(t, p, indexing="ij")
            L = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], axis=-1).reshape(-1, 3)
            f = model.eval(L, np.broadcast_to(V, L.shape))[:, 0].reshape(T.shape)
            g = f * np.cos(T) * np.sin(T)
            total += (t1 - t0) / 2 * (p1 - p0) / 2 * np.einsum("ij,i,j->", g, _W, _W)
    return 2.0 * total


def test_the_reference_reproduces_fons_closed_form():
    model = bn.load("fon", roughness=1.0)
    for theta in (0.3, 0.9355, 1.4):
        assert reference_albedo(model, theta) == pytest.approx(fon_albedo_exact(np.cos(theta), 1.0), rel=1e-13)


def _lobes():
    return [("fon", bn.load("fon", roughness=1.0)), ("fon r=0.4", bn.load("fon", roughness=0.4)),
            ("oren-nayar", bn.load("oren-nayar", sigma=0.5)),
            ("oren_nayar.brdf", bn.load(EXAMPLES / "oren_nayar.brdf", sigma=0.5, rho=1.0)),
            ("burley", bn.load("burley", roughness=0.7))]


def _probe(seed: int, cases: int, lobes: list[str] | None = None) -> list[str]:
    """Random (lobe, μ, rtol) cases; the failures as text (empty: every estimate covered its error)."""
    rng = np.random.default_rng(seed)
    chosen = [(name, model) for name, model in _lobes() if lobes is None or name in lobes]
    failures = []
    for _ in range(cases):
        name, model = chosen[rng.integers(len(chosen))]
        mu = rng.uniform(0.02, 1.0)
        rtol = 10.0 ** rng.uniform(-10, -6)
        theta = float(np.arccos(mu))
        result = bn.albedo(model, np.array([theta]), rtol=rtol)
        exact = (fon_albedo_exact(mu, model.params["roughness"]) if name.startswith("fon")
                 else reference_albedo(model, theta))
        error = abs(result.value[0, 0] - exact)
        # The reference is good to ~1e-14 (it matches FON's closed form to 1e-13 relative).
        if error > result.error[0, 0] + 2e-14:
            failures.append(f"{name} μ={mu!r} rtol={rtol:.2e}: error {error:.2e} > estimate {result.error[0, 0]:.2e}")
    return failures


def test_estimates_cover_the_error_on_kinked_lobes_quick():
    assert _probe(seed=2026, cases=6) == []


@pytest.mark.slow
def test_estimates_cover_the_error_on_kinked_lobes_sweep():
    assert _probe(seed=7, cases=80) == []
