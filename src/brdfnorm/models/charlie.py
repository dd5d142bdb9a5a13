"""The ``charlie`` sheen lobe: Estevez & Kulla 2017, "Production Friendly Microfacet Sheen BRDF" (SIGGRAPH talk).

A microfacet BRDF f = color · D(H) G2(L, V) / (4 N·L N·V) (their eq. 1, F = 1) over the "Charlie" distribution of
fibre-like normals (eq. 2):

    D(H) = (2 + 1/α) sin^{1/α}θ_H / (2π),        ∫ D(H) cos θ_H dω_H = 1 for every α,

(with x = sin²θ_H, ∫₀^{π/2} sin^{1/α+1}θ cos θ dθ = 1/(1/α + 2)). Shadowing, parameter ``shadowing``:

* ``kulla`` — the paper's fitted Smith Λ (its §3): L(x) = a/(1 + b x^c) + d x + e with (a, b, c, d, e) interpolated
  between the fits at α = 0 (25.3245, 3.32435, 0.16801, −1.27393, −4.85967) and α = 1 (21.5473, 3.82987, 0.19823,
  −1.97760, −4.32054) by t = (1 − α)²; Λ(μ) = exp(L(μ)) for μ < ½ and exp(2L(½) − L(1 − μ)) above, and the
  height-correlated G2 = 1/(1 + Λ(V) + Λ(L)). With ``terminator=1`` the paper's non-physical terminator softening
  Λ(μ)^{1 + 2(1 − μ)⁸} is applied to the light's term Λ(L) only — the lobe is then not reciprocal (``check``
  reports it). This softening is written from the paper's description, not checked against its code.
* ``neubelt`` — the visibility of Neubelt & Pettineo 2013 (after Ashikhmin & Premože 2007) that glTF
  (KHR_materials_sheen) and Filament use: D·V with V = 1/(4(N·L + N·V − N·L N·V)) replacing G2/(4 N·L N·V).

Parameters: ``roughness`` r with α = r² (the glTF sheen extension's mapping), or ``alpha`` directly (0, the
default, means r²); ``color`` (the sheen colour, three channels). Energy: the sheen lobe alone reflects far less
than 1 (it is a layer over a base); it does not claim energy conservation (``brdfnorm check`` measures it).
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..parameters import Parameter
from .base import Model

#: The paper's Λ fit at α = 0 and α = 1 (coefficients a, b, c, d, e of L(x) = a/(1 + b x^c) + d x + e).
LAMBDA_FIT_0 = np.array([25.3245, 3.32435, 0.16801, -1.27393, -4.85967])
LAMBDA_FIT_1 = np.array([21.5473, 3.82987, 0.19823, -1.97760, -4.32054])
#: Smallest α: below it sin^{1/α} underflows over most of the hemisphere (the lobe is a grazing delta).
ALPHA_MIN = 1e-3
SHADOWING = ("kulla", "neubelt")


def sheen_alpha(params) -> np.ndarray:
    """α: ``alpha`` where given (non-zero), roughness² otherwise."""
    alpha = np.asarray(params["alpha"], dtype=float)
    rough = np.asarray(params["roughness"], dtype=float)
    return np.where(alpha > 0, alpha, rough * rough)


def charlie_distribution(cos_h: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    """D(H) = (2 + 1/α) sin^{1/α}θ_H / (2π), from cos θ_H (sin²θ_H = 1 − cos², raised to 1/(2α))."""
    sin2 = np.clip(1.0 - cos_h * cos_h, 0.0, 1.0)
    inv = 1.0 / alpha
    return (2.0 + inv) * np.power(sin2, 0.5 * inv) / (2.0 * np.pi)


def _fit(x: np.ndarray, alpha: np.ndarray) -> np.ndarray:
    t = (1.0 - alpha) ** 2
    a, b, c, d, e = (t * p0 + (1.0 - t) * p1 for p0, p1 in zip(LAMBDA_FIT_0, LAMBDA_FIT_1, strict=True))
    return a / (1.0 + b * np.power(x, c)) + d * x + e


def charlie_lambda(mu: np.ndarray, alpha: np.ndarray, soften=False) -> np.ndarray:
    """The paper's fitted Λ(μ) (μ = cos θ ∈ (0, 1]), raised to 1 + 2(1 − μ)⁸ where ``soften`` (terminator)."""
    mu = np.clip(mu, 0.0, 1.0)
    with np.errstate(divide="ignore", over="ignore"):
        low = np.exp(_fit(mu, alpha))
        high = np.exp(2.0 * _fit(0.5, alpha) - _fit(1.0 - mu, alpha))
    value = np.where(mu < 0.5, low, high)
    soften = np.asarray(soften, dtype=bool)
    if np.any(soften):
        value = np.where(soften, np.power(value, 1.0 + 2.0 * (1.0 - mu) ** 8), value)
    return value


class Charlie(Model):
    name = "charlie"
    formula = ("f = color D G2 / (4 N·L N·V),  D = (2 + 1/α) sin^(1/α)θ_H / (2π),  G2 = 1/(1+Λ(L)+Λ(V)) (fitted Λ) "
               "or D/(4(N·L + N·V − N·L N·V)) (neubelt); α = roughness²")
    parameters = (
        Parameter("roughness", "float", 0.5, 0.0, 1.0, "sheen roughness r (α = r²)"),
        Parameter("alpha", "float", 0.0, 0.0, 1.0, "distribution width α (0: roughness²)"),
        Parameter("color", "color", (1.0, 1.0, 1.0), 0.0, 1.0, "sheen colour"),
        Parameter("shadowing", "choice", "kulla", choices=SHADOWING,
                  description="kulla: the paper's fitted Λ; neubelt: V = 1/(4(N·L+N·V−N·L N·V))"),
        Parameter("terminator", "bool", False, description="kulla only: soften Λ(L) to Λ^(1+2(1−N·L)^8)"),
    )
    channels = 3
    #: The smallest α the lobe takes (its ``alpha`` parameter declares 0 as "use roughness²"): tables and audits
    #: evaluate narrower cells here.
    alpha_min = ALPHA_MIN
    energy = ("a sheen layer, not a closed lobe; gains energy at grazing views at low roughness (89.9°, r = 0.1: "
              "2.13 kulla, 3.80 neubelt; r = 0.2: 1.18, 1.99; neubelt still 1.09 at r = 0.4)")

    def _check(self) -> None:
        # (1 − 1e-12): the search's lower end √ALPHA_MIN squares back to ALPHA_MIN only within rounding
        if np.any(sheen_alpha(self._params) < ALPHA_MIN * (1.0 - 1e-12)):
            raise ParameterError(f"the sheen width α (alpha, or roughness²) must be ≥ {ALPHA_MIN:g}",
                                 where="parameter roughness")

    def search_space(self) -> dict[str, tuple[float, float] | None]:
        """``check`` searches the roughness (from √ALPHA_MIN) and holds ``alpha`` (0 means roughness²)."""
        return {"alpha": None, "roughness": (float(np.sqrt(ALPHA_MIN)), 1.0)}


    def native_kernel(self):
        from .native import kernel_of  # Numba is imported only by the compiled backend

        return kernel_of(self)
    def _white(self, L: np.ndarray, V: np.ndarray, params) -> np.ndarray:
        """D·G2/(4 N·V): f·(N·L) of the white lobe, (...); 0 below either horizon."""
        alpha = sheen_alpha(params)
        mu_l, mu_v = L[..., 2], V[..., 2]
        S = L + V
        with np.errstate(divide="ignore", invalid="ignore"):
            cos_h = S[..., 2] / np.sqrt(np.einsum("...i,...i->...", S, S))
            D = charlie_distribution(cos_h, alpha)
            if params["shadowing"] == "neubelt":
                value = D * mu_l / (4.0 * (mu_l + mu_v - mu_l * mu_v))
            else:
                lam_l = charlie_lambda(mu_l, alpha, params["terminator"])
                value = D / ((1.0 + charlie_lambda(mu_v, alpha) + lam_l) * 4.0 * mu_v)
        return np.where((mu_l > 0) & (mu_v > 0), value, 0.0)

    def projected(self, L, V, params):
        return self._white(L, V, params)[..., None] * np.asarray(params["color"], dtype=float)

    def evaluate(self, L, V, params):
        with np.errstate(divide="ignore", invalid="ignore"):
            value = np.where(L[..., 2] > 0, self._white(L, V, params) / L[..., 2], 0.0)
        return value[..., None] * np.asarray(params["color"], dtype=float)
