"""Phong lobes: the original max(0,R·V)^n/(N·L) and the modified (BRDF) max(0,R·V)^n.

Seed 000 derives their albedos at normal incidence: 2π/(n+1) for the original (V = N) and 2π/(n+2) for the
modified lobe. R = 2(N·L)N − L is the mirror of L about N, so R·V = L·mirror(V): in the integrator's polar
coordinates around mirror(V) the lobe is exactly cos^n α, zero beyond α = π/2 (n > 0).
"""

from __future__ import annotations

import numpy as np

from ..parameters import Parameter
from . import closed_forms
from .base import Lobe, Model, at_normal, mirror, scalar_param

EXPONENT = Parameter("n", "float", 32.0, 0.0, None, "specular exponent")


def _r_dot_v(L: np.ndarray, V: np.ndarray) -> np.ndarray:
    return np.einsum("...i,...i->...", mirror(L), V)


def _cosine_lobe(L: np.ndarray, V: np.ndarray, n: np.ndarray) -> np.ndarray:
    # max(0, x)^n with 0^0 = 1, as C's pow and GLSL implementations give.
    return np.power(np.maximum(_r_dot_v(L, V), 0.0), n)


def _phong_lobe(fixed: np.ndarray, n: np.ndarray) -> Lobe:
    shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(n))
    width = np.broadcast_to(np.minimum(1.0, np.sqrt(2.0 / (n + 1.0))), shape)
    support = np.broadcast_to(np.where(n > 0, np.pi / 2, np.pi), shape)
    return Lobe(np.broadcast_to(mirror(fixed), shape + (3,)), width, support)


class PhongOriginal(Model):
    name = "phong"
    formula = "f = max(0, R·V)^n / (N·L),  R = 2(N·L)N − L"
    parameters = (EXPONENT,)


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        return (_cosine_lobe(L, V, scalar_param(params, "n")) / L[..., 2])[..., None]

    def projected(self, L, V, params):
        # f·(N·L) cancels exactly; computing it directly avoids 0/0 at the horizon.
        return _cosine_lobe(L, V, scalar_param(params, "n"))[..., None]

    def lobe(self, fixed, params, over):
        return _phong_lobe(fixed, scalar_param(params, "n"))

    def closed_form_albedo(self, fixed, params, over):
        n = scalar_param(params, "n")
        # Over the light at V = N: ∫cos^n = 2π/(n+1). Over the view at L = N the 1/(N·L) is 1 and the view
        # cosine remains: ∫cos^(n+1) = 2π/(n+2). The lobe is not reciprocal.
        value = (closed_forms.phong_original_albedo_normal if over == "light"
                 else closed_forms.phong_modified_albedo_normal)(n)
        return np.where(at_normal(fixed), value, np.nan)[..., None]


class PhongModified(Model):
    name = "modified-phong"
    formula = "f = max(0, R·V)^n,  R = 2(N·L)N − L"
    parameters = (EXPONENT,)


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def evaluate(self, L, V, params):
        return _cosine_lobe(L, V, scalar_param(params, "n"))[..., None]

    def lobe(self, fixed, params, over):
        return _phong_lobe(fixed, scalar_param(params, "n"))

    def closed_form_albedo(self, fixed, params, over):
        value = closed_forms.phong_modified_albedo_normal(scalar_param(params, "n"))
        return np.where(at_normal(fixed), value, np.nan)[..., None]
