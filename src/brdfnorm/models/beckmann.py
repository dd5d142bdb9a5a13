"""Beckmann microfacet lobe: Walter et al. 2007 with Heitz 2014's exact Smith Λ (with erf, no rational fit).

D(H) = exp(−(x²/α_x² + y²/α_y²)) / (π α_x α_y cos⁴θ_H) for the slopes (x, y) of H,
Λ(ω) = (erf(b) − 1)/2 + exp(−b²)/(2b√π), b = 1/(α_ω tan θ_ω); the shared pieces (G2, Fresnel, Kulla-Conty)
are in :mod:`brdfnorm.models.microfacet`. Its albedo is integrated by :mod:`brdfnorm.engine.routes.azimuthal`
(isotropic, F = 1) or
:mod:`brdfnorm.engine.routes.halfvector`.
"""

from __future__ import annotations

from .microfacet import BeckmannDistribution, MicrofacetModel, microfacet_parameters


class Beckmann(MicrofacetModel):
    name = "beckmann"
    formula = ("f = D G2 F / (4 N·L N·V),  D = exp(−tan²θ_H/α²)/(π α² cos⁴θ_H),  "
               "Λ = (erf(b) − 1)/2 + exp(−b²)/(2b√π), b = 1/(α tanθ)")
    parameters = microfacet_parameters(0.5)
    distribution = BeckmannDistribution()
