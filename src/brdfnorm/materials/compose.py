"""Composition rules: a material's BRDF as a sum of terms, each a lobe times albedo-scaling factors.

Every rule the standards use is linear in the lobes, so a material is the sum

    f(L, V) = Σ_k w_k · Π_{t ∈ view_k} (1 − E_t(μ_o)) · Π_{t ∈ light_k} (1 − E_t(μ_i)) · f_k(L, V),

with constant colour weights w_k, and E_t the directional albedo of a top lobe t (:mod:`brdfnorm.materials.albedo`).
The rules (OpenPBR Surface specification, https://academysoftwarefoundation.github.io/OpenPBR, section *Formalism*,
subsections *Layering* and *Mixing*, and its *Model* sections):

* **mix** (``mix``): M(A, B, w) = (1 − w) A + w B, the statistical mixture (OpenPBR *Mixing*; the metalness mix
  M_base-substrate = mix(M_dielectric-base, S_metal, base_metalness), section *Metal*).
* **layer** (``layer``) — the albedo-scaling approximation of a slab over a substrate, coverage C and tint T:
    - ``view`` — f = C f_top + lerp(1, T (1 − E_top(ω_o)), C) f_sub: OpenPBR eq. [non-reciprocal-albedo-scaling]
      (with T: eq. [non-reciprocal-albedo-scaling-with-T]; with C: the *Coat* section's f_weighted-layer),
      Autodesk Standard Surface's layering (Georgiev et al. 2019), openpbr-bsdf's default since its PR #30;
    - ``symmetric`` — (1 − E_top(ω_i))(1 − E_top(ω_o)) in place of (1 − E_top(ω_o)): openpbr-bsdf's
      ``OPENPBR_RECIPROCAL_COAT_AND_FUZZ`` (reciprocal, loses energy);
    - ``reciprocal`` — (1 − E_top(ω_i))(1 − E_top(ω_o)) / (1 − E_top,avg): the Kelemen / Ashikhmin–Shirley /
      Kulla–Conty normalized form (OpenPBR *Glossy-diffuse*, the 𝒩 of its reciprocal equation, exact for a
      Lambertian substrate).
  The fuzz is layered with its white lobe's albedo (OpenPBR eq. [fuzz-layering-approx]: the tint in f_fuzz only).
* **diffuse under a specular interface**: ``albedo-scaling`` — OpenPBR *Glossy-diffuse* f_dielectric +
  (1 − E_dielectric) f_diffuse, by the ``layering`` rule above; ``filament`` — Filament's standard model, the
  diffuse lobe added unattenuated (f_spec + f_diffuse; Filament #10140 discusses attenuating it).
* A lobe that **transmits** (the translucent base's refraction, :class:`brdfnorm.materials.components.Transmission`)
  takes every layer's view-side factor only: its light arrives from inside the object and crosses the layers above
  once, on the way to the view, so neither a light-side factor nor the reciprocal form's 1/(1 − E_avg) applies, nor
  the coat's darkening (which assumes that what the base does not reflect it absorbs).
* **F0 blend** (``base_mix = "f0-blend"``): the engines' shortcut — one Schlick specular lobe whose F0 is
  lerp(F0_dielectric, base colour, metalness), over (1 − metalness) × diffuse by the ``layering`` rule — for
  comparison with the BRDF mix (bevy #24246, three.js #32190).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from .albedo import top_albedo, top_average
from .components import Component

LAYERING = ("view", "symmetric", "reciprocal")


@dataclass(frozen=True)
class Term:
    """w · Π_view (1 − E_t(μ_o)) · Π_light (1 − E_t(μ_i)) · f(L, V)."""

    component: Component
    weight: np.ndarray  # (3,)
    view: tuple[Component, ...] = ()
    light: tuple[Component, ...] = ()

    def scaled(self, factor) -> Term:
        return replace(self, weight=self.weight * np.asarray(factor, dtype=float))


def lobe(component: Component, weight=1.0) -> list[Term]:
    return [Term(component, np.broadcast_to(np.asarray(weight, dtype=float), (3,)).copy())]


def mix(a: Sequence[Term], b: Sequence[Term], w: float) -> list[Term]:
    """(1 − w) A + w B, dropping a side of weight 0."""
    out = [t.scaled(1.0 - w) for t in a] if w < 1 else []
    return out + ([t.scaled(w) for t in b] if w > 0 else [])


def layer(top: Sequence[Term], sub: Sequence[Term], attenuator: Component, rule: str, *, coverage: float = 1.0,
          tint=1.0, source: str = "exact", size: int = 32, darkening: Component | None = None) -> list[Term]:
    """C·top + lerp(1, T·A·B, C)·sub with A the rule's albedo-scaling factor of ``attenuator`` (see the module
    docstring) and B = 1 − E_darkening(μ_o) a further view-side factor of the covered part (the coat's darkening,
    :class:`brdfnorm.materials.components.Darkening`); the reciprocal form's 1/(1 − E_avg) is folded into the
    weight."""
    if coverage <= 0:
        return list(sub)
    out = [t.scaled(coverage) for t in top]
    if coverage < 1:
        out += [t.scaled(1.0 - coverage) for t in sub]
    plain = coverage * np.broadcast_to(np.asarray(tint, dtype=float), (3,))
    factor = plain
    if rule == "reciprocal":
        lost = 1.0 - top_average(attenuator, source, size)
        factor = factor * np.where(lost > 0, 1.0 / np.where(lost > 0, lost, 1.0), 0.0)
    for t in sub:
        if t.component.transmits:  # light from the other side crosses the layer once, on the view's side
            out.append(replace(t.scaled(plain), view=t.view + (attenuator,)))
            continue
        view = t.view + (attenuator,) + ((darkening,) if darkening is not None else ())
        light = t.light + ((attenuator,) if rule != "view" else ())
        out.append(replace(t.scaled(factor), view=view, light=light))
    return out


def _factors(tops: tuple[Component, ...], mu: np.ndarray, source: str, size: int) -> np.ndarray | float:
    value = 1.0
    for top in tops:
        value = value * (1.0 - top_albedo(top, mu, source, size))
    return value


def evaluate_terms(terms: Sequence[Term], L: np.ndarray, V: np.ndarray, source: str, size: int) -> np.ndarray:
    """Σ of the terms' f·(N·L) at directions (…, 3): (…, 3). Each lobe is evaluated once, each factor once."""
    shape = np.broadcast_shapes(L.shape[:-1], V.shape[:-1])
    total = np.zeros(shape + (3,))
    lobes: dict[int, np.ndarray] = {}
    factors: dict[tuple, np.ndarray] = {}
    mu_o = np.broadcast_to(V[..., 2], shape)
    mu_i = np.broadcast_to(L[..., 2], shape)
    for term in terms:
        if not np.any(term.weight):
            continue
        key = id(term.component)
        if key not in lobes:
            lobes[key] = term.component.projected(L, V)
        value = lobes[key] * term.weight
        for side, tops, mu in (("o", term.view, mu_o), ("i", term.light, mu_i)):
            if tops:
                fkey = (side, tuple(id(t) for t in tops))
                if fkey not in factors:
                    factors[fkey] = _factors(tops, np.maximum(mu, 0.0), source, size)
                value = value * factors[fkey]
        total += value
    return total
