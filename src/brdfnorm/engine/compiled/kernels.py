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
* :func:`hemisphere` — the lobe-aligned map of :func:`brdfnorm.engine.machinery.tensor_rule.map_grid` (horizon
  grading p = 2), the shader and the Jacobian over whole panels, reduced by one of two rules (a flag: one kernel, one
  compile of the loop and the shader call): :func:`hemisphere_panels`, the G7/K15 tensor sums and rounding floor of
  :func:`brdfnorm.engine.machinery.panels.kronrod_estimate`, and :func:`hemisphere_sums`, any tensor rule (the
  Lobatto ⊗ G7 check on halves). The map and the rules are plain functions of :mod:`.hemimap`, compiled once per
  machine for every shader;
* :func:`padded_shader` — the shader padded to three outputs: the first-class function that the package's kernels
  of every shader call (the half-vector route's rectangle integrand :func:`.slopes.shader_grid` and its global
  rule :func:`.global_rule.shader_global`, each compiled once per machine, not once per shader).

The formulas are those of the numpy backend, term for term; the sums run in another order, so values agree to
rounding (far inside the error estimates), not bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brdfnorm.engine.compiled.hemimap import azimuth, kronrod_rule, node, tensor_rule

shader = None  # set per copy (drivers.py)


@njit(cache=True, error_model="numpy", nogil=True)
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


@njit(cache=True, error_model="numpy", nogil=True)
def hemisphere(panels, case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes_b, nodes_u,
               kronrod, gauss, value, err_b, err_u, magnitude, bad, first_bad, weights_b, weights_u,
               total):  # pragma: no cover - compiled
    """The hemisphere kernel: per panel r (case k = case[r], box [b0, b1] × [u0, u1]) the lobe-aligned map
    (:func:`.hemimap.azimuth`, :func:`.hemimap.node`), the shader and the Jacobian at the tensor nodes
    nodes_b ⊗ nodes_u into x (n_b, n_u, C) = g·(N·ω)·J, then one rule: where ``panels``, the K15 ⊗ K15 estimates
    of :func:`.hemimap.kronrod_rule` (nodes_b = nodes_u = the K15 nodes; J and the finiteness of g·(N·ω) in every
    channel kept per node for it), else the sums of :func:`.hemimap.tensor_rule` (any tensor rule). The arrays of
    the other rule are not read (empty ones are passed: both uses have one signature, one compile)."""
    channels = value.shape[1] if panels else total.shape[1]
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
        px, py, pz, w = P[k, 0], P[k, 1], P[k, 2], widths[k]
        fx, fy, fz, u = fixed[k, 0], fixed[k, 1], fixed[k, 2], U[k]
        for b in range(nodes_b.size):
            rx, ry, rz, A = azimuth(beta_mid + beta_half * nodes_b[b], pz, T[k, 0], T[k, 1], T[k, 2], B[k, 0],
                                    B[k, 1], B[k, 2], w, supports[k])
            for j in range(nodes_u.size):
                ox, oy, oz, J = node(rx, ry, rz, A, u_mid + u_half * nodes_u[j], weight, px, py, pz, w)
                if over_light:
                    g = shader(ox, oy, oz, fx, fy, fz, u)
                else:
                    g = shader(fx, fy, fz, ox, oy, oz, u)
                ok = True
                for c in range(channels):
                    if panels and not math.isfinite(g[c] * oz):
                        ok = False
                    x[b, j, c] = g[c] * oz * J
                if panels:
                    jac[b, j] = J
                    finite[b, j] = ok
        if panels:
            kronrod_rule(r, x, jac, finite, kronrod, gauss, value, err_b, err_u, magnitude, bad, first_bad)
        else:
            tensor_rule(r, x, weights_b, weights_u, total)


_NONE = np.zeros(0)


def hemisphere_panels(case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes, kronrod, gauss,
                      value, err_b, err_u, magnitude, bad, first_bad) -> None:
    """K15⊗K15 value, |KK − GK| (β), |KK − KG| (u) with the floor 50ε·magnitude, and the K15⊗K15 integral of |g|,
    per panel and channel; ``bad`` the solid angle of non-finite nodes (counted as 0); ``first_bad`` the first
    non-finite node b·n + u per panel, −1 where none (:func:`hemisphere` with the Kronrod rule)."""
    hemisphere(True, case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes, nodes, kronrod,
               gauss, value, err_b, err_u, magnitude, bad, first_bad, _NONE, _NONE, np.empty((0, value.shape[1])))


def hemisphere_sums(case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes_b, nodes_u,
                    weights_b, weights_u, total) -> None:
    """Σ g·J w_b w_u over the tensor rule nodes_b ⊗ nodes_u of each panel, non-finite values counted as 0
    (:func:`hemisphere` with a tensor rule)."""
    empty = np.empty((0, total.shape[1]))
    hemisphere(False, case, b0, b1, u0, u1, P, T, B, widths, supports, fixed, U, over_light, nodes_b, nodes_u, _NONE,
               _NONE, empty, empty, empty, empty, _NONE, np.zeros(0, dtype=np.int64), weights_b, weights_u, total)


@njit(cache=True, error_model="numpy", nogil=True)
def padded_shader(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    """The shader's outputs, then zeros up to three: the first-class function that
    :func:`.global_rule.shader_global` calls for a shader of fewer channels (it uses only the shader's own), so that
    one compile of that kernel serves one, two and three channels (:data:`.global_rule.PADDED`); so does
    :func:`.slopes.shader_grid`."""
    g = shader(lx, ly, lz, vx, vy, vz, u)
    n = len(g)
    return g[0], g[min(1, n - 1)] if n > 1 else 0.0, g[min(2, n - 1)] if n > 2 else 0.0
