"""The ``zeltner`` sheen lobe: Zeltner, Burley & Chiang 2022, "Practical Multiple-Scattering Sheen Using Linearly
Transformed Cosines" (SIGGRAPH talk), the fuzz lobe OpenPBR Surface recommends (specification, *Fuzz*).

The lobe is a linearly transformed cosine (Heitz et al. 2016) scaled by the fitted directional albedo R:

    f(L, V)·(N·L) = color · R(μ_o, r) · D(L),   D(L) = D_o(M⁻¹L/|M⁻¹L|) |M⁻¹| / |M⁻¹L|³,

in the frame (X, Y, N) with X the view's tangent direction (V − N μ_o normalized), D_o(ω) = max(ω_z, 0)/π the
clamped cosine, and M⁻¹ = [[a, 0, b], [0, a, 0], [0, 0, 1]] with the paper's rational fits a = aInv(μ_o, r),
b = bInv(μ_o, r); then |M⁻¹| = a², and with ω = M⁻¹L (unnormalized, ω_z = L_z): D(L) = max(L_z, 0)/π · (a/|ω|²)².
M⁻¹ keeps the z component, so D is a probability density over the upper hemisphere: ∫ D dL = 1 and the lobe's
albedo over the light is R(μ_o, r) exactly (:meth:`Zeltner.closed_form_albedo`; the tests integrate the lobe
against it). R is the paper's Gaussian fit to its tabulated albedo of the volumetric sheen:

    R(x, y) = exp(−½((x − m)/s)²)/(s√(2π)) + o,   x = μ_o, y = r, with s, m, o rational in y.

The coefficients are those of the paper's published fit, as MaterialX writes them (``mx_zeltner_sheen_dir_albedo``,
``mx_zeltner_sheen_ltc_aInv``, ``mx_zeltner_sheen_ltc_bInv`` in libraries/pbrlib/genglsl/lib/
mx_microfacet_sheen.glsl, Apache-2.0, read at AcademySoftwareFoundation/MaterialX 4177b2c); the code here is
written from the formulas. Roughness r ∈ [0.01, 1], the range of the original implementation (MaterialX clamps
its sampling there). The lobe is not reciprocal (M depends on the view) and does not claim energy conservation:
it is a layer whose albedo R is what the layering removes from the base (OpenPBR eq. [fuzz-layering-approx]).
The fit R is slightly negative for r ∈ [0.042, 0.132] (down to −2.11e-5 at μ_o = 0.7745, r = 0.0985: its offset
o(r) < 0 there); the lobe is reproduced as published, unclamped, as MaterialX evaluates it. The compiled kernel is
:mod:`brdfnorm.models.zeltner_native`.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter
from .base import Lobe, Model

#: The original implementation's roughness range (MaterialX clamps the sampling's roughness there too).
ROUGHNESS_MIN = 0.01


def albedo_fit(x, y) -> np.ndarray:
    """The paper's fit R(μ_o = x, r = y) of the sheen's directional albedo (``mx_zeltner_sheen_dir_albedo``)."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y))
    m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y)
    o = y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y))
    return np.exp(-0.5 * ((x - m) / s) ** 2) / (s * np.sqrt(2.0 * np.pi)) + o


def ltc_a(x, y) -> np.ndarray:
    """aInv(μ_o, r): the diagonal of M⁻¹ (``mx_zeltner_sheen_ltc_aInv``)."""
    return (2.58126 * x + 0.813703 * y) * y / (1.0 + 0.310327 * x * x + 2.60994 * x * y)


def ltc_b(x, y) -> np.ndarray:
    """bInv(μ_o, r): the (X, N) entry of M⁻¹ (``mx_zeltner_sheen_ltc_bInv``)."""
    return np.sqrt(np.maximum(1.0 - x, 0.0)) * (y - 1.0) * y ** 3 / (
        0.0000254053 + 1.71228 * x - 1.71506 * x * y + 1.34174 * y * y)


def ltc_density(L: np.ndarray, V: np.ndarray, roughness) -> np.ndarray:
    """D(L) of the view's LTC (…): a density over the upper hemisphere of L; 0 below either horizon."""
    mu_v = np.clip(V[..., 2], 0.0, 1.0)
    tangent = np.hypot(V[..., 0], V[..., 1])
    # X = the view's tangent direction; at normal incidence any (the lobe is then symmetric about N: b = 0).
    safe = np.where(tangent > 0, tangent, 1.0)
    cx, cy = np.where(tangent > 0, V[..., 0] / safe, 1.0), np.where(tangent > 0, V[..., 1] / safe, 0.0)
    lx = cx * L[..., 0] + cy * L[..., 1]
    ly = -cy * L[..., 0] + cx * L[..., 1]
    lz = L[..., 2]
    a, b = ltc_a(mu_v, roughness), ltc_b(mu_v, roughness)
    wx, wy = a * lx + b * lz, a * ly
    length2 = wx * wx + wy * wy + lz * lz
    with np.errstate(divide="ignore", invalid="ignore"):
        value = np.maximum(lz, 0.0) / np.pi * (a / length2) ** 2
    return np.where((lz > 0) & (V[..., 2] > 0) & (length2 > 0), value, 0.0)


class Zeltner(Model):
    name = "zeltner"
    formula = ("f·(N·L) = color R(μ_o, r) D_LTC(L),  D_LTC = (L_z/π)(a/|M⁻¹L|²)²,  M⁻¹ = [[a,0,b],[0,a,0],[0,0,1]] "
               "in the view's frame; R, a, b: the paper's fits")
    parameters = (
        Parameter("roughness", "float", 0.5, ROUGHNESS_MIN, 1.0, "sheen roughness r (the fits' variable)"),
        Parameter("color", "color", (1.0, 1.0, 1.0), 0.0, 1.0, "sheen colour"),
    )
    channels = 3
    energy = "a sheen layer, not a closed lobe: E(μ) = color·R(μ, r), the paper's fitted albedo (below 1)"
    closed_form_domain = "every view (over the light): color·R(μ_o, r)"

    def _check(self) -> None:
        if np.any(np.asarray(self._params["roughness"], dtype=float) < ROUGHNESS_MIN):
            raise ParameterError(f"must be ≥ {ROUGHNESS_MIN:g} (the fit's range)", where="parameter roughness")

    def native_kernel(self):
        from .zeltner_native import kernel  # Numba is imported only by the compiled backend

        return kernel()

    def projected(self, L, V, params):
        white = albedo_fit(np.clip(V[..., 2], 0.0, 1.0), params["roughness"]) * ltc_density(L, V,
                                                                                            params["roughness"])
        return white[..., None] * np.asarray(params["color"], dtype=float)

    def evaluate(self, L, V, params):
        with np.errstate(divide="ignore", invalid="ignore"):
            value = self.projected(L, V, params) / L[..., 2:3]
        return np.where(L[..., 2:3] > 0, value, 0.0)

    def lobe(self, fixed, params, over):
        """The LTC's peak lies between the normal and the backscatter direction; the hint is the normal, as wide as
        the hemisphere (the lobe is broad at every roughness of the fit's range)."""
        shape = np.broadcast_shapes(np.shape(fixed)[:-1], np.shape(params["roughness"]))
        direction = np.broadcast_to(np.array([0.0, 0.0, 1.0]), shape + (3,))
        return Lobe(direction, np.ones(shape), np.full(shape, np.pi))

    def closed_form_albedo(self, fixed, params, over):
        """color·R(μ_o, r) over the light (∫ D dL = 1); NaN over the view (the lobe is not reciprocal)."""
        fixed = np.asarray(fixed, dtype=float)
        rough = np.asarray(params["roughness"], dtype=float)
        color = np.asarray(params["color"], dtype=float)
        value = albedo_fit(np.clip(fixed[..., 2], 0.0, 1.0), rough)[..., None] * color
        if over != "light":
            value = np.full_like(value, np.nan)
        return np.where(fixed[..., 2:3] > 0, value, 0.0) if over == "light" else value


__all__ = ["Zeltner", "albedo_fit", "ltc_a", "ltc_b", "ltc_density"]
