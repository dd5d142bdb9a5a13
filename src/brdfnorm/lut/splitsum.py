"""The split-sum ("DFG") weightings of a lobe (Karis 2013): the coefficients of f0 and f90 in Schlick's Fresnel,
∫ f cos (1 − (1 − V·H)⁵) dL and ∫ f cos (1 − V·H)⁵ dL, as models that :mod:`.table` tabulates like any other."""

from __future__ import annotations

import numpy as np

from ..errors import ArgumentError
from ..models.base import Model


class SchlickWeighted(Model):
    """A model's lobe times a split-sum weight of V·H: 1 − (1 − V·H)⁵ (``f0``) or (1 − V·H)⁵ (``f90``).

    V·H = √((1 + L·V)/2) for H = normalize(L + V). Keeps the base model's parameters and lobe hint.
    """

    def __init__(self, base: Model, term: str) -> None:  # noqa: D107 — binds to the base's values
        if term not in ("f0", "f90"):
            raise ArgumentError(f"unknown split-sum term {term!r}", where="channels")
        self.base = base
        self.term = term
        self.name = f"{base.name}·schlick-{term}"
        self.parameters = base.parameters
        self.channels = base.channels
        self.isotropic = base.isotropic
        self._params = dict(base.params)

    def _weight(self, L: np.ndarray, V: np.ndarray) -> np.ndarray:
        cos_vh = np.sqrt(np.clip(0.5 * (1.0 + np.einsum("...i,...i->...", L, V)), 0.0, 1.0))
        tail = (1.0 - cos_vh) ** 5
        return (1.0 - tail if self.term == "f0" else tail)[..., None]

    def evaluate(self, L, V, params):
        return self.base.evaluate(L, V, params) * self._weight(L, V)

    def projected(self, L, V, params):
        return self.base.projected(L, V, params) * self._weight(L, V)

    def lobe(self, fixed, params, over):
        return self.base.lobe(fixed, params, over)


#: The split-sum tables' names: the DFG term that multiplies f0, and the one that multiplies f90.
DFG_F0, DFG_F90 = "DFG_f0", "DFG_f90"


def split_sum_models(model: Model) -> tuple[dict[str, Model], str]:
    """The two DFG models (coefficient of f0, of f90) and how they were made (recorded in the table's meta)."""
    names = {p.name for p in model.parameters}
    if {"fresnel", "f0", "f90"} <= names:
        return ({DFG_F0: model.with_params(fresnel="schlick", f0=1.0, f90=0.0),
                 DFG_F90: model.with_params(fresnel="schlick", f0=0.0, f90=1.0)},
                "the model's own fresnel=schlick with (f0, f90) = (1, 0) and (0, 1)")
    return ({DFG_F0: SchlickWeighted(model, "f0"), DFG_F90: SchlickWeighted(model, "f90")},
            "the model as given times 1 - (1 - V.H)^5 and (1 - V.H)^5; its own Fresnel must be off")
