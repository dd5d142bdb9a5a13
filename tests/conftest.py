"""Shared test helpers: independent reference integrals (not using brdfnorm's quadrature)."""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import settings
from scipy import integrate

# CI runs the property tests on a fixed example sequence, so a verdict there is reproducible; locally they
# keep exploring new inputs on every run.
settings.register_profile("ci", derandomize=True, database=None)
if os.environ.get("CI"):
    settings.load_profile("ci")


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


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    """Run the brdfnorm command line in-process: (exit code, stdout, stderr)."""
    from brdfnorm.cli import main

    try:
        main(list(argv))
        code = 0
    except SystemExit as done:
        code = done.code or 0
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def rng():
    return np.random.default_rng(20261121)
