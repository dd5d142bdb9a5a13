"""Certified albedo of the isotropic microfacet lobes ``ggx`` and ``beckmann`` (Walter et al. 2007; Heitz 2014's
Smith Λ, both shadowings): at any view with F = 1, and at normal incidence with Schlick or dielectric Fresnel.

Any view, F = 1 (:func:`white_albedo`)
-------------------------------------
The reduction of :mod:`brdfnorm.engine.routes.azimuthal` (its docstring has the derivation): the azimuth of L is
integrated in closed form, leaving one integral over the polar angle of L written in t (GGX, d = α sinh t) or
s (Beckmann, d = α s), d = tan((θ_L − θ_V)/2), from θ_L = 0 to the horizon θ_L = π/2:

    GGX:      E = (1/μ) ∫ G2 sin θ_L/(1 + d²) · [α²r + 2α²(1 − α²) m/√Q + (1 − α²)² m c/(cosh²t Q^{3/2})] dt,
    Beckmann: E = (1/μ) ∫ G2 sin θ_L/(1 + d²) · e^{−s²} (1/α)[(1 + d²)² J₀ + 2(b/m²)(1 + d²) J₁ + (b/m²)² J₂] ds,

r = α cosh t, m = cos θ_L + μ, Q = (sin θ_L + sin θ_V)² + α²m², c = (m²r² + Q)/2, b = 2 sin θ_L sin θ_V, and the
von Mises moments J_k(κ) = (1/2π)∫(1 − cos φ)^k e^{−κ(1 − cos φ)} dφ, κ = b/(α²m²), taken as Kummer functions
J_k = C_k ₁F₁(k + ½; k + 1; −2κ), C = (1, 1, 3/2) (Kummer's transformation of the azimuthal module's
e^{−2κ}₁F₁(½; k + 1; 2κ); Arb's ``hypgeom_1f1``, entire in κ). The bracket formula holds for every α > 0 (its two
factors c ∓ b of P are positive), α > 1 included: the cancellation the float64 route avoids there only costs Arb
precision, which the working-precision loop supplies.

Every piece is written without poles or cuts on the path, so each integrand is analytic on a neighbourhood of it
and Arb's error bounds apply (its analytic flag is honoured: ``atan`` off its cuts, every square root off (−∞, 0]):

* Shadowing without the poles of Λ at the horizon: with R_L = √(cos²θ_L + α² sin²θ_L) and R_V likewise,
  GGX height-correlated G2 = 2μ cos θ_L/(cos θ_L R_V + μ R_L), separable G1(L)G1(V) =
  2 cos θ_L/(cos θ_L + R_L) · 2μ/(μ + R_V). Both vanish at the horizon, where the path ends.
* Beckmann's Λ(b) = N(b)/(2b), N(b) = e^{−b²}/√π − b erfc b, b = cot θ/α, so G2 = 2b_L/(2b_L(1 + Λ_V) + N(b_L))
  (height-correlated) and G1_V·2b_L/(2b_L + N(b_L)) (separable), analytic through the horizon (b_L = 0). At θ_L = 0
  (b_L = ∞) Λ_L has an essential singularity (e^{−cot²θ/α²}): the lobe is smooth there but not analytic, and the
  path starts there. So G2 = G2⁰ − c with G2⁰ = 1/(1 + Λ_V) (resp. G1_V) constant and c = G2⁰ − G2 ≥ 0: the
  integral of G2⁰·(rest) is analytic throughout, and that of c·(rest) is enclosed directly where θ_L < θ_ε:
  c is increasing in θ_L and 0 ≤ c(θ_L) ≤ c(θ_upper) on a real ball, so there a ball of the path gets the
  enclosure rest·[−c(θ_upper), c(θ_upper)] with Arb's analytic flag refused (Arb accepts such a piece only when
  it is within the tolerance; θ_ε = atan(1/(α b_ε)) with e^{−b_ε²} ≈ 2^−(bits + 60)/α, so that is at once).
* Beckmann's Gaussian: the path is cut at |s| = S and the rest enclosed: there G2 ≤ 1, sin θ_L/(1 + d²) ≤ 1,
  1 + d² ≤ 2 (|θ_L − θ_V| ≤ π/2), b/m² ≤ 2/μ² (m ≥ μ), 0 ≤ J_k ≤ 2^k, so the integrand is at most
  e^{−s²}(4 + 16/μ² + 16/μ⁴)/α and the cut-off part at most (4 + 16/μ² + 16/μ⁴)e^{−S²}/(αS) (both tails), with
  S² = (bits + 20) ln 2 + ln((4 + 16/μ² + 16/μ⁴)/(μα)).
* The endpoints (θ_L = 0 and the horizon in t or s) depend on μ through balls; :meth:`Integrator.segment`
  integrates between their exact midpoints and encloses the two end pieces.

μ is taken as given (an exact float64 for a table's μ axis; cos θ in Arb for an angle θ). Fresnel other than
``none`` away from normal incidence, anisotropic α and ``ms=kulla-conty`` have no reduction here and are refused.

Normal incidence (:func:`microfacet_normal_albedo`): see that function (the distribution's CDF as the variable;
Fresnel too).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ....errors import ArgumentError
from ....models.microfacet import SHADOWING
from .core import Integrator, atan_ball, nan_ball


def microfacet_normal_albedo(work: Integrator, alpha, distribution: str, fresnel: Callable, critical_cos=None):
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


def _dielectric(work: Integrator, alpha, distribution: str, eta):
    critical = (1 - eta * eta).sqrt() if eta < 1 else None

    def exact(c, analytic, beyond):  # Walter et al. 2007, Eq. 22; beyond the critical angle F = 1
        if beyond:
            return 1
        g = (eta * eta - 1 + c * c).sqrt(analytic=analytic)
        ratio = (c * (g + c) - 1) / (c * (g - c) + 1)
        return (g - c) ** 2 / (2 * (g + c) ** 2) * (1 + ratio * ratio)

    return microfacet_normal_albedo(work, alpha, distribution, exact, critical)


def microfacet_reduction(distribution: str):
    def compute(work, theta, params, over, view_mu=None):
        arb = work.arb
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
            view = view_from_theta(arb, theta) if view_mu is None else view_from_mu(arb, view_mu)
            return [white_albedo(work, view, alpha, distribution, str(params.get("shadowing", "height-correlated")))]
        if theta != 0 or (view_mu is not None and view_mu != 1.0):
            raise ArgumentError(f"{distribution}: with fresnel={kind} the certified route is at normal incidence "
                                "only (theta 0, where the lobe is axisymmetric); any view needs fresnel=none",
                                where="theta")
        if kind == "schlick":  # F = f0 + (f90 − f0)(1 − cos θ_d)⁵ is linear in (f0, f90): two integrals
            weight = microfacet_normal_albedo(work, alpha, distribution, lambda c, analytic, beyond: (1 - c) ** 5)
            whole = microfacet_normal_albedo(work, alpha, distribution, lambda c, analytic, beyond: 1)
            f0, f90 = (np.broadcast_to(np.asarray(params[name], dtype=float), (3,)) for name in ("f0", "f90"))
            return [arb(float(a)) * (whole - weight) + arb(float(b)) * weight for a, b in zip(f0, f90, strict=True)]
        if kind == "dielectric":
            etas = np.broadcast_to(np.asarray(params["eta"], dtype=float), (3,))
            balls = {value: _dielectric(work, alpha, distribution, arb(float(value))) for value in set(etas)}
            return [balls[value] for value in etas]
        raise ArgumentError(f"{distribution}: fresnel={kind} has no certified route (the conductor's complex "
                            "square root is not enclosed here)", where="method")
    return compute


def _sqrt(z, analytic: bool, acb):
    """√z off its cut (−∞, 0]: under the analytic check a ball whose real part may reach 0 is refused."""
    if analytic and not z.real.lower() > 0:
        return nan_ball(acb)
    return z.sqrt()


def view_from_mu(arb, mu) -> tuple:
    """(μ, sin θ_V, θ_V) as balls for a view given by μ = cos θ_V (exact as given)."""
    mu = arb(mu)
    sv = ((1 - mu) * (1 + mu)).sqrt()
    return mu, sv, arb.atan2(sv, mu)


def view_from_theta(arb, theta) -> tuple:
    """(μ, sin θ_V, θ_V) as balls for a view given by its polar angle θ_V (exact as given)."""
    theta = arb(theta)
    return theta.cos(), theta.sin(), theta


def _lambda_beckmann_numerator(b):
    """N(b) = 2bΛ(b) = e^{−b²}/√π − b erfc b (Beckmann's Λ times 2b; N(0) = 1/√π)."""
    return (-(b * b)).exp() / type(b).pi().sqrt() - b * b.erfc()


def white_albedo(work: Integrator, view: tuple, alpha, distribution: str, shadowing: str):
    """An arb ball enclosing E(μ) of the isotropic lobe with F = 1; ``view`` from :func:`view_from_mu` or
    :func:`view_from_theta`, ``alpha`` > 0 an arb (the reduction in the module docstring)."""
    if shadowing not in SHADOWING:
        raise ArgumentError(f"unknown shadowing {shadowing!r}", where="shadowing")
    if distribution == "ggx":
        return _ggx(work, view, alpha, shadowing)
    if distribution == "beckmann":
        return _beckmann(work, view, alpha, shadowing)
    raise ArgumentError(f"{distribution}: no certified reduction", where="method")


def ggx_kernel(alpha, correlated: bool, t, sl, cl, sv, mu, analytic: bool, acb):
    """The GGX integrand in t of the module docstring's reduction without its 1/μ: G2 sin θ_L/(1 + d²)·bracket, at
    d = α sinh t with θ_L and θ_V given by their sines and cosines (balls, complex ones included: every square
    root is analytic-checked when ``analytic``)."""
    a2 = alpha * alpha
    g = 1 - a2
    d = alpha * t.sinh()
    ch = t.cosh()
    r = alpha * ch
    m = cl + mu
    q = (sl + sv) ** 2 + a2 * m * m
    rq = _sqrt(q, analytic, acb)
    c = (m * m * r * r + q) / 2
    bracket = a2 * (r + 2 * g * m / rq) + g * g * m * c / (ch * ch * q * rq)
    rl = _sqrt(cl * cl + a2 * sl * sl, analytic, acb)
    rv = _sqrt(mu * mu + a2 * sv * sv, analytic, acb)
    g2 = 2 * cl * mu / (cl * rv + mu * rl) if correlated else 2 * cl / (cl + rl) * 2 * mu / (mu + rv)
    return g2 * sl / (1 + d * d) * bracket


def _ggx(work: Integrator, view: tuple, alpha, shadowing: str):
    arb, acb = work.arb, work.acb
    mu, sv, thv = view
    correlated = shadowing == "height-correlated"

    def f(t, analytic):
        thl = thv + 2 * atan_ball(alpha * t.sinh(), analytic, acb)
        return ggx_kernel(alpha, correlated, t, thl.sin(), thl.cos(), sv, mu, analytic, acb)

    start = -((thv / 2).tan() / alpha).asinh()
    end = (((arb.pi() / 2 - thv) / 2).tan() / alpha).asinh()
    return work.segment(f, start, end) / mu


def _beckmann(work: Integrator, view: tuple, alpha, shadowing: str):
    arb, acb = work.arb, work.acb
    mu, sv, thv = view
    a2 = alpha * alpha
    half = arb(1) / 2
    lam_v = arb(0) if sv == 0 else _lambda_beckmann_numerator(mu / (alpha * sv)) * alpha * sv / (2 * mu)
    g1v = 1 / (1 + lam_v)  # = G2⁰ for both shadowings (height-correlated: 1/(1 + Λ_V))
    correlated = shadowing == "height-correlated"

    def rest(s, analytic):  # everything but G2
        d = alpha * s
        thl = thv + 2 * atan_ball(d, analytic, acb)
        sl, cl = thl.sin(), thl.cos()
        m = cl + mu
        ratio = 2 * sl * sv / (m * m)
        z = -2 * ratio / a2  # −2κ
        j0, j1, j2 = z.hypgeom_1f1(half, 1), z.hypgeom_1f1(3 * half, 2), 3 * half * z.hypgeom_1f1(5 * half, 3)
        dd = 1 + d * d
        return sl / dd * (-(s * s)).exp() * (dd * dd * j0 + 2 * ratio * dd * j1 + ratio * ratio * j2) / alpha, thl

    def shadow_loss(thl):  # c = G2⁰ − G2 at θ_L
        b = thl.cos() / (alpha * thl.sin())
        n = _lambda_beckmann_numerator(b)
        if correlated:
            return n / ((1 + lam_v) * (2 * b * (1 + lam_v) + n))
        return g1v * n / (2 * b + n)

    ln2 = arb(2).log()
    b_eps = ((work.bits + 60 + max(0.0, -float(alpha.log() / ln2))) * ln2).sqrt()
    theta_eps = (1 / (alpha * b_eps)).atan()

    def loss(s, analytic):  # rest · c, enclosed directly below θ_ε (see the module docstring)
        value, thl = rest(s, analytic)
        if thl.real.lower() < theta_eps:
            if analytic or not s.imag == 0:
                return nan_ball(acb)
            top = thl.real.upper()
            if not top < arb.pi() / 2:  # c increases up to the horizon, where G2 = 0: c ≤ G2⁰ on the whole path
                c = g1v
            else:
                c = shadow_loss(acb(top)).real if top > 0 else arb(0)
            return value * acb(arb(0, c.upper())) if c.is_finite() else nan_ball(acb)
        return value * shadow_loss(thl)

    scale = (4 + 16 / mu**2 + 16 / mu**4) / (mu * alpha)
    reach = arb((((work.bits + 20) * ln2 + scale.log()).sqrt()).upper())  # S, exact
    start = -(thv / 2).tan() / alpha
    end = ((arb.pi() / 2 - thv) / 2).tan() / alpha
    cut = not (start > -reach and end < reach)
    tail = arb(0, (scale * mu * (-(reach * reach)).exp() / reach).upper()) if cut else arb(0)
    lo = start if start > -reach else -reach
    hi = end if end < reach else reach

    def first(s, analytic):
        return rest(s, analytic)[0]

    whole = work.segment(first, lo, hi)
    tol = arb(2) ** (-(work.bits - 20)) * abs(whole.mid())
    # The loss integral starts at the exact midpoint of the start ball: the piece before it lies below θ_ε (far
    # below: its ball's θ_L is within its radius of 0), where c·rest is enclosed as in loss().
    low = arb(lo.mid())
    piece = arb(0)
    if lo.rad() != 0:
        value = loss(acb(lo), False)
        piece = arb(0, (arb(lo.rad()) * abs(value)).upper()) if value.is_finite() else arb("nan")
    lost = work.integral(loss, low, arb(hi.mid()), abs_tol=tol) + piece
    if hi.rad() != 0:
        value = rest(acb(hi), True)[0] * shadow_loss(rest(acb(hi), True)[1])
        lost += arb(0, (arb(hi.rad()) * abs(value)).upper()) if value.is_finite() else arb("nan")
    return (whole * g1v - lost + tail) / mu
