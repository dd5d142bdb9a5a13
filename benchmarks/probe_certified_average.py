"""Probe (issue 33): a rigorous E_avg(α) = 2∫₀¹ E(μ) μ dμ for isotropic GGX, F = 1 — measured, NOT shipped.

``brdfnorm.lut.certified`` refuses E_avg; this script measures the one 2-D route that did give a rigorous
enclosure, so that whoever takes it further starts from numbers. It is an experiment, not a product path.

Route (nested Arb integrals, both rigorous): with θ = θ_V, 2Eμ dμ = 2 sin θ · (μE) dθ and μE(θ) = ∫ k(θ, t) dt
(:func:`brdfnorm.engine.routes.certified.microfacet.ggx_kernel`, t from t₀(θ) at θ_L = 0 to t₁(θ) at the horizon).
The t-range is mapped to s ∈ [0, 1] (t = t₀ + L s, L = t₁ − t₀), so the inner domain no longer depends on θ, and
θ_L is written without ball arithmetic's dependency at its ends: with d = α sinh t, d₀ = −tan(θ/2),
d₁ = tan(π/4 − θ/2), tan(θ_L/2) = A = (d − d₀)/(1 + d d₀), tan((π/2 − θ_L)/2) = B = (d₁ − d)/(1 + d d₁), and
d − d₀ = 2α cosh((t + t₀)/2) sinh(L s/2), d₁ − d = 2α cosh((t₁ + t)/2) sinh(L(1 − s)/2): sin θ_L = 2A/(1 + A²) and
cos θ_L = 2B/(1 + B²) vanish exactly at s = 0 and s = 1. The outer integral over θ ∈ [0, b] is Arb's
``acb.integral`` whose integrand, on a complex ball Θ, is the inner ``acb.integral`` over s with Θ as a parameter
(every square root and logarithm analytic-checked on the whole ball, so the inner integrand is jointly holomorphic
where it is evaluated and the inner result bounds the analytic continuation of μE on Θ). The rest [b, π/2] is
[0, cos² b] ⊂ [0, (π/2 − b)²], since 0 ≤ E ≤ 1 for F = 1 with either shadowing (G2 ≤ G1(V) and Heitz 2014's
∫ G1(V) ⟨V, m⟩⁺ D(m) dm = cos θ_V).

Measured (see the report in docs/certified-tables.md): correct and rigorous, but complex balls of θ wider than
RMAX give NaN (the kernel's ball blow-up: at α = 1 a radius 0.01 already fails; at α = 1e-4 only ≲ 1e-4 gives
a usable bound), so the outer integrator bisects into thousands of subintervals: α = 1 at 3 digits took minutes.
Run alone: ``.venv/bin/python benchmarks/probe_certified_average.py DIGITS RMAX ALPHA…``.
"""

from __future__ import annotations

import math
import sys
import time

import flint
from flint import acb, arb

from brdfnorm.engine.routes.certified.microfacet import ggx_kernel


def _checked(z):
    """``z`` if its real part is > 0 (off the cut of √ and log), else NaN (Arb then bisects)."""
    return z if z.real.lower() > 0 else None


def _log_asinh(y):
    """asinh y = log(y + √(y² + 1)) for Re y ≥ 0, both cuts checked; None where a ball reaches one."""
    root = _checked(y * y + 1)
    if root is None:
        return None
    inside = _checked(y + root.sqrt())
    return None if inside is None else inside.log()


def inner(theta, alpha, correlated: bool, bits: int, counter: list, limit: int):
    """∫₀¹ h(θ, s) ds = μE(θ) (module docstring), θ a real point or a complex ball; NaN where it cannot bound it."""
    complex_ball = not theta.imag.is_zero() or theta.rad() > 2.0 ** -(bits - 8)
    d0 = -(theta / 2).tan()
    d1 = ((acb.pi() / 2 - theta) / 2).tan()
    t0, t1 = _log_asinh(-d0 / alpha), _log_asinh(d1 / alpha)
    if t0 is None or t1 is None:
        return acb("nan")
    t0 = -t0
    span = t1 - t0
    sv, mu = theta.sin(), theta.cos()

    def h(s, analytic):
        counter[0] += 1
        t = t0 + span * s
        d = alpha * t.sinh()
        a = 2 * alpha * ((t + t0) / 2).cosh() * (span * s / 2).sinh() / (1 + d * d0)
        b = 2 * alpha * ((t1 + t) / 2).cosh() * (span * (1 - s) / 2).sinh() / (1 + d * d1)
        sl, cl = 2 * a / (1 + a * a), 2 * b / (1 + b * b)
        # On a complex θ ball every evaluation is analytic-checked: the value must be the continuation's.
        return ggx_kernel(alpha, correlated, t, sl, cl, sv, mu, analytic or complex_ball, acb) * span

    return acb.integral(h, 0, 1, rel_tol=arb(2) ** (-(bits - 20)), eval_limit=limit)


def average(alpha: float, digits: int, rmax: float, correlated: bool = True):
    """(enclosure of E_avg, inner evaluations, outer evaluations)."""
    bits = int(math.ceil((digits + 2) * math.log2(10))) + 40
    old, flint.ctx.prec = flint.ctx.prec, bits
    try:
        a = arb(alpha)
        eps_bits = int(math.ceil((digits + 3) * math.log2(10) / 2)) + 2
        top = arb((arb.pi() / 2 - arb(2) ** -eps_bits).lower())  # exact, below the horizon
        counter, outer = [0], [0]

        def f(theta, analytic):
            outer[0] += 1
            if theta.rad() > rmax:
                return acb("nan")
            limit = 200_000 if theta.rad() < 2.0 ** -(bits - 8) else 20_000
            return 2 * theta.sin() * inner(theta, a, correlated, bits, counter, limit)

        body = acb.integral(f, 0, top, rel_tol=arb(2) ** (-(bits - 20)), eval_limit=200_000).real
        rest = (arb.pi() / 2 - top) ** 2
        return body + arb(0, rest.upper()) / 2 + arb(rest.upper()) / 2, counter[0], outer[0]
    finally:
        flint.ctx.prec = old


if __name__ == "__main__":
    digits, rmax = int(sys.argv[1]), float(sys.argv[2])
    for alpha in map(float, sys.argv[3:]):
        start = time.perf_counter()
        ball, inner_evaluations, outer_evaluations = average(alpha, digits, rmax)
        print({"alpha": alpha, "digits": digits, "rmax": rmax, "E_avg": ball.str(radius=True),
               "relative_radius": float(ball.rad() / abs(ball.mid())) if ball.is_finite() else math.inf,
               "inner_evaluations": inner_evaluations, "outer_evaluations": outer_evaluations,
               "seconds": round(time.perf_counter() - start, 1)}, flush=True)
