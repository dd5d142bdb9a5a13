"""The ``eon`` lobe: the energy-preserving Oren-Nayar model of Portsmouth, Kutz & Hill, "EON: A practical energy-
preserving rough diffuse BRDF" (JCGT 14(1), 2025; arXiv:2410.18026), §4 — the model OpenPBR and MaterialX adopted.
The formulas follow the authors' reference GLSL (github.com/portsmouth/OpenPBR-viewer, glsl/pathtracing/
diffuse_brdf.glsl, ``f_EON`` and ``E_EON``); the code is written here.

    f = f_FON + f_ms,   f_ms = (ρ_ms/π) (1 − E_F(μ_L)) (1 − E_F(μ_V)) / (1 − E_F,avg),
    ρ_ms = ρ² E_F,avg / (1 − ρ(1 − E_F,avg)),

with f_FON, E_F and E_F,avg of :mod:`.fon` (ρ = 1 in E_F). With ``fon_albedo=exact`` (the default) E_F is the closed
form, and the albedo is exactly ρ E_F(μ) + ρ_ms (1 − E_F(μ)) — 1 for ρ = 1 (energy-preserving). With
``fon_albedo=approx`` the paper's fitted E_F is used in f_ms (E_F,avg stays exact, as in the reference code); the
white albedo is then E_F(μ) + (1 − Ẽ(μ))(1 − Ẽ_avg)/(1 − E_F,avg) ≠ 1, and the excess is what the approximation
costs (``brdfnorm check eon -p fon_albedo=approx``; ``verify`` claim ``eon-approx-albedo``).

The reference code clamps 1 − E and 1 − E_avg below at 1e-7; here they are not clamped (E_F < 1 for r > 0, and at
r = 0 the factor is 0/0: the multiple-scattering lobe is 0 there — Lambert).

Energy: conserved (exactly 1 for white with ``fon_albedo=exact``; see above for ``approx``).
"""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from .base import Model, normal_lobe, scalar_param
from .fon import (
    FON_PARAMETERS,
    fon_albedo_approx,
    fon_albedo_exact,
    fon_average_approx,
    fon_average_exact,
    fon_single_scattering,
)

FON_ALBEDO = ("exact", "approx")


def multiple_scattering_albedo(rho: np.ndarray, average: np.ndarray) -> np.ndarray:
    """ρ_ms = ρ² E_avg / (1 − ρ(1 − E_avg))."""
    return rho * rho * average / (1.0 - rho * (1.0 - average))


class EnergyPreservingOrenNayar(Model):
    name = "eon"
    formula = ("f = f_fon + ρ_ms/π (1 − E_F(μ_L))(1 − E_F(μ_V))/(1 − E_F,avg),  "
               "ρ_ms = ρ² E_F,avg/(1 − ρ(1 − E_F,avg)); E_F exact or the paper's fit (fon_albedo)")
    energy = "conserved: E = 1 for ρ = 1 with fon_albedo=exact; the fitted E_F gains up to 1.5e-4"
    closed_form_domain = "every direction"
    parameters = FON_PARAMETERS + (
        Parameter("fon_albedo", "choice", "exact", choices=FON_ALBEDO,
                  description="E_F in the multiple-scattering lobe: closed form, or the paper's fitted polynomial"),
    )


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        r = scalar_param(params, "roughness")
        rho = scalar_param(params, "reflectance")
        albedo = fon_albedo_exact if params["fon_albedo"] == "exact" else fon_albedo_approx
        average = fon_average_exact(r)
        mu_l, mu_v = L[..., 2], V[..., 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            ms = (multiple_scattering_albedo(rho, average) / np.pi * (1.0 - albedo(mu_l, r)) * (1.0 - albedo(mu_v, r))
                  / (1.0 - average))
        ms = np.where((mu_l > 0) & (mu_v > 0) & (average < 1.0), ms, 0.0)
        return (fon_single_scattering(L, V, r, rho) + ms)[..., None]

    def lobe(self, fixed, params, over):
        return normal_lobe(fixed)

    def closed_form_albedo(self, fixed, params, over):
        """ρ E_F(μ) + ρ_ms (1 − Ẽ(μ)) (1 − Ẽ_avg)/(1 − E_F,avg), Ẽ the E_F in f_ms (exact or the fit, whose
        average is a polynomial's, in closed form); the lobe is reciprocal, so over the light or the view alike."""
        r = scalar_param(params, "roughness")
        rho = scalar_param(params, "reflectance")
        mu = np.asarray(fixed)[..., 2]
        average = fon_average_exact(r)
        if params["fon_albedo"] == "exact":
            used, used_average = fon_albedo_exact(mu, r), average
        else:
            used, used_average = fon_albedo_approx(mu, r), fon_average_approx(r)
        with np.errstate(divide="ignore", invalid="ignore"):
            ms = np.where(average < 1.0, multiple_scattering_albedo(rho, average) * (1.0 - used)
                          * (1.0 - used_average) / (1.0 - average), 0.0)
        return np.asarray(rho * fon_albedo_exact(mu, r) + ms)[..., None]
