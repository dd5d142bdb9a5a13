"""White (F = 1) albedo of anisotropic GGX and Beckmann lobes, compiled: at a view, averaged over the view
azimuth, and its cosine-weighted hemispherical average E_avg — the cells of the anisotropic tables
(:mod:`brdfnorm.lut.anisotropy`) and of the anisotropic compensation (:mod:`brdfnorm.engine.routes.microfacet`).

What it computes
----------------
The half-vector form of :mod:`brdfnorm.engine.routes.halfvector` (Walter et al. 2007 eq. 14; Heitz 2014 §5.2),
with F = 1: in standardized slope polar coordinates (s, φ), real slopes x = s·d(φ), d = (α_x cos φ, α_y sin φ),

    E(V) = (1/2π) ∫₀^{2π} ∫₀^{s_h(φ)} G2(L, V) (1 + s·p(φ)) du(s) dφ,   p = c·d, c = (V_x, V_y)/V_z,

u the distribution's radial CDF (GGX s²/(1+s²), Beckmann 1 − e^{−s²}), L the mirror of V about H ∝ (x, 1),
N·L = V_z (s_h − s)(|d|² s + q − p)/(1 + s²|d|²), s_h = (q + p)/|d|², q = √(p² + |d|²) (the horizon, on the
domain's edge). Radial coordinate t = atan s for both (GGX: u = sin²t, du = sin 2t dt, analytic at the pole and in
the heavy tail's inverse slope; Beckmann: du = 2s(1 + s²)e^{−s²} dt). A cut of Beckmann's tail at a fixed slope
(s = 8) was tried and found wrong: where the horizon s_h(φ) crosses the cut, t_h(φ) = min(s_h, 8) has a kink in φ
inside a panel, and at μ = 1e-3, α = 1 the cubature settled 7.9e-7 off with an estimate of 1e-10; atan s_h(φ) is
smooth. Each ray is split where the linearized N·L reaches 4·max(α_x, α_y) (Smith's boundary layer
at the horizon gets a piece of its own, as in the half-vector route), the two pieces mapped to v ∈ [0, 1] and
[1, 2]; the φ panels start at the zeros of p(φ) (and its extrema φ0, φ0 + π in a principal plane, where they end
the mirrored half) and, for lobes flatter than α_y/α_x = 1/4 (:data:`PRINCIPAL_EDGES`), at the lobe's principal
directions (where |d|² is extreme and the horizon peaks). Radial grading: the first piece's v edges start
graded by 8 (:data:`GRADING`) towards v = 1, from 1 − 8·g up to 1 − 1/8, g = min over the φ panel of
(t_h − t_split)/t_split. Why: at grazing views of narrow lobes the horizon slope s_h ~ 2 tan θ_V/α is large,
t_h = atan s_h lies 1/s_h below π/2, and the
integrand, a function of s/s_h near the horizon (N·L, Λ(L)) with (1 + s·p) du → 2p there, has its singularities
(the zero of N·L, the pole of tan at π/2, Λ's branch points) within about t_h − t_split beyond the piece's end — at
μ = α = 1/64 about 1e-4 of the piece's length. Neither K15 nor the embedded G7 resolves such a near-singular
panel, and their difference was about 3 times below the K15 error (3.0e-6 off, estimate 1.6e-6 at rtol 2.5e-6); a
check by halves did not see it either (the halves' discrepancy 3.4e-7 on a panel 1.3e-6 off). With panels no
longer than 8 times their distance to the singularities both rules converge and |K15 − G7| bounds the K15 error.
A view in a principal plane (φ_v = 0 or π/2) mirrors the integrand: half the azimuth is integrated and doubled.

Cubature: globally adaptive G7/K15 ⊗ G7/K15 over (φ, v) panels per case (225 nodes a panel), compiled with Numba.
A panel's error is |KK − GK| + |KK − KG| (the embedded Gauss rule in each direction: the coarser rule's error,
pessimistic for the K15 value used while the integrand is smooth on the panel), and each half of a bisected
panel carries at least half its parent's bisection discrepancy |Q_parent − (Q_left + Q_right)| in the direction
split (a feature inside a panel cannot hide behind one shared error of both rules). The worst panel is bisected
along its worse direction until the summed error is ≤ max(atol, rtol·|E|). A rounding floor of
64·ε·Σ|panel values| is added.

View-azimuth average Ē(μ) = (1/2π)∫ E(μ, φ_v) dφ_v (one view for an isotropic lobe): E is even and π-periodic in φ_v
and symmetric about π/2 (the slope distribution and Λ are even in each slope), so the average over [0, π/2] is the
whole; E is analytic in φ_v, a cosine series in 2φ_v, and the trapezoid rule with M intervals on [0, π/2] is the
4M-point periodic rule, exact through cos(2(2M − 1)φ_v). Nested doubling M = 1, 2, 4, … 128 (each level reuses the
previous nodes), stopping at M ≥ 4; the error of T_2M is taken as |T_2M − T_M| (the size of the first neglected
coefficient, which bounds the later ones while they decay) plus the nodes' own errors through the weights (the nodes
get half the tolerance, :data:`INNER_SHARE`). Once two doublings show geometric convergence, d_2M = |T_2M − T_M| ≤
d_M/4 (:data:`RATIO_MAX`), the rule's part is d_2M·(d_2M/d_M) instead: for an analytic periodic integrand the
coefficients decay as ρ^{-n}, d_M is T_{M/2}'s error ~ ρ^{-cM/2}, and T_2M's error is about d_2M·(d_2M/d_M)², so one
factor of the ratio keeps a margin of 1/ratio ≥ 4 (checked against 129-view references with views at rtol 1e-11,
``tests/test_anisotropy_azimuth.py``: at rtol 1e-5 and 1e-7 over 192 cells of GGX and Beckmann, μ from 1e-4 to 1,
α_y/α_x down to 0.01, the error was at most 0.13 of the estimate). This stops one doubling earlier than
|T_2M − T_M| alone (9 views instead of 17 for most anisotropic cells).

View-azimuth stretch: the average runs over χ, φ_v = atan2(k sin χ, cos χ), k = :func:`view_stretch`. E(φ_v) is
singular off the real axis near φ_v = π/2 (α_x > α_y): at Λ(V)'s branch point, a distance η with
tanh²η = (μ² + (1 − μ²)α_y²)/(μ² + (1 − μ²)α_x²), whose image balanced against the stretch's own
poles gives k_Λ = (tanh η)^{-1/2}; and at a distance ~α_y/α_x at every μ (the standardized view's azimuth enters
through the reflection), which k = √(α_x/α_y) balances. k_Λ alone failed for narrow, very flat lobes at mid views
(μ = 0.4, (α_x, α_y) = (0.2, 0.002): stopped at M = 4, 6.1e-7 off, estimate 4.8e-8); the geometric mean
√(√(α_x/α_y)·k_Λ) held on 32 random cells at three rtols (at most 0.57 of the estimate off; √(α_x/α_y): 0.56)
with 16% fewer views (``tests/lut/test_anisotropy_speed.py``, ``tests/lut/test_anisotropy_azimuth.py``).

E_avg = 2∫₀¹ Ē(μ) μ dμ = ∫₀¹ 4x³ Ē(x²) dx (x = √μ; the weight vanishes where E has its grazing boundary layer):
one K15 panel over [0, 1] when its |K15 − G7| meets the tolerance (E(μ) of a white microfacet lobe is analytic on
(0, 1]: no kink for a shared error of both rules to hide), else globally adaptive G7/K15 with the
parent-discrepancy floor of :mod:`brdfnorm.engine.machinery.interval`, node albedos to
tolerances loosened where the weight 4x³ is small (≤ rtol/2 of the integral in all, :data:`INNER_SHARE`); a node
whose tolerance is ≥ ½ takes the white lobe's bound E ∈ [0, 1] as ½ ± ½ (no view; the first K15 node at x = 0);
nodes below μ = 1e-7 are evaluated there (a change ≤ 1e-14 · max E, added). Narrow (max α ≤ 0.1) and very wide
(max α ≥ 2.2) lobes start from the two halves of [0, 1] instead of the whole (:data:`HALVES_NARROW`).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from ...errors import ArgumentError
from ...models.microfacet import SHADOWING
from ..compiled.backend import numba_available
from ..machinery.kronrod import GAUSS, KRONROD, NODES

DISTRIBUTIONS = ("ggx", "beckmann")
#: What multiplies the lobe: nothing (E), Schlick's coefficient of f0, 1 − (1 − V·H)⁵, or of f90, (1 − V·H)⁵.
WEIGHTS = ("white", "f0", "f90")
#: Panels per case before the 2-D cubature gives up (reported as not converged).
MAX_PANELS = 4000
#: Nested trapezoid levels of the view-azimuth average: M = 1 … 2**MAX_LEVEL intervals on [0, π/2].
MAX_LEVEL = 7
#: The share of a nested average's tolerance given to its nodes' own errors (views in the φ_v average, φ_v
#: averages in E_avg); the rule's error estimate gets the rest.
INNER_SHARE = 0.5
#: The largest ratio |T_2M − T_M| / |T_M − T_{M/2}| read as geometric convergence (module docstring).
RATIO_MAX = 0.25
#: Ratio of the graded v edges of the first radial piece towards the horizon (module docstring).
GRADING = 8.0
#: The lobe's principal directions start φ panels of a view only where α_y/α_x (or α_x/α_y) is below this.
PRINCIPAL_EDGES = 0.25
#: E_avg: smallest μ evaluated, and panels of its μ integral.
MU_FLOOR = 1e-7
MAX_AVG_PANELS = 200
#: E_avg starts from two halves of [0, 1] for lobes with max(α_x, α_y) at most / at least these.
HALVES_NARROW = 0.1
HALVES_WIDE = 2.2
_EPS = float(np.finfo(float).eps)
_SQRT_PI = math.sqrt(math.pi)
_X = NODES.copy()
_WK = KRONROD.copy()
_WG = GAUSS.copy()

# This module's kernels are loaded from Numba's cache at their first call, which need not pass through the compiled
# backend's loading: the cache of kernels whose inlined sources changed is refreshed here first (staleness.py).
numba_available()


@numba.njit(cache=True, fastmath=False)
def _smith_lambda(dist: int, a2: float) -> float:
    if dist == 0:
        return 0.5 * a2 / (1.0 + math.sqrt(1.0 + a2))
    if a2 <= 0.0:
        return 0.0
    b = 1.0 / math.sqrt(a2)
    if b > 27.0:  # e^{-b²} underflows the sum's precision: Λ < 1e-300
        return 0.0
    return 0.5 * (math.exp(-b * b) / (b * _SQRT_PI) - math.erfc(b))


@numba.njit(cache=True)
def _stretch(theta: float, k: float) -> tuple[float, float, float]:
    """(cos φ, sin φ, dφ/dθ) of φ = atan2(k sin θ, cos θ): a monotone, periodic map of [0, 2π] onto itself."""
    c, s = math.cos(theta), k * math.sin(theta)
    r2 = c * c + s * s
    r = math.sqrt(r2)
    return c / r, s / r, k / r2


@numba.njit(cache=True)
def _unstretch(phi: float, k: float) -> float:
    """θ of φ under :func:`_stretch`: φ plus the periodic shift atan2(sin φ/k, cos φ) − atan2(sin φ, cos φ) (both
    angles in one quadrant, so the shift is below π/2 and continuous: no branch cut to land on)."""
    s, c = math.sin(phi), math.cos(phi)
    return phi + (math.atan2(s / k, c) - math.atan2(s, c))


@numba.njit(cache=True)
def _ray(cphi, sphi, vx, vy, vz, ax, ay):
    """The ray at φ: d = (d_x, d_y), |d|², p, q, the horizon s_h and the radial pieces' ends t_split, t_h = atan s_h
    (the split where the linearized N·L reaches 4·max(α_x, α_y))."""
    dx, dy = ax * cphi, ay * sphi
    dd = dx * dx + dy * dy
    p = (vx * dx + vy * dy) / vz
    q = math.sqrt(p * p + dd)
    s_h = (q + p) / dd
    delta = 4.0 * max(ax, ay) * (1.0 + s_h * s_h * dd) / (2.0 * q * vz)
    s_split = s_h / (1.0 + delta / s_h)
    return dx, dy, dd, p, q, s_h, math.atan(s_split), math.atan(s_h)


@numba.njit(cache=True)
def _point(theta: float, v: float, vx: float, vy: float, vz: float, ax: float, ay: float, dist: int, sep: int,
           lam_v: float, k: float, weight: int) -> float:
    """The integrand at (θ, v) times dφ/dθ · dt/dv, over 2π (so that the (θ, v) integral is E), times the
    split-sum weight of ``weight`` (:data:`WEIGHTS`: 1, 1 − (1 − V·H)⁵ or (1 − V·H)⁵)."""
    cphi, sphi, dphi = _stretch(theta, k)
    dx, dy, dd, p, q, s_h, t_split, t_h = _ray(cphi, sphi, vx, vy, vz, ax, ay)
    if v < 1.0:
        t, jac = v * t_split, t_split
    else:
        t, jac = t_split + (v - 1.0) * (t_h - t_split), t_h - t_split
    if jac <= 0.0:
        return 0.0
    s = math.tan(t)
    if dist == 0:
        du = math.sin(2.0 * t)
    else:
        du = 2.0 * s * (1.0 + s * s) * math.exp(-s * s)  # 2s e^{−s²} ds/dt, ds/dt = 1 + s²
    gap = s_h - s
    if gap <= 0.0:
        return 0.0
    nl = vz * gap * (dd * s + q - p) / (1.0 + s * s * dd)
    x1, x2 = s * dx, s * dy
    scale = 2.0 * (vx * x1 + vy * x2 + vz) / (1.0 + x1 * x1 + x2 * x2)
    lx, ly = scale * x1 - vx, scale * x2 - vy
    a2_l = ((ax * lx) ** 2 + (ay * ly) ** 2) / (nl * nl)
    lam_l = _smith_lambda(dist, a2_l)
    if sep == 1:
        g2 = 1.0 / ((1.0 + lam_l) * (1.0 + lam_v))
    else:
        g2 = 1.0 / (1.0 + lam_l + lam_v)
    f = g2 * (1.0 + s * p) * du * jac * dphi / (2.0 * math.pi)
    if weight == 0:
        return f
    # V·H = (V_x x1 + V_y x2 + V_z)/|(x1, x2, 1)| for H ∝ (x1, x2, 1), i.e. scale·|(x1, x2, 1)|/2
    tail = (1.0 - min(1.0, 0.5 * scale * math.sqrt(1.0 + x1 * x1 + x2 * x2))) ** 5
    return f * (1.0 - tail) if weight == 1 else f * tail


@numba.njit(cache=True)
def _panel(a0, a1, b0, b1, vx, vy, vz, ax, ay, dist, sep, lam_v, k, weight, x, wk, wg):
    """K15⊗K15 value, |KK − GK| (error along φ), |KK − KG| (along v) and Σ|f| (for the rounding floor)."""
    ha, hb = 0.5 * (a1 - a0), 0.5 * (b1 - b0)
    ca, cb = 0.5 * (a0 + a1), 0.5 * (b0 + b1)
    kk = gk = kg = absum = 0.0
    for i in range(15):
        phi = ca + ha * x[i]
        rk = rg = 0.0
        for j in range(15):
            f = _point(phi, cb + hb * x[j], vx, vy, vz, ax, ay, dist, sep, lam_v, k, weight)
            rk += wk[j] * f
            rg += wg[j] * f
            absum += wk[i] * wk[j] * abs(f)
        kk += wk[i] * rk
        gk += wg[i] * rk
        kg += wk[i] * rg
    area = ha * hb
    return kk * area, abs(kk - gk) * area, abs(kk - kg) * area, absum * abs(area)


@numba.njit(cache=True)
def view_albedo(mu: float, phi_v: float, ax: float, ay: float, dist: int, sep: int, rtol: float, atol: float,
                max_panels: int, weight: int, x, wk, wg):
    """(E, error, evaluations, converged) at the view (μ, φ_v) of one lobe (times a split-sum ``weight``)."""
    st = math.sqrt(max(0.0, 1.0 - mu * mu))
    vx, vy, vz = st * math.cos(phi_v), st * math.sin(phi_v), mu
    # A view in the plane of a principal axis (φ_v = 0 or π/2 up to rounding: E is even there, the change of
    # snapping is second order, ~1e-32) is a mirror of the integrand: φ → −φ (V_y = 0) or φ → π − φ (V_x = 0),
    # θ alike under the stretch. Half the azimuth, [φ0, φ0 + π], is integrated and doubled.
    if abs(vx) <= 1e-12 * st:
        vx = 0.0
    if abs(vy) <= 1e-12 * st:
        vy = 0.0
    mirrored = vx == 0.0 or vy == 0.0
    fold = 2.0 if mirrored else 1.0
    lam_v = _smith_lambda(dist, ((ax * vx) ** 2 + (ay * vy) ** 2) / (vz * vz))
    a0 = np.empty(max_panels)
    a1 = np.empty(max_panels)
    b0 = np.empty(max_panels)
    b1 = np.empty(max_panels)
    val = np.empty(max_panels)
    ea = np.empty(max_panels)
    eb = np.empty(max_panels)
    ab = np.empty(max_panels)
    cuts = np.empty(24)
    # The azimuth θ of the standardized slopes' angle φ = atan2(k sin θ, cos θ), k = √(α_x/α_y): in φ the real
    # slope direction turns within a width α_y/α_x about φ = ±π/2 (α_x > α_y), in θ within √(α_y/α_x) only.
    k = math.sqrt(ax / ay)
    # Panels from the extrema and zeros of p(φ) = c·d(φ) = R cos(φ − φ0), mapped to θ; at grazing views further
    # edges graded by 8 away from each zero of p, from w0 = |d|/(4R) on: within ~|d|/R of a zero the horizon
    # s_h(φ) turns from ~1/(2|p|) to ~2|p|/|d|², a sliver that no node of a quarter panel sees (Beckmann α = 3 at
    # μ = 1e-4: 3.9e-9 missed with an estimate of 9e-11 before these edges).
    phi0 = math.atan2(vy * ay, vx * ax)
    radius = math.hypot(vx * ax, vy * ay) / vz
    edges = np.empty(100)
    m = 0
    base = phi0 if mirrored else phi0 - 0.5 * math.pi
    for quarter in range(4):
        if mirrored or quarter % 2 == 1:
            edges[m] = phi0 + quarter * 0.5 * math.pi
            m += 1
    # and the lobe's principal directions φ = 0, π/2, π, 3π/2 (θ the same), where |d|² is extreme and the
    # horizon s_h(φ) peaks: at (α_x, α_y) = (2.82, 0.282), μ = 0.734, φ_v = 1.363 a band of θ within 0.03 of π/2
    # fell between the nodes of a quarter panel (4.2e-5 missed at rtol 5e-6 with an estimate of 6e-7). Only for a
    # lobe flatter than PRINCIPAL_EDGES: for α_y/α_x ≥ 1/4 |d|² varies by at most 4 and the peak spans the whole
    # quarter panel (150 random views with α_y/α_x in [0.25, 0.6], μ from 1e-4 to 1, α from 0.003 to 3, rtol 1e-7
    # to 1e-4: at most 0.74 of the estimate off; tests/lut/test_anisotropy_speed.py)
    if min(ax, ay) < PRINCIPAL_EDGES * max(ax, ay):
        for quarter in range(4):
            edges[m] = quarter * 0.5 * math.pi
            m += 1
    for side in (-1.0, 1.0):
        zero = phi0 + side * 0.5 * math.pi
        width = math.hypot(ax * math.cos(zero), ay * math.sin(zero)) / (4.0 * max(radius, 1e-300))
        while width < math.pi / 8 and m < 98:
            edges[m], edges[m + 1] = zero - width, zero + width
            m += 2
            width *= 8.0
    for i in range(m):  # into [base, base + 2π)
        edges[i] = base + (edges[i] - base) % (2.0 * math.pi)
    edges[:m] = np.sort(edges[:m])
    edges[m] = base + 2.0 * math.pi
    if mirrored:  # the edges are symmetric about φ0 and φ0 + π (extrema and zeros of p): keep the first half
        half = 1
        while half < m and edges[half] < phi0 + math.pi:
            half += 1
        edges[half] = phi0 + math.pi
        m = half
    n = 0
    for e in range(m):
        lo, hi = _unstretch(edges[e], k), _unstretch(edges[e + 1], k)
        if hi <= lo:
            continue
        # The first radial piece's v edges graded towards v = 1 (module docstring, "radial grading"): the
        # horizon's singularities lie about (t_h − t_split)/t_split beyond its end, in units of its length.
        gap = 1.0
        for i in range(17):
            theta = lo + (hi - lo) * i / 16.0
            cphi, sphi, _ = _stretch(theta, k)
            t_split, t_h = _ray(cphi, sphi, vx, vy, vz, ax, ay)[6:]
            if t_split > 0.0:
                gap = min(gap, (t_h - t_split) / t_split)
        c = 0  # graded edges 1 − 8·gap, 1 − 64·gap, … while below 1 − 1/8, then in increasing order
        width = GRADING * gap
        while width < 1.0 / GRADING and c < cuts.size - 3:
            cuts[c] = 1.0 - width
            c += 1
            width *= GRADING
        cuts[:c] = cuts[:c][::-1].copy()
        cuts[1:c + 1] = cuts[:c].copy()
        cuts[0] = 0.0
        c += 1
        cuts[c], cuts[c + 1] = 1.0, 2.0
        if n + c + 1 >= max_panels:
            return 0.0, math.inf, 225 * n, False
        for piece in range(c + 1):
            a0[n], a1[n] = lo, hi
            b0[n], b1[n] = cuts[piece], cuts[piece + 1]
            val[n], ea[n], eb[n], ab[n] = _panel(a0[n], a1[n], b0[n], b1[n], vx, vy, vz, ax, ay, dist, sep,
                                                  lam_v, k, weight, x, wk, wg)
            n += 1
    evaluations = 225 * n
    while True:
        total = err = absum = 0.0
        worst, worst_err = 0, -1.0
        for i in range(n):
            total += val[i]
            e = ea[i] + eb[i]
            err += e
            absum += ab[i]
            if e > worst_err:
                worst, worst_err = i, e
        total, err, floor = fold * total, fold * err, fold * 64.0 * _EPS * absum
        if err + floor <= max(atol, rtol * abs(total)):
            return total, err + floor, evaluations, True
        if n + 1 >= max_panels:
            return total, err + floor, evaluations, False
        i = worst
        along_a = ea[i] >= eb[i]
        pa0, pa1, pb0, pb1, parent = a0[i], a1[i], b0[i], b1[i], val[i]
        if along_a:
            mid = 0.5 * (pa0 + pa1)
            a0[i], a1[i], b0[i], b1[i] = pa0, mid, pb0, pb1
            a0[n], a1[n], b0[n], b1[n] = mid, pa1, pb0, pb1
        else:
            mid = 0.5 * (pb0 + pb1)
            a0[i], a1[i], b0[i], b1[i] = pa0, pa1, pb0, mid
            a0[n], a1[n], b0[n], b1[n] = pa0, pa1, mid, pb1
        for m in (i, n):
            val[m], ea[m], eb[m], ab[m] = _panel(a0[m], a1[m], b0[m], b1[m], vx, vy, vz, ax, ay, dist, sep,
                                                  lam_v, k, weight, x, wk, wg)
        half = 0.5 * abs(parent - val[i] - val[n])
        for m in (i, n):
            if along_a:
                ea[m] = max(ea[m], half)
            else:
                eb[m] = max(eb[m], half)
        n += 1
        evaluations += 450


@numba.njit(cache=True)
def view_stretch(mu: float, ax: float, ay: float) -> float:
    """k of the view-azimuth stretch ψ = atan2(k sin χ, cos χ): the geometric mean of √(α_x/α_y) (the grazing
    limit) and ((μ² + (1 − μ²)α_x²)/(μ² + (1 − μ²)α_y²))^{1/4} (the balance for Λ(V)'s branch point alone) —
    module docstring, "view-azimuth stretch"."""
    s2 = 1.0 - mu * mu
    return math.sqrt(math.sqrt(ax / ay) * math.sqrt(math.sqrt((mu * mu + s2 * ax * ax) / (mu * mu + s2 * ay * ay))))


@numba.njit(cache=True)
def _stretched_view(mu, chi, ax, ay, dist, sep, rtol, atol, weight, x, wk, wg):
    """E(μ, ψ(χ))·ψ'(χ) with ψ = atan2(k sin χ, cos χ), k = :func:`view_stretch`; the tolerance is E's, scaled by
    ψ'."""
    cpsi, spsi, dpsi = _stretch(chi, view_stretch(mu, ax, ay))
    v, e, ev, c = view_albedo(mu, math.atan2(spsi, cpsi), ax, ay, dist, sep, rtol, atol / dpsi, MAX_PANELS,
                              weight, x, wk, wg)
    return v * dpsi, e * dpsi, ev, c


@numba.njit(cache=True)
def azimuth_average(mu: float, ax: float, ay: float, dist: int, sep: int, rtol: float, atol: float, weight: int,
                    x, wk, wg):
    """(Ē, error, evaluations, converged, intervals M used): the view-azimuth average (module docstring)."""
    if ax == ay:  # an isotropic lobe: E does not depend on φ_v, one view is the average (M = 0)
        v, e, ev, c = view_albedo(mu, 0.0, ax, ay, dist, sep, rtol, atol, MAX_PANELS, weight, x, wk, wg)
        return v, e, ev, c, 0
    size = 2 ** MAX_LEVEL + 1
    values = np.empty(size)
    errors = np.empty(size)
    inner_rtol, inner_atol = rtol * INNER_SHARE, atol * INNER_SHARE
    evaluations = 0
    ok = True
    step = 2 ** MAX_LEVEL  # index stride of M = 1 (the two ends) within the finest level's nodes
    for j in range(0, size, step):
        v, e, ev, c = _stretched_view(mu, j * (0.5 * math.pi) / (size - 1), ax, ay, dist, sep, inner_rtol,
                                      inner_atol, weight, x, wk, wg)
        values[j], errors[j], evaluations, ok = v, e, evaluations + ev, ok and c
    previous = _trapezoid(values, errors, step)[0]
    change = -1.0  # |T_M − T_{M/2}| of the previous level (none yet)
    while True:
        step //= 2
        for j in range(step, size, 2 * step):
            v, e, ev, c = _stretched_view(mu, j * (0.5 * math.pi) / (size - 1), ax, ay, dist, sep, inner_rtol,
                                          inner_atol, weight, x, wk, wg)
            values[j], errors[j], evaluations, ok = v, e, evaluations + ev, ok and c
        value, inner = _trapezoid(values, errors, step)
        intervals = (size - 1) // step
        difference = abs(value - previous)
        error = difference + inner
        if change > 0.0 and difference <= RATIO_MAX * change:
            # geometric convergence seen over two doublings: T_2M's error is about difference·ratio² (module
            # docstring); difference·ratio keeps a factor 1/ratio ≥ 4 in hand
            error = difference * (difference / change) + inner
        tolerance = max(atol, rtol * abs(value))
        if (intervals >= 4 and error <= tolerance) or step == 1:
            return value, error, evaluations, ok and error <= tolerance, intervals
        previous, change = value, difference


@numba.njit(cache=True)
def _trapezoid(values, errors, step):
    """Mean over [0, π/2] by the trapezoid rule on every ``step``-th node, and the nodes' errors through it."""
    last = values.size - 1
    total = 0.5 * (values[0] + values[last])
    error = 0.5 * (errors[0] + errors[last])
    for j in range(step, last, step):
        total += values[j]
        error += errors[j]
    count = last // step
    return total / count, error / count


@numba.njit(cache=True)
def _cell(mu, phi_v, ax, ay, dist, sep, rtol, average, weight, x, wk, wg):
    if average:
        v, e, ev, c, _ = azimuth_average(mu, ax, ay, dist, sep, rtol, 0.0, weight, x, wk, wg)
        return v, e, ev, c
    return view_albedo(mu, phi_v, ax, ay, dist, sep, rtol, 0.0, MAX_PANELS, weight, x, wk, wg)


@numba.njit(cache=True)
def _cells(mu, phi_v, ax, ay, dist, sep, rtol, average, weight, x, wk, wg):
    n = mu.size
    value, error = np.empty(n), np.empty(n)
    evaluations, converged = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.bool_)
    for i in range(n):
        value[i], error[i], evaluations[i], converged[i] = _cell(mu[i], phi_v[i], ax[i], ay[i], dist, sep, rtol,
                                                                 average, weight, x, wk, wg)
    return value, error, evaluations, converged


@numba.njit(cache=True)
def _average_panel(left, width, ax, ay, dist, sep, rtol, scale, x, wk, wg):
    """K15 and |K15 − G7| of ∫ 4x³ Ē(x²) dx over one panel of x = √μ, the node errors added; evaluations."""
    half = 0.5 * width
    kron = gauss = prop = 0.0
    evaluations = 0
    ok = True
    for i in range(15):
        xi = left + half * (x[i] + 1.0)
        mu = max(xi * xi, MU_FLOOR)
        weight = 4.0 * xi ** 3
        # A node's albedo needs rtol·share·scale/weight absolutely (scale ~ the integral): looser where weight is
        # small; the nodes' errors take that share of the tolerance, |K15 − G7| the rest.
        atol = rtol * INNER_SHARE * scale / max(weight, 1e-300)
        if atol >= 0.5:
            # A white lobe's albedo lies in [0, 1] (G2 ≤ G1: E is at most the visible normals' mass): ½ ± ½ meets
            # the node's tolerance without a view (the first node of a panel at x = 0, weight ~1e-7); its
            # uncertainty enters the G7 value too.
            v, e = 0.5, 0.5
            prop += abs(wk[i] - wg[i]) * weight * e
        else:
            v, e, ev, c, _ = azimuth_average(mu, ax, ay, dist, sep, rtol * INNER_SHARE, atol, 0, x, wk, wg)
            evaluations += ev
            ok = ok and c
        kron += wk[i] * weight * v
        gauss += wg[i] * weight * v
        prop += wk[i] * weight * e
    return half * kron, half * abs(kron - gauss) + half * prop, evaluations, ok


@numba.njit(cache=True)
def hemispherical_average(ax, ay, dist, sep, rtol, x, wk, wg):
    """(E_avg, error, evaluations, converged) = 2∫₀¹ Ē(μ) μ dμ (module docstring)."""
    left = np.empty(MAX_AVG_PANELS)
    width = np.empty(MAX_AVG_PANELS)
    val = np.empty(MAX_AVG_PANELS)
    err = np.empty(MAX_AVG_PANELS)
    widest = max(ax, ay)
    halves = widest <= HALVES_NARROW or widest >= HALVES_WIDE
    evaluations, ok, parent = 0, True, 0.0
    if halves:
        # the first level is the two halves of [0, 1] for narrow and very wide lobes: of 128 (α, aspect) pairs of
        # the 32 × 32 × 16 table, one K15 panel's G7 difference was above rtol 1e-5 for 16, 14 of them in these
        # ranges (the boundary layer at grazing μ ≲ α, the wide flat lobes' structure), 2 more here would have
        # passed: a whole panel there is mostly work thrown away. E_avg ≳ 0.9 (narrow) and ≳ 0.15 (α_x up to 3.2)
        # set the nodes' scale; it is refined from the sum once the halves are in.
        scale = 0.5 if widest <= HALVES_NARROW else 0.15
    else:
        scale = 0.5  # E_avg of a white lobe is ≥ ~0.3 on the tables' domain; refined after the first pass
        whole, whole_error, evaluations, ok = _average_panel(0.0, 1.0, ax, ay, dist, sep, rtol, scale, x, wk, wg)
        floor = MU_FLOOR * MU_FLOOR
        if whole_error + floor <= rtol * abs(whole) and abs(whole) >= scale / 2:
            # E(μ) is analytic on (0, 1] for these white lobes (no kink for the parent discrepancy to guard
            # against): one K15 panel whose G7 difference meets the tolerance is accepted.
            return whole, whole_error + floor, evaluations, ok
        scale = max(min(abs(whole), 1.0), 1e-3)
        parent = whole
    for k in range(2):
        left[k], width[k] = 0.5 * k, 0.5
        val[k], err[k], ev, c = _average_panel(left[k], 0.5, ax, ay, dist, sep, rtol, scale, x, wk, wg)
        evaluations += ev
        ok = ok and c
    n = 2
    if not halves:
        discrepancy = 0.5 * abs(parent - val[0] - val[1])
        err[0], err[1] = max(err[0], discrepancy), max(err[1], discrepancy)
    largest = 1.0
    while True:
        total = error = 0.0
        worst, worst_err = 0, -1.0
        for i in range(n):
            total += val[i]
            error += err[i]
            if err[i] > worst_err:
                worst, worst_err = i, err[i]
        floor = MU_FLOOR * MU_FLOOR * largest
        if error + floor <= rtol * abs(total):
            return total, error + floor, evaluations, ok
        scale = max(min(abs(total), 1.0), 1e-3)
        if n + 1 >= MAX_AVG_PANELS or width[worst] < 1e-12:
            return total, error + floor, evaluations, False
        i = worst
        parent, w = val[i], 0.5 * width[i]
        left[n], width[n], width[i] = left[i] + w, w, w
        for k in (i, n):
            val[k], err[k], ev, c = _average_panel(left[k], w, ax, ay, dist, sep, rtol, scale, x, wk, wg)
            evaluations += ev
            ok = ok and c
        discrepancy = 0.5 * abs(parent - val[i] - val[n])
        err[i], err[n] = max(err[i], discrepancy), max(err[n], discrepancy)
        n += 1


@numba.njit(cache=True)
def _averages(ax, ay, dist, sep, rtol, x, wk, wg):
    n = ax.size
    value, error = np.empty(n), np.empty(n)
    evaluations, converged = np.empty(n, dtype=np.int64), np.empty(n, dtype=np.bool_)
    for i in range(n):
        value[i], error[i], evaluations[i], converged[i] = hemispherical_average(ax[i], ay[i], dist, sep, rtol,
                                                                                 x, wk, wg)
    return value, error, evaluations, converged


def kernel_codes(distribution: str, shadowing: str) -> tuple[int, int]:
    if distribution not in DISTRIBUTIONS:
        raise ArgumentError(f"unknown distribution {distribution!r} (known: {', '.join(DISTRIBUTIONS)})",
                            where="distribution")
    if shadowing not in SHADOWING:
        raise ArgumentError(f"unknown shadowing {shadowing!r} (known: {', '.join(SHADOWING)})", where="shadowing")
    return DISTRIBUTIONS.index(distribution), SHADOWING.index(shadowing)


def _checked(mu, alpha_x, alpha_y, phi_v=None):
    arrays = np.broadcast_arrays(mu, alpha_x, alpha_y, 0.0 if phi_v is None else phi_v)
    mu, ax, ay, phi = (np.array(a, dtype=float).ravel() for a in arrays)  # writable copies
    if np.any(~(mu > 0)) or np.any(mu > 1):
        raise ArgumentError("mu must lie in (0, 1]", where="mu")
    for name, a in (("alpha_x", ax), ("alpha_y", ay)):
        if np.any(~(a >= 1e-12)) or np.any(a > 100):
            raise ArgumentError("must lie in [1e-12, 100]", where=name)
    if np.any(~np.isfinite(phi)):
        raise ArgumentError("must be finite", where="phi_v")
    return mu, ax, ay, phi


def albedo(distribution: str, shadowing: str, mu, alpha_x, alpha_y, phi_v=None, *, rtol: float = 1e-8,
           weight: str = "white"):
    """White single-scattering albedo of anisotropic GGX/Beckmann (arrays broadcast together, flattened):
    at the view (μ, φ_v) — φ_v measured from the X axis (α_x's) — or, with ``phi_v=None``, averaged over φ_v.
    ``weight`` ``f0`` or ``f90``: the split-sum (DFG) terms instead, the lobe times 1 − (1 − V·H)⁵ or
    (1 − V·H)⁵ (the coefficients of f0 and f90 in Schlick's Fresnel; Karis 2013).
    Returns (value, error, evaluations, converged), each (K,)."""
    d, s = kernel_codes(distribution, shadowing)
    if weight not in WEIGHTS:
        raise ArgumentError(f"unknown weight {weight!r} (known: {', '.join(WEIGHTS)})", where="weight")
    mu, ax, ay, phi = _checked(mu, alpha_x, alpha_y, phi_v)
    return _cells(mu, phi, ax, ay, d, s, float(rtol), phi_v is None, WEIGHTS.index(weight), _X, _WK, _WG)


def average_albedo(distribution: str, shadowing: str, alpha_x, alpha_y, *, rtol: float = 1e-8):
    """E_avg = 2∫₀¹ Ē(μ) μ dμ = (1/π)∫ E cos θ dω of anisotropic GGX/Beckmann, (value, error, evaluations,
    converged), each (K,) over the broadcast (α_x, α_y)."""
    d, s = kernel_codes(distribution, shadowing)
    _, ax, ay, _ = _checked(1.0, alpha_x, alpha_y)
    return _averages(ax, ay, d, s, float(rtol), _X, _WK, _WG)
