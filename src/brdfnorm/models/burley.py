"""The ``burley`` lobe: the diffuse of the Disney principled BRDF (Burley 2012, "Physically-Based Shading at Disney",
§5.3, eq. for f_d), the built-in twin of ``examples/disney_diffuse.brdf``.

    f = ρ/π (1 + (F_D90 − 1)(1 − N·L)⁵)(1 + (F_D90 − 1)(1 − N·V)⁵),   F_D90 = 0.5 + 2 r cos²θ_d,  cos θ_d = L·H,

r the roughness, H = normalize(L + V). The Schlick-like factors darken grazing views at low roughness and brighten
them (retro-reflection) at high roughness.

Energy: NOT conserved, by design — the retro-reflection gains energy at grazing views and high roughness
(``brdfnorm check burley`` finds the maximum and where); at low roughness it loses energy at grazing views.
"""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from .base import Model, normal_lobe, scalar_param


class Burley(Model):
    name = "burley"
    formula = "f = ρ/π (1 + (F_D90 − 1)(1 − N·L)⁵)(1 + (F_D90 − 1)(1 − N·V)⁵),  F_D90 = 0.5 + 2 r (L·H)²"
    energy = "not conserved: gains up to 55 % at grazing views and roughness 1; loses at low roughness"
    parameters = (
        Parameter("roughness", "float", 0.5, 0.0, 1.0, "roughness r"),
        Parameter("reflectance", "float", 1.0, 0.0, 1.0, "base colour ρ"),
    )


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        r = scalar_param(params, "roughness")
        rho = scalar_param(params, "reflectance")
        mu_l, mu_v = L[..., 2], V[..., 2]
        # cos²θ_d = (L·H)² = (1 + L·V)/2 for H = normalize(L + V) (no normalization, no 0/0 at L = −V).
        cos2_d = 0.5 * (1.0 + np.einsum("...i,...i->...", L, V))
        f90 = 0.5 + 2.0 * r * cos2_d
        value = (rho / np.pi * (1.0 + (f90 - 1.0) * (1.0 - np.clip(mu_l, 0, 1)) ** 5)
                 * (1.0 + (f90 - 1.0) * (1.0 - np.clip(mu_v, 0, 1)) ** 5))
        return np.where((mu_l > 0) & (mu_v > 0), value, 0.0)[..., None]

    def lobe(self, fixed, params, over):
        return normal_lobe(fixed)
