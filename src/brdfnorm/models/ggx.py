"""GGX (Trowbridge-Reitz) microfacet lobe: Walter et al. 2007 with Heitz 2014's exact Smith Λ.

D(H) = 1 / (π α_x α_y cos⁴θ_H (1 + x²/α_x² + y²/α_y²)²) for the slopes (x, y) of H,
Λ(ω) = (−1 + √(1 + α_ω² tan²θ_ω))/2; the shared pieces (G2, Fresnel, Kulla-Conty) are in
:mod:`brdfnorm.models.microfacet`. Its albedo is integrated by :mod:`brdfnorm.engine.routes.azimuthal` (isotropic, F =
1) or
:mod:`brdfnorm.engine.routes.halfvector`.
"""

from __future__ import annotations

from .microfacet import GGXDistribution, MicrofacetModel, microfacet_parameters


class GGX(MicrofacetModel):
    name = "ggx"
    formula = "f = D G2 F / (4 N·L N·V),  D = 1/(π α² cos⁴θ_H (1 + tan²θ_H/α²)²),  Λ = (√(1+α²tan²θ) − 1)/2"
    parameters = microfacet_parameters(0.5)
    distribution = GGXDistribution()
