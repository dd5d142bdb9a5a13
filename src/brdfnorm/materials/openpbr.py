"""The ``openpbr`` material: OpenPBR Surface (Andersson, Kutz, Portsmouth et al., v1.1 specification,
https://academysoftwarefoundation.github.io/OpenPBR, fetched from github.com/AcademySoftwareFoundation/OpenPBR at
f8d6d94) as a BRDF built from brdfnorm's lobes, with the parameter names and defaults of the specification's
parameter tables.

Structure (specification, *Model* → *Appendix: Mixture model*, non-thin-walled mode, with its albedo-scaling
layering eq. [non-reciprocal-albedo-scaling]):

    f_surface = F f_fuzz + lerp(1, 1 − E[f̄_fuzz], F) f_coated-base                  (fuzz, eq. [fuzz-layering-approx])
    f_coated-base = C f_coat + lerp(1, T_coat (1 − E[f_coat]), C) f_base-substrate    (coat, *Coat*)
    f_base-substrate = mix(f_dielectric-base, f_metal, M)                             (*Metal*)
    f_dielectric-base = f_specular + (1 − E[f_specular]) f_diffuse                    (*Glossy-diffuse*)

* specular: GGX, α = specular_roughness², Fresnel of the IOR ratio η'_s modulated by specular_weight (*Dielectric
  base*, eqs. [unmodulated_fresnel], [modulated_ior]: F_s = ((1 − η_s)/(1 + η_s))², ε = sgn(η_s − 1)√(ξ_s F_s),
  η'_s = (1 + ε)/(1 − ε), ξ_s clamped to [0, 1/F_s]), tinted by specular_color;
* metal: GGX with F_metal = specular_weight · F82-tint(F0 = base_weight·base_color, tint = specular_color)
  (*Metal*, [#Kutz2021]; :func:`brdfnorm.models.fresnel.f82_tint`; specular_weight clamped to 1 there, the range
  the Metal section's table gives it);
* diffuse: Lambert (base_diffuse_roughness 0) or EON (Portsmouth et al. 2025, the *Glossy-diffuse* section's
  f_diffuse), ρ = base_weight·base_color;
* coat: GGX, α = coat_roughness², exact dielectric Fresnel of coat_ior, T_coat = coat_color;
* fuzz: the specification's recommended Zeltner et al. 2022 LTC sheen (*Fuzz*; :mod:`brdfnorm.models.zeltner`,
  albedo R(μ, r) exact), fuzz_color the tint, fuzz_roughness its roughness; ``fuzz_lobe = "charlie"`` puts the
  Estevez–Kulla ``charlie`` sheen (α = fuzz_roughness²) in its place.

Coat adjustments (*Coat*; ``coat_adjustments = "spec"``, the default): the specular IOR ratio under the coat
(:func:`specular_ior_ratio`, eqs. [specular_ior_ratio], [specular_ior_ratio_with_tir_fix]), the roughening of the
specular and metal lobes (:func:`coat_roughened`, *Roughening*) and the darkening of the coated base
(:func:`darkening`, :class:`brdfnorm.materials.components.Darkening`, *Darkening*, with ``coat_darkening``).

Not modelled (documented in docs/materials.md): subsurface, thin film, the coat's view-dependent absorption,
anisotropy, emission, geometry_opacity.

``metal_ms = "kulla-conty"`` adds Kulla & Conty's multiple-scattering lobe to the metal (the white metal then passes
the furnace the specification's *White furnace testing* section lists).

Rules beyond the specification, as parameters (:mod:`brdfnorm.materials.compose`): ``layering`` (view | symmetric
| reciprocal), ``base_mix`` (brdf | f0-blend), ``diffuse_under`` (albedo-scaling | filament), ``metal_fresnel``
(f82-tint | schlick | artistic | conductor with metal_eta, metal_k), ``dielectric_fresnel`` (exact | schlick),
``coat_fresnel`` (dielectric | none: F = 1, the furnace's coat), ``fuzz_shadowing`` and ``albedo_source`` (exact
| table with ``albedo_table`` N).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..models.dielectric import ETA_MATCH
from ..models.fresnel import COAT_KINDS, METAL_KINDS, Fresnel, multiple_scattering_colour
from ..parameters import Parameter
from . import compose
from .albedo import top_average
from .components import Darkening, Diffuse, LTCSheen, Microfacet, Sheen, Transmission
from .compose import Term, layer, lobe, mix
from .terms import term_albedo

#: Tolerance of the base's normal-incidence albedo E_b in the coat's darkening.
BASE_ALBEDO_RTOL = 1e-12

_C = "color"

PARAMETERS = (
    Parameter("base_weight", "float", 1.0, 0.0, 1.0, "scalar multiplier of base_color"),
    Parameter("base_color", _C, (0.8, 0.8, 0.8), 0.0, 1.0, "diffuse albedo; the metal's F0"),
    Parameter("base_metalness", "float", 0.0, 0.0, 1.0, "mix weight of the metal (M)"),
    Parameter("base_diffuse_roughness", "float", 0.0, 0.0, 1.0, "EON roughness of the diffuse lobe (0: Lambert)"),
    Parameter("specular_weight", "float", 1.0, 0.0, 1e3, "modulates the dielectric F0 (clamped to 1/F_s); scales "
              "the metal's Fresnel"),
    Parameter("specular_color", _C, (1.0, 1.0, 1.0), 0.0, 1.0, "tints the dielectric Fresnel; the metal's F82 tint"),
    Parameter("specular_roughness", "float", 0.3, 0.0, 1.0, "roughness r of the GGX specular and metal (α = r²)"),
    Parameter("specular_ior", "float", 1.5, 1e-3, 1e3, "refractive index of the dielectric base"),
    Parameter("transmission_weight", "float", 0.0, 0.0, 1.0, "mix weight T of the translucent base (refraction)"),
    Parameter("transmission_color", _C, (1.0, 1.0, 1.0), 0.0, 1.0, "tint of the refraction (transmission_depth 0)"),
    Parameter("transmission_depth", "float", 0.0, 0.0, 1e6, "distance at which white light becomes "
              "transmission_color inside the medium (0: the colour tints the refraction instead)"),
    Parameter("geometry_thin_walled", "bool", False, description="thin-walled mode (with transmission: not "
              "modelled)"),
    Parameter("coat_weight", "float", 0.0, 0.0, 1.0, "coverage C of the coat"),
    Parameter("coat_color", _C, (1.0, 1.0, 1.0), 0.0, 1.0, "T_coat: the coat's transmittance squared"),
    Parameter("coat_roughness", "float", 0.0, 0.0, 1.0, "roughness of the GGX coat (α = r²)"),
    Parameter("coat_ior", "float", 1.6, 1e-3, 1e3, "refractive index of the coat"),
    Parameter("coat_darkening", "float", 1.0, 0.0, 1.0, "modulates the coat's darkening of the base (δ; 0: none)"),
    Parameter("fuzz_weight", "float", 0.0, 0.0, 1.0, "coverage F of the fuzz"),
    Parameter("fuzz_color", _C, (1.0, 1.0, 1.0), 0.0, 1.0, "tint of the fuzz lobe"),
    Parameter("fuzz_roughness", "float", 0.5, 0.0, 1.0, "roughness of the fuzz (zeltner: r ≥ 0.01; charlie: α = r²)"),
    Parameter("layering", "choice", "view", choices=compose.LAYERING,
              description="albedo scaling: view (1−E(ωo)), symmetric (1−E(ωi))(1−E(ωo)), reciprocal (…)/(1−E_avg)"),
    Parameter("base_mix", "choice", "brdf", choices=("brdf", "f0-blend"),
              description="metalness: mix the dielectric and metal BRDFs, or blend F0 into one Schlick lobe"),
    Parameter("diffuse_under", "choice", "albedo-scaling", choices=("albedo-scaling", "filament"),
              description="diffuse under the specular: scaled by 1 − E_spec (OpenPBR) or added as is (Filament)"),
    Parameter("metal_fresnel", "choice", "f82-tint", choices=METAL_KINDS,
              description="the metal's Fresnel: OpenPBR's F82-tint, Schlick(F0), Gulbrandsen (r, g), or eta + ik"),
    Parameter("metal_eta", "spectrum", (0.143, 0.374, 1.442), 1e-3, 1e3, "conductor η (metal_fresnel=conductor)"),
    Parameter("metal_k", "spectrum", (3.983, 2.385, 1.603), 0.0, 1e3, "conductor k (metal_fresnel=conductor)"),
    Parameter("metal_ms", "choice", "none", choices=("none", "kulla-conty"),
              description="the metal's multiple scattering: none, or Kulla-Conty's lobe with the exact F_avg"),
    Parameter("dielectric_fresnel", "choice", "exact", choices=("exact", "schlick"),
              description="the specular's Fresnel: exact dielectric of η'_s, or Schlick of its F0"),
    Parameter("coat_adjustments", "choice", "spec", choices=("spec", "spec-no-tir-fix", "none"),
              description="the coat's darkening, roughening and IOR ratio under it as the specification gives them "
                          "(spec-no-tir-fix: without inverting a denser coat's ratio), or none of them"),
    Parameter("coat_fresnel", "choice", "dielectric", choices=COAT_KINDS,
              description="the coat's Fresnel: exact dielectric of coat_ior, or none (F = 1)"),
    Parameter("fuzz_lobe", "choice", "zeltner", choices=("zeltner", "charlie"),
              description="the fuzz lobe: Zeltner et al. 2022's LTC sheen (the specification's), or charlie"),
    Parameter("fuzz_shadowing", "choice", "kulla", choices=("kulla", "neubelt"),
              description="the charlie sheen's shadowing (fuzz_lobe=charlie)"),
    Parameter("albedo_source", "choice", "exact", choices=("exact", "table"),
              description="E of the top lobes: exact integrals, or an engine's N×N (μ, roughness) bilinear table"),
    Parameter("albedo_table", "int", 32, 2.0, 1024.0, "table size N (albedo_source=table)"),
)


def modulated_ior(ior: float, weight: float) -> float:
    """η'_s of OpenPBR eq. [modulated_ior]: the IOR whose F0 is ξ_s F_s, ξ_s clamped to [0, 1/F_s]."""
    f_s = ((1.0 - ior) / (1.0 + ior)) ** 2
    if f_s == 0.0:
        return ior
    xi = min(max(weight, 0.0), 1.0 / f_s)
    epsilon = np.sign(ior - 1.0) * np.sqrt(xi * f_s)
    if epsilon >= 1.0:  # F0 = 1: a perfect mirror's index
        return np.inf
    return float((1.0 + epsilon) / (1.0 - epsilon))


def _colour(value) -> np.ndarray:
    return np.broadcast_to(np.asarray(value, dtype=float), (3,)).astype(float)


def metal_fresnel(p: dict) -> Fresnel:
    f0 = p["base_weight"] * _colour(p["base_color"])
    tint = _colour(p["specular_color"])
    kind = p["metal_fresnel"]
    if kind == "f82-tint":
        return Fresnel("f82-tint", f0=f0, tint=tint)
    if kind == "schlick":
        return Fresnel("schlick", f0=f0)
    if kind == "artistic":
        return Fresnel("artistic", r=np.minimum(f0, 1.0 - 1e-9), g=tint)
    return Fresnel("conductor", eta=_colour(p["metal_eta"]), k=_colour(p["metal_k"]))


def specular_ior_ratio(p: dict) -> float:
    """η_s, the specular IOR over its surroundings' (*Coat*, eq. [specular_ior_ratio]): lerp(n_b/n_a, n_b/n_c, C)
    with n_a = 1, the coat-base ratio inverted where the coat is denser (eq. [specular_ior_ratio_with_tir_fix]) under
    ``coat_adjustments = "spec"``; n_b alone (the coat ignored) under ``"none"``."""
    n_b, n_c, coverage = float(p["specular_ior"]), float(p["coat_ior"]), float(p["coat_weight"])
    if p["coat_adjustments"] == "none" or coverage == 0.0:
        return n_b
    eta_bc = n_c / n_b if (p["coat_adjustments"] == "spec" and n_c > n_b) else n_b / n_c
    return n_b + (eta_bc - n_b) * coverage


def coat_roughened(p: dict) -> float:
    """r'_B = lerp(r_B, min(1, r_B⁴ + 2 r_C⁴)^¼, C) (*Coat* → *Roughening*), r_B = specular_roughness,
    r_C = coat_roughness; r_B itself under ``coat_adjustments = "none"``."""
    r_b, r_c, coverage = float(p["specular_roughness"]), float(p["coat_roughness"]), float(p["coat_weight"])
    if p["coat_adjustments"] == "none":
        return r_b
    return r_b + (min(1.0, r_b**4 + 2.0 * r_c**4) ** 0.25 - r_b) * coverage


def dielectric_f0(p: dict) -> float:
    """ξ_s F_s clamped to [0, 1]: the F0 of the modulated IOR η'_s (eq. [modulated_ior]) of η_s."""
    eta = modulated_ior(specular_ior_ratio(p), float(p["specular_weight"]))
    return 1.0 if np.isinf(eta) else ((eta - 1.0) / (eta + 1.0)) ** 2


def darkening(p: dict, substrate: list[Term], source: str, size: int) -> Darkening | None:
    """The coat's darkening factor of the base (:class:`Darkening`) with E_b the base substrate's exact albedo at
    normal incidence (reflected plus transmitted: the energy the base does not absorb, so that a white translucent
    base under a clear coat passes the specification's white furnace) and r_b = lerp(r_d, r_m, M)
    (eq. [base_roughness_estimate]), r_d = lerp(1, r, ξ_s F_s) (eq. [dielectric_roughness_estimate]),
    r_m = r = specular_roughness; None where it does nothing (no coat,
    ``coat_darkening = 0``, ``coat_adjustments = "none"``, or the furnace's coat with F = 1, whose K = 1)."""
    delta = float(p["coat_darkening"])
    if (p["coat_adjustments"] == "none" or float(p["coat_weight"]) == 0.0 or delta == 0.0
            or p["coat_fresnel"] != "dielectric" or float(p["coat_ior"]) == 1.0):
        return None
    e_b = np.zeros(3)
    for term in substrate:  # what the base does not absorb, transmitted light included (a lossless base: Δ = 1)
        e_b += term_albedo(term, np.array([1.0]), source, size, BASE_ALBEDO_RTOL)[0][0]
    r = float(p["specular_roughness"])
    r_d = 1.0 + (r - 1.0) * min(max(dielectric_f0(p), 0.0), 1.0)
    r_b = r_d + (r - r_d) * float(p["base_metalness"])
    return Darkening("coat-darkening", float(p["coat_ior"]), tuple(e_b), r_b, delta, p["layering"] != "view")


def compensation(metal: Microfacet, source: str, size: int) -> list[Term]:
    """Kulla & Conty 2017's multiple-scattering lobe of a GGX metal as one term: F_ms (1 − E(μ_i))(1 − E(μ_o)) /
    (π(1 − E_avg)), E the white lobe's albedo (exact, or the table), F_ms = F_avg² E_avg/(1 − F_avg(1 − E_avg)) with
    the metal's exact F_avg (:mod:`brdfnorm.models.fresnel`), times its tint."""
    white = Microfacet("metal-white", metal.roughness)
    e_avg = top_average(white, source, size)
    f_avg = metal.fresnel.average()[0] * np.asarray(metal.tint, dtype=float)
    lost = 1.0 - e_avg
    if np.all(lost <= 0):
        return []
    rho = multiple_scattering_colour(f_avg, e_avg) / lost
    return [Term(Diffuse("metal-ms", tuple(np.broadcast_to(rho, (3,)))), np.ones(3), (white,), (white,))]


def check_transmission(p: dict) -> None:
    """Refuse the translucent base where it is not modelled (one material's scalar parameters)."""
    if float(p["transmission_weight"]) <= 0:
        return
    where = "parameter transmission_weight"
    if p["geometry_thin_walled"]:
        raise ParameterError("thin-walled transmission (a thin sheet's inter-reflections) is not modelled; use "
                             "geometry_thin_walled=0", where=where)
    if p["base_mix"] != "brdf" or p["dielectric_fresnel"] != "exact":
        raise ParameterError("transmission needs base_mix=brdf and dielectric_fresnel=exact (the refraction is the "
                             "rough dielectric's, with its exact Fresnel)", where=where)
    eta = modulated_ior(specular_ior_ratio(p), float(p["specular_weight"]))
    if abs(eta - 1.0) < ETA_MATCH:
        raise ParameterError(f"the specular IOR ratio η'_s = {eta:.9g} is index-matched: the transmission is a "
                             "delta straight through, not a lobe", where=where)


def build(p: dict) -> list[Term]:
    """The terms of one material (scalar parameter values ``p``)."""
    check_transmission(p)
    source, size = p["albedo_source"], int(p["albedo_table"])
    rule = p["layering"]
    r_spec = coat_roughened(p)
    rho = p["base_weight"] * _colour(p["base_color"])
    diffuse = lobe(Diffuse("diffuse", tuple(rho), float(p["base_diffuse_roughness"])))
    metalness = float(p["base_metalness"])
    spec_tint = tuple(_colour(p["specular_color"]))
    if p["dielectric_fresnel"] == "exact":
        eta = modulated_ior(specular_ior_ratio(p), float(p["specular_weight"]))
        dielectric_f = Fresnel("dielectric", eta=eta) if np.isfinite(eta) else Fresnel("none")
    else:
        dielectric_f = Fresnel("schlick", f0=dielectric_f0(p))
    # F_metal = specular_weight · F82 with specular_weight in [0, 1] (the Metal section's table): clamped at 1.
    metal = Microfacet("metal", r_spec, metal_fresnel(p), (min(float(p["specular_weight"]), 1.0),) * 3)

    def under(spec: Microfacet, base: list[Term]) -> list[Term]:
        if spec.fresnel.kind == "dielectric" and spec.fresnel.eta == 1.0:  # specular_weight 0: no interface
            return base
        if p["diffuse_under"] == "filament":
            return lobe(spec) + base
        return layer(lobe(spec), base, spec, rule, source=source, size=size)

    if p["base_mix"] == "brdf":
        specular = Microfacet("specular", r_spec, dielectric_f, spec_tint)
        metal_terms = lobe(metal) + (compensation(metal, source, size) if p["metal_ms"] == "kulla-conty" else [])
        dielectric = under(specular, diffuse) if metalness < 1 else []
        weight = float(p["transmission_weight"])
        if weight > 0 and metalness < 1 and dielectric_f.kind == "dielectric":
            # *Translucent base*: the interface's own BSDF, f^R_specular + f^T (transmission_color tints f^T at
            # transmission_depth 0; a medium of depth > 0 absorbs inside the object, beyond the surface's albedo)
            tint = tuple(_colour(p["transmission_color"])) if float(p["transmission_depth"]) == 0 else (1.0,) * 3
            translucent = lobe(specular) + lobe(Transmission("transmission", r_spec, float(dielectric_f.eta), tint))
            dielectric = mix(dielectric, translucent, weight)
        substrate = mix(dielectric, metal_terms if metalness > 0 else [], metalness)
    else:
        # One Schlick lobe, F0 = lerp(F0_dielectric · specular_color, F0_metal, M), over (1 − M) × diffuse.
        f0 = (1.0 - metalness) * dielectric_f0(p) * np.asarray(spec_tint) + metalness * rho
        blended = Microfacet("specular", r_spec, Fresnel("schlick", f0=f0))
        substrate = under(blended, [t.scaled(1.0 - metalness) for t in diffuse] if metalness < 1 else [])
    coat_f = Fresnel("dielectric", eta=float(p["coat_ior"])) if p["coat_fresnel"] == "dielectric" else Fresnel("none")
    coat = Microfacet("coat", float(p["coat_roughness"]), coat_f)
    coated = layer(lobe(coat), substrate, coat, rule, coverage=float(p["coat_weight"]), tint=p["coat_color"],
                   source=source, size=size, darkening=darkening(p, substrate, source, size))
    r_fuzz, fuzz_colour = float(p["fuzz_roughness"]), tuple(_colour(p["fuzz_color"]))
    if p["fuzz_lobe"] == "zeltner":
        fuzz_white, fuzz = LTCSheen("fuzz", (1.0, 1.0, 1.0), r_fuzz), LTCSheen("fuzz", fuzz_colour, r_fuzz)
    else:
        fuzz_white = Sheen("fuzz", (1.0, 1.0, 1.0), r_fuzz, p["fuzz_shadowing"])
        fuzz = Sheen("fuzz", fuzz_colour, r_fuzz, p["fuzz_shadowing"])
    return layer(lobe(fuzz), coated, fuzz_white, rule, coverage=float(p["fuzz_weight"]), source=source, size=size)
