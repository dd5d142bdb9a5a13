"""Fresnel factors as engines use them, and their exact hemispherical averages F_avg = 2∫₀¹ F(μ) μ dμ.

Factors (μ = cos of the angle to the facet normal; every reflectance per channel):

* ``schlick`` — Schlick 1994, F = f0 + (f90 − f0)(1 − μ)^p with p = 5; ``generalized schlick`` takes any exponent
  p > 0 (as Unreal's and OSPRay's ``f90``/exponent variants). F_avg = f0 + 2(f90 − f0)/((p + 1)(p + 2)) exactly
  (2∫(1 − μ)^p μ dμ = 2B(2, p + 1)); p = 5 gives Kulla & Conty's f0 + (f90 − f0)/21.
* ``f82-tint`` — Kutz, Hasan & Edmondson 2021 ("Novel aspects of the Adobe Standard Material"), after Hoffman 2019,
  as the OpenPBR Surface specification states it (section *Metal*):
  F = F_S(μ) − μ(1 − μ)⁶ / (μ̄(1 − μ̄)⁶) · (F_S(μ̄) − tint·F_S(μ̄)), μ̄ = 1/7, F_S Schlick with f90 = 1. Its
  F_avg = f0 + (1 − f0)/21 − a/126 with a = F_S(μ̄)(1 − tint)/(μ̄(1 − μ̄)⁶) exactly (2∫μ²(1 − μ)⁶ dμ = 2B(3, 7)
  = 1/126).
* ``conductor`` — the exact unpolarized reflectance of a complex index η + ik (:func:`fresnel_conductor`).
* ``artistic`` — Gulbrandsen 2014 ("Artist friendly metallic Fresnel", JCGT 3(4)): reflectivity r and edge tint g
  mapped to η = g(1 − r)/(1 + r) + (1 − g)(1 + √r)/(1 − √r), k = √((r(η + 1)² − (η − 1)²)/(1 − r)), then the exact
  conductor (his eqs. for n(r, g) and k(r, n)).
* ``dielectric`` — the exact unpolarized dielectric reflectance (1 under total internal reflection).

The conductor, artistic and dielectric F_avg have no closed form here: :func:`average` integrates them by adaptive
Gauss–Legendre bisection (a 20-point rule on a panel against the sum on its halves; the difference, which
overestimates the error of the halves' sum by orders of magnitude for these analytic integrands, is the reported
error), with a float64 rounding floor. The dielectric uses the substitution of
:func:`brdfnorm.models.microfacet.fresnel_average` at its critical angle.

Kulla & Conty 2017 ("Revisiting physically based shading at Imageworks"): the multiple-scattering colour
F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg)) (:func:`multiple_scattering_colour`). Their slides fit the
artistic conductor's F_avg by a cubic in (r, g), which OSPRay ships (``FresnelConductorArtistic_evalAvg`` in
``modules/cpu/render/bsdfs/Fresnel.ih``, Apache-2.0; coefficients restated in :data:`KULLA_CONTY_ARTISTIC_FIT`):
:func:`audit_artistic_fit` measures it against the exact F_avg.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError

#: The F82-tint model's reference cosine μ̄ = 1/7 (≈ 81.8°; OpenPBR, Metal section).
MU_BAR = 1.0 / 7.0
#: Every Fresnel factor's name: the one home of the word list (tests/test_structure.py refuses another literal list
#: of these names in src/); the subsets below are the ones a model offers.
KINDS = ("none", "schlick", "generalized-schlick", "f82-tint", "conductor", "artistic", "dielectric")
#: The factors of the built-in microfacet lobes' ``fresnel`` parameter, in the order of the codes their compiled
#: kernels take (:data:`KERNEL_CODES`: none 0, schlick 1, dielectric 2, conductor 3).
MICROFACET_KINDS = ("none", "schlick", "dielectric", "conductor")
KERNEL_CODES = {kind: code for code, kind in enumerate(MICROFACET_KINDS)}
#: OpenPBR's ``metal_fresnel`` and ``coat_fresnel`` choices (its ``dielectric_fresnel`` says exact | schlick).
METAL_KINDS = ("f82-tint", "schlick", "artistic", "conductor")
COAT_KINDS = ("dielectric", "none")
#: Each factor's name in prose (the audit's F_avg findings name the factor by it).
DESCRIPTIONS = {"none": "constant factor F = 1", "schlick": "Schlick factor (f0 + (1 - f0)/21)",
                "generalized-schlick": "generalized Schlick factor (exponent p)",
                "f82-tint": "F82-tint conductor (Hoffman 2023)", "conductor": "conductor Fresnel factor (eta + ik)",
                "artistic": "artistic conductor (Gulbrandsen 2014, r and g)",
                "dielectric": "exact dielectric Fresnel factor"}
#: Kulla & Conty 2017's fit of the artistic conductor's F_avg, as OSPRay evaluates it: the constant, then the
#: coefficients of g, g², g³, r, r², r³, gr, g²r, gr².
KULLA_CONTY_ARTISTIC_FIT = (0.087237, 0.0230685, -0.0864902, 0.0774594, 0.782654, -0.136432, 0.278708, 0.19744,
                            0.0360605, -0.2586)
#: OSPRay clamps the artistic reflectivity r to 0.99 before mapping it (r = 1 makes η and k infinite).
OSPRAY_R_MAX = 0.99


def fresnel_schlick(cos: np.ndarray, f0: np.ndarray, f90: np.ndarray) -> np.ndarray:
    return f0 + (f90 - f0) * (1.0 - cos) ** 5


def fresnel_dielectric(cos: np.ndarray, eta: np.ndarray) -> np.ndarray:
    """Exact unpolarized reflectance of a dielectric interface (Walter et al. 2007 eq. 22); 1 under TIR."""
    g2 = eta * eta - 1.0 + cos * cos
    g = np.sqrt(np.maximum(g2, 0.0))
    with np.errstate(divide="ignore", invalid="ignore"):
        a = (g - cos) / (g + cos)
        b = (cos * (g + cos) - 1.0) / (cos * (g - cos) + 1.0)
        value = 0.5 * a * a * (1.0 + b * b)
    return np.where(g2 <= 0.0, 1.0, value)


def fresnel_conductor(cos: np.ndarray, eta: np.ndarray, k: np.ndarray) -> np.ndarray:
    """Exact unpolarized reflectance for the complex index η + ik: (R_s + R_p)/2 with a² + b² = |n̂² − sin²θ|."""
    c2 = cos * cos
    s2 = 1.0 - c2
    t = eta * eta - k * k - s2
    a2b2 = np.sqrt(t * t + 4.0 * eta * eta * k * k)
    a = np.sqrt(np.maximum(0.5 * (a2b2 + t), 0.0))
    rs = (a2b2 - 2.0 * a * cos + c2) / (a2b2 + 2.0 * a * cos + c2)
    rp = rs * (c2 * a2b2 - 2.0 * a * cos * s2 + s2 * s2) / (c2 * a2b2 + 2.0 * a * cos * s2 + s2 * s2)
    return 0.5 * (rs + rp)


def schlick(mu, f0, f90=1.0, exponent=5.0) -> np.ndarray:
    """f0 + (f90 − f0)(1 − μ)^p (Schlick 1994; generalized with the exponent p)."""
    mu = np.asarray(mu, dtype=float)
    return f0 + (np.asarray(f90, dtype=float) - f0) * (1.0 - mu) ** exponent


def f82_tint(mu, f0, tint) -> np.ndarray:
    """OpenPBR's metallic F82 (section *Metal*): Schlick minus μ(1 − μ)⁶ scaled to hit tint·F_S(μ̄) at μ̄ = 1/7."""
    mu = np.asarray(mu, dtype=float)
    f0 = np.asarray(f0, dtype=float)
    return schlick(mu, f0) - mu * (1.0 - mu) ** 6 * f82_coefficient(f0, tint)


def f82_coefficient(f0, tint) -> np.ndarray:
    """a = F_S(μ̄)(1 − tint) / (μ̄(1 − μ̄)⁶), the weight of the F82 correction μ(1 − μ)⁶."""
    f_bar = schlick(MU_BAR, np.asarray(f0, dtype=float))
    return f_bar * (1.0 - np.asarray(tint, dtype=float)) / (MU_BAR * (1.0 - MU_BAR) ** 6)


def artistic_to_complex(r, g) -> tuple[np.ndarray, np.ndarray]:
    """Gulbrandsen 2014's (r, g) → (η, k): r ∈ [0, 1) the normal reflectivity, g ∈ [0, 1] the edge tint."""
    r = np.asarray(r, dtype=float)
    g = np.asarray(g, dtype=float)
    if np.any((r < 0) | (r >= 1)) or np.any((g < 0) | (g > 1)):
        raise ArgumentError("the artistic conductor needs 0 ≤ r < 1 and 0 ≤ g ≤ 1", where="r")
    root = np.sqrt(r)
    n = g * (1.0 - r) / (1.0 + r) + (1.0 - g) * (1.0 + root) / (1.0 - root)
    k2 = ((n + 1.0) ** 2 * r - (n - 1.0) ** 2) / (1.0 - r)
    return n, np.sqrt(np.maximum(k2, 0.0))  # k² = −0 at r = 0


@dataclass(frozen=True, eq=False)
class Fresnel:
    """One Fresnel factor with its inputs (per channel arrays broadcasting together); compared by identity (its
    inputs may be arrays)."""

    kind: str
    f0: np.ndarray | float = 0.04
    f90: np.ndarray | float = 1.0
    exponent: float = 5.0
    tint: np.ndarray | float = 1.0
    eta: np.ndarray | float = 1.5
    k: np.ndarray | float = 0.0
    r: np.ndarray | float = 0.9
    g: np.ndarray | float = 0.9

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ArgumentError(f"unknown Fresnel {self.kind!r}; one of {', '.join(KINDS)}", where="kind")
        if not (np.isfinite(self.exponent) and self.exponent > 0):
            raise ArgumentError(f"the Schlick exponent must be > 0, got {self.exponent!r}", where="exponent")

    def __call__(self, mu) -> np.ndarray:
        """F(μ), broadcasting μ against the inputs."""
        mu = np.asarray(mu, dtype=float)
        if self.kind == "none":
            return np.ones_like(mu)
        if self.kind == "schlick":
            return schlick(mu, np.asarray(self.f0, dtype=float), self.f90)
        if self.kind == "generalized-schlick":
            return schlick(mu, np.asarray(self.f0, dtype=float), self.f90, self.exponent)
        if self.kind == "f82-tint":
            return f82_tint(mu, self.f0, self.tint)
        if self.kind == "dielectric":
            return fresnel_dielectric(mu, np.asarray(self.eta, dtype=float))
        eta, k = self.complex_index()
        return fresnel_conductor(mu, eta, k)

    def complex_index(self) -> tuple[np.ndarray, np.ndarray]:
        """(η, k) of a conductor: as given, or mapped from (r, g) for ``artistic``."""
        if self.kind == "artistic":
            return artistic_to_complex(self.r, self.g)
        return np.asarray(self.eta, dtype=float), np.asarray(self.k, dtype=float)

    def average(self, *, rtol: float = 1e-14) -> tuple[np.ndarray, np.ndarray]:
        """(F_avg, error): closed forms where they exist (error a few roundings), else :func:`average_quadrature`."""
        eps = np.finfo(float).eps
        if self.kind == "none":
            return np.ones(1), np.zeros(1)
        if self.kind in ("schlick", "generalized-schlick"):
            p = 5.0 if self.kind == "schlick" else float(self.exponent)
            f0, f90 = np.asarray(self.f0, dtype=float), np.asarray(self.f90, dtype=float)
            value = f0 + (f90 - f0) * (2.0 / ((p + 1.0) * (p + 2.0)))
            return value, 4 * eps * np.maximum(np.abs(f0), np.abs(f90))
        if self.kind == "f82-tint":
            f0 = np.asarray(self.f0, dtype=float)
            a = f82_coefficient(f0, self.tint)
            value = f0 + (1.0 - f0) / 21.0 - a / 126.0
            return value, 8 * eps * (1.0 + np.abs(a))
        if self.kind == "dielectric":
            eta = np.asarray(self.eta, dtype=float)
            critical = np.sqrt(np.clip(1.0 - eta * eta, 0.0, 1.0))
            span = 1.0 - critical

            def above(t: np.ndarray, index: np.ndarray) -> np.ndarray:
                mu = critical.ravel()[index] + span.ravel()[index] * t * t
                return 2.0 * mu * fresnel_dielectric(mu, eta.ravel()[index]) * 2.0 * span.ravel()[index] * t

            value, error = average_quadrature(above, eta.size, rtol=rtol)
            return critical**2 + value.reshape(eta.shape), error.reshape(eta.shape) + 4 * eps
        eta, k = np.broadcast_arrays(*self.complex_index())

        def conductor(mu: np.ndarray, index: np.ndarray) -> np.ndarray:
            return 2.0 * mu * fresnel_conductor(mu, eta.ravel()[index], k.ravel()[index])

        value, error = average_quadrature(conductor, eta.size, rtol=rtol)
        return value.reshape(eta.shape), error.reshape(eta.shape)


_X, _W = np.polynomial.legendre.leggauss(20)
#: Bisection depth limit: 2⁻⁴⁰ panels are far below any feature of these integrands.
_MAX_DEPTH = 40


def average_quadrature(integrand: Callable[[np.ndarray, np.ndarray], np.ndarray], cases: int, *,
                       rtol: float = 1e-14) -> tuple[np.ndarray, np.ndarray]:
    """∫₀¹ integrand(x, case) dx for ``cases`` cases at once by adaptive bisection: a panel's 20-point
    Gauss–Legendre value Q₁ against the sum Q₂ of its halves'; accepted when |Q₂ − Q₁| ≤ max(rtol, 1e-15)·
    (panel width)·(1 + |running estimate|), and the accepted |Q₂ − Q₁| summed is the error reported (the halves'
    error is far smaller for an analytic integrand), plus 64 ulps of the value for the rounding of the sums."""
    def rule(a: np.ndarray, b: np.ndarray, case: np.ndarray) -> np.ndarray:
        x = (a + b)[:, None] / 2 + (b - a)[:, None] / 2 * _X
        return np.sum(integrand(x, np.broadcast_to(case[:, None], x.shape)) * _W, axis=1) * (b - a) / 2

    value = np.zeros(cases)
    error = np.zeros(cases)
    a = np.zeros(cases)
    b = np.ones(cases)
    case = np.arange(cases)
    whole = rule(a, b, case)
    scale = np.abs(whole) + 1.0
    tolerance = max(rtol, 1e-15)
    for depth in range(_MAX_DEPTH):
        mid = (a + b) / 2
        left, right = rule(a, mid, case), rule(mid, b, case)
        halves = left + right
        change = np.abs(halves - whole)
        done = (change <= tolerance * (b - a) * scale[case]) | (depth == _MAX_DEPTH - 1)
        np.add.at(value, case[done], halves[done])
        np.add.at(error, case[done], change[done])
        keep = ~done
        if not keep.any():
            break
        a = np.concatenate([a[keep], mid[keep]])
        b = np.concatenate([mid[keep], b[keep]])
        whole = np.concatenate([left[keep], right[keep]])
        case = np.concatenate([case[keep], case[keep]])
    return value, error + 64 * np.finfo(float).eps * np.abs(value)


def multiple_scattering_colour(f_avg, e_avg) -> np.ndarray:
    """Kulla & Conty 2017's F_ms = F_avg² E_avg / (1 − F_avg (1 − E_avg))."""
    f_avg = np.asarray(f_avg, dtype=float)
    e_avg = np.asarray(e_avg, dtype=float)
    return f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg))


def kulla_conty_dielectric_fit(eta) -> np.ndarray:
    """Kulla & Conty 2017's fit of the dielectric F_avg as OSPRay's ``fresnelDielectricAvg`` evaluates it, written
    for η = interior/exterior (OSPRay's argument is its reciprocal): (η − 1)/(4.08567 + 1.00071 η) for η ≥ 1, else
    0.997118 + 0.1014 η − 0.965241 η² − 0.130607 η³."""
    eta = np.asarray(eta, dtype=float)
    return np.where(eta >= 1.0, (eta - 1.0) / (4.08567 + 1.00071 * eta),
                    0.997118 + 0.1014 * eta - 0.965241 * eta**2 - 0.130607 * eta**3)


def kulla_conty_artistic_fit(r, g) -> np.ndarray:
    """Kulla & Conty 2017's cubic fit of the artistic conductor's F_avg(r, g), as OSPRay ships it."""
    r = np.asarray(r, dtype=float)
    g = np.asarray(g, dtype=float)
    c = KULLA_CONTY_ARTISTIC_FIT
    return (c[0] + c[1] * g + c[2] * g * g + c[3] * g**3 + c[4] * r + c[5] * r * r + c[6] * r**3 + c[7] * g * r
            + c[8] * g * g * r + c[9] * g * r * r)


@dataclass(frozen=True)
class FitAudit:
    """The fit against the exact F_avg on a grid of (r, g): the largest |fit − exact| and where."""

    max_error: float
    argmax_r: float
    argmax_g: float
    max_relative_error: float  # where the exact F_avg > 1e-3
    mean_error: float
    quadrature_error: float
    points: int


def audit_artistic_fit(points: int = 101, r_min: float = 0.0, r_max: float = OSPRAY_R_MAX) -> FitAudit:
    """Kulla & Conty's cubic against the exact artistic F_avg on a ``points`` × ``points`` grid over
    r ∈ [r_min, r_max] (OSPRay clamps r to 0.99), g ∈ [0, 1]."""
    r, g = np.meshgrid(np.linspace(r_min, r_max, points), np.linspace(0.0, 1.0, points), indexing="ij")
    exact, error = Fresnel("artistic", r=r, g=g).average()
    difference = kulla_conty_artistic_fit(r, g) - exact
    i = np.unravel_index(np.argmax(np.abs(difference)), difference.shape)
    # relative to F_avg where it is not ~0 (at r = 0 the exact conductor is index-matched: F = F_avg = 0)
    relative = np.abs(difference)[exact > 1e-3] / exact[exact > 1e-3]
    return FitAudit(float(np.abs(difference[i])), float(r[i]), float(g[i]), float(relative.max()),
                    float(np.mean(np.abs(difference))), float(error.max()), points * points)
