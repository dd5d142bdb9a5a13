"""Certified albedo: guaranteed enclosures [lower, upper] of E by ball arithmetic (Arb, through python-flint).

``method="certified"`` reduces the albedo of a lobe to one-dimensional integrals of functions that are analytic
on every piece of the path, and integrates each with Arb's rigorous adaptive Gauss–Legendre
(``acb.integral``, Johansson 2018, "Numerical integration in arbitrary-precision ball arithmetic"), whose error
bounds come from bounds of the integrand on complex ellipses — not from comparing two estimates. Every
elementary and special function is Arb's own, evaluated with its ``analytic`` check where it has a branch cut,
so a piece of the path that touches a non-analytic point is bisected instead of being trusted. The parameters
are the float64 values the user gave, taken exactly. The result is a ball: ``value`` its midpoint, ``error`` its
radius (plus the rounding of the midpoint to float64), and ``lower``/``upper`` decimal strings rounded outward.

Reductions (derivations; V in the xz-plane at polar angle θ_o, c_o = cos θ_o, s_o = sin θ_o)
-------------------------------------------------------------------------------------------------
**lambert** — f = ρ/π and ∫ cos dω = π over the hemisphere: E = ρ exactly (no integral is needed).

**phong, modified-phong** (seed 000's lobes, any view angle). R·V = L·mirror(V), so in polar coordinates
(α, β) about P = mirror(V) the lobe is cos^n α (n > 0: zero for α > π/2) and N·L = a + b cos β with
a = c_o cos α, b = s_o sin α. With u = cos α the β-integral is elementary: the whole circle lies above the
horizon for u ≥ s_o, and for u < s_o only |β| < β₀ = arccos(−a/b). Hence, for the modified lobe (f·(N·L)),

    E = 2π c_o (1 − s_o^{n+2})/(n+2) + ∫₀^{s_o} u^n · 2(c_o u β₀ + √(s_o² − u²)) du,

and for the original lobe (f·(N·L) = cos^n α on N·L > 0) E = 2π(1 − s_o^{n+1})/(n+1) + ∫₀^{s_o} u^n · 2β₀ du.
Substituting u = s_o sin φ removes the square root at u = s_o, and with x = c_o sin φ/√(1 − s_o² sin² φ),
1 − x² = cos² φ/(1 − s_o² sin² φ), so β₀ = π − arccos x = π − atan(cot φ/c_o) = π/2 + atan(c_o tan φ): two
forms of one analytic function, used on [π/4, π/2] and [0, π/4] so that neither tan nor cot meets its pole.
At θ_o = 0 the formulas give seed 000's 2π/(n+1) and 2π/(n+2). The original lobe over the view is the
modified one divided by cos θ_L; n = 0 is the constant lobe (π for the modified lobe, 2π for the original).

**blinn-phong, blinn-phong-gaussian** (any lobe h(N·H), any view angle). Integrate over the half vector H
(polar angles θ_h, φ_h about N): L = 2(V·H)H − V, dL = 4(V·H) dH, and with c = cos θ_h, s = sin θ_h,
X = V·H = p + q cos φ_h (p = c_o c, q = s_o s), N·L = 2cX − c_o, the integrand is 4 h(c) (2cX² − c_o X) s.
The horizon N·L > 0 is cos φ_h > κ = −c_o cos 2θ_h/(s_o sin 2θ_h): the whole circle for θ_h ≤ θ₁ =
(π/2 − θ_o)/2, nothing for θ_h ≥ θ₂ = (π/2 + θ_o)/2, and |φ_h| < φ₁ = arccos κ between, where the φ_h
integrals of X and X² are elementary:

    ∫X = 2(pφ₁ + q sin φ₁),    ∫X² = 2(p²φ₁ + 2pq sin φ₁ + q²(φ₁ + sin φ₁ cos φ₁)/2)    (φ₁ = π on [0, θ₁]).

On [θ₁, θ₂] the substitution θ_h = θ₁ + θ_o sin²(ψ/2), ψ ∈ [0, π], makes φ₁ analytic: 1 ± κ =
sin(2(θ_h − θ₁)) / (s_o sin 2θ_h) and sin(2(θ₂ − θ_h)) / (s_o sin 2θ_h) respectively, so with
S₁ = sinc(2θ_o sin²(ψ/2)), S₂ = sinc(2θ_o cos²(ψ/2)) (both positive),
tan(φ₁/2) = cot(ψ/2)√(S₂/S₁) and sin φ₁ = θ_o sin ψ √(S₁S₂)/(s_o sin 2θ_h): no square root of anything that
vanishes. This is the double integral of seed 002 (E = ∫(N·H)^n (N·L) dL) with its inner integral done in
closed form by the half-vector change of variables instead of the hypergeometric ₂F₁, which Arb evaluates
poorly at the large parameters n/4 (≈ 8 digits at n = 10⁴). h = c^n for Blinn-Phong and
exp(−((c − 1)/(k − 1))²), k = 0.04^(1/n), for seed 003's lobe. Both lobes are reciprocal: over the view alike.

Models with no reduction here (``.brdf`` files, the microfacet models away from their own reductions) raise
:class:`~brdfnorm.errors.ArgumentError` naming the model and the reason — never a silent fallback.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ....errors import ArgumentError, EvaluationError
from ...machinery.result import RouteResult
from .core import (
    DEFAULT_DIGITS,
    EVAL_LIMIT,
    GUARD_DIGITS,
    MAX_DIGITS,
    PRECISION_ATTEMPTS,
    Enclosure,
    Integrator,
    require_flint,
    starting_bits,
    validate_digits,
)
from .microfacet import microfacet_normal_albedo, microfacet_reduction, white_albedo
from .seeds import blinn_phong_albedo, blinn_phong_gaussian_albedo, phong_albedo

__all__ = ["DEFAULT_DIGITS", "EVAL_LIMIT", "GUARD_DIGITS", "MAX_DIGITS", "Enclosure", "REDUCTIONS",
           "Reduction", "albedo_method", "applies", "closed_form_inside", "enclose", "require_flint", "route",
           "starting_bits", "validate_digits", "white_albedo", "Integrator", "microfacet_normal_albedo"]


@dataclass(frozen=True)
class Reduction:
    """A certified route for one built-in model: ``compute(work, theta, params, over) -> [arb per channel]``."""

    compute: Callable
    description: str
    takes_mu: bool = False  # compute(..., view_mu=μ) certifies at μ itself (a table's μ axis) instead of cos θ


def _scalar(params: dict, name: str, arb):
    value = float(params[name])
    return arb(value)


def _reflectance(work, theta, params, over):
    return [_scalar(params, "reflectance", work.arb)]


def _phong_route(original: bool):
    def compute(work, theta, params, over):
        n = _scalar(params, "n", work.arb)
        if original and over == "view":  # ∫(R·V)^n (N·V) dV / (N·L): the modified integral over cos θ_L
            return [phong_albedo(work, theta, n, original=False) / theta.cos()]
        return [phong_albedo(work, theta, n, original)]
    return compute


REDUCTIONS: dict[str, Reduction] = {
    "lambert": Reduction(_reflectance, "exact: ∫ρ/π cos dω = ρ"),
    "phong": Reduction(_phong_route(True), "1-D in cos α about the mirror direction (seed 000's form)"),
    "modified-phong": Reduction(_phong_route(False), "1-D in cos α about the mirror direction"),
    "blinn-phong": Reduction(
        lambda work, theta, params, over: [blinn_phong_albedo(work, theta, _scalar(params, "n", work.arb))],
        "1-D in the half-vector angle (seed 002's double integral, inner integral in closed form)"),
    "blinn-phong-gaussian": Reduction(
        lambda work, theta, params, over: [blinn_phong_gaussian_albedo(work, theta, _scalar(params, "n", work.arb))],
        "1-D in the half-vector angle (any lobe of N·H)"),
    "ggx": Reduction(microfacet_reduction("ggx"), "any view with F = 1: 1-D with the azimuth in closed form; normal "
                     "incidence with Fresnel: 1-D in the distribution's CDF", takes_mu=True),
    "beckmann": Reduction(microfacet_reduction("beckmann"), "any view with F = 1: 1-D with the azimuth in closed "
                          "form; normal incidence with Fresnel: 1-D in the distribution's CDF", takes_mu=True),
}


#: Seed 000's closed forms of the albedo at normal incidence (over the light), as functions of n in Arb ball
#: arithmetic (``(n, pi, arb) -> arb``): what a certified enclosure is checked against.
NORMAL_INCIDENCE_CLOSED_FORMS: dict[str, Callable] = {
    "phong": lambda n, pi, arb: 2 * pi / (n + 1),
    "modified-phong": lambda n, pi, arb: 2 * pi / (n + 2),
    "blinn-phong": lambda n, pi, arb: 8 * pi * (arb(2) ** (-n / 2) + n) / ((n + 2) * (n + 4)),
}


def closed_form_inside(model_name: str, n: float, enclosure: Enclosure) -> bool:
    """Whether seed 000's closed form for ``model_name`` at exponent ``n``, evaluated in ball arithmetic, lies inside
    ``enclosure`` (both balls: the closed form's whole ball must be inside the reported [lower, upper])."""
    flint = require_flint()
    old, flint.ctx.prec = flint.ctx.prec, int(4 * enclosure.digits) + 64
    try:
        exact = NORMAL_INCIDENCE_CLOSED_FORMS[model_name](flint.arb(float(n)), flint.arb.pi(), flint.arb)
        return bool(flint.arb(enclosure.lower) <= exact.lower() and exact.upper() <= flint.arb(enclosure.upper))
    finally:
        flint.ctx.prec = old


def route(model) -> Reduction:
    """The certified reduction for ``model``, or an ArgumentError naming the model and why there is none."""
    reduction = REDUCTIONS.get(getattr(model, "name", ""))
    if reduction is None or type(model).__module__.startswith("brdfnorm.brdffile"):
        known = ", ".join(REDUCTIONS)
        raise ArgumentError(
            f"no certified route for {model.name}: its albedo has no reduction to one-dimensional integrals of "
            f"analytic functions here (certified: {known}); use method 'quadrature'", where="method")
    return reduction


def enclose(model, theta: float, params: dict, over: str = "light", digits: int = DEFAULT_DIGITS,
            phi: float = 0.0, mu: float | None = None) -> list[Enclosure]:
    """Enclosures (one per channel) of the albedo of ``model`` at polar angle ``theta`` (radians: the float64 given,
    taken exactly) — or, with ``mu``, at the view μ = cos θ_o given exactly (microfacet lobes; what a table's μ axis
    means).

    ``digits`` is met, not merely aimed at: while the reported interval's relative radius exceeds 10^−digits
    (:attr:`Enclosure.reached`), the working precision is doubled and the enclosure recomputed, up to
    :data:`PRECISION_ATTEMPTS` times; what still misses it is returned with ``reached`` false (a valid enclosure,
    only wider).
    """
    digits = validate_digits(digits)
    reduction = route(model)
    if mu is not None and not reduction.takes_mu:
        raise ArgumentError(f"{model.name}: the certified route takes a view angle, not mu", where="mu")
    flint = require_flint()
    old = flint.ctx.prec
    bits, evaluations = starting_bits(digits), 0
    try:
        for _ in range(PRECISION_ATTEMPTS):
            work = Integrator(digits, bits)
            flint.ctx.prec = work.bits
            extra = {} if mu is None else {"view_mu": float(mu)}
            angle = flint.arb(float(theta)) if mu is None else flint.arb(0)
            balls = reduction.compute(work, angle, params, over, **extra)
            evaluations += work.evaluations
            for ball in balls:  # before Enclosure.of: an infinite endpoint has no decimal (issue 46: n=1e300)
                if not ball.is_finite():
                    where = f"theta={float(theta)!r}" if mu is None else f"mu={float(mu)!r}"
                    raise EvaluationError(f"Arb could not enclose the albedo at {where} with {digits} digits "
                                          "(an enclosure is not finite: a parameter too large?)", where=model.name)
            enclosures = [Enclosure.of(ball, digits, evaluations, work.bits) for ball in balls]
            if all(e.reached for e in enclosures):
                break
            bits *= 2
        return enclosures
    finally:
        flint.ctx.prec = old


def albedo_method(problem, *, digits: int = DEFAULT_DIGITS, **_: object):
    """The ``certified`` albedo method: per case, Arb enclosures; the result's extras are the bounds."""
    route(problem.model)  # the model's reason for having no certified route, before any work
    K = problem.fixed.shape[0]
    C = problem.model.channels
    value, error = np.empty((K, C)), np.empty((K, C))
    lower, upper = np.empty((K, C), dtype=object), np.empty((K, C), dtype=object)
    evaluations = np.zeros(K, dtype=np.int64)
    reached = np.ones(K, dtype=bool)
    theta = np.asarray(problem.theta, dtype=float).reshape(-1)
    for k in range(K):
        params = {name: np.asarray(v)[k] if name in problem.per_case else v
                  for name, v in problem.params.items()}
        enclosures = enclose(problem.model, theta[k], params, problem.over, digits)
        channels = enclosures if len(enclosures) == C else enclosures * C
        for c, e in enumerate(channels):
            value[k, c], error[k, c], lower[k, c], upper[k, c] = e.value, e.error, e.lower, e.upper
        evaluations[k] = enclosures[0].evaluations
        reached[k] = all(e.reached for e in enclosures)
    # An enclosure is always valid; "converged" says whether it is as narrow as the digits asked for.
    return RouteResult(value, error, evaluations, reached, extras={"lower": lower, "upper": upper})


def applies(model, over) -> bool:
    """Always: asked for by name, the method itself says why a model has no certified route."""
    return True
