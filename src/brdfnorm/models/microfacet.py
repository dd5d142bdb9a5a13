"""The microfacet BRDF shared by the ``ggx`` and ``beckmann`` lobes: distributions, Smith shadowing, Fresnel.

Walter et al. 2007 ("Microfacet models for refraction through rough surfaces", eq. 20):

    f(L, V) = D(H) G2(L, V) F(V·H) / (4 (N·L)(N·V)),   H = normalize(L + V).

Distributions are written in slope space (Heitz 2014, "Understanding the masking-shadowing function in
microfacet-based BRDFs", §5.2): a microfacet normal m has slopes x = −m_x/m_z, y = −m_y/m_z, and
D(m) = P22(x/α_x, y/α_y) / (α_x α_y cos⁴θ_m) with a standardized slope density P22 (α = 1):

    GGX (Trowbridge-Reitz):  P22(r²) = 1 / (π (1 + r²)²)        Λ(ω) = (−1 + √(1 + a²)) / 2
    Beckmann:                P22(r²) = exp(−r²) / π              Λ(ω) = (erf(b) − 1)/2 + exp(−b²)/(2b√π)

with a² = (α_x² ω_x² + α_y² ω_y²)/ω_z² = 1/b² (Heitz 2014 eqs. 72, 86 — the exact Λ, not the rational fit
of Walter et al.). Smith shadowing is ``height-correlated`` G2 = 1/(1 + Λ(L) + Λ(V)) (Heitz eq. 99) or
``separable`` G2 = G1(L) G1(V), G1 = 1/(1 + Λ). Fresnel: ``none`` (F = 1), ``schlick`` f0 + (f90 − f0)(1 − c)⁵,
``dielectric`` (exact unpolarized, Walter et al. eq. 22, η = interior/exterior) and ``conductor`` (exact
unpolarized for a complex index η + ik, e.g. Lazányi & Szirmay-Kalos 2005 / pbrt-v4 FrComplex).

Channels: ``fresnel=none`` is one channel; every other Fresnel takes colours (f0, f90, eta, k; one number means
grey) and makes the lobe three-channel.

Multiple scattering (``ms=kulla-conty``, Kulla & Conty 2017, "Revisiting physically based shading at
Imageworks"): f_ms(L, V) = F_ms (1 − E(μ_L))(1 − E(μ_V)) / (π (1 − E_avg)) with E(μ, α) the white (F = 1) lobe's
own albedo, E_avg(α) = 2∫₀¹ E(μ) μ dμ, and — with a Fresnel — their colour term F_ms = F_avg² E_avg / (1 − F_avg (1 −
E_avg)) per channel (the energy of the light that keeps bouncing, each bounce scaled by F_avg; F_ms = 1 for F = 1),
F_avg = 2∫₀¹ F(μ) μ dμ exact: f0 + (f90 − f0)/21 for Schlick (Fdez-Agüera 2019), a Gauss–Legendre integral
(from the critical angle on) for the exact dielectric and conductor. ``ms=turquin`` (Turquin 2019, "Practical
multiple scattering compensation for microfacet models", eq. 16): f = f_ss (1 + F0 (1/E(μ_V) − 1)), F0 = F(μ = 1)
per channel — not reciprocal (it depends on the view only), so its albedo over the view goes to quadrature.
E and E_avg come from :mod:`brdfnorm.engine.routes.microfacet`. With ``ms_table=N`` the renderer's way —
E on an N × N node grid over (μ, α) ∈ [0, 1]², interpolated bilinearly, E_avg on N nodes in α, linearly (the
μ = 0 row is evaluated at μ = 1e-4); with ``ms_table=0`` exact values at every evaluation (slow: an albedo
integral per direction — meant for checks). Both need isotropic α ≤ 1 (the tables' range), or one anisotropic lobe
(α_x, α_y ≤ 10, aspect ≥ 0.01), whose compensation uses its own E(μ, φ) and E_avg
(:mod:`brdfnorm.engine.routes.anisotropic_compensation`) — not the isotropic table at √(α_x α_y). The table size is
at most :data:`MAX_MS_TABLE` (issue 41: N = 1024, inside the range once declared, allocated 880 MiB at once and
peaked at 3.6 GB; N = 256 takes about 0.4 GB and 8 s, N = 512 1.3 GB).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
from scipy.special import erfcx

from ..errors import ParameterError
from ..parameters import Parameter
from ..registry import Reference
from .base import Lobe, Model, mirror
from .fresnel import MICROFACET_KINDS, fresnel_conductor, fresnel_dielectric, fresnel_schlick

#: The largest Kulla–Conty table ``ms_table`` may ask for: what is computed within 1 GB and ~10 s.
MAX_MS_TABLE = 256

_SQRT_PI = np.sqrt(np.pi)
#: Smallest roughness: below it D overflows float64 in ``evaluate`` (the albedo method itself works at α = 0).
ALPHA_MIN = 1e-12


class Distribution:
    """A slope distribution: its standardized slope density P22, its Smith Λ and the radial density du/ds of the
    standardized slope radius s. The coordinates an integrator runs in over it are the engine's
    (:mod:`brdfnorm.engine.machinery.slope_coordinates`)."""

    name = ""

    def density(self, r2: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def smith_lambda(self, a2: np.ndarray) -> np.ndarray:
        """Λ as a function of a² = α_ω² tan²θ_ω."""
        raise NotImplementedError

    def slope_density(self, s: np.ndarray) -> np.ndarray:
        """du/ds of the radial CDF u(s) of the standardized slope radius."""
        raise NotImplementedError


class GGXDistribution(Distribution):
    """Trowbridge-Reitz: u(s) = s²/(1 + s²)."""

    name = "ggx"

    def density(self, r2):
        return 1.0 / (np.pi * (1.0 + r2) ** 2)

    def smith_lambda(self, a2):
        return 0.5 * a2 / (1.0 + np.sqrt(1.0 + a2))  # (−1 + √(1 + a²))/2 without cancellation

    def slope_density(self, s):
        return 2.0 * s / (1.0 + s * s) ** 2


class BeckmannDistribution(Distribution):
    """Beckmann: u(s) = 1 − exp(−s²), du/ds = 2s·exp(−s²)."""

    name = "beckmann"

    def density(self, r2):
        return np.exp(-r2) / np.pi

    def smith_lambda(self, a2):
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            b = 1.0 / np.sqrt(a2)
            # (erf(b) − 1)/2 + e^{−b²}/(2b√π) = e^{−b²}(1/(b√π) − erfcx(b))/2, stable for large b.
            value = 0.5 * np.exp(-b * b) * (1.0 / (b * _SQRT_PI) - erfcx(b))
        return np.where(a2 == 0.0, 0.0, np.where(np.isinf(a2), np.inf, value))

    def slope_density(self, s):
        return 2.0 * s * np.exp(-s * s)


# -- the model ---------------------------------------------------------------------------------------------

#: Kulla & Conty's tables are the lobe's own albedo, computed by the integrator layer: declared here by where they
#: live and imported on first use (models stay below the integrator in the import graph):
#: ``provider(distribution, shadowing, size)`` -> an object with ``energies(mu_l, mu_v, alpha)``.
COMPENSATION = Reference("brdfnorm.engine.routes.microfacet:compensation")
#: The anisotropic lobes' compensation, likewise:
#: ``provider(distribution_name, shadowing, size, alpha_x, alpha_y)`` -> an object with ``albedo(mu, phi)``,
#: ``average`` (E_avg) and ``missing`` ((1/π)∫(1 − E) cos dω of E as read).
ANISOTROPIC_COMPENSATION = Reference("brdfnorm.engine.routes.anisotropic_compensation:anisotropic_compensation")
#: Anisotropic compensation tables cover lobes up to this width and down to this aspect α_y/α_x.
ANISOTROPIC_ALPHA_MAX = 10.0
ANISOTROPIC_ASPECT_MIN = 0.01


SHADOWING = ("height-correlated", "separable")
MULTIPLE_SCATTERING = ("none", "kulla-conty", "turquin")


def microfacet_parameters(default_alpha: float) -> tuple[Parameter, ...]:
    return (
        Parameter("alpha", "float", default_alpha, ALPHA_MIN, 100.0, "roughness α (slope width), isotropic"),
        Parameter("alpha_x", "float", 0.0, 0.0, 100.0, "roughness along X (0: alpha)"),
        Parameter("alpha_y", "float", 0.0, 0.0, 100.0, "roughness along Y (0: alpha)"),
        Parameter("shadowing", "choice", "height-correlated", choices=SHADOWING,
                  description="Smith G2: 1/(1+Λ(L)+Λ(V)) or G1(L)G1(V)"),
        Parameter("fresnel", "choice", "none", choices=MICROFACET_KINDS, description="F(V·H); none is F = 1"),
        Parameter("f0", "spectrum", (0.04, 0.04, 0.04), 0.0, 1.0, "Schlick reflectance at normal incidence"),
        Parameter("f90", "spectrum", (1.0, 1.0, 1.0), 0.0, 1.0, "Schlick reflectance at grazing incidence"),
        Parameter("eta", "spectrum", (1.5, 1.5, 1.5), 1e-3, 1e3, "index of refraction (dielectric, conductor)"),
        Parameter("k", "spectrum", (0.0, 0.0, 0.0), 0.0, 1e3, "extinction coefficient (conductor)"),
        Parameter("ms", "choice", "none", choices=MULTIPLE_SCATTERING,
                  description="multiple-scattering compensation (Kulla & Conty 2017, Turquin 2019)"),
        Parameter("ms_table", "int", 32, 0.0, float(MAX_MS_TABLE), "kulla-conty table size N (0: exact, slow)"),
    )


def roughness(params: Mapping[str, object]) -> tuple[np.ndarray, np.ndarray]:
    """(α_x, α_y): ``alpha_x``/``alpha_y`` where given (non-zero), ``alpha`` otherwise."""
    alpha = np.asarray(params["alpha"], dtype=float)
    ax = np.asarray(params["alpha_x"], dtype=float)
    ay = np.asarray(params["alpha_y"], dtype=float)
    for name, value in (("alpha_x", ax), ("alpha_y", ay)):
        if np.any((value > 0) & (value < ALPHA_MIN)):
            raise ParameterError(f"must be 0 (use alpha) or ≥ {ALPHA_MIN:g}", where=f"parameter {name}")
    return np.where(ax > 0, ax, alpha), np.where(ay > 0, ay, alpha)


def smith_a2(omega: np.ndarray, ax: np.ndarray, ay: np.ndarray) -> np.ndarray:
    """a² = (α_x² ω_x² + α_y² ω_y²)/ω_z² for directions (..., 3)."""
    with np.errstate(divide="ignore"):
        return ((ax * omega[..., 0]) ** 2 + (ay * omega[..., 1]) ** 2) / omega[..., 2] ** 2


def shadowing_masking(kind: str, lambda_l: np.ndarray, lambda_v: np.ndarray) -> np.ndarray:
    if kind == "separable":
        return 1.0 / ((1.0 + lambda_l) * (1.0 + lambda_v))
    return 1.0 / (1.0 + lambda_l + lambda_v)


def fresnel(params: Mapping[str, object], cos: np.ndarray) -> np.ndarray:
    """F(V·H) with a trailing channel axis: (..., 1) for ``none``, (..., 3) otherwise."""
    kind = params["fresnel"]
    if kind == "none":
        return np.ones(np.shape(cos) + (1,))
    c = np.asarray(cos)[..., None]
    if kind == "schlick":
        return fresnel_schlick(c, np.asarray(params["f0"], dtype=float), np.asarray(params["f90"], dtype=float))
    eta = np.asarray(params["eta"], dtype=float)
    if kind == "dielectric":
        return fresnel_dielectric(c, eta)
    return fresnel_conductor(c, eta, np.asarray(params["k"], dtype=float))


#: Gauss–Legendre nodes for F_avg: 48 points on each of 8 panels per smooth piece (F is analytic in μ there).
_GL_X, _GL_W = np.polynomial.legendre.leggauss(48)
_PANELS = 8


def _gauss_legendre(function: Callable[[np.ndarray], np.ndarray], lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """∫_lo^hi function(μ) dμ elementwise over (...) bounds, composite Gauss–Legendre (8 × 48 points)."""
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    edges = lo[..., None] + (hi - lo)[..., None] * np.linspace(0.0, 1.0, _PANELS + 1)
    a, b = edges[..., :-1, None], edges[..., 1:, None]
    mu = (a + b) / 2 + (b - a) / 2 * _GL_X
    return np.sum(function(mu) * (b - a) / 2 * _GL_W, axis=(-2, -1))


def fresnel_average(params: Mapping[str, object]) -> np.ndarray:
    """F_avg = 2∫₀¹ F(μ) μ dμ per channel, (..., C): f0 + (f90 − f0)/21 for Schlick (2∫(1 − μ)⁵μ dμ = 1/21);
    for the exact Fresnels a Gauss–Legendre integral, for a dielectric from the critical angle μ_c = √(1 − η²) on
    (η < 1: F = 1 below it, an exact μ_c² there) in t with μ = μ_c + (1 − μ_c) t²."""
    kind = params["fresnel"]
    if kind == "none":
        return np.ones(1)
    if kind == "schlick":
        f0, f90 = np.asarray(params["f0"], dtype=float), np.asarray(params["f90"], dtype=float)
        return f0 + (f90 - f0) / 21.0
    eta = np.asarray(params["eta"], dtype=float)
    if kind == "conductor":
        k = np.asarray(params["k"], dtype=float)
        return _gauss_legendre(lambda mu: 2.0 * mu * fresnel_conductor(mu, eta[..., None, None], k[..., None, None]),
                               np.zeros(eta.shape), np.ones(eta.shape))
    critical = np.sqrt(np.clip(1.0 - eta * eta, 0.0, 1.0))
    span = (1.0 - critical)[..., None, None]

    def above(t: np.ndarray) -> np.ndarray:
        # μ = μ_c + (1 − μ_c) t²: F has a square-root edge at μ_c (√(μ² − μ_c²)), analytic in t.
        mu = critical[..., None, None] + span * t * t
        return 2.0 * mu * fresnel_dielectric(mu, eta[..., None, None]) * 2.0 * span * t

    return critical**2 + _gauss_legendre(above, np.zeros(eta.shape), np.ones(eta.shape))


def fresnel_normal(params: Mapping[str, object]) -> np.ndarray:
    """F0 = F(μ = 1) per channel, (C,) or (..., C): Turquin's scale of the missing energy."""
    return fresnel(params, np.ones(np.shape(params["alpha"])))


def fresnel_multiple_scattering(params: Mapping[str, object], e_avg: np.ndarray) -> np.ndarray:
    """Kulla & Conty's F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)), (..., C) against ``e_avg`` (...)."""
    f_avg = fresnel_average(params)
    e_avg = np.asarray(e_avg, dtype=float)[..., None]
    return f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg))


class MicrofacetModel(Model):
    """Walter et al.'s microfacet BRDF over a slope distribution (subclasses name the distribution)."""

    #: Engines and .brdf files speak of perceptual roughness: α = roughness² (Burley 2012; Karis 2013).
    aliases = {"roughness": ("alpha", np.square, "alpha = roughness²")}

    distribution: Distribution = GGXDistribution()
    energy = ("conserved: single scattering loses energy (E < 1 for α > 0); ms=kulla-conty or turquin restore "
              "it to 1 for F = 1")

    def _check(self) -> None:
        p = self._params
        roughness(p)
        if p["ms"] == "none":
            return
        table = float(np.asarray(p["ms_table"]).max())
        if np.ndim(p["ms_table"]) or (table != 0 and (table < 2 or table != int(table))):
            raise ParameterError("must be 0 (exact) or one whole number ≥ 2", where="parameter ms_table")
        if not self.isotropic:
            ax, ay = roughness(p)
            if np.ndim(ax) or np.ndim(ay):
                raise ParameterError(f"ms={p['ms']} with alpha_x/alpha_y takes one lobe (numbers, not arrays)",
                                     where="parameter ms")
            if max(ax, ay) > ANISOTROPIC_ALPHA_MAX or min(ax, ay) < ANISOTROPIC_ASPECT_MIN * max(ax, ay):
                raise ParameterError(f"ms={p['ms']} covers anisotropic lobes with alpha_x, alpha_y ≤ "
                                     f"{ANISOTROPIC_ALPHA_MAX:g} and aspect alpha_y/alpha_x in "
                                     f"[{ANISOTROPIC_ASPECT_MIN:g}, {1 / ANISOTROPIC_ASPECT_MIN:g}]",
                                     where="parameter ms")
        elif np.any(np.asarray(p["alpha"]) > 1.0):
            raise ParameterError(f"ms={p['ms']} tables cover isotropic alpha ≤ 1 only", where="parameter ms")

    def search_space(self) -> dict[str, tuple[float, float] | None]:
        """``check`` holds the table size, the Fresnel inputs the chosen Fresnel does not read, and — with a
        compensation, whose tables cover isotropic α ≤ 1 — the anisotropic widths, searching α over [ALPHA_MIN, 1]."""
        p = self._params
        space: dict[str, tuple[float, float] | None] = {"ms_table": None}
        if p["fresnel"] != "dielectric" and p["fresnel"] != "conductor":
            space["eta"] = None
        if p["fresnel"] != "conductor":
            space["k"] = None
        if p["ms"] != "none" and self.isotropic:
            space.update(alpha=(ALPHA_MIN, 1.0), alpha_x=None, alpha_y=None)
        elif p["ms"] != "none":  # one anisotropic lobe: its table is built for these widths
            space.update(alpha=None, alpha_x=None, alpha_y=None)
        return space

    @property
    def channels(self) -> int:  # type: ignore[override]
        return 1 if self._params["fresnel"] == "none" else 3

    @property
    def isotropic(self) -> bool:  # type: ignore[override]
        return not (np.any(np.asarray(self._params["alpha_x"]) > 0) or np.any(np.asarray(self._params["alpha_y"]) > 0))

    def single_scattering(self, L: np.ndarray, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """D G2 F / (4 N·V): f·(N·L) of the single-scattering lobe, (..., C); 0 below either horizon."""
        ax, ay = roughness(params)
        S = L + V
        with np.errstate(divide="ignore", invalid="ignore"):
            # Slopes of H = normalize(L + V) scaled by the roughness: r² = (x/α_x)² + (y/α_y)².
            r2 = (S[..., 0] / (S[..., 2] * ax)) ** 2 + (S[..., 1] / (S[..., 2] * ay)) ** 2
            hz2 = S[..., 2] ** 2 / np.einsum("...i,...i->...", S, S)
            D = self.distribution.density(r2) / (ax * ay * hz2 * hz2)
            shadow = self.distribution.smith_lambda
            G2 = shadowing_masking(params["shadowing"], shadow(smith_a2(L, ax, ay)), shadow(smith_a2(V, ax, ay)))
            cos_vh = np.einsum("...i,...i->...", V, S) / np.sqrt(np.einsum("...i,...i->...", S, S))
            value = (D * G2 / (4.0 * V[..., 2]))[..., None] * fresnel(params, np.clip(cos_vh, 0.0, 1.0))
        upper = (L[..., 2] > 0) & (V[..., 2] > 0)
        return np.where(upper[..., None], value, 0.0)

    def projected(self, L, V, params):
        value = self.single_scattering(L, V, params)
        if params["ms"] == "turquin":
            return value * self.turquin_factor(V, params)
        if params["ms"] == "kulla-conty":
            value = value + self.multiple_scattering(L, V, params) * np.maximum(L[..., 2:3], 0.0)
        return value


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        with np.errstate(divide="ignore", invalid="ignore"):
            value = self.single_scattering(L, V, params) / L[..., 2:3]
        value = np.where(L[..., 2:3] > 0, value, 0.0)
        if params["ms"] == "turquin":
            return value * self.turquin_factor(V, params)
        if params["ms"] == "kulla-conty":
            value = value + self.multiple_scattering(L, V, params)
        return value

    def _table(self, params):
        return COMPENSATION.resolve()(self.distribution, params["shadowing"], int(np.asarray(params["ms_table"])))

    def anisotropic_table(self, params: Mapping[str, object]):
        """The compensation of this anisotropic lobe: E(μ, φ), E_avg (engine.routes.anisotropic_compensation)."""
        ax, ay = (np.unique(np.ravel(a)) for a in roughness(params))  # one lobe, however broadcast
        if ax.size != 1 or ay.size != 1:
            raise ParameterError(f"ms={params['ms']} with alpha_x/alpha_y takes one lobe", where="parameter ms")
        return ANISOTROPIC_COMPENSATION.resolve()(self.distribution.name, params["shadowing"],
                                                  int(np.ravel(params["ms_table"])[0]), float(ax[0]), float(ay[0]))

    def _anisotropic(self, params: Mapping[str, object]) -> bool:
        return bool(np.any(np.asarray(params["alpha_x"]) > 0) or np.any(np.asarray(params["alpha_y"]) > 0))

    def _view_albedo(self, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """E at the directions V (...) as the compensation reads it (μ clamped at 0)."""
        mu_v = np.maximum(V[..., 2], 0.0)
        if self._anisotropic(params):
            return self.anisotropic_table(params).albedo(mu_v, np.arctan2(V[..., 1], V[..., 0]))
        alpha = np.asarray(params["alpha"], dtype=float)
        shape = np.broadcast_shapes(mu_v.shape, alpha.shape)
        return self._table(params).albedo(np.broadcast_to(mu_v, shape), np.broadcast_to(alpha, shape))

    def turquin_factor(self, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """Turquin's 1 + F0 (1/E(μ_V) − 1), (..., C); 1 where μ_V ≤ 0."""
        mu_v = V[..., 2]
        e_v = self._view_albedo(V, params)
        shape = e_v.shape
        f0 = fresnel_normal(params)
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = 1.0 + f0 * (1.0 / e_v[..., None] - 1.0)
        return np.where((np.broadcast_to(mu_v, shape) > 0)[..., None] & (e_v[..., None] > 0), factor, 1.0)

    def multiple_scattering(self, L: np.ndarray, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """Kulla & Conty's f_ms = F_ms (1 − E(μ_L))(1 − E(μ_V)) / (π(1 − E_avg)), (..., C); 0 at α = 0 (a mirror
        loses no energy: E = E_avg = 1)."""
        if self._anisotropic(params):
            table = self.anisotropic_table(params)
            e_l, e_v = self._view_albedo(L, params), self._view_albedo(V, params)
            lossy = (L[..., 2] > 0) & (V[..., 2] > 0) & (table.missing > 0)
            with np.errstate(divide="ignore", invalid="ignore"):
                value = (1.0 - e_l) * (1.0 - e_v) / (np.pi * table.missing)
            return np.where(lossy, value, 0.0)[..., None] * fresnel_multiple_scattering(params, table.average)
        shape = np.broadcast_shapes(L.shape[:-1], V.shape[:-1], np.shape(params["alpha"]))
        alpha = np.broadcast_to(np.asarray(params["alpha"], dtype=float), shape)
        mu_l = np.broadcast_to(L[..., 2], shape)
        mu_v = np.broadcast_to(V[..., 2], shape)
        e_l, e_v, e_avg = self._table(params).energies(mu_l, mu_v, alpha)
        lossy = (mu_l > 0) & (mu_v > 0) & (e_avg < 1.0)
        with np.errstate(divide="ignore", invalid="ignore"):
            value = (1.0 - e_l) * (1.0 - e_v) / (np.pi * (1.0 - e_avg))
        return np.where(lossy, value, 0.0)[..., None] * fresnel_multiple_scattering(params, e_avg)

    def lobe(self, fixed, params, over):
        ax, ay = roughness(params)
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(ax), np.shape(ay))
        # The reflected lobe is about twice as wide as the slope distribution (θ_L ≈ 2θ_H near the mirror).
        width = np.broadcast_to(np.clip(2.0 * np.maximum(ax, ay), 1e-6, 1.0), shape)
        return Lobe(np.broadcast_to(mirror(fixed), shape + (3,)), width, np.full(shape, np.pi))
