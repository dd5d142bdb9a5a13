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

import math
from collections.abc import Callable
from dataclasses import dataclass
from decimal import ROUND_CEILING, ROUND_FLOOR, Context, Decimal

import numpy as np

from ...errors import ArgumentError, EvaluationError

#: Default number of significant decimal digits asked of an enclosure.
DEFAULT_DIGITS = 30
#: Digits the CLI and the API accept (Arb works at any precision; beyond this the cost is rarely wanted).
MAX_DIGITS = 1000
#: Integrand evaluations Arb may spend on one integral before it returns the (wider) enclosure it has.
EVAL_LIMIT = 200_000
def require_flint():
    """The python-flint module, or a MissingExtraError saying how to install it (it is an optional extra)."""
    from ...extras import require

    return require("flint", "certified", where="method certified")


@dataclass(frozen=True)
class Enclosure:
    """A rigorous enclosure of one albedo value: Arb's ball and what is reported of it.

    ``lower``/``upper`` are decimals with ``digits`` significant digits rounded outward; ``value`` is the
    midpoint rounded to float64 and ``error`` an upper bound of |true albedo − value| (the radius plus that
    rounding, rounded up).
    """

    ball: object  # flint.arb
    digits: int
    evaluations: int
    reached: bool  # the relative radius is within the digits asked for
    lower: str
    upper: str
    value: float
    error: float

    @classmethod
    def of(cls, ball, digits: int, evaluations: int) -> Enclosure:
        """Report ``ball``; call at the working precision (the endpoints are exact there)."""
        arb = type(ball)
        value = float(ball.mid())
        bound = (arb(ball.rad()) + abs(ball.mid() - arb(value))).upper()
        error = float(bound)
        if arb(error) < bound:  # round the bound up, never down
            error = float(np.nextafter(error, np.inf))
        reached = bool(arb(ball.rad()) <= arb(10) ** -digits * abs(ball.mid()))
        return cls(ball, digits, evaluations, reached, _decimal(ball.lower(), digits, ROUND_FLOOR),
                   _decimal(ball.upper(), digits, ROUND_CEILING), value, error)


def _decimal(endpoint, digits: int, rounding: str) -> str:
    """An exact dyadic endpoint (an exact arb) as a decimal string rounded in the given direction."""
    mantissa, exponent = (int(part) for part in endpoint.mid().man_exp())
    # m·2^e written exactly in decimal: m·2^e for e ≥ 0, m·5^(−e)·10^e for e < 0 (string construction is exact).
    exact = Decimal(mantissa << exponent) if exponent >= 0 else Decimal(f"{mantissa * 5 ** -exponent}E{exponent}")
    return str(Context(prec=digits, rounding=rounding).plus(exact))


class _Integrator:
    """Arb integrals at a working precision, counting integrand evaluations."""

    def __init__(self, digits: int) -> None:
        flint = require_flint()
        self.arb, self.acb = flint.arb, flint.acb
        self.digits = digits
        self.bits = int(math.ceil(digits * math.log2(10))) + 40
        self.evaluations = 0

    def integral(self, f: Callable, a, b):
        def counted(x, analytic):
            self.evaluations += 1
            return f(x, analytic)

        tol = self.arb(2) ** (-(self.bits - 20))
        return self.acb.integral(counted, a, b, rel_tol=tol, eval_limit=EVAL_LIMIT).real

    def integral_of_power(self, base: Callable, n, rest: Callable, a, b, slope):
        """∫_a^b base(x)^n · rest(x) dx, base ≥ 0 on [a, b]; if base(a) = 0, base(x) ≤ slope·(x − a) is required.

        Arb converges slowly into an endpoint branch point of the power, so [a, a + ε] is enclosed directly:
        |∫| ≤ slope^n ε^(n+1)/(n+1) · sup|rest|, with ε chosen to make that 2^−(bits+30) of the scale, and the
        rest, where the power is analytic, is integrated.
        """
        arb, acb = self.arb, self.acb

        def integrand(x, analytic):
            return _power(base(x), n, analytic, acb, arb) * rest(x, analytic)

        exponent = float(n.mid())
        if exponent.is_integer() or not base(acb(a)).is_zero():  # no branch point at a: Arb alone suffices
            return self.integral(integrand, a, b)
        eps = arb(2) ** -math.ceil((self.bits + 30) / (exponent + 1))
        if eps > (b - a) / 2:
            eps = (b - a) / 2
        cover = acb(a + eps / 2 + arb(0, float((eps / 2).upper())))
        bound = slope ** n * eps ** (n + 1) / (n + 1) * arb(abs(rest(cover, False)).upper())
        return arb(0, float(bound.upper())) + self.integral(integrand, a + eps, b)


def _nan(acb):
    return acb("nan")


def _atan(z, analytic: bool, acb):
    """atan z, analytic off its cuts i·[1, ∞) and −i·[1, ∞): under the analytic check a ball whose imaginary part
    may reach ±1 is refused (a non-finite ball), so Arb bisects instead of integrating across a cut."""
    if analytic and not abs(z.imag).upper() < 1:
        return _nan(acb)
    return z.atan()


def _power(x, n, analytic: bool, acb, arb):
    """x^n (n ≥ 0 real) on a ball around a piece of the path, where x ≥ 0.

    Off the cut (−∞, 0] of the power this is Arb's power. A ball that reaches the cut is non-analytic there: under
    the analytic check that is said with a non-finite ball (Arb then bisects), and for a plain enclosure on the
    path the disk |x^n| ≤ max|x|^n is returned, which holds for every x ≥ 0 of the ball.
    """
    if x.real.lower() > 0:
        return x.pow(n, analytic=analytic)
    if analytic:
        return _nan(acb)
    bound = arb(x.abs_upper()) ** n
    return acb(arb(0, bound), arb(0, bound))


# -- reductions ------------------------------------------------------------------------------------------------

def _phong(work: _Integrator, theta, n, original: bool):
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

    near = rest(lambda phi, analytic: pi / 2 + _atan(c * phi.tan(), analytic, acb))  # β₀ for φ ∈ [0, π/4]
    far = rest(lambda phi, analytic: pi - _atan(phi.cot() / c, analytic, acb))  # the same for φ ∈ [π/4, π/2]
    return (head + work.integral_of_power(base, n, near, arb(0), pi / 4, s)
            + work.integral(lambda phi, analytic: _power(base(phi), n, analytic, acb, arb) * far(phi, analytic),
                            pi / 4, pi / 2))


def _half_vector_lobe(work: _Integrator, theta, h: Callable):
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
                    return _nan(acb)
                if upper_half:   # ψ ∈ [π/2, π]: tan(ψ/2) ≥ 1
                    phi1 = 2 * _atan(half.cot() * (s2 / s1).sqrt(analytic=analytic), analytic, acb)
                else:
                    phi1 = pi - 2 * _atan(half.tan() * (s1 / s2).sqrt(analytic=analytic), analytic, acb)
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


def _blinn_phong(work: _Integrator, theta, n):
    acb, arb = work.acb, work.arb

    def h(c, analytic):
        return _power(c, n, analytic, acb, arb)

    return _half_vector_lobe(work, theta, h)


def _blinn_phong_gaussian(work: _Integrator, theta, n):
    arb = work.arb
    # c = 0.04^(1/n) with seed 003's threshold as the decimal 0.04 it is written as; c = 0 at n = 0.
    k = arb("0.04") ** (1 / n) if n > 0 else arb(0)

    def h(c, analytic):
        x = (c - 1) / (k - 1)
        return (-(x * x)).exp()

    return _half_vector_lobe(work, theta, h)


def _microfacet(work: _Integrator, alpha, distribution: str, fresnel: Callable, critical_cos=None):
    """E at normal incidence of a microfacet lobe D·G2·F/(4 N·L N·V) (Walter et al. 2007; Heitz 2014's Smith Λ).

    With V = N the half vector's polar angle is θ_h = θ_L/2, dω_L = 4 cos θ_h dω_h and Λ(V) = 0, so both the
    height-correlated and the separable G2 are G1(L) = 1/(1 + Λ(θ_L)), and
    E = ∫ D(θ_h) cos θ_h G1(2θ_h) F(cos θ_h) dω_h over θ_h ∈ [0, π/4]. The distribution's own CDF P (the share of
    projected microfacet area with a smaller θ_h) is the variable, so the lobe is smooth whatever α is:
    GGX P = t²/(α² + t²), t = tan θ_h, and E = ∫₀^{P(π/4)} G1 F dP; Beckmann P = 1 − exp(−q), q = t²/α², taken
    as E = ∫₀^{1/α²} e^{−q} G1 F dq (P itself would crowd the range to within e^{−1/α²} of 1 for small α).
    G1 is written without poles: GGX G1 = 2 cos θ_L/(cos θ_L + √(cos² θ_L + α² sin² θ_L)); Beckmann, with
    a = cos θ_L/(α sin θ_L), G1 = 2a/(a(1 + erf a) + e^{−a²}/√π) (Λ with erf, not the rational approximation).
    ``fresnel(cos θ_h, analytic, beyond)`` is F, ``beyond`` telling the pieces apart where F stops being analytic
    at ``critical_cos`` (total internal reflection); the path is split there.
    """
    arb = work.arb
    a2 = alpha * alpha
    ggx = distribution == "ggx"

    def variable(t2):  # the integration variable at tan² θ_h = t2
        return t2 / (a2 + t2) if ggx else t2 / a2

    def integrand(beyond: bool):
        def f(x, analytic):
            t2 = a2 * x / (1 - x) if ggx else a2 * x
            weight = 1 if ggx else (-x).exp()
            cos_l = (1 - t2) / (1 + t2)
            if ggx:
                root = (cos_l * cos_l + a2 * 4 * t2 / ((1 + t2) * (1 + t2))).sqrt(analytic=analytic)
                g1 = 2 * cos_l / (cos_l + root)
            else:
                a = cos_l * (1 + t2) / (2 * alpha * t2.sqrt(analytic=analytic))
                g1 = 2 * a / (a * (1 + a.erf()) + (-(a * a)).exp() / arb.pi().sqrt())
            return weight * g1 * fresnel((1 / (1 + t2)).sqrt(analytic=analytic), analytic, beyond)
        return f

    upper = variable(arb(1))  # θ_h = π/4
    breaks = [arb(0), upper]
    if critical_cos is not None:
        split = variable(1 / (critical_cos * critical_cos) - 1)
        if split < upper:
            breaks.insert(1, split)
    total = arb(0)
    for index, (lo, hi) in enumerate(zip(breaks[:-1], breaks[1:], strict=True)):
        f = integrand(beyond=index > 0)
        if not ggx and index == 0:
            # G1 → 1 like 1 − e^(−1/(4α⁴q)) at q = 0: smooth but not analytic, so [0, δ] is enclosed directly
            # (0 ≤ e^(−q) G1 ≤ 1 and |F| ≤ 1 there: F(cos θ_h = 1) with θ_h → 0).
            delta = arb(2) ** -(work.bits + 30)
            total += arb(0, float(delta.upper()))
            lo = delta
        total += work.integral(f, lo, hi)
    return total


def _dielectric(work: _Integrator, alpha, distribution: str, eta):
    critical = (1 - eta * eta).sqrt() if eta < 1 else None

    def exact(c, analytic, beyond):  # Walter et al. 2007, Eq. 22; beyond the critical angle F = 1
        if beyond:
            return 1
        g = (eta * eta - 1 + c * c).sqrt(analytic=analytic)
        ratio = (c * (g + c) - 1) / (c * (g - c) + 1)
        return (g - c) ** 2 / (2 * (g + c) ** 2) * (1 + ratio * ratio)

    return _microfacet(work, alpha, distribution, exact, critical)


def _microfacet_route(distribution: str):
    def compute(work, theta, params, over):
        arb = work.arb
        if theta != 0:
            raise ArgumentError(f"{distribution}: the certified route is at normal incidence only (theta 0), where "
                                "the lobe is axisymmetric", where="theta")
        alpha = float(params["alpha"])
        ax, ay = (float(params.get(name, 0.0)) or alpha for name in ("alpha_x", "alpha_y"))
        if ax != ay:
            raise ArgumentError(f"{distribution}: the certified route needs an isotropic alpha (alpha_x = alpha_y)",
                                where="method")
        if params.get("ms", "none") != "none":
            raise ArgumentError(f"{distribution}: ms={params['ms']} uses interpolated tables; no certified route",
                                where="method")
        alpha = arb(ax)
        kind = params.get("fresnel", "none")
        if kind == "none":
            return [_microfacet(work, alpha, distribution, lambda c, analytic, beyond: 1)]
        if kind == "schlick":  # F = f0 + (f90 − f0)(1 − cos θ_d)⁵ is linear in (f0, f90): two integrals
            weight = _microfacet(work, alpha, distribution, lambda c, analytic, beyond: (1 - c) ** 5)
            whole = _microfacet(work, alpha, distribution, lambda c, analytic, beyond: 1)
            f0, f90 = (np.broadcast_to(np.asarray(params[name], dtype=float), (3,)) for name in ("f0", "f90"))
            return [arb(float(a)) * (whole - weight) + arb(float(b)) * weight for a, b in zip(f0, f90, strict=True)]
        if kind == "dielectric":
            etas = np.broadcast_to(np.asarray(params["eta"], dtype=float), (3,))
            balls = {value: _dielectric(work, alpha, distribution, arb(float(value))) for value in set(etas)}
            return [balls[value] for value in etas]
        raise ArgumentError(f"{distribution}: fresnel={kind} has no certified route (the conductor's complex "
                            "square root is not enclosed here)", where="method")
    return compute


@dataclass(frozen=True)
class Reduction:
    """A certified route for one built-in model: ``compute(work, theta, params, over) -> [arb per channel]``."""

    compute: Callable
    description: str


def _scalar(params: dict, name: str, arb):
    value = float(params[name])
    return arb(value)


def _reflectance(work, theta, params, over):
    return [_scalar(params, "reflectance", work.arb)]


def _phong_route(original: bool):
    def compute(work, theta, params, over):
        n = _scalar(params, "n", work.arb)
        if original and over == "view":  # ∫(R·V)^n (N·V) dV / (N·L): the modified integral over cos θ_L
            return [_phong(work, theta, n, original=False) / theta.cos()]
        return [_phong(work, theta, n, original)]
    return compute


REDUCTIONS: dict[str, Reduction] = {
    "lambert": Reduction(_reflectance, "exact: ∫ρ/π cos dω = ρ"),
    "phong": Reduction(_phong_route(True), "1-D in cos α about the mirror direction (seed 000's form)"),
    "modified-phong": Reduction(_phong_route(False), "1-D in cos α about the mirror direction"),
    "blinn-phong": Reduction(
        lambda work, theta, params, over: [_blinn_phong(work, theta, _scalar(params, "n", work.arb))],
        "1-D in the half-vector angle (seed 002's double integral, inner integral in closed form)"),
    "blinn-phong-gaussian": Reduction(
        lambda work, theta, params, over: [_blinn_phong_gaussian(work, theta, _scalar(params, "n", work.arb))],
        "1-D in the half-vector angle (any lobe of N·H)"),
    "ggx": Reduction(_microfacet_route("ggx"), "normal incidence: 1-D in the distribution's CDF"),
    "beckmann": Reduction(_microfacet_route("beckmann"), "normal incidence: 1-D in the distribution's CDF"),
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


def validate_digits(digits: object) -> int:
    """The number of significant digits asked of an enclosure (an integer in [1, MAX_DIGITS])."""
    if isinstance(digits, bool) or not isinstance(digits, (int, np.integer)):
        raise ArgumentError(f"digits must be an integer, got {digits!r}", where="digits")
    if not 1 <= digits <= MAX_DIGITS:
        raise ArgumentError(f"digits must lie in [1, {MAX_DIGITS}], got {digits}", where="digits")
    return int(digits)


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
            phi: float = 0.0) -> list[Enclosure]:
    """Enclosures (one per channel) of the albedo of ``model`` at polar angle ``theta`` (radians)."""
    digits = validate_digits(digits)
    reduction = route(model)
    flint = require_flint()
    work = _Integrator(digits)
    old = flint.ctx.prec
    flint.ctx.prec = work.bits
    try:
        balls = reduction.compute(work, flint.arb(float(theta)), params, over)
        for ball in balls:
            if not ball.is_finite():
                raise EvaluationError(f"Arb could not enclose the albedo at theta={float(theta)!r} with {digits} "
                                      "digits", where=model.name)
        return [Enclosure.of(ball, digits, work.evaluations) for ball in balls]
    finally:
        flint.ctx.prec = old


def albedo_method(problem, *, digits: int = DEFAULT_DIGITS, **_: object):
    """The ``certified`` albedo method: per case, Arb enclosures; returns the albedo module's tuple + bounds."""
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
    return value, error, evaluations, reached, None, {"lower": lower, "upper": upper}


def applies(model, over) -> bool:
    """Always: asked for by name, the method itself says why a model has no certified route."""
    return True
