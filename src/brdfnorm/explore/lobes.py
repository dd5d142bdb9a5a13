"""The lobes the explorer draws, for a view direction V at polar angle θ_o and azimuth φ_o.

* In the plane of incidence (the plane of N and V), for L at signed polar angle t (t < 0 on the mirror side):
  the normalized projected lobe α·f(L, V)(N·L) and the raw BRDF f(L, V) (1/sr, no factor, no cosine), each for
  the largest channel. The samples are uniform plus geometrically graded about the mirror direction
  (t = −θ_o), so a lobe a hundredth of a degree wide is still drawn.
* Over the hemisphere: α·f(L, V)(N·L) as a surface in polar coordinates (a, b) about the mirror direction with
  a ∝ (i/N)², for the same reason.

A second lobe (the page's overlay) is drawn the same way in the same plane, normalized under the same
convention by its own factor (:func:`overlay_view`).
"""

from __future__ import annotations

import math

import numpy as np

from ..models.base import Model, mirror


def direction(theta: float, phi: float = 0.0) -> np.ndarray:
    """The unit vector at polar angle ``theta`` and azimuth ``phi`` (radians), N = +z."""
    return np.array([math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta)])


def finite(values: np.ndarray) -> list:
    """Values as a JSON list, None where not finite."""
    return [None if not math.isfinite(v) else v for v in np.asarray(values, dtype=float).ravel().tolist()]


def plane_lobe(model: Model, theta_v: float, phi_v: float, alpha: np.ndarray) -> dict:
    """α·f(L, V)(N·L) (``r``) and f(L, V) (``raw``), largest channel, for L in the plane of N and V."""
    offsets = np.geomspace(1e-4, np.pi, 90)
    t = np.concatenate([np.linspace(-np.pi / 2, np.pi / 2, 241), -theta_v + offsets, -theta_v - offsets, [-theta_v]])
    t = np.unique(t[(t >= -np.pi / 2) & (t <= np.pi / 2)])
    L = np.stack([np.sin(t) * math.cos(phi_v), np.sin(t) * math.sin(phi_v), np.cos(t)], axis=-1)
    V = direction(theta_v, phi_v)
    with np.errstate(all="ignore"):
        f = model.eval(L, V)
        r = (f * np.asarray(alpha)).max(axis=-1) * np.cos(t)
        raw = f.max(axis=-1)
    above = np.cos(t) > 0
    return {"t_deg": np.degrees(t).tolist(), "r": finite(np.where(above, r, 0.0)),
            "raw": finite(np.where(above, raw, 0.0))}


def surface_lobe(model: Model, theta_v: float, phi_v: float, alpha: np.ndarray) -> dict:
    """α·f(L, V)(N·L) (largest channel) over the hemisphere, as x, y, z grids, and V."""
    V = direction(theta_v, phi_v)
    P = mirror(V)
    e1 = np.cross(P, [0.0, 1.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(P, e1)
    a = np.pi * np.linspace(0.0, 1.0, 25) ** 2
    b = np.linspace(0.0, 2 * np.pi, 49)
    A, B = np.meshgrid(a, b, indexing="ij")
    L3 = (np.cos(A)[..., None] * P + np.sin(A)[..., None] * (np.cos(B)[..., None] * e1 + np.sin(B)[..., None] * e2))
    with np.errstate(all="ignore"):
        cos_l = L3[..., 2]
        r3 = (model.eval(L3, np.broadcast_to(V, L3.shape)) * np.asarray(alpha)).max(axis=-1) * cos_l
        r3 = np.where(cos_l > 0, r3, 0.0)
    xyz = r3[..., None] * L3
    # A drawing needs ~5 digits: rounding to 1e-5 of the lobe's size keeps the page's JSON small.
    ok = np.isfinite(xyz)
    scale = float(np.max(np.abs(xyz[ok]), initial=0.0)) or 1.0
    step = 10.0 ** (math.floor(math.log10(scale)) - 5)
    xyz = np.where(ok, np.round(xyz / step) * step, np.nan)
    surface = {axis: [finite(row) for row in xyz[..., k]] for k, axis in enumerate("xyz")}
    surface["view"] = V.tolist()
    return surface
