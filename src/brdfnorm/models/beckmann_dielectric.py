"""Rough dielectric interface with the Beckmann distribution: reflection and refraction
(Walter et al. 2007; :mod:`brdfnorm.models.dielectric`). Albedo by :mod:`brdfnorm.engine.routes.dielectric`."""

from __future__ import annotations

from .dielectric import MicrofacetDielectric, dielectric_parameters
from .microfacet import BeckmannDistribution


class BeckmannDielectric(MicrofacetDielectric):
    name = "beckmann-dielectric"
    formula = ("BSDF: f_r = D G2 F/(4|N·L||N·V|),  f_t = |L·H||V·H|/(|N·L||N·V|) η_L²(1−F) G2 D/(η_V V·H + η_L L·H)²,"
               "  Beckmann D (energy form)")
    parameters = dielectric_parameters(0.5)
    distribution = BeckmannDistribution()
