"""The ``oren-nayar`` lobe: Oren & Nayar 1994's qualitative model ("Generalization of Lambert's reflectance model",
SIGGRAPH 94, eq. 30).

    f = ρ/π (A + B max(0, cos(φ_L − φ_V)) sin α tan β),  A = 1 − σ²/(2(σ² + 0.33)),  B = 0.45 σ²/(σ² + 0.09),

α = max(θ_L, θ_V), β = min(θ_L, θ_V), σ the standard deviation of the facet slope angle (radians). Written without
inverse trigonometry as ``examples/oren_nayar.brdf`` does: sin θ_L sin θ_V cos(φ_L − φ_V) = L·V − (N·L)(N·V) = s
and sin α tan β = sin θ_L sin θ_V / max(N·L, N·V), so the lobe is ρ/π (A + B max(0, s)/max(N·L, N·V)).

Energy: NOT conserved — the qualitative model is a fit; it gains energy at grazing views for moderate σ
(``brdfnorm check``), and loses it elsewhere (no interreflection term). At σ = 0 it is Lambert.
"""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from .base import Model, normal_lobe, scalar_param


class OrenNayar(Model):
    name = "oren-nayar"
    formula = "f = ρ/π (A + B max(0, L·V − N·L N·V)/max(N·L, N·V)),  A = 1 − σ²/(2(σ²+0.33)),  B = 0.45σ²/(σ²+0.09)"
    energy = "not conserved: up to 1.5 % gain at grazing views (σ ≈ 0.2); no interreflection"
    parameters = (
        Parameter("sigma", "float", 0.5, 0.0, np.pi / 2, "facet slope-angle deviation σ (radians)"),
        Parameter("reflectance", "float", 1.0, 0.0, 1.0, "diffuse reflectance ρ"),
    )


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        s2 = scalar_param(params, "sigma") ** 2
        rho = scalar_param(params, "reflectance")
        A = 1.0 - 0.5 * s2 / (s2 + 0.33)
        B = 0.45 * s2 / (s2 + 0.09)
        mu_l, mu_v = L[..., 2], V[..., 2]
        s = np.einsum("...i,...i->...", L, V) - mu_l * mu_v
        with np.errstate(divide="ignore", invalid="ignore"):
            value = rho / np.pi * (A + B * np.maximum(s, 0.0) / np.maximum(mu_l, mu_v))
        return np.where((mu_l > 0) & (mu_v > 0), value, 0.0)[..., None]

    def lobe(self, fixed, params, over):
        return normal_lobe(fixed)
