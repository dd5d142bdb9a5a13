"""Albedo of rough dielectrics (:mod:`brdfnorm.models.dielectric`): reflection plus refraction, over the
microfacet normal with the slope distribution as the measure, exact from rough interfaces down to mirrors.

Reflection is the microfacet BRDF with the exact dielectric Fresnel: from outside (η > 1) its half-vector albedo
(:mod:`brdfnorm.engine.routes.halfvector`), from inside its F = 1 albedo by
:func:`brdfnorm.engine.routes.azimuthal.white_albedo` less the loss
∫ G2 (1 − F) over the facets below the critical angle (:data:`PARTS`), so that the Fresnel kink at total internal
reflection is an edge of the domain rather than inside it (:func:`reflection_albedo`). Refraction follows the same
route (Walter et al. 2007, §5.3: sampling the facet normal m with density D(m)(N·m), the refracted direction's
weight is |V·m| G2 (1 − F)/(|N·V| |N·m|), the same form as the reflected one with F → 1 − F), so in the energy form

    E_T(V) = (1/2π) ∫₀^{2π} ∫ G2(L, V) (1 − F(V·m)) (1 + c·x) du dφ,    L = refract(V, m, η),        (T1)

in the slope coordinates of :mod:`brdfnorm.engine.routes.halfvector` (m ∝ (x, y, 1), x = s d(φ), c = V_xy/V_z, u(s) the
distribution's radial CDF), with G2 the refraction shadowing (Heitz's B(1 + Λ_V, 1 + Λ_L) when
height-correlated).

Where refraction exists along a ray. With β the facet's polar angle (tan β = s|d|), V·m = A cos(β − β₀)
(A = √(V_z² + (V·d̂)²)): refraction needs V·m > c* (c* = √(1 − η²) for η < 1, the critical cosine, else 0),
an interval of β in closed form; within it the refracted L must also point below the surface (L_z < 0), whose
ends are in closed form too. The ray's piece [s_a, s_b] is then integrated in three parts as the reflection is
(pole coordinate, tail coordinate, and a last part next to s_b where G2's boundary layer at L_z → 0 lives), with
quadratic grading at both ends: 1 − F vanishes like a square root at the critical angle, and the grading makes that
analytic. Where refraction reaches the horizontal facet (s_b = ∞), the heavy GGX tail is cut at s = 1e16 and the
dropped share bounded in the error. The azimuths where a part's bounds have a kink (:func:`_switches`) are panel
edges, and the panels are graded towards the azimuths where the window opens.
"""

from __future__ import annotations

import numpy as np

from ...models.dielectric import MicrofacetDielectric, refraction_kind, refraction_shadowing
from ...models.microfacet import Distribution, fresnel_dielectric, shadowing_masking
from ...validate import DEFAULT_MAX_EVALUATIONS, DEFAULT_RTOL
from ..machinery.grazing_panels import ladder
from ..machinery.panels import Panels, adaptive_rectangles
from ..machinery.result import RouteResult
from ..machinery.slope_coordinates import slope_coordinates
from .azimuthal import white_albedo
from .halfvector import MU_MIN, fill_pieces, single_scattering_albedo

#: Slope radius at which a ray that refracts up to the horizontal facet is cut (its dropped share is bounded).
_S_CAP = 1e16
#: The last part of a ray spans the band where Λ(L) turns on: |L_z| ≲ LAYER·α.
_LAYER = 4.0
#: Views with V_z/|V_xy| below this get azimuth panels graded towards φ_V + π/2 (:func:`_azimuth_edges`).
_GRAZING = 0.05
#: Panels per integrand call: more than the reflection's, as the ray search per azimuth node is a loop of small
#: array operations whose per-call overhead wants amortizing.
_PANELS_PER_CHUNK = 512
#: The kink search (:func:`_kinks`): uniform samples over the half range, offsets π·4^−k of the graded samples on
#: either side of each edge, and bisection steps (enough to reach float64's resolution from π/256).
_KINK_SAMPLES = 257
_KINK_RUNGS = np.concatenate([-(4.0 ** -np.arange(2, 27)), 4.0 ** -np.arange(2, 27)])
_KINK_BISECTIONS = 56


#: The window integrals: over the facets with V·m above the critical cosine c* (c* = 0 for η > 1), where
#: 1 − F is analytic, "refraction" is ∫ G2_t (1 − F)(1 + c·x) and "reflection-loss" ∫ G2_r (1 − F)(1 + c·x) with
#: the reflected direction's G2. The reflection is the lobe's F = 1 albedo (the half-vector integral of
#: :mod:`brdfnorm.engine.routes.halfvector`) less that loss: R = ∫ G2_r F = ∫ G2_r − ∫_window G2_r (1 − F), since F = 1
#: outside
#: the window (total internal reflection). Both integrands vanish continuously at the window's edge.
PARTS = ("refraction", "reflection-loss")


def _critical_window(V, eta, angle):
    """Per ray: w = V·d̂, β₀ and the unclipped window [β₀ − h, β₀ + h] of the facet angles with V·m > c* (V·m =
    A cos(β − β₀), A = √(V_z² + w²); h = 0 where even the best facet is past c*)."""
    vx, vy, vz = V
    w = vx * np.cos(angle) + vy * np.sin(angle)
    beta0 = np.arctan2(w, vz)
    critical = np.sqrt(np.maximum(1.0 - eta * eta, 0.0))
    half = np.arccos(np.clip(critical / np.hypot(vz, w), -1.0, 1.0))
    return w, beta0, beta0 - half, beta0 + half


def _clipped_window(beta0, start, end, part):
    """The β-window [lo, hi] ⊂ [0, π/2] of :func:`_critical_window`'s [start, end] (and for reflection the
    reflected L above the surface), and a mask of empty windows."""
    lo, hi = start, end
    if part != "refraction":
        # The reflected L_z = 2(V·m) cos β − V_z = A cos(2β − β₀) (as A cos β₀ = V_z) is positive exactly for
        # |2β − β₀| < π/2: the horizon, in closed form.
        lo, hi = np.maximum(lo, (beta0 - np.pi / 2) / 2), np.minimum(hi, (beta0 + np.pi / 2) / 2)
    lo, hi = np.clip(lo, 0.0, np.pi / 2), np.clip(hi, 0.0, np.pi / 2)
    return lo, hi, hi <= lo


def _scattered_z(part, w, vz, eta, beta):
    """L_z of V scattered by the facet (sin β cos a, sin β sin a, cos β): refracted or reflected; w = V·d̂ =
    V_x cos a + V_y sin a, fixed along the ray."""
    sb, cb = np.sin(beta), np.cos(beta)
    cos_i = w * sb + vz * cb
    if part != "refraction":
        return 2.0 * cos_i * cb - vz
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    return -vz / eta + cb * (cos_i / eta - cos_t)


def _ray(V, alpha, eta, angle, part):
    """Per ray (broadcast arrays): the direction d and the β-interval [b_lo, b_hi] of the part's window where
    the scattered L lies on its side of the surface (in closed form)."""
    dx, dy = alpha * np.cos(angle), alpha * np.sin(angle)
    vz = V[2]
    w, beta0, start, end = _critical_window(V, eta, angle)
    lo, hi, empty = _clipped_window(beta0, start, end, part)
    # The window is exact already for reflection, and for refraction into a denser medium: there
    # L_z = −V_z/η + m_z(V·m/η − cos θ_t) < 0 always, as cos θ_t > V·m/η when η > 1.
    if part != "refraction" or np.all(eta > 1.0):
        return dx, dy, np.where(empty, 0.0, lo), np.where(empty, 0.0, hi), empty

    # L_z = 0 where the refracted ray grazes the surface: with c = V·m = w sin β + V_z cos β, cos θ_t = (c − V_z/cos
    # β)/η, and squaring gives P cos 2β + Q sin 2β = S (P = (η² − 1 + 2V_z²)/2, Q = V_z w, S = V_z² − P), two roots
    # in closed form (one may be spurious, from the squaring: it only adds a cut). L_z keeps its sign between the
    # cuts, so its sign at each sub-interval's middle says where the refracted ray is below the surface.
    p, q = 0.5 * (eta * eta - 1.0 + 2.0 * vz * vz), vz * w
    radius = np.hypot(p, q)
    centre, spread = np.arctan2(q, p), np.arccos(np.clip((vz * vz - p) / radius, -1.0, 1.0))
    roots = np.stack(np.broadcast_arrays(*(np.mod(centre + sign * spread, 2.0 * np.pi) / 2.0 for sign in (-1, 1))))
    roots = _polished(roots, w, vz, eta)
    cuts = np.sort(np.concatenate([np.stack(np.broadcast_arrays(lo, hi)), np.clip(roots, lo, hi)]), axis=0)
    left, right = cuts[:-1], cuts[1:]
    below = (_scattered_z(part, w, vz, eta, 0.5 * (left + right)) < 0) & (right > left) & ~empty
    none = ~np.any(below, axis=0)
    first = np.argmax(below, axis=0)
    last = below.shape[0] - 1 - np.argmax(below[::-1], axis=0)
    b_lo = np.take_along_axis(left, first[None], 0)[0]
    b_hi = np.take_along_axis(right, last[None], 0)[0]
    return dx, dy, np.where(none, 0.0, b_lo), np.where(none, 0.0, b_hi), none


def _polished(beta, w, vz, eta):
    """Two Newton steps on L_z(β) = −V_z/η + cos β (c/η − cos θ_t): the closed form's arccos loses digits where
    its argument nears ±1 (1e-11 rad at V_z ~ 1e-5, against a bisection's 1e-16). A step larger than the closed
    form's worst error (a double root, where L_z' vanishes) is not taken."""
    for _ in range(2):
        sb, cb = np.sin(beta), np.cos(beta)
        c, dc = w * sb + vz * cb, w * cb - vz * sb
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_t = np.sqrt(np.maximum(1.0 - (1.0 - c * c) / (eta * eta), 0.0))
            z = -vz / eta + cb * (c / eta - cos_t)
            slope = -sb * (c / eta - cos_t) + cb * (dc / eta - c * dc / (eta * eta * cos_t))
            step = z / slope
        beta = np.where(np.abs(step) < 1e-6, beta - step, beta)
    return beta


def _far_coordinate(s, alpha):
    """σ = −log(1 + 1/(α s)) = −log(1 + cot β), β the facet's polar angle: logarithmic in tan β while the facet is
    steep no more than ~45° (the lobe's scales), analytic in cot β beyond, where a refracted ray's end runs off to
    the horizontal facet (σ → 0) as a smooth function of the azimuth. In asinh s (the distribution's tail
    coordinate, logarithmic to the end) that end is log(1/|V·d̂|) next to φ_V + π/2, and the cubature bisected
    towards it: 2.7 times the evaluations of T for GGX at η = 1.5 (16 μ × 16 α, rtol 1e-9), 1.8 times at 1/1.5.
    s = 1/(α·expm1(−σ)), ds/dσ = α e^{−σ} s²."""
    with np.errstate(divide="ignore"):
        return -np.log1p(1.0 / (alpha * s))


def _ray_parts(V, alpha, eta, angle, part):
    """Per ray (broadcast arrays): the direction d, the slope radii s_lo ≤ s_middle ≤ s_split ≤ s_hi that bound
    its three parts (before the distribution's cap) and the mask of empty rays.

    The last part: the band next to s_hi where |L_z| < LAYER·α, its width Δ linearized through the slope of L_z (a
    difference over a thousandth of the ray: over less, L_z cancels to rounding noise next to the horizon and the
    split jitters from azimuth to azimuth). The split is a smooth function of Δ and of the ray's span that never
    passes the ray's middle, so that s_lo is never in the last part: where the layer covers the whole ray
    (α ≳ V_z), the first parts collapsed and left the square-root onset of 1 − F at s_lo ungraded in the last one,
    and the cubature converged to a value 5e-6 off with an estimate of 4e-10 (η = 1/1.1, α = 1, μ = 1/15); where
    the ray is cut at S_CAP (L_z has no root there: it tends to −V_z/η), the band covered the whole ray and its
    nodes, graded towards s = 1e16, missed all of T at V_z ≲ 2e-7. The pole part ends before s = 1 (atan s
    resolves s ≫ 1 only to ~1e-16·s², too coarse for a window that opens far out) and is empty where the window
    opens beyond it."""
    dx, dy, b_lo, b_hi, none = _ray(V, alpha, eta, angle, part)
    vx, vy, vz = V
    s_lo = np.tan(b_lo) / alpha  # |d| = α for an isotropic distribution
    s_hi = np.where(b_hi >= np.pi / 2, _S_CAP, np.minimum(np.tan(b_hi) / alpha, _S_CAP))
    span = s_hi - s_lo
    step = 1e-3 * span
    z_end = _scattered_z(part, vx * np.cos(angle) + vy * np.sin(angle), vz, eta, np.arctan((s_hi - step) * alpha))
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        layer = _LAYER * alpha * step / np.abs(z_end)
        s_split = np.where(layer < np.inf, s_hi - layer / (1.0 + 2.0 * layer / span), s_lo + 0.5 * span)
        s_split = np.where(span > 0, s_split, s_hi)
        s_middle = np.clip(s_split / (1.0 + s_split), s_lo, s_split)
    return dx, dy, s_lo, s_middle, s_split, s_hi, none


def _switches(distribution: Distribution, V, alpha, eta, angle, part) -> np.ndarray:
    """Smooth functions of the azimuth whose sign changes are the kinks of a ray's part bounds — a max, min, clip or
    cap changing branch — stacked on the last axis; NaN where the ray is empty. A kink of the bounds is a kink, in
    the azimuth, of the integrand at every fixed node of the parts' maps: inside a panel, between its nodes, no
    rule sees it (η = 1/1.5, α = 1, μ = 0.216: R was 4.7e-8 off with an estimate of 1.3e-10, from the kink where
    the pole part empties, 8e-4 inside a 0.19 rad wide panel), so :func:`_kinks` makes them panel edges."""
    vz = V[2]
    w, beta0, start, end = _critical_window(V, eta, angle)
    # The window's start reaching the pole (the clip at β = 0); its end reaching the horizontal facet (refraction)
    # or passing the reflected direction's horizon (the min in _clipped_window).
    functions = [start, end - np.pi / 2 if part == "refraction" else end - (beta0 + np.pi / 2) / 2]
    lo, hi, empty = _clipped_window(beta0, start, end, part)
    if part == "refraction" and not np.all(eta > 1.0):
        # A root of L_z entering the window at either end (where _ray's closed-form end takes over from the window's).
        functions += [_scattered_z(part, w, vz, eta, lo), _scattered_z(part, w, vz, eta, hi)]
    _, _, s_lo, s_middle, s_split, s_hi, none = _ray_parts(V, alpha, eta, angle, part)
    functions.append(s_lo - s_split / (1.0 + s_split))  # the pole part emptying (the clip of s_middle)
    cap = slope_coordinates(distribution).CAP
    if cap is not None:
        functions += [q - cap for q in (s_lo, s_middle, s_split, s_hi)]
    values = np.stack(np.broadcast_arrays(*functions), axis=-1)
    return np.where((empty | none)[..., None], np.nan, values)


def _part_integrand(distribution: Distribution, shadowing: str, V: np.ndarray, alpha: np.ndarray,
                    eta: np.ndarray, part: str, edges: np.ndarray, graded: np.ndarray):
    """The integrand on the rectangle (x, v): x ∈ [i, i + 1] spans the case's azimuth panel [edges[i], edges[i+1]],
    graded quadratically towards the ``graded`` edges (φ = e_i + (e_{i+1} − e_i) g(x − i), g = f², 1 − (1 − f)² or
    (1 − cos πf)/2 by the ends): where the window opens (like √(φ − φ_c), which the grading makes analytic) and at
    the kinks of the part bounds (where, on one side, a ray's end nears a feature just beyond it). In φ itself the
    cubature bisected towards both: 16 μ × 16 α inside cells took 25.2 M evaluations with the openings graded, 31.0
    M with neither, 21.4 M with both."""
    lam = distribution.smith_lambda
    coords = slope_coordinates(distribution)
    lambda_v = lam(alpha**2 * (V[:, 0] ** 2 + V[:, 1] ** 2) / V[:, 2] ** 2)
    refraction = part == "refraction"
    # The far coordinate for the tail part where rays reach the horizontal facet: refraction with a heavy tail (a
    # capped distribution's rays end at its cap, and reflected rays never reach it); elsewhere the distribution's
    # own tail coordinate, which measured a little cheaper there (GGX reflection loss 1.1×, Beckmann 1.05×).
    far = refraction and coords.CAP is None

    def integrand(case, x, v, piece):
        k = case[:, None, None]
        a, e = alpha[k], eta[k]
        panel = np.floor(x).astype(int)
        start, stop = edges[k, panel], edges[k, panel + 1]
        f = x - panel
        left, right = graded[k, panel], graded[k, panel + 1]
        ends = [left & right, left, right]
        grade = np.select(ends, [0.5 - 0.5 * np.cos(np.pi * f), f * f, f * (2.0 - f)], f)
        slope = np.select(ends, [0.5 * np.pi * np.sin(np.pi * f), 2.0 * f, 2.0 - 2.0 * f], 1.0)
        phi, jacobian = start + (stop - start) * grade, (stop - start) * slope
        vx, vy, vz = V[k, 0], V[k, 1], V[k, 2]
        # Ray quantities per (panel, azimuth node), then broadcast over the radial nodes. Panels that differ only
        # in their radial range (the pieces, and halvings along v) share their rays: each is searched once.
        key = np.stack([case.astype(float), phi[:, 0, 0], phi[:, -1, 0]], axis=1)
        _, unique, inverse = np.unique(key, axis=0, return_index=True, return_inverse=True)
        ray = _ray_parts((vx[unique, :, 0], vy[unique, :, 0], vz[unique, :, 0]), a[unique, :, 0], e[unique, :, 0],
                         phi[unique, :, 0], part)
        dx, dy, s_lo, s_middle, s_split, s_hi, none = (q[inverse.ravel()][..., None] for q in ray)
        # Beckmann's truncation (its dropped mass is bounded below); GGX has none.
        s_lo, s_middle, s_split, s_hi = (coords.cap(q) for q in (s_lo, s_middle, s_split, s_hi))
        local = v - piece[:, None, None]
        # Grading: quadratic towards s_lo in the first part (1 − F ~ √ at the critical angle), towards the start
        # of the second (which is s_lo where the first is empty) and towards s_hi in the last part (the boundary
        # layer and the square root alike). Each part on its own panels only.
        def piece_nodes(kind, rows, at):
            if kind == 0:
                t_lo, t_mid = coords.pole_coordinate(s_lo[rows]), coords.pole_coordinate(s_middle[rows])
                radius, density = coords.pole(t_lo + at * at * (t_mid - t_lo))
                return radius, density, (t_mid - t_lo) * (2.0 * at)
            if kind == 1 and far:
                t_start, t_stop = _far_coordinate(s_middle[rows], a[rows]), _far_coordinate(s_split[rows], a[rows])
                with np.errstate(invalid="ignore", divide="ignore"):  # empty rays (s = 0): masked below
                    t = t_start + at * at * (t_stop - t_start)
                    radius = 1.0 / (a[rows] * np.expm1(-t))
                    density = distribution.slope_density(radius) * (a[rows] * np.exp(-t)) * radius ** 2
                    return radius, density, (t_stop - t_start) * (2.0 * at)
            if kind == 1:
                t_start = coords.tail_coordinate(s_middle[rows])
                t_stop = coords.tail_coordinate(s_split[rows])
                radius, density = coords.tail(t_start + at * at * (t_stop - t_start))
                return radius, density, (t_stop - t_start) * (2.0 * at)
            near = s_split[rows] + (1.0 - (1.0 - at) ** 2) * (s_hi[rows] - s_split[rows])
            return near, distribution.slope_density(near), (s_hi[rows] - s_split[rows]) * (2.0 * (1.0 - at))

        s, density, length = fill_pieces(piece, local, s_lo.shape, piece_nodes)
        x, y = s * dx, s * dy
        n = np.sqrt(1.0 + x * x + y * y)
        one_sp = 1.0 + (vx * x + vy * y) / vz
        cos_i = vz * one_sp / n
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            if refraction:
                sin2_t = (1.0 - cos_i * cos_i) / (e * e)
                cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
                scale = (cos_i / e - cos_t) / n
                Lx, Ly, Lz = -vx / e + scale * x, -vy / e + scale * y, -vz / e + scale
            else:
                scale = 2.0 * cos_i / n
                Lx, Ly, Lz = scale * x - vx, scale * y - vy, scale - vz
            lambda_l = lam(a * a * (Lx * Lx + Ly * Ly) / (Lz * Lz))
            G2 = (refraction_shadowing if refraction else shadowing_masking)(shadowing, lambda_l, lambda_v[k])
            factor = G2 * (1.0 - fresnel_dielectric(np.clip(cos_i, 0.0, 1.0), e))
            # 1/2π, twice: half the azimuths are integrated
            weight = factor * one_sp * density * length * jacobian / np.pi
        side = (Lz < 0) if refraction else (Lz > 0)
        valid = side & (cos_i > 0) & ~none & np.isfinite(weight)
        return np.where(valid, weight, 0.0)[..., None]

    return integrand


def _azimuth_edges(V: np.ndarray, eta: float) -> tuple[np.ndarray, np.ndarray]:
    """Initial azimuth panel edges over [φ_V, φ_V + π], and those of them where the window opens: the lobe is
    isotropic, so the integrand is even about the plane of N and V and half the azimuths, counted twice, are the
    whole integral. Four even panels, and (η < 1) the rays on which the window V·m > c* opens (A(φ) = c*), where
    every part's ray integral has a square-root onset — on a panel edge, never inside one, where the cubature's
    nodes could step over it."""
    phi_v = np.arctan2(V[1], V[0])
    edges = [phi_v + np.linspace(0.0, np.pi, 5)]
    # At grazing views the facet angle β₀ = atan2(V·d̂, V_z) of the best-lit facets swings from +π/2 to −π/2 within
    # δ = V_z/|V_xy| of the azimuth φ_V + π/2 (where V·d̂ = 0), and every window end with it: panels graded
    # geometrically towards that azimuth, from δ/4 out, so that no panel's nodes straddle the swing.
    vxy = np.hypot(V[0], V[1])
    if V[2] < _GRAZING * vxy:
        rungs, kept = ladder(np.array([V[2] / vxy / 4.0]), np.pi / 4, 4.0)
        offsets = rungs[kept]
        edges.append(phi_v + np.pi / 2 + np.concatenate([-offsets, offsets]))
    openings = np.empty(0)
    critical2 = max(1.0 - eta * eta, 0.0)
    if critical2 > V[2] ** 2 and vxy > 0:
        ratio = np.sqrt(critical2 - V[2] ** 2) / vxy
        if ratio <= 1.0:
            openings = phi_v + np.array([np.arccos(ratio), np.arccos(-ratio)])
    return _distinct(np.concatenate([*edges, openings])), openings


def _distinct(edges: np.ndarray) -> np.ndarray:
    """Sorted edges, those within 1e-12 of the previous one dropped."""
    edges = np.unique(edges)
    return edges[np.concatenate([[True], np.diff(edges) > 1e-12])]


def _kinks(distribution: Distribution, fixed: np.ndarray, alpha, eta, part: str, edges: list[np.ndarray]
           ) -> list[np.ndarray]:
    """Per case, the azimuths inside its range where :func:`_switches` change sign: located on a grid (uniform,
    and graded geometrically towards the case's edges, where the window closes and the switches move fastest),
    then bisected to float64's resolution, all cases at once."""
    grids = [np.unique(np.concatenate([np.linspace(e[0], e[-1], _KINK_SAMPLES),
                                       np.clip((e[:, None] + np.pi * _KINK_RUNGS).ravel(), e[0], e[-1])]))
             for e in edges]
    width = max(g.size for g in grids)
    grid = np.stack([np.pad(g, (0, width - g.size), mode="edge") for g in grids])  # repeats: empty intervals
    V = tuple(fixed[:, i, None] for i in range(3))

    def switches(rows, angle):
        return _switches(distribution, tuple(q[rows] for q in V), alpha[rows, None], eta[rows, None], angle, part)

    values = switches(np.arange(len(edges)), grid)
    sign = np.sign(values)
    case, left, which = np.nonzero(sign[:, :-1] * sign[:, 1:] < 0)  # NaN (an empty ray) compares False
    lo, hi = grid[case, left], grid[case, left + 1]
    first = sign[case, left, which]
    for _ in range(_KINK_BISECTIONS):
        mid = 0.5 * (lo + hi)
        same = np.sign(switches(case, mid[:, None])[:, 0, :][np.arange(case.size), which]) == first
        lo, hi = np.where(same, mid, lo), np.where(same, hi, mid)
    return [0.5 * (lo + hi)[case == k] for k in range(len(edges))]


def part_albedo(distribution: Distribution, fixed: np.ndarray, alpha, eta, shadowing: str, part: str, *,
                rtol: float = DEFAULT_RTOL, atol: float = 0.0,
                max_evaluations: int = DEFAULT_MAX_EVALUATIONS) -> RouteResult:
    """One part (:data:`PARTS`) of E(V) for fixed directions (K, 3) (upper hemisphere) and per-case α, η."""
    fixed = np.atleast_2d(np.asarray(fixed, dtype=float))
    K = fixed.shape[0]
    alpha = np.broadcast_to(np.asarray(alpha, dtype=float), (K,)).copy()
    eta = np.broadcast_to(np.asarray(eta, dtype=float), (K,)).copy()
    base, openings = zip(*(_azimuth_edges(fixed[k], eta[k]) for k in range(K)), strict=True)
    kinks = _kinks(distribution, fixed, alpha, eta, part, list(base))
    edges = [_distinct(np.concatenate([base[k], kinks[k]])) for k in range(K)]
    counts = np.array([e.size - 1 for e in edges])
    table = np.stack([np.pad(e, (0, counts.max() + 1 - e.size), mode="edge") for e in edges])
    graded = np.stack([np.isin(row, np.concatenate([o, k])) for row, o, k in zip(table, openings, kinks, strict=True)])
    cases = np.repeat(np.arange(K), counts)
    a0 = np.concatenate([np.arange(n, dtype=float) for n in counts])
    cases, a0 = np.repeat(cases, 3), np.repeat(a0, 3)
    b0 = np.tile([0.0, 1.0, 2.0], a0.size // 3)
    initial = Panels(cases, a0, a0 + 1.0, b0, b0 + 1.0)
    integrand = _part_integrand(distribution, shadowing, fixed, alpha, eta, part, table, graded)
    result = adaptive_rectangles(integrand, initial, K, rtol=rtol, atol=atol, max_evaluations=max_evaluations,
                                 chunk=_PANELS_PER_CHUNK)
    # Dropped: rays cut at s = 1e16 (GGX's tail beyond carries ≤ 1/S² + 2|p|/S of weight, p = |c|α), and
    # Beckmann's cap, where the weight (1 − F) G2 (1 + c·x) ≤ 1 + |c| α s over the dropped slope radii.
    p = alpha * np.hypot(fixed[:, 0], fixed[:, 1]) / fixed[:, 2]
    mass, moment = slope_coordinates(distribution).truncated_moments()
    dropped = 1.0 / _S_CAP**2 + 2.0 * p / _S_CAP + mass + moment * p
    return RouteResult(result.value, result.error + dropped[:, None], result.evaluations, result.converged)


def reflection_albedo(distribution: Distribution, fixed: np.ndarray, alpha: np.ndarray, eta: np.ndarray,
                      shadowing: str, *, rtol: float, atol: float | np.ndarray = 0.0,
                      max_evaluations: int = DEFAULT_MAX_EVALUATIONS) -> RouteResult:
    """R(V) per case (``atol`` scalar or (K,)). From the rarer side (η > 1) F is analytic over every facet, so R is
    the microfacet BRDF's albedo with the exact dielectric Fresnel, by the half-vector route of
    :mod:`brdfnorm.engine.routes.halfvector` (GGX, 16 μ × 16 α at η = 1.5, rtol 1e-9: 1.56 M evaluations against 4.67 M
    for the
    route below). Seen from inside (η < 1), and at views closer to the horizon than that route admits, R is the
    F = 1 albedo less the reflection loss, where total internal reflection's kink is the window's edge."""
    K = fixed.shape[0]
    atol = np.broadcast_to(np.asarray(atol, dtype=float).ravel(), (K,))
    direct = (eta > 1.0) & (fixed[:, 2] >= MU_MIN)
    value, error = np.zeros((K, 1)), np.zeros((K, 1))
    evaluations, converged = np.zeros(K, dtype=np.int64), np.ones(K, dtype=bool)
    if np.any(direct):
        params = {"alpha": alpha[direct], "alpha_x": 0.0, "alpha_y": 0.0, "shadowing": shadowing,
                  "fresnel": "dielectric", "eta": eta[direct, None], "k": 0.0, "f0": 0.0, "f90": 1.0}
        r = single_scattering_albedo(distribution, fixed[direct], params, rtol=rtol, atol=atol[direct, None],
                                     max_evaluations=max_evaluations)
        value[direct], error[direct] = r.value, r.error
        evaluations[direct], converged[direct] = r.evaluations, r.converged
    if not np.all(direct):
        rest = ~direct
        loss = part_albedo(distribution, fixed[rest], alpha[rest], eta[rest], shadowing, "reflection-loss", rtol=rtol,
                           atol=atol[rest, None] / 2, max_evaluations=max_evaluations // 2)
        white = white_albedo(distribution, shadowing, fixed[rest], alpha[rest], rtol=rtol, atol=atol[rest] / 2,
                             max_evaluations=max_evaluations // 2)
        value[rest], error[rest] = white.value - loss.value, white.error + loss.error
        evaluations[rest] = white.evaluations + loss.evaluations
        converged[rest] = white.converged & loss.converged
    return RouteResult(value, error, evaluations, converged)


def albedo_method(problem, *, rtol: float, atol: float = 0.0, max_evaluations: int = DEFAULT_MAX_EVALUATIONS,
                  **_: object):
    """``brdfnorm.albedo`` method ``"dielectric"``: R (:func:`reflection_albedo`) and T, each integral to ``rtol``
    of itself, and then to rtol·E/2 absolute where their estimates add up to more than rtol·E: from inside R is the
    F = 1 albedo less the loss, both larger than R (13 of the 4096 cells of a 16³ glass table were over, up to
    ~3×; redoing them costs little)."""
    model: MicrofacetDielectric = problem.model
    K = problem.fixed.shape[0]
    params = problem.case_params(np.arange(K))
    alpha = np.broadcast_to(np.asarray(params["alpha"], dtype=float), (K,))
    eta = np.broadcast_to(np.asarray(params["eta"], dtype=float), (K,))
    budget = max_evaluations // 2
    # the refraction part takes the refraction's G2 kind (its integrand uses ``shadowing`` for nothing else)
    refraction = refraction_kind(str(params["shadowing"]), str(params.get("refraction_shadowing", "auto")))

    def parts(rows: np.ndarray, relative: float, absolute: np.ndarray) -> tuple[RouteResult, RouteResult]:
        fixed, a, e = problem.fixed[rows], alpha[rows], eta[rows]
        return (reflection_albedo(model.distribution, fixed, a, e, params["shadowing"], rtol=relative,
                                  atol=absolute, max_evaluations=budget),
                part_albedo(model.distribution, fixed, a, e, refraction, "refraction", rtol=relative,
                            atol=absolute[:, None], max_evaluations=budget))

    reflected, transmitted = parts(np.arange(K), rtol, np.full(K, atol / 2))
    r, t = reflected.value.copy(), transmitted.value.copy()
    error = reflected.error + transmitted.error
    evaluations = reflected.evaluations + transmitted.evaluations
    converged = reflected.converged & transmitted.converged
    goal = np.maximum(atol, rtol * np.abs(r + t)[:, 0])
    over = np.flatnonzero((error[:, 0] > goal) & (goal > 0) & converged)
    if over.size:
        # Half of the goal each, less a margin for E's own change between the passes (below its estimate).
        again_r, again_t = parts(over, 0.0, 0.5 * goal[over] * (1.0 - 1e-3))
        r[over], t[over], error[over] = again_r.value, again_t.value, again_r.error + again_t.error
        evaluations[over] += again_r.evaluations + again_t.evaluations
        converged[over] = again_r.converged & again_t.converged
    return RouteResult(r + t, error, evaluations, converged, extras={"reflected": r, "transmitted": t})
