"""Certified reductions of the seed lobes (Phong, modified Phong, Blinn-Phong and its Gaussian variant) at any
view: the derivations are in the package docstring (:mod:`brdfnorm.engine.routes.certified`)."""

from __future__ import annotations

from collections.abc import Callable

from .core import Integrator, atan_ball, nan_ball, power_ball


def phong_albedo(work: Integrator, theta, n, original: bool):
    arb, acb = work.arb, work.acb
    if n == 0:  # max(0, x)^0 = 1 everywhere: the constant lobe
        return arb.pi() * (2 if original else 1)
    c, s = theta.cos(), theta.sin()
    pi = arb.pi()

    # Integrated, not taken from its antiderivative, so that seed 000's closed forms (the θ_o = 0 case) are
    # checked against an integral rather than restated. u = cos α ∈ [s_o, 1]: the β-circle lies above the horizon.
    head = work.integral_of_power(lambda u: u, n, lambda u, analytic: 2 * pi * (1 if original else c * u),
                                  s, arb(1), arb(1))
    if theta == 0:
        return head

    def rest(beta0: Callable):  # all but (s_o sin φ)^n of the tail's integrand
        def f(phi, analytic):
            cos_phi = phi.cos()
            b0 = beta0(phi, analytic)
            if original:
                return s * cos_phi * 2 * b0
            return s * cos_phi * 2 * (c * s * phi.sin() * b0 + s * cos_phi)
        return f

    def base(phi):
        return s * phi.sin()

    near = rest(lambda phi, analytic: pi / 2 + atan_ball(c * phi.tan(), analytic, acb))  # β₀ for φ ∈ [0, π/4]
    far = rest(lambda phi, analytic: pi - atan_ball(phi.cot() / c, analytic, acb))  # the same for φ ∈ [π/4, π/2]
    return (head + work.integral_of_power(base, n, near, arb(0), pi / 4, s)
            + work.integral(lambda phi, analytic: power_ball(base(phi), n, analytic, acb, arb) * far(phi, analytic),
                            pi / 4, pi / 2))


def _half_vector_lobe(work: Integrator, theta, h: Callable):
    """E for a lobe h(N·H) at view angle θ_o (the half-vector reduction in the module docstring)."""
    arb, acb = work.arb, work.acb
    pi = arb.pi()
    co, so = theta.cos(), theta.sin()
    theta1 = (pi / 2 - theta) / 2

    def full_circle(t, analytic):
        c, s = t.cos(), t.sin()
        p, q = co * c, so * s
        value = h(c, analytic)
        return 4 * value * s * (2 * c * 2 * pi * (p * p + q * q / 2) - co * 2 * pi * p)

    pieces = [(full_circle, arb(0), theta1)]
    if theta != 0:
        def partial(upper_half: bool):
            def f(psi, analytic):
                half = psi / 2
                sh, ch = half.sin(), half.cos()
                t = theta1 + theta * sh * sh
                c, s = t.cos(), t.sin()
                s1 = (2 * theta * sh * sh).sinc()
                s2 = (2 * theta * ch * ch).sinc()
                if analytic and not (s1.real.lower() > 0 and s2.real.lower() > 0):
                    return nan_ball(acb)
                if upper_half:   # ψ ∈ [π/2, π]: tan(ψ/2) ≥ 1
                    phi1 = 2 * atan_ball(half.cot() * (s2 / s1).sqrt(analytic=analytic), analytic, acb)
                else:
                    phi1 = pi - 2 * atan_ball(half.tan() * (s1 / s2).sqrt(analytic=analytic), analytic, acb)
                sin_phi1 = theta * psi.sin() * (s1 * s2).sqrt(analytic=analytic) / (so * (2 * t).sin())
                cos_phi1 = -co * (2 * t).cos() / (so * (2 * t).sin())
                p, q = co * c, so * s
                i1 = 2 * (p * phi1 + q * sin_phi1)
                i2 = 2 * (p * p * phi1 + 2 * p * q * sin_phi1 + q * q * (phi1 + sin_phi1 * cos_phi1) / 2)
                jacobian = theta / 2 * psi.sin()
                return 4 * h(c, analytic) * s * (2 * c * i2 - co * i1) * jacobian
            return f

        pieces += [(partial(False), arb(0), pi / 2), (partial(True), pi / 2, pi)]
    total = arb(0)
    for f, a, b in pieces:
        total += work.integral(f, a, b)
    return total


def blinn_phong_albedo(work: Integrator, theta, n):
    acb, arb = work.acb, work.arb

    def h(c, analytic):
        return power_ball(c, n, analytic, acb, arb)

    return _half_vector_lobe(work, theta, h)


def blinn_phong_gaussian_albedo(work: Integrator, theta, n):
    arb = work.arb
    # c = 0.04^(1/n) with seed 003's threshold as the decimal 0.04 it is written as; c = 0 at n = 0.
    k = arb("0.04") ** (1 / n) if n > 0 else arb(0)

    def h(c, analytic):
        x = (c - 1) / (k - 1)
        return (-(x * x)).exp()

    return _half_vector_lobe(work, theta, h)

