"""The lobe-aligned hemisphere map and the two tensor rules of the shader kernel
:func:`brdfnorm.engine.compiled.kernels.hemisphere`, compiled once per machine for every shader.

The map is :func:`brdfnorm.engine.machinery.tensor_rule.map_grid` (horizon grading p = 2, width scale 1), split as
the kernel loops: :func:`azimuth` once per azimuth β, :func:`node` once per radial node. The rules reduce one
panel's values: :func:`kronrod_rule` (K15 ⊗ K15 with its G7 estimates and the rounding floor of
:func:`brdfnorm.engine.machinery.panels.kronrod_estimate`) and :func:`tensor_rule` (any tensor rule: the
Lobatto ⊗ G7 check on halves). Formulas and order of operations are those the kernel inlined before, term for term.

Why a module of its own, with plain (not inlined) functions: the kernels' template is compiled once per shader, and
Numba inlines an ``inline="always"`` helper by copying and re-typing its IR at every call site — 40 % of a shader's
kernels' compile time went there. Called as ordinary functions, these are compiled (or loaded from Numba's disk
cache) once per process and linked into each kernel, where LLVM inlines them as it inlines the shader. They take
scalars, not arrays, where called per node: an array passed to a function is reference-counted at every call.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_OPTIONS = dict(cache=True, error_model="numpy")
_EPS = 2.220446049250313e-16


@njit(**_OPTIONS)
def azimuth(beta, pz, tx, ty, tz, bx, by, bz, width, support):  # pragma: no cover - compiled
    """What map_grid computes once per azimuth β of a lobe (axis P, tangents T, B, width w, support): the radial
    unit vector cos β T + sin β B and A = atan(α_max/w)."""
    cos_b, sin_b = math.cos(beta), math.sin(beta)
    s = math.sqrt(max(1.0 - pz * pz, 0.0))
    alpha_max = min(math.atan2(pz, -s * cos_b), support)
    A = math.atan(alpha_max / width)
    return cos_b * tx + sin_b * bx, cos_b * ty + sin_b * by, cos_b * tz + sin_b * bz, A


@njit(**_OPTIONS)
def node(rx, ry, rz, A, u, weight, px, py, pz, w):  # pragma: no cover - compiled
    """ω and the Jacobian sin α dα/du · weight of map_grid at the radial coordinate u of one azimuth."""
    one_minus_u = 1.0 - u
    v = 1.0 - one_minus_u * one_minus_u
    t = math.tan(v * A)
    h = math.tan(t * (0.5 * w))
    h2 = h * h
    scale = 1.0 / (1.0 + h2)
    sin_a = h * (2.0 * scale)
    cos_a = (1.0 - h2) * scale
    jacobian = (t * t + 1.0) * (A * (w * weight)) * (2.0 * one_minus_u) * sin_a
    return sin_a * rx + cos_a * px, sin_a * ry + cos_a * py, sin_a * rz + cos_a * pz, jacobian


@njit(**_OPTIONS)
def kronrod_rule(r, x, jac, finite, kronrod, gauss, value, err_b, err_u, magnitude, bad,
                 first_bad):  # pragma: no cover - compiled
    """Panel r's K15⊗K15 value, |KK − GK| (β), |KK − KG| (u) with the floor 50ε·magnitude, and the K15⊗K15
    integral of |g|, per channel, from x (n, n, C) = g·(N·ω)·J; non-finite nodes (``finite``) count as 0, their
    solid angle (Jacobians ``jac``) into ``bad[r]``, the first of them b·n + u into ``first_bad[r]`` (−1: none)."""
    n = kronrod.size
    C = value.shape[1]
    kk = np.zeros(C)
    gk = np.zeros(C)
    kg = np.zeros(C)
    mag = np.zeros(C)
    over_u_k = np.zeros(C)
    over_u_g = np.zeros(C)
    over_u_m = np.zeros(C)
    lost = 0.0
    first_bad[r] = -1
    for b in range(n):
        for c in range(C):
            over_u_k[c] = 0.0
            over_u_g[c] = 0.0
            over_u_m[c] = 0.0
        for j in range(n):
            if not finite[b, j]:
                if first_bad[r] < 0:
                    first_bad[r] = b * n + j
                lost += jac[b, j] * kronrod[b] * kronrod[j]
                continue
            for c in range(C):
                over_u_k[c] += x[b, j, c] * kronrod[j]
                over_u_g[c] += x[b, j, c] * gauss[j]
                over_u_m[c] += abs(x[b, j, c]) * kronrod[j]
        for c in range(C):
            kk[c] += over_u_k[c] * kronrod[b]
            gk[c] += over_u_k[c] * gauss[b]
            kg[c] += over_u_g[c] * kronrod[b]
            mag[c] += over_u_m[c] * kronrod[b]
    for c in range(C):
        floor = 50.0 * _EPS * mag[c]
        value[r, c] = kk[c]
        err_b[r, c] = max(abs(kk[c] - gk[c]), floor)
        err_u[r, c] = max(abs(kk[c] - kg[c]), floor)
        magnitude[r, c] = mag[c]
    bad[r] = lost


@njit(**_OPTIONS)
def tensor_rule(r, x, weights_b, weights_u, total):  # pragma: no cover - compiled
    """total[r] = Σ x w_b w_u over panel r's values x (n_b, n_u, C), non-finite values counted as 0."""
    for c in range(total.shape[1]):
        total[r, c] = 0.0
    for b in range(weights_b.size):
        for j in range(weights_u.size):
            for c in range(total.shape[1]):
                if math.isfinite(x[b, j, c]):
                    total[r, c] += x[b, j, c] * weights_b[b] * weights_u[j]
