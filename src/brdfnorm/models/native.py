"""The built-in lobes as compiled scalar functions (:class:`brdfnorm.models.base.NativeKernel`), for the compiled
engine (:mod:`brdfnorm.engine.compiled`).

Each function is its lobe's :meth:`~brdfnorm.models.base.Model.evaluate` written for one (L, V) pair, term for term
(the same cancellation-free forms, the same clamps and horizon tests), returning f itself (not f·N·L) as a tuple of
channels; ``error_model="numpy"`` gives IEEE results (inf, NaN) where numpy's would, never an exception. The
parameters of one case are packed into a float64 vector ``u`` by the lobe's ``pack``. Lobes and options without a
kernel here (Kulla–Conty and Turquin compensation, the rough dielectrics, Mitsuba plugins)
return None from ``native_kernel()`` and are evaluated through numpy.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import numpy as np
from numba import njit

from .base import Model, NativeKernel
from .fresnel import KERNEL_CODES

_PI = math.pi
_SQRT_PI = math.sqrt(math.pi)
_OPTIONS = dict(cache=True, error_model="numpy")


@njit(**_OPTIONS)
def lambert(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    return (u[0] / _PI,)


@njit(**_OPTIONS)
def phong(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    rv = -lx * vx - ly * vy + lz * vz
    return (math.pow(max(rv, 0.0), u[0]) / lz,)


@njit(**_OPTIONS)
def modified_phong(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    rv = -lx * vx - ly * vy + lz * vz
    return (math.pow(max(rv, 0.0), u[0]),)


@njit(**_OPTIONS)
def _half_cosine(lx, ly, lz, vx, vy, vz):  # pragma: no cover - compiled
    sx, sy, sz = lx + vx, ly + vy, lz + vz
    c = sz / math.sqrt(sx * sx + sy * sy + sz * sz)
    return min(max(c, 0.0), 1.0) if c == c else c


@njit(**_OPTIONS)
def blinn_phong(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    return (math.pow(_half_cosine(lx, ly, lz, vx, vy, vz), u[0]),)


@njit(**_OPTIONS)
def blinn_phong_gaussian(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    n = u[0]
    c = math.pow(0.04, 1.0 / n) if n > 0 else 0.0
    angle = (_half_cosine(lx, ly, lz, vx, vy, vz) - 1.0) / (c - 1.0)
    return (math.exp(-angle * angle),)


@njit(**_OPTIONS)
def burley(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    if not (lz > 0 and vz > 0):
        return (0.0,)
    cos2_d = 0.5 * (1.0 + lx * vx + ly * vy + lz * vz)
    f90 = 0.5 + 2.0 * u[0] * cos2_d
    return (u[1] / _PI * (1.0 + (f90 - 1.0) * (1.0 - min(lz, 1.0)) ** 5)
            * (1.0 + (f90 - 1.0) * (1.0 - min(vz, 1.0)) ** 5),)


@njit(**_OPTIONS)
def oren_nayar(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    if not (lz > 0 and vz > 0):
        return (0.0,)
    s2 = u[0] * u[0]
    A = 1.0 - 0.5 * s2 / (s2 + 0.33)
    B = 0.45 * s2 / (s2 + 0.09)
    s = lx * vx + ly * vy + lz * vz - lz * vz
    return (u[1] / _PI * (A + B * max(s, 0.0) / max(lz, vz)),)


# -- the energy-preserving Oren-Nayar family (fon.py, eon.py): u = (r, ρ) ----------------------------------------

# fon.py's constants, restated (fon.py imports this module; the kernels' tests compare with its numpy lobes)
_C1 = 0.5 - 2.0 / (3.0 * math.pi)
_C2 = 2.0 / 3.0 - 28.0 / (15.0 * math.pi)
_APPROX = (0.0571085289, 0.491881867, -0.332181442, 0.0714429953)


@njit(**_OPTIONS)
def _fon_single(lx, ly, lz, vx, vy, vz, r, rho):  # pragma: no cover - compiled
    if not (lz > 0 and vz > 0):
        return 0.0
    s = lx * vx + ly * vy + lz * vz - lz * vz
    s_over_t = s / max(lz, vz) if s > 0 else s
    return rho / _PI / (1.0 + _C1 * r) * (1.0 + r * s_over_t)


@njit(**_OPTIONS)
def _fon_albedo_exact(mu, r):  # pragma: no cover - compiled
    mu = min(max(mu, 0.0), 1.0)
    S = math.sqrt(max(0.0, (1.0 - mu) * (1.0 + mu)))
    g = S * (math.acos(mu) - S * mu) + (2.0 / 3.0) * (S * mu * (1.0 + S + S * S) / (1.0 + S) - S)
    a = 1.0 / (1.0 + _C1 * r)
    return a + r * a / _PI * g


@njit(**_OPTIONS)
def _fon_albedo_approx(mu, r):  # pragma: no cover - compiled
    x = 1.0 - min(max(mu, 0.0), 1.0)
    c1, c2, c3, c4 = _APPROX
    return (1.0 + r * (x * (c1 + x * (c2 + x * (c3 + x * c4))))) / (1.0 + _C1 * r)


@njit(**_OPTIONS)
def fon_lobe(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    return (_fon_single(lx, ly, lz, vx, vy, vz, u[0], u[1]),)


@njit(**_OPTIONS)
def _eon(lx, ly, lz, vx, vy, vz, u, exact):  # pragma: no cover - compiled
    r, rho = u[0], u[1]
    single = _fon_single(lx, ly, lz, vx, vy, vz, r, rho)
    average = (1.0 + _C2 * r) / (1.0 + _C1 * r)
    if not (lz > 0 and vz > 0 and average < 1.0):
        return single
    if exact:
        el, ev = _fon_albedo_exact(lz, r), _fon_albedo_exact(vz, r)
    else:
        el, ev = _fon_albedo_approx(lz, r), _fon_albedo_approx(vz, r)
    rho_ms = rho * rho * average / (1.0 - rho * (1.0 - average))
    return single + rho_ms / _PI * (1.0 - el) * (1.0 - ev) / (1.0 - average)


@njit(**_OPTIONS)
def eon_exact(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    return (_eon(lx, ly, lz, vx, vy, vz, u, True),)


@njit(**_OPTIONS)
def eon_approx(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    return (_eon(lx, ly, lz, vx, vy, vz, u, False),)


# -- the charlie sheen lobe (charlie.py): u = (α, neubelt, terminator, colour[3]) -----------------------------------

# charlie.py's Λ fits at α = 0 and α = 1, restated (charlie.py imports this module)
_FIT_0 = (25.3245, 3.32435, 0.16801, -1.27393, -4.85967)
_FIT_1 = (21.5473, 3.82987, 0.19823, -1.97760, -4.32054)


@njit(**_OPTIONS)
def _charlie_fit(x, alpha):  # pragma: no cover - compiled
    t = (1.0 - alpha) ** 2
    a = t * _FIT_0[0] + (1.0 - t) * _FIT_1[0]
    b = t * _FIT_0[1] + (1.0 - t) * _FIT_1[1]
    c = t * _FIT_0[2] + (1.0 - t) * _FIT_1[2]
    d = t * _FIT_0[3] + (1.0 - t) * _FIT_1[3]
    e = t * _FIT_0[4] + (1.0 - t) * _FIT_1[4]
    return a / (1.0 + b * math.pow(x, c)) + d * x + e


@njit(**_OPTIONS)
def _charlie_lambda(mu, alpha, soften):  # pragma: no cover - compiled
    mu = min(max(mu, 0.0), 1.0)
    if mu < 0.5:
        value = math.exp(_charlie_fit(mu, alpha))
    else:
        value = math.exp(2.0 * _charlie_fit(0.5, alpha) - _charlie_fit(1.0 - mu, alpha))
    return math.pow(value, 1.0 + 2.0 * (1.0 - mu) ** 8) if soften else value


@njit(**_OPTIONS)
def charlie(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    alpha = u[0]
    if not (lz > 0 and vz > 0):
        return (0.0, 0.0, 0.0)
    sx, sy, sz = lx + vx, ly + vy, lz + vz
    cos_h = sz / math.sqrt(sx * sx + sy * sy + sz * sz)
    sin2 = min(max(1.0 - cos_h * cos_h, 0.0), 1.0)
    inv = 1.0 / alpha
    D = (2.0 + inv) * math.pow(sin2, 0.5 * inv) / (2.0 * _PI)
    if u[1] == 1.0:
        white = D * lz / (4.0 * (lz + vz - lz * vz))
    else:
        white = D / ((1.0 + _charlie_lambda(vz, alpha, False) + _charlie_lambda(lz, alpha, u[2] == 1.0)) * 4.0 * vz)
    f = white / lz
    return (f * u[3], f * u[4], f * u[5])


def _pack_charlie(params: Mapping[str, object]) -> np.ndarray:
    alpha = float(np.asarray(params["alpha"], dtype=float).reshape(-1)[0])
    rough = float(np.asarray(params["roughness"], dtype=float).reshape(-1)[0])
    colour = np.broadcast_to(np.asarray(params["color"], dtype=float).reshape(-1), (3,))
    return np.concatenate([[alpha if alpha > 0 else rough * rough, 1.0 if params["shadowing"] == "neubelt" else 0.0,
                            1.0 if bool(params["terminator"]) else 0.0], colour])


# -- microfacet lobes: u = (α_x, α_y, separable, fresnel kind, f0[3], f90[3], η[3], k[3]) -----------------------

@njit(**_OPTIONS)
def ggx_lambda(a2):  # pragma: no cover - compiled
    return 0.5 * a2 / (1.0 + math.sqrt(1.0 + a2))


@njit(**_OPTIONS)
def beckmann_lambda(a2):  # pragma: no cover - compiled
    if a2 == 0.0:
        return 0.0
    if math.isinf(a2):
        return math.inf
    b = 1.0 / math.sqrt(a2)
    # e^{−b²}/(2b√π) − erfc(b)/2: the same value as numpy's erfcx form; both terms underflow together
    return 0.5 * (math.exp(-b * b) / (b * _SQRT_PI) - math.erfc(b))


@njit(**_OPTIONS)
def fresnel_factor(kind, c, u, i):  # pragma: no cover - compiled
    if kind == 1:  # schlick
        f0, f90 = u[4 + i], u[7 + i]
        return f0 + (f90 - f0) * (1.0 - c) ** 5
    eta = u[10 + i]
    if kind == 2:  # dielectric
        g2 = eta * eta - 1.0 + c * c
        if g2 <= 0.0:
            return 1.0
        g = math.sqrt(g2)
        a = (g - c) / (g + c)
        b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
        return 0.5 * a * a * (1.0 + b * b)
    k = u[13 + i]
    c2 = c * c
    s2 = 1.0 - c2
    t = eta * eta - k * k - s2
    a2b2 = math.sqrt(t * t + 4.0 * eta * eta * k * k)
    a = math.sqrt(max(0.5 * (a2b2 + t), 0.0))
    rs = (a2b2 - 2.0 * a * c + c2) / (a2b2 + 2.0 * a * c + c2)
    rp = rs * (c2 * a2b2 - 2.0 * a * c * s2 + s2 * s2) / (c2 * a2b2 + 2.0 * a * c * s2 + s2 * s2)
    return 0.5 * (rs + rp)


@njit(**_OPTIONS)
def _microfacet(lx, ly, lz, vx, vy, vz, u, beckmann):  # pragma: no cover - compiled
    """(D G2 / (4 N·L N·V), clamped V·H): the single-scattering lobe without its Fresnel factor; D G2 = 0 below
    either horizon."""
    ax, ay = u[0], u[1]
    sx, sy, sz = lx + vx, ly + vy, lz + vz
    ss = sx * sx + sy * sy + sz * sz
    r2 = (sx / (sz * ax)) ** 2 + (sy / (sz * ay)) ** 2
    hz2 = sz * sz / ss
    density = math.exp(-r2) / _PI if beckmann else 1.0 / (_PI * (1.0 + r2) ** 2)
    D = density / (ax * ay * hz2 * hz2)
    a2l = ((ax * lx) ** 2 + (ay * ly) ** 2) / (lz * lz)
    a2v = ((ax * vx) ** 2 + (ay * vy) ** 2) / (vz * vz)
    if beckmann:
        ll, lv = beckmann_lambda(a2l), beckmann_lambda(a2v)
    else:
        ll, lv = ggx_lambda(a2l), ggx_lambda(a2v)
    G2 = 1.0 / ((1.0 + ll) * (1.0 + lv)) if u[2] == 1.0 else 1.0 / (1.0 + ll + lv)
    cos_vh = (vx * sx + vy * sy + vz * sz) / math.sqrt(ss)
    cos_vh = min(max(cos_vh, 0.0), 1.0) if cos_vh == cos_vh else cos_vh
    if not (lz > 0 and vz > 0):
        return 0.0, cos_vh
    return D * G2 / (4.0 * vz) / lz, cos_vh


@njit(**_OPTIONS)
def ggx(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    return (_microfacet(lx, ly, lz, vx, vy, vz, u, False)[0],)


@njit(**_OPTIONS)
def beckmann(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    return (_microfacet(lx, ly, lz, vx, vy, vz, u, True)[0],)


@njit(**_OPTIONS)
def ggx_fresnel(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    f, c = _microfacet(lx, ly, lz, vx, vy, vz, u, False)
    kind = int(u[3])
    return (f * fresnel_factor(kind, c, u, 0), f * fresnel_factor(kind, c, u, 1), f * fresnel_factor(kind, c, u, 2))


@njit(**_OPTIONS)
def beckmann_fresnel(lx, ly, lz, vx, vy, vz, u):  # pragma: no cover - compiled
    f, c = _microfacet(lx, ly, lz, vx, vy, vz, u, True)
    kind = int(u[3])
    return (f * fresnel_factor(kind, c, u, 0), f * fresnel_factor(kind, c, u, 1), f * fresnel_factor(kind, c, u, 2))


# -- packing -------------------------------------------------------------------------------------------------------

def _floats(*names: str) -> Callable[[Mapping[str, object]], np.ndarray]:
    def pack(params: Mapping[str, object]) -> np.ndarray:
        return np.array([float(np.asarray(params[name], dtype=float).reshape(-1)[0]) for name in names])
    return pack


def _pack_microfacet(params: Mapping[str, object]) -> np.ndarray:
    def scalar(name: str) -> float:
        return float(np.asarray(params[name], dtype=float).reshape(-1)[0])

    alpha = scalar("alpha")
    ax, ay = scalar("alpha_x"), scalar("alpha_y")
    colours = [np.broadcast_to(np.asarray(params[name], dtype=float).reshape(-1), (3,)) for name in
               ("f0", "f90", "eta", "k")]
    return np.concatenate([[ax if ax > 0 else alpha, ay if ay > 0 else alpha,
                            1.0 if params["shadowing"] == "separable" else 0.0,
                            float(KERNEL_CODES[params["fresnel"]])], *colours])


_SIMPLE = {
    "lambert": (lambert, ("reflectance",)),
    "phong": (phong, ("n",)),
    "modified-phong": (modified_phong, ("n",)),
    "blinn-phong": (blinn_phong, ("n",)),
    "blinn-phong-gaussian": (blinn_phong_gaussian, ("n",)),
    "burley": (burley, ("roughness", "reflectance")),
    "oren-nayar": (oren_nayar, ("sigma", "reflectance")),
    "fon": (fon_lobe, ("roughness", "reflectance")),
}


def kernel_of(model: Model) -> NativeKernel | None:
    """The compiled lobe of a built-in model at its bound choices (None where there is none)."""
    if model.name in _SIMPLE:
        function, names = _SIMPLE[model.name]
        return NativeKernel(function, 1, _floats(*names), f"builtin:{model.name}")
    if model.name == "charlie":
        return NativeKernel(charlie, 3, _pack_charlie, "builtin:charlie")
    if model.name == "eon":
        function = eon_exact if model.params["fon_albedo"] == "exact" else eon_approx
        return NativeKernel(function, 1, _floats("roughness", "reflectance"), f"builtin:{function.py_func.__name__}")
    if model.name in ("ggx", "beckmann"):
        params = model.params
        if params["ms"] != "none":
            return None
        plain = params["fresnel"] == "none"
        function = {("ggx", True): ggx, ("ggx", False): ggx_fresnel, ("beckmann", True): beckmann,
                    ("beckmann", False): beckmann_fresnel}[(model.name, plain)]
        return NativeKernel(function, 1 if plain else 3, _pack_microfacet,
                            f"builtin:{function.py_func.__name__}")
    return None
