"""The lobes a material is made of, each with its exact directional albedo E(μ) at any view.

A component evaluates f·(N·L) for scalar (one material's) parameters — three channels — and computes its own E(μ)
with brdfnorm's engine, so that the layering rules (:mod:`brdfnorm.materials.compose`) can use exact albedos:

* :class:`Microfacet` — a GGX lobe (Walter et al. 2007, Heitz 2014's height-correlated Smith G2) with any Fresnel
  of :mod:`brdfnorm.models.fresnel` and a constant tint. E(μ) with F = 1 by the 1-D azimuthal route
  (:func:`brdfnorm.engine.routes.azimuthal.white_albedo`); with a Fresnel by the half-vector cubature of
  :mod:`brdfnorm.engine.routes.halfvector` with F(V·H) in its weight (the albedo's error estimate as that route
  gives it).
* :class:`Diffuse` — Lambert ρ/π (E = ρ exactly) or EON (Portsmouth et al. 2025, the ``eon`` lobe, whose albedo is
  exact in closed form).
* :class:`Sheen` — the ``charlie`` lobe (Estevez & Kulla 2017) as the fuzz; E(μ) by the engine's quadrature.
* :class:`Transmission` — the refraction of brdfnorm's ``ggx-dielectric`` lobe (Walter et al. 2007, energy form,
  its exact Fresnel 1 − F kept), the translucent base's f^T; E_T(μ) by the dielectric route
  (:mod:`brdfnorm.engine.routes.dielectric`), exact from rough to smooth.
* :class:`Darkening` — not a lobe: OpenPBR's coat darkening factor lerp(1, Δ(μ_o), δ) as a view-side layering
  factor (its "albedo" is δ(1 − Δ), so that 1 − E is the factor), exact in closed form.
* :class:`LTCSheen` — the ``zeltner`` lobe (Zeltner et al. 2022's LTC sheen, OpenPBR's recommended fuzz); E(μ) is
  the fit R(μ, r) in closed form (the LTC integrates to 1: :mod:`brdfnorm.models.zeltner`).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from ..engine.methods import albedo as engine_albedo
from ..engine.routes import halfvector
from ..engine.routes.azimuthal import white_albedo
from ..models.charlie import Charlie
from ..models.eon import EnergyPreservingOrenNayar
from ..models.fresnel import Fresnel
from ..models.ggx_dielectric import GGXDielectric
from ..models.microfacet import GGXDistribution, shadowing_masking, smith_a2
from ..models.zeltner import albedo_fit, ltc_density
from ..validate import DEFAULT_MAX_EVALUATIONS

#: Tolerance of every exact component albedo (the layering's E(μ) inside the integrand).
ALBEDO_RTOL = 1e-12
#: The sheen's albedo goes through the generic cubature, which stalls near 1e-12 on it: 1e-10.
SHEEN_RTOL = 1e-10
_GGX = GGXDistribution()
#: The microfacet route refuses views closer to the horizon than this cos θ; E there is taken at it.
MU_MIN = halfvector.MU_MIN


def _view(mu: np.ndarray) -> np.ndarray:
    mu = np.clip(np.asarray(mu, dtype=float).ravel(), MU_MIN, 1.0)
    return np.stack([np.sqrt((1.0 - mu) * (1.0 + mu)), np.zeros_like(mu), mu], axis=-1)


@dataclass(frozen=True, eq=False)
class Component:
    """A lobe of a material: f·(N·L) for (…, 3) directions, and E(μ) exact with an error estimate."""

    label: str = ""

    def projected(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        raise NotImplementedError

    def albedo(self, mu: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(E, error) at view cosines μ (n,): arrays (n, 3)."""
        raise NotImplementedError

    @property
    def key(self) -> tuple:
        """What identifies the lobe's values (for caches of its albedo)."""
        raise NotImplementedError

    #: An albedo in closed form, read as is by every ``albedo_source`` (no curve, no table).
    closed_form = False
    #: Scatters into the lower hemisphere (light from inside the object): the refraction of a translucent base.
    transmits = False

    #: The table axis an engine tabulates this lobe over (its roughness; a dataclass field of each lobe).
    roughness = None

    def with_roughness(self, roughness: float) -> Component:
        raise NotImplementedError

    @property
    def table_key(self) -> tuple:
        """The key without the roughness: what an engine's (μ, roughness) table of this lobe depends on."""
        return self.with_roughness(0.0).key


@dataclass(frozen=True, eq=False)
class Microfacet(Component):
    """GGX with roughness r (α = r², at least 1e-12 as the ``ggx`` lobe's), Fresnel F(V·H) and a tint."""

    roughness: float = 0.5
    fresnel: Fresnel = field(default_factory=lambda: Fresnel("none"))
    tint: tuple = (1.0, 1.0, 1.0)

    @property
    def alpha(self) -> float:
        return max(self.roughness * self.roughness, 1e-12)

    @property
    def key(self) -> tuple:
        f = self.fresnel
        inputs = tuple(tuple(np.ravel(np.asarray(v, dtype=float))) for v in (f.f0, f.f90, f.tint, f.eta, f.k, f.r, f.g))
        return ("ggx", self.roughness, f.kind, f.exponent, inputs, tuple(self.tint))

    def with_roughness(self, roughness: float) -> Microfacet:
        return Microfacet(self.label, roughness, self.fresnel, self.tint)

    def projected(self, L, V):
        alpha = self.alpha
        S = L + V
        with np.errstate(divide="ignore", invalid="ignore"):
            norm2 = np.einsum("...i,...i->...", S, S)
            r2 = (S[..., 0] ** 2 + S[..., 1] ** 2) / (S[..., 2] * alpha) ** 2
            hz2 = S[..., 2] ** 2 / norm2
            D = _GGX.density(r2) / (alpha * alpha * hz2 * hz2)
            G2 = shadowing_masking("height-correlated", _GGX.smith_lambda(smith_a2(L, alpha, alpha)),
                                   _GGX.smith_lambda(smith_a2(V, alpha, alpha)))
            cos_vh = np.clip(np.einsum("...i,...i->...", V, S) / np.sqrt(norm2), 0.0, 1.0)
            value = (D * G2 / (4.0 * V[..., 2]))[..., None] * self._fresnel(cos_vh)
        upper = (L[..., 2] > 0) & (V[..., 2] > 0)
        return np.where(upper[..., None], value, 0.0) * np.asarray(self.tint)

    def _fresnel(self, cos: np.ndarray) -> np.ndarray:
        value = np.asarray(self.fresnel(np.asarray(cos)[..., None]), dtype=float)
        return np.broadcast_to(value, np.shape(cos) + (3,))

    def albedo(self, mu):
        fixed = _view(mu)
        K = fixed.shape[0]
        if self.fresnel.kind == "none":
            result = white_albedo(_GGX, "height-correlated", fixed, np.full(K, self.alpha), rtol=ALBEDO_RTOL)
            value, error = np.repeat(result.value, 3, axis=1), np.repeat(result.error, 3, axis=1)
        else:
            value, error = self._fresnel_albedo(fixed)
        tint = np.asarray(self.tint, dtype=float)
        return value * tint, error * tint

    def _fresnel_albedo(self, fixed: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The half-vector cubature (H1) of :mod:`brdfnorm.engine.routes.halfvector` with F = 1 in its own weight
        and this lobe's Fresnel multiplied in at V·H = V_z (1 + c·x)/√(1 + |x|²)."""
        K = fixed.shape[0]
        params = {"alpha": np.full(K, self.alpha), "alpha_x": 0.0, "alpha_y": 0.0, "shadowing": "height-correlated",
                  "fresnel": "none", "f0": 0.0, "f90": 1.0, "eta": 1.0, "k": 0.0}
        g = halfvector.slope_geometry(_GGX, fixed, params)
        white = halfvector.microfacet_weight(g)

        def weight(nodes):
            return white(nodes) * self._fresnel(g.V[nodes.k, 2] * nodes.one_sp / np.sqrt(nodes.n2))

        rtol = np.full((K, 1), ALBEDO_RTOL)
        result = halfvector.integrate_slopes(g, weight, g.ax == g.ay, rtol=rtol, atol=0.0,
                                             max_evaluations=DEFAULT_MAX_EVALUATIONS)
        return np.broadcast_to(result.value, (K, 3)).copy(), np.broadcast_to(result.error, (K, 3)).copy()


@dataclass(frozen=True, eq=False)
class Diffuse(Component):
    """Lambert (roughness 0) or EON (roughness σ > 0) with albedo colour ρ; E exact in closed form."""

    rho: tuple = (0.8, 0.8, 0.8)
    roughness: float = 0.0

    @property
    def key(self) -> tuple:
        return ("diffuse", tuple(self.rho), self.roughness)

    def with_roughness(self, roughness: float) -> Diffuse:
        return Diffuse(self.label, self.rho, roughness)

    def _eon(self, channel: int) -> EnergyPreservingOrenNayar:
        return EnergyPreservingOrenNayar(reflectance=self.rho[channel], roughness=self.roughness)

    def projected(self, L, V):
        rho = np.asarray(self.rho, dtype=float)
        mu_l = np.maximum(L[..., 2:3], 0.0)
        upper = (V[..., 2:3] > 0)
        if self.roughness == 0.0:
            return np.where(upper, rho / np.pi * mu_l, 0.0)
        channels = [self._eon(c) for c in range(3)]
        return np.concatenate([m.projected(L, V, m.params) for m in channels], axis=-1)

    def albedo(self, mu):
        fixed = _view(mu)
        if self.roughness == 0.0:
            value = np.broadcast_to(np.asarray(self.rho, dtype=float), (fixed.shape[0], 3)).copy()
        else:
            value = np.concatenate([m.closed_form_albedo(fixed, m.params, "light")
                                    for m in (self._eon(c) for c in range(3))], axis=-1)
        return value, 8 * np.finfo(float).eps * np.abs(value)


@dataclass(frozen=True, eq=False)
class Sheen(Component):
    """The ``charlie`` sheen lobe with colour and roughness r (α = r²), as the fuzz layer."""

    color: tuple = (1.0, 1.0, 1.0)
    roughness: float = 0.5
    shadowing: str = "kulla"

    @property
    def key(self) -> tuple:
        return ("sheen", tuple(self.color), self.roughness, self.shadowing)

    def with_roughness(self, roughness: float) -> Sheen:
        return Sheen(self.label, self.color, roughness, self.shadowing)

    def _model(self) -> Charlie:
        return Charlie(roughness=self.roughness, color=self.color, shadowing=self.shadowing)

    def projected(self, L, V):
        model = self._model()
        return model.projected(L, V, model.params)

    def albedo(self, mu):
        fixed = _view(mu)
        with warnings.catch_warnings():  # a stalled integral keeps its error estimate, which the callers carry
            warnings.simplefilter("ignore", UserWarning)
            result = engine_albedo(self._model(), np.arccos(fixed[:, 2]), rtol=SHEEN_RTOL)
        return result.value.reshape(-1, 3), result.error.reshape(-1, 3)


@dataclass(frozen=True, eq=False)
class LTCSheen(Component):
    """The ``zeltner`` LTC sheen with colour and roughness r ∈ [0.01, 1]; E(μ) = colour·R(μ, r) exactly."""

    color: tuple = (1.0, 1.0, 1.0)
    roughness: float = 0.5

    @property
    def key(self) -> tuple:
        return ("ltc-sheen", tuple(self.color), self.roughness)

    def with_roughness(self, roughness: float) -> LTCSheen:
        # an engine's table row at roughness 0 is read at the fit's smallest roughness
        return LTCSheen(self.label, self.color, max(roughness, 0.01))

    def projected(self, L, V):
        white = albedo_fit(np.clip(V[..., 2], 0.0, 1.0), self.roughness) * ltc_density(L, V, self.roughness)
        return white[..., None] * np.asarray(self.color, dtype=float)

    def albedo(self, mu):
        mu = np.clip(np.asarray(mu, dtype=float).ravel(), 0.0, 1.0)
        value = albedo_fit(mu, self.roughness)[:, None] * np.asarray(self.color, dtype=float)
        return value, 8 * np.finfo(float).eps * np.abs(value)


@dataclass(frozen=True, eq=False)
class Darkening(Component):
    """OpenPBR's coat darkening (*Coat* → *Darkening*) as a factor of the coated base, at view cosine μ_o:

    Δ(μ_o) = (1 − K)/(1 − E_b K)  (eq. [general_darkening_formula]),  K = lerp(K_s, K_r, r_b)
    (eq. [internal_diffuse_reflection_coefficient_for_general_base]), K_s = F_c(μ_o) (eq. [..._smooth_base]),
    K_r = 1 − (1 − E_F)/η_c² (eq. [..._rough_base]) with E_F the coat Fresnel's exact hemispherical average;
    the coated base is multiplied by B(δ) Δ = lerp(1, Δ, δ) (eq. [boost_factor], B_0 = 1/Δ). E_b (per channel) is
    the base's albedo at normal incidence, Δ = 1 where E_b K = 1 (E_b = K = 1: no energy is lost). With
    ``reciprocal`` (the symmetric and reciprocal layering rules) K_s is its hemispherical average E_F, so that the
    factor is a constant and the material stays reciprocal (brdfnorm's choice; the specification gives the view-side
    form only)."""

    eta: float = 1.6
    base_albedo: tuple = (1.0, 1.0, 1.0)
    base_roughness: float = 1.0
    darkening: float = 1.0
    #: K_s averaged over the hemisphere (E_F): a constant factor, for the reciprocal layering rules.
    reciprocal: bool = False
    closed_form = True

    @property
    def key(self) -> tuple:
        return ("darkening", self.eta, tuple(self.base_albedo), self.base_roughness, self.darkening, self.reciprocal)

    def with_roughness(self, roughness: float) -> Darkening:
        return self

    @property
    def roughness(self) -> float:  # the table axis: none (the factor is read exactly)
        return 0.0

    def factor(self, mu: np.ndarray) -> np.ndarray:
        """lerp(1, Δ(μ), δ): (n, 3) at view cosines μ (n,)."""
        mu = np.clip(np.asarray(mu, dtype=float).ravel(), 0.0, 1.0)
        coat = Fresnel("dielectric", eta=self.eta)
        e_f = float(np.ravel(coat.average()[0])[0])
        k_rough = 1.0 - (1.0 - e_f) / self.eta**2
        k_smooth = np.full((mu.size, 1), e_f) if self.reciprocal else np.asarray(coat(mu[:, None]), dtype=float)[:, :1]
        K = k_smooth + (k_rough - k_smooth) * self.base_roughness
        e_b = np.asarray(self.base_albedo, dtype=float)
        lost = 1.0 - e_b * K
        with np.errstate(divide="ignore", invalid="ignore"):
            delta = np.where(lost > 0, (1.0 - K) / np.where(lost > 0, lost, 1.0), 1.0)
        return 1.0 + self.darkening * (delta - 1.0)

    def albedo(self, mu):
        value = 1.0 - self.factor(mu)
        return value, 8 * np.finfo(float).eps * (1.0 + np.abs(value))


@dataclass(frozen=True, eq=False)
class Transmission(Component):
    """The refraction of the ``ggx-dielectric`` lobe (roughness r, α = r², at least the lobe's α_min; interior index
    ``eta``), times a tint: f·|N·L| for L below the surface and V above, 0 elsewhere."""

    roughness: float = 0.5
    eta: float = 1.5
    tint: tuple = (1.0, 1.0, 1.0)
    transmits = True

    @property
    def key(self) -> tuple:
        return ("transmission", self.roughness, self.eta, tuple(self.tint))

    def with_roughness(self, roughness: float) -> Transmission:
        return Transmission(self.label, roughness, self.eta, self.tint)

    def model(self) -> GGXDielectric:
        return GGXDielectric(alpha=max(self.roughness * self.roughness, 1e-12), eta=self.eta)

    def projected(self, L, V):
        model = self.model()
        value = model.projected(L, V, model.params)
        below = np.broadcast_to(L[..., 2:3] < 0, value.shape)
        return np.where(below, value, 0.0) * np.asarray(self.tint, dtype=float)

    def albedo(self, mu):
        fixed = _view(mu)
        result = engine_albedo(self.model(), np.arccos(fixed[:, 2]), method="dielectric", rtol=ALBEDO_RTOL)
        tint = np.asarray(self.tint, dtype=float)
        # the route's estimate covers reflection plus refraction: a bound on the refraction's own error
        return result.transmitted.reshape(-1, 1) * tint, result.error.reshape(-1, 1) * tint
