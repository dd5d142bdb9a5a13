"""The half-vector route's slope map (:func:`brdfnorm.engine.routes.halfvector.slope_integrand`, equation (H1) of
:mod:`brdfnorm.engine.routes.halfvector`) for one azimuth and one radial node, compiled; and the microfacet lobes'
rectangle integrand on it (:func:`microfacet_grid`, the weight of ``halfvector.microfacet_weight``), which needs no
shader and so is one cached kernel for every ggx/beckmann lobe.

The loop over panels, azimuths and radial nodes is :func:`slope_loop` alone: :func:`microfacet_grid` and the shader
kernel (:func:`shader_grid`) pass it their weights. Term for term the numpy
formulas: the zero of p(φ) kept apart so that p keeps its relative accuracy, the cancellation-free roots, the
three radial pieces (pole, tail, horizon layer) and N·L as a product that keeps its accuracy at the horizon.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.extending import intrinsic

from ...models.fresnel import KERNEL_CODES
from ...models.native import beckmann_lambda, fresnel_factor, ggx_lambda
from .marks import compile_marked, first_class_argtypes

_OPTIONS = dict(cache=True, error_model="numpy", nogil=True)
#: Beckmann's slope radius cap (``engine.machinery.slope_coordinates.BeckmannCoordinates.CAP``).
CAP = 8.0


#: The per-case arrays of the half-vector slope map (``engine.routes.halfvector.slope_map``) that the rectangle
#: kernels (:func:`shader_grid`, :func:`microfacet_grid`) take, in their order.
SLOPE_MAP = ("vz", "cos_offset", "sin_offset", "amplitude", "ax", "ay", "layer", "delta", "kappa", "multiplicity")


def slope_arrays(geometry: dict, cases: int) -> list[np.ndarray]:
    """The :data:`SLOPE_MAP` arrays of ``geometry``, broadcast to ``cases`` cases, as writeable contiguous float64
    copies (a read-only broadcast view of one case would be another type to Numba: a second compilation)."""
    return [np.array(np.broadcast_to(geometry[name], (cases,)), dtype=float) for name in SLOPE_MAP]


def rectangle_grids(case: np.ndarray, phi: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A rectangle integrand's φ (R, n, 1) and v (R, 1, m) as the kernels' contiguous grids (R, n) and (R, m)."""
    R = case.size
    return (np.ascontiguousarray(np.broadcast_to(phi, (R, phi.shape[1], 1)), dtype=float).reshape(R, -1),
            np.ascontiguousarray(np.broadcast_to(v, (R, 1, v.shape[-1])), dtype=float).reshape(R, -1))


@intrinsic
def borrowed(typingctx, array):
    """A view of ``array`` that holds no reference (no meminfo, as :func:`numba.carray`'s views): Numba's reference
    counts on it are a null test, not an atomic add and subtract. Only for views used while ``array`` itself is
    held, as the kernels' arguments are for the whole call: the per-node calls of a shader, whose parameters are an
    array."""
    def codegen(context, builder, signature, args):
        source = context.make_array(signature.args[0])(context, builder, value=args[0])
        view = context.make_array(signature.return_type)(context, builder)
        context.populate_array(view, data=source.data, shape=source.shape, strides=source.strides,
                               itemsize=source.itemsize, meminfo=None, parent=None)
        return view._getvalue()

    return array(array), codegen


@njit(**_OPTIONS, inline="always")
def _round_half_even(x):  # pragma: no cover - compiled
    r = math.floor(x + 0.5)
    if r - x == 0.5 and r % 2.0 != 0.0:
        r -= 1.0
    return r


@njit(**_OPTIONS, inline="always")
def azimuth_node(ph, linear, cos_offset, sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity, vz,
                 beckmann):  # pragma: no cover - compiled
    """Per azimuth φ: (dx, dy, d2, p, q − p, s_h, s_split, s_middle, s_end, dφ/dξ · multiplicity/2π)."""
    zero = math.pi * _round_half_even(ph / math.pi)
    if linear:
        epsilon, phi_jacobian = ph - zero, 1.0
    else:
        stretch = kappa * abs(ph - zero) / (0.5 * math.pi)
        sign = 1.0 if ph > zero else (-1.0 if ph < zero else 0.0)
        epsilon = sign * delta * math.sinh(stretch)
        phi_jacobian = delta * kappa * math.cosh(stretch) / (0.5 * math.pi)
    parity = 1.0 - 2.0 * (_round_half_even(zero / math.pi) % 2.0)
    cos_e, sin_e = math.cos(epsilon), math.sin(epsilon)
    cos_a = parity * (cos_offset * cos_e - sin_offset * sin_e)
    sin_a = parity * (sin_offset * cos_e + cos_offset * sin_e)
    dx, dy = ax * cos_a, ay * sin_a
    d2 = dx * dx + dy * dy
    p = -amplitude * parity * sin_e
    q = math.sqrt(p * p + d2)
    q_plus_p = q + p if p > 0 else d2 / (q - p)
    q_minus_p = d2 / (q + p) if p > 0 else q - p
    s_h = q_plus_p / d2
    r_h2 = q_plus_p * q_plus_p / d2
    gap = layer * (1.0 + r_h2) / (2.0 * q * vz)
    s_split = s_h / (1.0 + gap / s_h)
    s_middle = s_split / (1.0 + s_split)
    s_end = s_h
    if beckmann:
        s_end, s_split, s_middle = min(s_h, CAP), min(s_split, CAP), min(s_middle, CAP)
    return dx, dy, d2, p, q_minus_p, s_h, s_split, s_middle, s_end, phi_jacobian * (multiplicity / (2.0 * math.pi))


@njit(**_OPTIONS, inline="always")
def piece_extent(kind, s_middle, s_split, s_end, log_horizon, beckmann):  # pragma: no cover - compiled
    """(start, length, ln(s_end/s_split)) of radial piece ``kind`` in its own coordinate, once per azimuth."""
    start, length, log_ratio = 0.0, 0.0, 0.0
    if kind == 0:
        length = s_middle if beckmann else math.atan(s_middle)
    elif kind == 1:
        start = s_middle if beckmann else math.asinh(s_middle)
        length = (s_split if beckmann else math.asinh(s_split)) - start
    elif log_horizon:
        log_ratio = math.log(s_end / s_split)
    else:
        length = s_end - s_split
    return start, length, log_ratio


@njit(**_OPTIONS, inline="always")
def _density(s, beckmann):  # pragma: no cover - compiled
    return 2.0 * s * math.exp(-s * s) if beckmann else 2.0 * s / (1.0 + s * s) ** 2


@njit(**_OPTIONS, inline="always")
def radial_node(kind, at, start, length, log_ratio, s_h, s_split, s_end, log_horizon, beckmann):  # pragma: no cover
    """(slope radius s, du/dt · the piece's length, s_h − s accurately) at position ``at`` ∈ [0, 1] of a piece."""
    if kind == 0:
        t = at * length
        if beckmann:
            return t, _density(t, True) * length, s_h - t
        return math.tan(t), math.sin(2.0 * t) * length, s_h - math.tan(t)
    if kind == 1:
        t = start + at * length
        if beckmann:
            return t, _density(t, True) * length, s_h - t
        e2 = math.exp(-2.0 * t)
        radius = math.sinh(t)
        return radius, 8.0 * e2 * (1.0 - e2) / (1.0 + e2) ** 3 * length, s_h - radius
    if log_horizon:
        radius = s_end * math.exp((at - 1.0) * log_ratio)
        to_end = -s_end * math.expm1((at - 1.0) * log_ratio)
        return radius, _density(radius, beckmann) * radius * log_ratio, (s_h - s_end) + to_end
    radius = s_split + at * length
    return radius, _density(radius, beckmann) * length, (s_h - s_end) + length * (1.0 - at)


@njit(**_OPTIONS, inline="always")
def slope_node(kind, at, start, length, log_ratio, s_h, s_split, s_end, log_horizon, beckmann, d2, p, q_minus_p,
               vz):  # pragma: no cover - compiled
    """(s, du/dt · the piece's length, 1 + s p, 1 + s² d², N·L) at position ``at`` of radial piece ``kind`` of one
    azimuth (:func:`radial_node`; N·L as the product that keeps its accuracy at the horizon)."""
    s, weight_t, gap_h = radial_node(kind, at, start, length, log_ratio, s_h, s_split, s_end, log_horizon, beckmann)
    n2 = 1.0 + s * s * d2
    return s, weight_t, 1.0 + s * p, n2, vz * gap_h * (d2 * s + q_minus_p) / n2


@njit(**_OPTIONS, inline="always")
def microfacet_value(s, weight_t, one_sp, n2, Lz, azimuth, beckmann, dx, vz, vx, ax, ay, lambda_v, separable,
                     fresnel_kind, fresnel):  # pragma: no cover - compiled
    """(w, F) at one node of :func:`slope_node` for one case's parameters: w = G2(L, V)(1 + c·x) times du/dt and
    the azimuth's Jacobian (0 below the horizon), F the three channels of F(V·H) (1 where ``fresnel_kind`` is 0)."""
    if not Lz > 0:
        return 0.0, (1.0, 1.0, 1.0)
    tangent2 = max((1.0 - Lz) * (1.0 + Lz), 0.0) * (ay * ay)
    if ax != ay:
        Lx = 2.0 * vz * one_sp * s * dx / n2 - vx
        tangent2 += (ax * ax - ay * ay) * Lx * Lx
    a2 = tangent2 / (Lz * Lz)
    lambda_l = beckmann_lambda(a2) if beckmann else ggx_lambda(a2)
    if separable:
        G2 = 1.0 / ((1.0 + lambda_l) * (1.0 + lambda_v))
    else:
        G2 = 1.0 / (1.0 + lambda_l + lambda_v)
    weight = G2 * one_sp * weight_t * azimuth
    if fresnel_kind == 0:
        return weight, (1.0, 1.0, 1.0)
    cos_vh = vz * one_sp / math.sqrt(n2)
    return weight, (fresnel_factor(fresnel_kind, cos_vh, fresnel, 0), fresnel_factor(fresnel_kind, cos_vh, fresnel, 1),
                    fresnel_factor(fresnel_kind, cos_vh, fresnel, 2))


@njit(**_OPTIONS, inline="always")
def reflected_value(shader, s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, ax, case):  # pragma: no cover - compiled
    """The generic weight g·J of the reflected direction ω = 2(F·H)H − F at one node of :func:`slope_loop` (the
    weight of :func:`brdfnorm.engine.routes.halfvector_generic.route`): (g, N·L, J, finite above the horizon,
    non-finite above the horizon); ``case``: F, the shader's fixed direction and parameters u, and whether ω is the
    light (the shader's first direction); ``shader``: f(lx, ly, lz, vx, vy, vz, u) -> tuple (the kernels' copy's
    own, or a first-class function of :func:`brdfnorm.engine.compiled.global_rule.shader_global`)."""
    fx, fy, fz, wx, wy, wz, u, over_light = case[0], case[1], case[2], case[3], case[4], case[5], case[6], case[7]
    root = math.sqrt(n2)
    cos_fh = fz * one_sp / root
    ox = 2.0 * cos_fh * (s * dx / root) - fx
    oy = 2.0 * cos_fh * (s * dy / root) - fy
    if over_light:
        g = shader(ox, oy, Lz, wx, wy, wz, u)
    else:
        g = shader(wx, wy, wz, ox, oy, Lz, u)
    one_s2 = 1.0 + s * s
    jacobian = 4.0 * cos_fh * math.pi * ax * ax * one_s2 * one_s2 / (n2 * root) * weight_t * azimuth
    inside = Lz > 0
    finite = True
    for c in range(len(g)):
        if not math.isfinite(g[c] * Lz):
            finite = False
    return g, Lz, jacobian, inside and finite, inside and not finite


@njit(error_model="numpy", inline="always")
def slope_loop(case, value, k, phi, v, piece, linear, log_horizon, beckmann, vz, cos_offset, sin_offset, amplitude, ax,
               ay, layer, delta, kappa, multiplicity, extra, largest, out, flags):  # pragma: no cover - compiled
    """The one loop of the half-vector route's rectangle integrands on grids φ (R, nφ) × v (R, nv) of the panels of
    cases ``k`` (R,) in radial ``piece`` (R,): per panel ``case(q, extra)`` -> the case's parameters, per azimuth
    :func:`azimuth_node` and :func:`piece_extent`, per radial node :func:`slope_node`, then ``value(s, du/dt, 1 + s p,
    1 + s² d², N·L, azimuth Jacobian, dx, dy, vz, ax, ay, parameters)`` -> (g, a, b, keep, flag):
    out[r, i, j, c] = g[c]·a·b (0 where not ``keep``) for the channels of ``out``, the last of them |·|'s largest
    where ``largest``; ``flag`` marks flags[q]. The weights: :func:`microfacet_grid` (no shader) and
    :func:`shader_grid` (a shader's, the shader a first-class function).

    Not cached and always inlined: ``case`` and ``value`` are first-class function arguments, whose types Numba's
    disk cache cannot key across processes; inlined into each cached caller (whose signature holds no function), the
    loop is compiled with it and loaded from the cache with it. Why ``case`` apart and values returned, not written:
    an array passed into a per-node function is reference-counted (an atomic add and subtract) at every node, 20-40 %
    of a kernel's time when its arrays were passed so; per panel the count is paid once."""
    C = out.shape[3] - 1 if largest else out.shape[3]
    for r in range(k.size):
        q = k[r]
        kind = piece[r]
        parameters = case(q, extra)
        for i in range(phi.shape[1]):
            dx, dy, d2, p, q_minus_p, s_h, s_split, s_middle, s_end, azimuth = azimuth_node(
                phi[r, i], linear, cos_offset[q], sin_offset[q], amplitude[q], ax[q], ay[q], layer[q], delta[q],
                kappa[q], multiplicity[q], vz[q], beckmann)
            start, length, log_ratio = piece_extent(kind, s_middle, s_split, s_end, log_horizon, beckmann)
            for j in range(v.shape[1]):
                s, weight_t, one_sp, n2, Lz = slope_node(kind, v[r, j] - kind, start, length, log_ratio, s_h, s_split,
                                                         s_end, log_horizon, beckmann, d2, p, q_minus_p, vz[q])
                g, a, b, keep, flag = value(s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, vz[q], ax[q], ay[q],
                                            parameters)
                if flag:
                    flags[q] = True
                most = 0.0
                for c in range(C):
                    x = g[c] * a * b if keep else 0.0
                    out[r, i, j, c] = x
                    most = max(most, abs(x))
                if largest:
                    out[r, i, j, C] = most


@njit(**_OPTIONS, inline="always")
def microfacet_case(q, extra):  # pragma: no cover - compiled
    """Case ``q``'s parameters of :func:`microfacet_value`, its Fresnel row as numbers: an array (``fresnel[q]``)
    in them would be reference-counted at every node (an atomic add and subtract, ~10 % of the fused loop)."""
    beckmann, vx, lambda_v, separable, fresnel_kind, fresnel = extra
    u = fresnel[q]
    return beckmann, vx[q], lambda_v[q], separable, fresnel_kind, (
        u[0], u[1], u[2], u[3], u[4], u[5], u[6], u[7], u[8], u[9], u[10], u[11], u[12], u[13], u[14], u[15])


@njit(**_OPTIONS, inline="always")
def microfacet_node(s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, vz, ax, ay, case):  # pragma: no cover - compiled
    """(F, w, 1, True, False) of :func:`microfacet_value` (F·w·1 is w·F to the bit)."""
    weight, F = microfacet_value(s, weight_t, one_sp, n2, Lz, azimuth, case[0], dx, vz, case[1], ax, ay, case[2],
                                 case[3], case[4], case[5])
    return F, weight, 1.0, True, False


@njit(**_OPTIONS)
def microfacet_grid(k, phi, v, piece, linear, log_horizon, beckmann, vz, vx, cos_offset, sin_offset, amplitude,
                    ax, ay, layer, delta, kappa, multiplicity, lambda_v, separable, fresnel_kind, fresnel,
                    out):  # pragma: no cover - compiled
    """w·F of :func:`microfacet_value` on grids φ (R, nφ) × v (R, nv) of the panels of cases ``k`` (R,) in radial
    ``piece`` (R,) (:func:`slope_loop`): out (R, nφ, nv, C), C = 1 where ``fresnel_kind`` is 0 (F = 1), else 3
    (``fresnel`` (K, 16): the packed f0, f90, η, k of :func:`brdfnorm.models.native.fresnel_factor`)."""
    slope_loop(microfacet_case, microfacet_node, k, phi, v, piece, linear, log_horizon, beckmann, vz, cos_offset,
               sin_offset, amplitude, ax, ay, layer, delta, kappa, multiplicity,
               (beckmann, vx, lambda_v, separable, fresnel_kind, fresnel), False, out, np.zeros(0, dtype=np.bool_))


def microfacet_rectangle(g, linear: bool, log_horizon: bool, geometry: dict):
    """The microfacet rectangle integrand (case, φ (R, n, 1), v (R, 1, m), piece (R,)) -> (R, n, m, C) of the
    half-vector geometry ``g`` (:class:`brdfnorm.engine.routes.halfvector.SlopeGeometry`) as the compiled kernel;
    ``geometry`` is ``halfvector.slope_map(g)``."""
    K = g.V.shape[0]
    per_case = slope_arrays(geometry, K)
    vx = np.ascontiguousarray(g.V[:, 0], dtype=float)
    lambda_v = np.ascontiguousarray(np.broadcast_to(g.lambda_v, (K,)), dtype=float)
    kind = KERNEL_CODES[g.fresnel_params["fresnel"]]
    fresnel = np.zeros((K, 16))
    for column, name in ((4, "f0"), (7, "f90"), (10, "eta"), (13, "k")):
        value = np.asarray(g.fresnel_params[name], dtype=float)
        fresnel[:, column:column + 3] = np.broadcast_to(value.reshape(-1, value.shape[-1]) if value.ndim else value,
                                                        (K, 3))
    channels = 1 if kind == 0 else 3
    beckmann = g.distribution.name == "beckmann"
    separable = g.shadowing == "separable"

    def integrand(case, phi, v, piece):
        phi, v = rectangle_grids(case, phi, v)
        out = np.empty((case.size, phi.shape[1], v.shape[1], channels))
        microfacet_grid(np.ascontiguousarray(case, dtype=np.int64), phi, v, np.ascontiguousarray(piece, dtype=np.int64),
                        linear, log_horizon, beckmann, per_case[0], vx, *per_case[1:], lambda_v, separable, kind,
                        fresnel, out)
        return out

    integrand.compiled = True  # the route's sums run compiled too
    # and its global rule (compiled.global_rule.integrate), with these arguments of the lobe
    integrand.fused = ("microfacet", channels, (linear, log_horizon, beckmann, separable, per_case[0], vx,
                                                *per_case[1:], lambda_v, kind, fresnel))
    return integrand


@njit(**_OPTIONS, inline="always")
def shader_case(q, extra):  # pragma: no cover - compiled
    """Per case: the reflection's fixed direction F, the shader's fixed direction and parameters U, ``over_light``
    (:func:`reflected_value`'s ``case``) and the shader (extra: F, rows, fixed, U, over_light, shader). The
    parameters are a :func:`borrowed` view of U's row: the shader takes an array, and an owned view would be
    reference-counted at every node (an atomic add and subtract around each shader call)."""
    F, rows, fixed, U, over_light, shader = extra
    row = rows[q]
    return (F[q, 0], F[q, 1], F[q, 2], fixed[row, 0], fixed[row, 1], fixed[row, 2], borrowed(U[row]), over_light,
            shader)


@njit(**_OPTIONS, inline="always")
def shader_node(s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, vz, ax, ay, case):  # pragma: no cover - compiled
    """The generic weight of :func:`reflected_value` with the case's shader (:func:`shader_case`)."""
    return reflected_value(case[8], s, weight_t, one_sp, n2, Lz, azimuth, dx, dy, ax, case)


@njit(**_OPTIONS)
def shader_grid(k, phi, v, piece, linear, log_horizon, vz, cos_offset, sin_offset, amplitude, ax, ay, layer, delta,
                kappa, multiplicity, F, rows, fixed, U, over_light, shader, out, failed):  # pragma: no cover - compiled
    """The half-vector route's rectangle integrand for a ``.brdf`` shader
    (:func:`brdfnorm.engine.routes.halfvector.slope_integrand` for the GGX slope measure, with the generic weight of
    :func:`brdfnorm.engine.routes.halfvector_generic.route`) on grids φ (R, nφ) × v (R, nv) of the panels of the
    local cases ``k`` (R,) in radial ``piece`` (R,) (:func:`slope_loop` with :func:`shader_node`): out
    (R, nφ, nv, C + 1), the weighted values and their largest |value|; ``failed[k]`` where a value above the horizon
    is not finite. ``shader`` is a first-class function (:func:`shader_grid_kernel`), so this kernel is compiled once
    per machine for every shader, as :func:`brdfnorm.engine.compiled.global_rule.shader_global` is, not once per
    shader (1.7-2.5 s of CPU each); it returns at least :data:`.global_rule.PADDED` outputs, of which the channels of
    ``out`` are used."""
    slope_loop(shader_case, shader_node, k, phi, v, piece, linear, log_horizon, False, vz, cos_offset, sin_offset,
               amplitude, ax, ay, layer, delta, kappa, multiplicity, (F, rows, fixed, U, over_light, shader), True,
               out, failed)


def shader_grid_kernel(arguments: list, shader: int, outputs: int):
    """:func:`shader_grid` compiled (or loaded from Numba's cache) for ``arguments``, the one at index ``shader`` (a
    jitted shader of ``outputs`` outputs) typed as a first-class function f(6 × float64, u (P,)) -> ``outputs``
    float64s (called with the jitted function itself, Numba would type the kernel by that function object and compile
    it anew in every process). Returns the compiled entry point, which takes the shader's dispatcher.

    The compile under a mark (:mod:`.marks`) beside Numba's cache of the kernel: where another process is compiling
    the same signature (:mod:`brdfnorm.parallel.warm`'s child, or the command), this one waits for it and loads its
    result instead of compiling it beside it; whichever process needs it first compiles it."""
    argtypes = first_class_argtypes(arguments, shader, outputs)
    if argtypes not in shader_grid.overloads:
        compile_marked(shader_grid, "shader_grid", argtypes)
    return shader_grid.overloads[argtypes].entry_point
