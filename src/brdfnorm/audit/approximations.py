"""Fitted approximations engines ship as code, recognised in a table: when a table is none of the exact
conventions, it may be one of these formulas tabulated, and the audit then names it as what it approximates.

* ``karis-envbrdfapprox`` — Karis 2014, "Physically Based Shading on Mobile" (Unreal Engine's ``EnvBRDFApprox``):
  the split-sum pair (DFG_f0, DFG_f90) of GGX as a function of roughness r (α = r²) and μ = N·V::

      c = r·(−1, −0.0275, −0.572, 0.022) + (1, 0.0425, 1.04, −0.04)
      a = min(c₀², 2^(−9.28 μ))·c₀ + c₁;  (DFG_f0, DFG_f90) = (−1.04 a + c₂, 1.04 a + c₃)

* ``yocto-gl-cosintegral`` — yocto-gl's ``microfacet_cosintegral`` (after Kulla & Conty 2017, "Revisiting
  Physically Based Shading at Imageworks", the fit of GGX's directional albedo E(μ, r), r = √α)::

      s = S₀√μ + S₁r + S₂r² + S₃r³ + S₄r⁴,  t = T₀μ + T₁r + T₂r² + T₃r³ + T₄r⁴
      E = 1 − s⁶ μ^¾ / (t⁶ + μ²)
      S = (−0.170718, 4.07985, −11.5295, 18.4961, −9.23618), T = (0.0632331, 3.1434, −7.47567, 13.0482, −7.0401)

Each is written here from its published constants (not copied code). A table is *this approximation tabulated*
when more than half of its cells equal the formula, at some declared geometry, within the table's storage
step plus its noise; its error against the exact quantity is then the table's residual in that geometry.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..lut.splitsum import DFG_F0, DFG_F90
from .conventions import Convention, coordinates


def _karis(mu: np.ndarray, r: np.ndarray) -> list[np.ndarray]:
    c = [r * a + b for a, b in zip((-1.0, -0.0275, -0.572, 0.022), (1.0, 0.0425, 1.04, -0.04), strict=True)]
    a = np.minimum(c[0] * c[0], np.exp2(-9.28 * mu)) * c[0] + c[1]
    return [-1.04 * a + c[2], 1.04 * a + c[3]]


_S = (-0.170718, 4.07985, -11.5295, 18.4961, -9.23618)
_T = (0.0632331, 3.1434, -7.47567, 13.0482, -7.0401)


def _yocto(mu: np.ndarray, r: np.ndarray) -> list[np.ndarray]:
    s = _S[0] * np.sqrt(mu) + sum(_S[k] * r ** k for k in range(1, 5))
    t = _T[0] * mu + sum(_T[k] * r ** k for k in range(1, 5))
    return [1.0 - s ** 6 * mu ** 0.75 / (t ** 6 + mu * mu)]


@dataclass(frozen=True)
class Approximation:
    name: str
    source: str
    meanings: tuple[str, ...]  # what each output approximates (a channel meaning of the exact lobe)
    model: str  # the lobe it approximates
    evaluate: object  # (mu, r) -> list of arrays, one per output


APPROXIMATIONS = (
    Approximation("karis-envbrdfapprox", "Karis 2014, Physically Based Shading on Mobile (Unreal's EnvBRDFApprox)",
                  (DFG_F0, DFG_F90), "ggx", _karis),
    Approximation("yocto-gl-cosintegral", "yocto-gl microfacet_cosintegral, after Kulla & Conty 2017",
                  ("E",), "ggx", _yocto),
)


def recognise(values: np.ndarray, names: list[str], candidates: list[Convention], step: float,
              model: str) -> dict | None:
    """The approximation (and geometry, and output per channel) that equals the most cells of a 2-D table, when it
    equals more than half of them within ``step`` (storage) plus 1e-6 (a float32 evaluation of the formula);
    None otherwise."""
    grid = values.shape[:-1]
    if len(grid) != 2:
        return None
    mesh = list(np.meshgrid(*[np.arange(n) for n in grid], indexing="ij"))
    tolerance = step + 1e-6
    best = None
    seen = set()
    for c in candidates:
        key = c.geometry()[:-1]  # the shadowing does not change a formula
        if key in seen or c.explicit:
            continue
        seen.add(key)
        coords = coordinates(c, grid, mesh)
        mu, r = coords["mu"], np.sqrt(coords["alpha"])
        for approx in APPROXIMATIONS:
            if approx.model != model:
                continue
            with np.errstate(all="ignore"):
                outputs = approx.evaluate(mu, r)
            picks, within = [], 0
            for k in range(values.shape[-1]):
                scores = [int(np.sum(np.abs(values[..., k] - out) <= tolerance)) for out in outputs]
                j = int(np.argmax(scores))
                picks.append(approx.meanings[j])
                within += scores[j]
            if best is None or within > best[0]:
                best = (within, approx, c, picks)
    if best is None or best[0] <= 0.5 * values.size:
        return None
    within, approx, c, picks = best
    return {"name": approx.name, "source": approx.source, "within": within, "cells": int(values.size),
            "convention": c, "meanings": picks}
