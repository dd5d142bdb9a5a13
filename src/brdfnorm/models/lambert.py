"""Lambertian lobe f = reflectance/π; its albedo is the reflectance at every direction."""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from .base import Model, normal_lobe, scalar_param


class Lambert(Model):
    name = "lambert"
    formula = "f = reflectance / π"
    energy = "conserved (E = reflectance)"
    closed_form_domain = "every direction"
    parameters = (Parameter("reflectance", "float", 1.0, 0.0, 1.0, "diffuse reflectance (albedo)"),)


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        rho = scalar_param(params, "reflectance")
        shape = np.broadcast_shapes(L.shape[:-1], V.shape[:-1], np.shape(rho))
        return np.broadcast_to(rho / np.pi, shape)[..., None] * np.ones(1)

    def lobe(self, fixed, params, over):
        return normal_lobe(fixed)

    def closed_form_albedo(self, fixed, params, over):
        rho = scalar_param(params, "reflectance")
        return np.broadcast_to(rho, np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(rho)))[..., None] * 1.0
