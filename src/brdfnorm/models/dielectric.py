"""Rough dielectric interfaces: microfacet reflection and refraction over the whole sphere (a BSDF).

Walter et al. 2007 ("Microfacet models for refraction through rough surfaces"): light arriving from direction
L leaves towards V, either reflected (L and V on one side, H = normalize(L + V), eq. 20) or refracted (on
opposite sides, generalized half vector H = −(η_V V + η_L L) normalized, eq. 16):

    f_r = D(H) G2 F(V·H) / (4 |N·L| |N·V|)
    f_t = |L·H| |V·H| / (|N·L| |N·V|) · η_L² (1 − F(V·H)) G2 D(H) / (η_V (V·H) + η_L (L·H))²

with D and Smith Λ from :mod:`brdfnorm.models.microfacet` (Heitz 2014), and F the exact unpolarized dielectric
Fresnel for the ratio of the indices across the interface (total internal reflection included).

Transport convention: **energy**, not radiance. f_t carries η_L² (the light's side), where Walter's radiance
form carries η_V² — the two differ by (η_L/η_V)², the 1/η² radiance compression a renderer applies when
radiance crosses the interface. In this form the directional albedo ∫ f |N·L| dL is the share of energy
scattered, reflection plus transmission, so a smooth interface gives R + T = 1 exactly, and reciprocity reads
f(L, V)/η_L² = f(V, L)/η_V² (the radiance form's f(L, V)/η_V² = f(V, L)/η_L², rewritten).

Smith shadowing: ``height-correlated`` is Heitz 2014's — 1/(1 + Λ(L) + Λ(V)) for reflection and, for
refraction, where the two directions see the surface from opposite sides, the Beta function
B(1 + Λ(V), 1 + Λ(L)) (Heitz 2014 §6.2, eq. 100); ``separable`` is G1(L)G1(V) for both.
``refraction_shadowing`` overrides the refraction's G2 alone, so that every engine's glass can be reproduced:
``auto`` (the default) follows ``shadowing`` as above; ``correlated-beta`` is Heitz's B(1 + Λ_V, 1 + Λ_L);
``reflection-form`` is the reflection's 1/(1 + Λ_V + Λ_L) (Blender Cycles' glass); ``separable`` is G1·G1
(OpenPBR, Mitsuba).

The exterior is the upper hemisphere (index 1), the interior the lower one; ``eta`` is the interior's index
over the exterior's. A view from inside the denser medium is the same interface with eta < 1 (1/1.5 for glass
seen from within), where total internal reflection sends everything past the critical angle back.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from scipy.special import beta

from ..errors import ParameterError
from ..parameters import Parameter
from .base import Lobe, Model, mirror
from .microfacet import ALPHA_MIN, SHADOWING, Distribution, fresnel_dielectric, shadowing_masking, smith_a2

#: Choices of the refraction's shadowing (see the module docstring).
REFRACTION_SHADOWING = ("auto", "correlated-beta", "reflection-form", "separable")
#: |eta − 1| below this is refused: an index-matched interface refracts into a delta, not a lobe.
ETA_MATCH = 1e-6


def dielectric_parameters(default_alpha: float) -> tuple[Parameter, ...]:
    return (
        Parameter("alpha", "float", default_alpha, ALPHA_MIN, 100.0, "roughness α (slope width), isotropic"),
        Parameter("eta", "float", 1.5, 1e-3, 1e3, "interior index over exterior index (< 1: seen from inside)"),
        Parameter("shadowing", "choice", "height-correlated", choices=SHADOWING,
                  description="Smith G2: Heitz's height-correlated (reflection and refraction) or G1(L)G1(V)"),
        Parameter("refraction_shadowing", "choice", "auto", choices=REFRACTION_SHADOWING,
                  description="the refraction's G2: auto (follows shadowing), correlated-beta B(1+Λv, 1+Λl), "
                              "reflection-form 1/(1+Λv+Λl) (Cycles), separable G1·G1 (OpenPBR, Mitsuba)"),
    )


def refraction_kind(shadowing: str, refraction: str = "auto") -> str:
    """The refraction's G2 (a kind :func:`refraction_shadowing` takes) for the parameters ``shadowing`` and
    ``refraction_shadowing``."""
    if refraction == "auto":
        return "separable" if shadowing == "separable" else "correlated-beta"
    return refraction


def refraction_shadowing(kind: str, lambda_l: np.ndarray, lambda_v: np.ndarray) -> np.ndarray:
    """G2 for L and V on opposite sides: Heitz's B(1 + Λ_V, 1 + Λ_L) (``correlated-beta``, or ``height-correlated``
    as the ``shadowing`` parameter names it), the reflection's 1/(1 + Λ_V + Λ_L) (``reflection-form``), or the
    separable G1·G1. scipy's beta rather than
    exp of three log-gammas: 1.5 times faster, and within 4e-9 of mpmath where the log-gamma difference was 8e-8
    off (Λ up to 1e7, random)."""
    if kind == "separable":
        return 1.0 / ((1.0 + lambda_l) * (1.0 + lambda_v))
    if kind == "reflection-form":
        return 1.0 / (1.0 + lambda_l + lambda_v)
    with np.errstate(invalid="ignore"):
        value = beta(1.0 + lambda_l, 1.0 + lambda_v)
    return np.where(np.isinf(lambda_l) | np.isinf(lambda_v), 0.0, value)


def refract(V: np.ndarray, m: np.ndarray, eta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The direction refracted from V through a facet of normal m (V·m > 0) into a medium eta times denser,
    and a mask of where it exists (no total internal reflection)."""
    cos_i = np.einsum("...i,...i->...", V, m)
    sin2_t = (1.0 - cos_i * cos_i) / (eta * eta)
    cos_t = np.sqrt(np.maximum(1.0 - sin2_t, 0.0))
    L = -V / eta[..., None] + (cos_i / eta - cos_t)[..., None] * m
    return L, sin2_t < 1.0


class MicrofacetDielectric(Model):
    """A rough dielectric BSDF over a slope distribution (subclasses name the distribution)."""

    distribution: Distribution
    #: Scatters into both hemispheres: the integrators cover the sphere, results report both parts.
    transmits = True

    def _check(self) -> None:
        if np.any(np.abs(np.asarray(self._params["eta"], dtype=float) - 1.0) < ETA_MATCH):
            raise ParameterError(f"must differ from 1 by at least {ETA_MATCH:g} (an index-matched interface "
                                 "does not scatter)", where="parameter eta")

    def evaluate(self, L, V, params):
        with np.errstate(divide="ignore", invalid="ignore"):
            value = self.projected(L, V, params) / np.abs(L[..., 2:3])
        return np.where(L[..., 2:3] != 0, value, 0.0)

    def projected(self, L: np.ndarray, V: np.ndarray, params: Mapping[str, object]) -> np.ndarray:
        """f·|N·L| over the sphere of L (either side of V), (..., 1)."""
        shape = np.broadcast_shapes(L.shape[:-1], V.shape[:-1], np.shape(params["alpha"]), np.shape(params["eta"]))
        L, V = np.broadcast_to(L, shape + (3,)), np.broadcast_to(V, shape + (3,))
        alpha = np.broadcast_to(np.asarray(params["alpha"], dtype=float), shape)
        eta = np.broadcast_to(np.asarray(params["eta"], dtype=float), shape)
        # Seen from below, the interface is the same with the indices' ratio inverted: flip to V above.
        below = V[..., 2] < 0
        flip = np.where(below[..., None], np.array([1.0, 1.0, -1.0]), np.ones(3))
        L, V, eta = L * flip, V * flip, np.where(below, 1.0 / eta, eta)
        reflected = L[..., 2] > 0
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            S = np.where(reflected[..., None], L + V, -(V + eta[..., None] * L))
            S = S * np.where(S[..., 2:3] < 0, -1.0, 1.0)  # the facet normal faces the exterior
            H = S / np.linalg.norm(S, axis=-1, keepdims=True)
            r2 = (H[..., 0] ** 2 + H[..., 1] ** 2) / (H[..., 2] ** 2 * alpha * alpha)
            D = self.distribution.density(r2) / (alpha * alpha * H[..., 2] ** 4)
            lam = self.distribution.smith_lambda
            lambda_l, lambda_v = lam(smith_a2(L, alpha, alpha)), lam(smith_a2(V, alpha, alpha))
            vh = np.einsum("...i,...i->...", V, H)
            lh = np.einsum("...i,...i->...", L, H)
            F = fresnel_dielectric(np.abs(vh), eta)
            kind = params["shadowing"]
            f_r = D * shadowing_masking(kind, lambda_l, lambda_v) * F / (4.0 * V[..., 2])
            f_t = (np.abs(lh * vh) / V[..., 2] * eta * eta * (1.0 - F) * refraction_shadowing(
                refraction_kind(kind, str(params.get("refraction_shadowing", "auto"))), lambda_l, lambda_v)
                   * D / (vh + eta * lh) ** 2)
            # χ⁺: V sees the facet from its front, L from the front (reflection) or the back (refraction).
            value = np.where(reflected, np.where((vh > 0) & (lh > 0), f_r, 0.0),
                             np.where((vh > 0) & (lh < 0), f_t, 0.0))
        value = np.where((L[..., 2] != 0) & (V[..., 2] > 0) & np.isfinite(value), value, 0.0)
        return value[..., None]

    def lobe(self, fixed, params, over):
        """The reflection lobe (about the mirror direction), as the microfacet BRDFs give it."""
        alpha = np.asarray(params["alpha"], dtype=float)
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(alpha))
        width = np.broadcast_to(np.clip(2.0 * alpha, 1e-6, 1.0), shape)
        return Lobe(np.broadcast_to(mirror(fixed), shape + (3,)), width, np.full(shape, np.pi))

    def transmission_lobe(self, fixed, params) -> Lobe:
        """The refraction lobe, about the direction refracted through the mean facet N (in the lower
        hemisphere; towards the horizon under total internal reflection, where the lobe is only tails)."""
        alpha = np.asarray(params["alpha"], dtype=float)
        eta = np.asarray(params["eta"], dtype=float)
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(alpha), np.shape(eta))
        V = np.broadcast_to(fixed, shape + (3,))
        eta = np.broadcast_to(eta, shape)
        normal = np.broadcast_to(np.array([0.0, 0.0, 1.0]), shape + (3,))
        L, exists = refract(V, normal, eta)
        grazing = np.stack([-V[..., 0], -V[..., 1], np.full(shape, -1e-3)], axis=-1)
        direction = np.where(exists[..., None], L, grazing)
        direction = direction / np.linalg.norm(direction, axis=-1, keepdims=True)
        width = np.broadcast_to(np.clip(2.0 * np.maximum(alpha, alpha / eta), 1e-6, 1.0), shape)
        return Lobe(direction, width, np.full(shape, np.pi))
