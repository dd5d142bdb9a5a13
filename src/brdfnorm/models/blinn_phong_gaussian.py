"""Seed 003's Blinn-Phong lobe with Gaussian falloff (a BRDF Explorer shader), unnormalized.

f = exp(−((N·H − 1)/(c − 1))²) with c = 0.04^(1/n): the cosine at which the plain lobe (N·H)^n falls to the
threshold 0.04. Seed 003 fitted its normalization as 0.17287429 + 0.01388682·n; no closed form is known.
Near the peak N·H − 1 ≈ −α²/8 (α from the mirror direction), so f ≈ exp(−(α²/(8(1−c)))²): width √(8(1−c)).
"""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from .base import Lobe, Model, mirror, scalar_param
from .blinn_phong import half_vector_cosine

THRESHOLD = 0.04  # seed 003: "float Threshold = 0.04"


def threshold_cosine(n: np.ndarray) -> np.ndarray:
    """c = 0.04^(1/n), with the n → 0 limit c = 0."""
    n = np.asarray(n, dtype=float)
    with np.errstate(divide="ignore"):
        return np.where(n > 0, np.power(THRESHOLD, 1.0 / np.where(n > 0, n, 1.0)), 0.0)


class BlinnPhongGaussian(Model):
    name = "blinn-phong-gaussian"
    formula = "f = exp(−((N·H − 1)/(c − 1))²),  c = 0.04^(1/n)  (seed 003, unnormalized)"
    parameters = (Parameter("n", "float", 100.0, 0.0, None, "Blinn-Phong specular power"),)


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        c = threshold_cosine(scalar_param(params, "n"))
        angle = (half_vector_cosine(L, V) - 1.0) / (c - 1.0)
        return np.exp(-angle * angle)[..., None]

    def lobe(self, fixed, params, over):
        c = threshold_cosine(scalar_param(params, "n"))
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(c))
        width = np.broadcast_to(np.minimum(1.0, np.sqrt(8.0 * (1.0 - c))), shape)
        return Lobe(np.broadcast_to(mirror(fixed), shape + (3,)), width, np.full(shape, np.pi))
