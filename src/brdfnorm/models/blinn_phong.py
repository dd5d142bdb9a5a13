"""Blinn-Phong lobe f = max(0, N·H)^n with H = normalize(L + V).

Seed 000 gives its albedo at L = N (equal to V = N by reciprocity): 8π(2^(−n/2)+n)/((n+2)(n+4)). Seed 002
poses the problem for every view direction. The integrand peaks at L = mirror(V); since the half-vector
angle is about half the angle from the mirror direction, (N·H)^n ≈ exp(−nα²/8): width 2√2/√(n+1).
"""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from . import closed_forms
from .base import Lobe, Model, at_normal, mirror, scalar_param


def half_vector_cosine(L: np.ndarray, V: np.ndarray) -> np.ndarray:
    """N·H for H = normalize(L + V), clamped to [0, 1]."""
    S = L + V
    return np.clip(S[..., 2] / np.sqrt(np.einsum("...i,...i->...", S, S)), 0.0, 1.0)


class BlinnPhong(Model):
    name = "blinn-phong"
    formula = "f = max(0, N·H)^n,  H = normalize(L + V)"
    parameters = (Parameter("n", "float", 32.0, 0.0, None, "specular exponent"),)


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        return np.power(half_vector_cosine(L, V), scalar_param(params, "n"))[..., None]

    def lobe(self, fixed, params, over):
        n = scalar_param(params, "n")
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(n))
        width = np.broadcast_to(np.minimum(1.0, 2.0 * np.sqrt(2.0 / (n + 1.0))), shape)
        return Lobe(np.broadcast_to(mirror(fixed), shape + (3,)), width, np.full(shape, np.pi))

    def closed_form_albedo(self, fixed, params, over):
        value = closed_forms.blinn_phong_albedo_normal(scalar_param(params, "n"))
        return np.where(at_normal(fixed), value, np.nan)[..., None]
