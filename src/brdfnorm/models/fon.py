"""The ``fon`` lobe: Fujii's improved Oren-Nayar model, in the form and parametrization of Portsmouth, Kutz & Hill,
"EON: A practical energy-preserving rough diffuse BRDF" (JCGT 14(1), 2025; arXiv:2410.18026), §3 — the single-
scattering lobe of the ``eon`` model (:mod:`.eon`).

    f = ρ/π A_F (1 + r s/t),   s = L·V − (N·L)(N·V),   t = max(N·L, N·V) where s > 0, else 1,
    A_F = 1/(1 + c₁ r),  c₁ = 1/2 − 2/(3π),  roughness r ∈ [0, 1]  (B_F = r A_F).

Its directional albedo has a closed form (the paper's eq. for E_F, here for ρ = 1):

    E_F(μ) = A_F + (B_F/π) G(μ),  G(μ) = S(θ − Sμ) + (2/3)((S/μ)(1 − S³) − S),  S = sin θ = √(1 − μ²), θ = acos μ,

and its cosine-weighted average E_F,avg = 2∫₀¹ E_F μ dμ = A_F (1 + c₂ r), c₂ = 2/3 − 28/(15π). The paper also fits
a cheap approximation (its listing; the reference GLSL of github.com/portsmouth/OpenPBR-viewer,
glsl/pathtracing/diffuse_brdf.glsl, ``E_FON_approx``):

    E_F ≈ (1 + r G̃) / (1 + c₁ r),  G̃ = 0.0571085289 x + 0.491881867 x² − 0.332181442 x³ + 0.0714429953 x⁴,
    x = 1 − μ,

used by ``eon`` with ``fon_albedo=approx`` (what that costs is measured by ``brdfnorm verify`` and ``check``).

Energy: conserved (E_F ≤ ρ ≤ 1 for every μ and r: the single-scattering lobe loses the interreflected part; at
r = 0 it is Lambert).
"""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from .base import Model, normal_lobe, scalar_param

C1 = 0.5 - 2.0 / (3.0 * np.pi)
C2 = 2.0 / 3.0 - 28.0 / (15.0 * np.pi)
#: The paper's fitted G̃ coefficients of x = 1 − μ, x², x³, x⁴.
APPROX_COEFFICIENTS = (0.0571085289, 0.491881867, -0.332181442, 0.0714429953)

FON_PARAMETERS = (
    Parameter("roughness", "float", 0.5, 0.0, 1.0, "roughness r ∈ [0, 1]"),
    Parameter("reflectance", "float", 1.0, 0.0, 1.0, "single-scattering albedo ρ"),
)


def fon_g(mu: np.ndarray) -> np.ndarray:
    """G(μ) = S(acos μ − Sμ) + (2/3)((S/μ)(1 − S³) − S), with (S/μ)(1 − S³) = Sμ(1 + S + S²)/(1 + S) (no 0/0 as
    μ → 0: 1 − S = μ²/(1 + S))."""
    mu = np.clip(mu, 0.0, 1.0)
    S = np.sqrt(np.maximum(0.0, (1.0 - mu) * (1.0 + mu)))
    return S * (np.arccos(mu) - S * mu) + (2.0 / 3.0) * (S * mu * (1.0 + S + S * S) / (1.0 + S) - S)


def fon_albedo_exact(mu: np.ndarray, r: np.ndarray) -> np.ndarray:
    """E_F(μ) at ρ = 1: A_F + (r A_F/π) G(μ)."""
    a = 1.0 / (1.0 + C1 * r)
    return a + r * a / np.pi * fon_g(mu)


def fon_albedo_approx(mu: np.ndarray, r: np.ndarray) -> np.ndarray:
    """The paper's fitted E_F(μ) at ρ = 1: (1 + r G̃(1 − μ))/(1 + c₁ r)."""
    x = 1.0 - np.clip(mu, 0.0, 1.0)
    c1, c2, c3, c4 = APPROX_COEFFICIENTS
    return (1.0 + r * (x * (c1 + x * (c2 + x * (c3 + x * c4))))) / (1.0 + C1 * r)


def fon_average_exact(r: np.ndarray) -> np.ndarray:
    """E_F,avg = 2∫₀¹ E_F(μ) μ dμ = A_F (1 + c₂ r)."""
    return (1.0 + C2 * r) / (1.0 + C1 * r)


def fon_average_approx(r: np.ndarray) -> np.ndarray:
    """2∫₀¹ μ (1 + r G̃(1 − μ)) dμ/(1 + c₁ r), exactly: 2∫₀¹(1 − x) xᵏ dx = 2/((k + 1)(k + 2))."""
    moment = sum(c * 2.0 / ((k + 1) * (k + 2)) for k, c in enumerate(APPROX_COEFFICIENTS, start=1))
    return (1.0 + r * moment) / (1.0 + C1 * r)


def fon_single_scattering(L: np.ndarray, V: np.ndarray, r: np.ndarray, rho: np.ndarray) -> np.ndarray:
    """ρ/π A_F (1 + r s/t) over (...), 0 below either horizon."""
    mu_l, mu_v = L[..., 2], V[..., 2]
    s = np.einsum("...i,...i->...", L, V) - mu_l * mu_v
    with np.errstate(divide="ignore", invalid="ignore"):
        s_over_t = np.where(s > 0, s / np.maximum(mu_l, mu_v), s)
    value = rho / np.pi / (1.0 + C1 * r) * (1.0 + r * s_over_t)
    return np.where((mu_l > 0) & (mu_v > 0), value, 0.0)


class FujiiOrenNayar(Model):
    name = "fon"
    formula = ("f = ρ/π A (1 + r s/t),  s = L·V − N·L N·V,  t = max(N·L, N·V) if s > 0 else 1,  "
               "A = 1/(1 + (1/2 − 2/(3π)) r)")
    parameters = FON_PARAMETERS
    energy = "conserved (E ≤ ρ; loses the interreflected part)"
    closed_form_domain = "every direction"


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        return fon_single_scattering(L, V, scalar_param(params, "roughness"),
                                     scalar_param(params, "reflectance"))[..., None]

    def lobe(self, fixed, params, over):
        return normal_lobe(fixed)

    def closed_form_albedo(self, fixed, params, over):
        # The lobe is reciprocal: over the light or the view, the same function of the fixed direction's μ.
        value = scalar_param(params, "reflectance") * fon_albedo_exact(np.asarray(fixed)[..., 2],
                                                                      scalar_param(params, "roughness"))
        return np.asarray(value)[..., None]
