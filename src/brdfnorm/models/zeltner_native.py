"""The ``zeltner`` LTC sheen as a compiled scalar function (:class:`brdfnorm.models.base.NativeKernel`) for the
compiled engine: :mod:`brdfnorm.models.zeltner`'s ``evaluate`` for one (L, V) pair, term for term (the same fits, the
same frame, the same horizon tests), returning f itself. Imported only by the compiled backend (Numba)."""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np
from numba import njit

from .base import NativeKernel

_OPTIONS = dict(cache=True, error_model="numpy")


@njit(**_OPTIONS)
def _albedo_fit(x, y):  # pragma: no cover - compiled
    s = y * (0.0206607 + 1.58491 * y) / (0.0379424 + y * (1.32227 + y))
    m = y * (-0.193854 + y * (-1.14885 + y * (1.7932 - 0.95943 * y * y))) / (0.046391 + y)
    o = y * (0.000654023 + (-0.0207818 + 0.119681 * y) * y) / (1.26264 + y * (-1.92021 + y))
    return math.exp(-0.5 * ((x - m) / s) ** 2) / (s * math.sqrt(2.0 * math.pi)) + o


@njit(**_OPTIONS)
def zeltner(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    r = u[0]
    if not (lz > 0.0 and vz > 0.0):
        return (0.0, 0.0, 0.0)
    mu = min(vz, 1.0)
    tangent = math.hypot(vx, vy)
    cx, cy = (vx / tangent, vy / tangent) if tangent > 0.0 else (1.0, 0.0)
    x = cx * lx + cy * ly
    y = -cy * lx + cx * ly
    a = (2.58126 * mu + 0.813703 * r) * r / (1.0 + 0.310327 * mu * mu + 2.60994 * mu * r)
    b = math.sqrt(max(1.0 - mu, 0.0)) * (r - 1.0) * r ** 3 / (
        0.0000254053 + 1.71228 * mu - 1.71506 * mu * r + 1.34174 * r * r)
    wx, wy = a * x + b * lz, a * y
    length2 = wx * wx + wy * wy + lz * lz
    if not length2 > 0.0:
        return (0.0, 0.0, 0.0)
    white = _albedo_fit(mu, r) * (lz / math.pi * (a / length2) ** 2) / lz
    return (white * u[1], white * u[2], white * u[3])


def _pack(params: Mapping[str, object]) -> np.ndarray:
    color = np.broadcast_to(np.asarray(params["color"], dtype=float), (3,))
    return np.concatenate([[float(np.ravel(params["roughness"])[0])], color])


def kernel() -> NativeKernel:
    return NativeKernel(zeltner, 3, _pack, "builtin:zeltner")
