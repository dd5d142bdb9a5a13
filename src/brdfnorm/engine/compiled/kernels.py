"""The compiled engine's kernels, written against one module-level ``shader`` (a model's
:class:`brdfnorm.models.base.NativeKernel` function f(lx, ly, lz, vx, vy, vz, u) -> tuple of floats).

This file is a template: :mod:`brdfnorm.engine.compiled.drivers` copies it once per shader into the per-user cache
directory and sets ``shader`` there before the first call, so that Numba's on-disk cache (``cache=True``) holds the
compiled kernels of every shader (a kernel given the shader as an argument is compiled anew in every process).

What the kernels fuse, per node and in one loop over the cells' panels (one thread: tables spread their cells over
processes, :mod:`brdfnorm.parallel`; Numba's ``parallel=True`` took 20 s instead of 8 s to compile the kernels of
one lobe and its threads, woken per call, cost more than they gave on a loaded machine):

* :func:`integrand_nodes` — the integrand f·(N·ω) of :meth:`brdfnorm.engine.methods.Problem.integrand` at given
  directions (every route that samples the integrand: lobe search, rounding noise, global rules, isotropy test);
* :func:`hemisphere_loop` — the one loop of the next two, which differ in their rules;
* :func:`hemisphere_panels` — the lobe-aligned map of :func:`brdfnorm.engine.machinery.tensor_rule.map_grid`
  (horizon grading p = 2), the shader, the Jacobian and the G7/K15 tensor sums and rounding floor of
  :func:`brdfnorm.engine.machinery.panels.kronrod_estimate` for whole panels;
* :func:`hemisphere_sums` — the same map and shader under any tensor rule (the Lobatto ⊗ G7 check on halves);
* :func:`slope_grid` — the half-vector route's rectangle integrand
  (:func:`brdfnorm.engine.routes.halfvector_generic.route`): the slope map of the GGX measure, the reflection
  L = 2(V·H)H − V, the shader and the Jacobian (the loop :func:`.slopes.slope_loop`, shared with the microfacet
  lobes' :func:`.slopes.microfacet_grid`).

The formulas are those of the numpy backend, term for term; the sums run in another order, so values agree to
rounding (far inside the error estimates), not bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brdfnorm.engine.compiled.slopes import reflected_value, slope_loop

shader = None  # set per copy (drivers.py)

_EPS = 2.220446049250313e-16


@njit(cache=True, error_model="numpy")
def integrand_nodes(omega, case, fixed, U, over_light, out):  # pragma: no cover - compiled
    """out[i] = f(ω_i, V) ω_z (over the light) or f(L, ω_i) ω_z (over the view), case[i] the row of fixed and U."""
    for i in range(omega.shape[0]):
        k = case[i]
        wx, wy, wz = omega[i, 0], omega[i, 1], omega[i, 2]
        if over_light:
            r = shader(wx, wy, wz, fixed[k, 0], fixed[k, 1], fixed[k, 2], U[k])
        else:
            r = shader(fixed[k, 0], fixed[k, 1], fixed[k, 2], wx, wy, wz, U[k])
        for c in range(len(r)):
            out[i, c] = r[c] * wz


@njit(cache=True, error_model="numpy", inline="always")
def _azimuth(k, beta, P, T, B, widths, supports):  # pragma: no cover - compiled
    """What map_grid (grading p = 2, width scale 1) computes once per azimuth β: the radial unit vector
    cos β T + sin β B and A = atan(α_max/w)."""
    cos_b, sin_b = math.cos(beta), math.sin(beta)
    pz = P[k, 2]
    s = math.sqrt(max(1.0 - pz * pz, 0.0))
    alpha_max = min(math.atan2(pz, -s * cos_b), supports[k])
    A = math.atan(alpha_max / widths[k])
    rx = cos_b * T[k, 0] + sin_b * B[k, 0]
    ry = cos_b * T[k, 1] + sin_b * B[k, 1]
    rz = cos_b * T[k, 2] + sin_b * B[k, 2]
    return rx, ry, rz, A


@njit(cache=True, error_model="numpy", inline="always")
def _node(k, rx, ry, rz, A, u, weight, P, widths):  # pragma: no cover - compiled
    """ω and the Jacobian sin α dα/du · weight of map_grid at the radial coordinate u of one azimuth."""
    w = widths[k]
    one_minus_u = 1.0 - u
    v = 1.0 - one_minus_u * one_minus_u
    t = math.tan(v * A)
    h = math.tan(t * (0.5 * w))
    h2 = h * h
    scale = 1.0 / (1.0 + h2)
    sin_a = h * (2.0 * scale)
    cos_a = (1.0 - h2) * scale
    jacobian = (t * t + 1.0) * (A * (w * weight)) * (2.0 * one_minus_u) * sin_a
    return (sin_a * rx + cos_a * P[k, 0], sin_a * ry + cos_a * P[k, 1], sin_a * rz + cos_a * P[k, 2],
            jacobian)


@njit(cache=True, error_model="numpy", inline="always")
def _integrand(k, ox, oy, oz, fixed, U, over_light):  # pragma: no cover - compiled
    if over_light:
        return shader(ox, oy, oz, fixed[k, 0], fixed[k, 1], fixed[k, 2], U[k])
    return shader(fixed[k, 0], fixed[k, 1], fixed[k, 2], ox, oy, oz, U[k])


@njit(error_model="numpy", inline="always")
def hemisphere_loop(rule, case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes_b, nodes_u,
                    channels, checked, outputs):  # pragma: no cover - compiled
    """The one loop of the hemisphere kernels: per panel r (case k = case[r], box [b0, b1] × [u0, u1]) the map,
    the shader and the Jacobian at the tensor nodes nodes_b ⊗ nodes_u into x (n_b, n_u, C) = g·(N·ω)·J, with J
    (n_b, n_u) and ``finite`` (n_b, n_u: g·(N·ω) finite in every channel; both only where ``checked``), then
    ``rule(r, x, J, finite, outputs)`` reduces them. The rules: :func:`hemisphere_panels` (K15 ⊗ K15 and its G7
    estimates) and :func:`hemisphere_sums` (any tensor rule; it reads x alone).

    Not cached and always inlined, like :func:`.slopes.slope_loop`: ``rule`` is a first-class function argument;
    the arrays pass to it once per panel, not per node. Against the two loops it replaced, on the captured calls of
    an Oren-Nayar table: +2 % (panels) and +4 % (sums) of the kernels' CPU, the values the same to the bit."""
    x = np.empty((nodes_b.size, nodes_u.size, channels))
    jac = np.empty((nodes_b.size, nodes_u.size))
    finite = np.empty((nodes_b.size, nodes_u.size), dtype=np.bool_)
    for r in range(case.size):
        k = case[r]
        beta_half = 0.5 * (b1[r] - b0[r])
        u_half = 0.5 * (u1[r] - u0[r])
        beta_mid = 0.5 * (b0[r] + b1[r])
        u_mid = 0.5 * (u0[r] + u1[r])
        weight = beta_half * u_half
        for b in range(nodes_b.size):
            rx, ry, rz, A = _azimuth(k, beta_mid + beta_half * nodes_b[b], P, T, B, widths, supports)
            for j in range(nodes_u.size):
                ox, oy, oz, J = _node(k, rx, ry, rz, A, u_mid + u_half * nodes_u[j], weight, P, widths)
                g = _integrand(k, ox, oy, oz, fixed, U, over_light)
                ok = True
                for c in range(channels):
                    if checked and not math.isfinite(g[c] * oz):
                        ok = False
                    x[b, j, c] = g[c] * oz * J
                if checked:
                    jac[b, j] = J
                    finite[b, j] = ok
        rule(r, x, jac, finite, outputs)


@njit(cache=True, error_model="numpy", inline="always")
def _kronrod_rule(r, x, jac, finite, outputs):  # pragma: no cover - compiled
    kronrod, gauss, value, err_b, err_u, magnitude, bad, first_bad = outputs
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


@njit(cache=True, error_model="numpy")
def hemisphere_panels(case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes, kronrod, gauss,
                      value, err_b, err_u, magnitude, bad, first_bad):  # pragma: no cover - compiled
    """K15⊗K15 value, |KK − GK| (β), |KK − KG| (u) with the floor 50ε·magnitude, and the K15⊗K15 integral of |g|,
    per panel and channel; ``bad`` the solid angle of non-finite nodes (counted as 0); ``first_bad`` the first
    non-finite node b·n + u per panel, −1 where none (:func:`hemisphere_loop` with the Kronrod rule)."""
    hemisphere_loop(_kronrod_rule, case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes, nodes,
                    value.shape[1], True, (kronrod, gauss, value, err_b, err_u, magnitude, bad, first_bad))


@njit(cache=True, error_model="numpy", inline="always")
def _tensor_rule(r, x, jac, finite, outputs):  # pragma: no cover - compiled
    weights_b, weights_u, total = outputs
    for c in range(total.shape[1]):
        total[r, c] = 0.0
    for b in range(weights_b.size):
        for j in range(weights_u.size):
            for c in range(total.shape[1]):
                if math.isfinite(x[b, j, c]):
                    total[r, c] += x[b, j, c] * weights_b[b] * weights_u[j]


@njit(cache=True, error_model="numpy")
def hemisphere_sums(case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes_b, nodes_u,
                    weights_b, weights_u, total):  # pragma: no cover - compiled
    """Σ g·J w_b w_u over the tensor rule nodes_b ⊗ nodes_u of each panel, non-finite values counted as 0
    (:func:`hemisphere_loop` with a tensor rule)."""
    hemisphere_loop(_tensor_rule, case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes_b,
                    nodes_u, total.shape[1], False, (weights_b, weights_u, total))


@njit(cache=True, error_model="numpy", inline="always")
def _slope_case(q, extra):  # pragma: no cover - compiled
    """Per panel of :func:`.slopes.slope_loop`: F (the reflection's fixed direction), the fixed direction of the
    shader and its parameters U of case q (extra: F, rows, fixed, U, over_light)."""
    F, rows, fixed, U, over_light = extra
    row = rows[q]
    return F[q, 0], F[q, 1], F[q, 2], fixed[row, 0], fixed[row, 1], fixed[row, 2], U[row], over_light


@njit(cache=True, error_model="numpy", inline="always")
def _slope_value(s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, vz, ax, ay, case):  # pragma: no cover - compiled
    """The generic weight of the reflected direction at one node of :func:`.slopes.slope_loop`
    (:func:`.slopes.reflected_value` with this copy's shader)."""
    return reflected_value(shader, s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, ax, case)


@njit(cache=True, error_model="numpy")
def slope_grid(k, phi, v, piece, linear, log_horizon, vz, cos_offset, sin_offset, amplitude, ax, ay, layer, delta,
               kappa, multiplicity, F, rows, fixed, U, over_light, out, failed):  # pragma: no cover - compiled
    """The half-vector route's rectangle integrand (:func:`brdfnorm.engine.routes.halfvector.slope_integrand` for
    the GGX slope measure, with the generic weight of :func:`brdfnorm.engine.routes.halfvector_generic.route`) on
    grids φ (R, nφ) × v (R, nv) of the panels of the local cases ``k`` (R,) in radial ``piece`` (R,)
    (:func:`.slopes.slope_loop` with :func:`_slope_value`): out (R, nφ, nv, C + 1), the weighted values and their
    largest |value|; ``failed[k]`` where a value above the horizon is not finite."""
    slope_loop(_slope_case, _slope_value, k, phi, v, piece, linear, log_horizon, False, vz, cos_offset, sin_offset,
               amplitude, ax, ay, layer, delta, kappa, multiplicity, (F, rows, fixed, U, over_light), True, out, failed)

