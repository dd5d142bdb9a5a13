"""Certified energy tables: every cell of E(μ, α) — and E_avg(α) — a proven enclosure, not an estimate.

``lut.compute(..., method="certified", digits=N)`` for the isotropic ``ggx`` and ``beckmann`` lobes with
``fresnel=none`` (either shadowing) over a direction axis (``mu``, certified at the float64 μ given, exactly; or
``theta``, at the float64 radian given) and optionally an ``alpha`` axis. Each cell is
:func:`brdfnorm.engine.routes.certified.enclose` (Arb ball arithmetic, the azimuth in closed form), so the tables
carry, besides ``E`` (the enclosure's midpoint rounded to float64) and ``E_error`` (a bound on |E − true|):

* ``E_lower``/``E_upper``: float64 bounds rounded outward (E_lower ≤ true value ≤ E_upper, always);
* ``meta["certified"]["E"]["lower"/"upper"]``: the decimal bounds (N + 2 significant digits, rounded outward)
  as nested lists of strings, which every format that keeps the meta (``.json``, ``.npz``, …) carries.

``digits`` is met: every enclosure's relative radius is ≤ 10^−N (the working precision is raised until it is;
a cell that still misses it is counted in ``meta["unconverged"]``).

E_avg(α) = 2∫₀¹ E(μ) μ dμ is NOT certified: it is refused (pass ``average=False`` / ``--no-average``), never
replaced by an estimate. Two 2-D rigorous integrals were tried and give no usable bound in reasonable time:
(1) Arb over θ_V with the 1-D reduction as its integrand, continued to complex θ_V: on a complex ball of θ_V the
horizon end θ_L = θ_V + 2 atan d(θ_V) = π/2 loses its exactness to ball arithmetic's dependency problem (a ball of
radius 0.01 in θ_V gave θ_L ± 0.9); (2) Arb over t (d = α sinh t, δ = θ_L − θ_V fixed) with θ_V on [0, π/2 − δ]
inside (endpoints exact, no dependency at the horizon): there a complex ball of t of radius 0.1 already makes
√(cos²θ_L + α² sin²θ_L)'s argument a ball containing 0 (δ = 2 atan(α sinh t) ± 0.35), so the inner bound fails
and the outer integrator bisects without end (a third variant, the outer variable d itself with
√(cos²θ_L + α² sin²θ_L) written as √(1 − (1 − α²) sin²θ_L), bounds its inner integral on complex balls of d up to
radius 0.02 but meets a corner: at d = 0 and θ_V = θ_L = π/2 the height-correlated G2 = 2μ cos θ_L/(cos θ_L R_V +
μ R_L) is 0/0 — bounded but not analytic — so the outer integrand is not analytic at d = 0 and Arb bisects towards
it level by level).

A fourth route is rigorous and measured, but too slow to ship (``benchmarks/probe_certified_average.py`` has it and
its docstring the derivation): Arb over θ_V on [0, π/2 − ε] (the rest is [0, ε²] because 0 ≤ E ≤ 1 for F = 1),
its integrand the inner Arb integral over s ∈ [0, 1] with t = t₀ + (t₁ − t₀)s, so the inner domain is fixed, and
sin θ_L, cos θ_L written through tan(θ_L/2) and tan((π/2 − θ_L)/2) as products with sinh(Ls/2) and
sinh(L(1 − s)/2), so they vanish exactly at the ends. The horizon is then exact, but the kernel's plain ball
arithmetic still blows a complex ball of θ_V up (radius 0.01 at α = 1: sin θ_L ± 0.8, NaN; at α = 1e-4 only radius
≲ 1e-4 gives a usable bound), so the outer integrator must bisect into ~10³ subintervals: GGX height-correlated
α = 1 took 370 s for 12 digits ([0.409137092586740 ± 4.7e-16]; the float64 route's 0.40913709258673825 ± 5.8e-12
agrees) on the shared 2-core machine, and small α needs balls of radius ~α. (python-flint's ``acb.asinh`` also
returns NaN on complex balls of real part ~4·10³; the probe uses log(y + √(y² + 1)).) What would make it fast: a
centred (mid + derivative, e.g. ``acb_series``) evaluation of the kernel on complex balls, so that the outer
ellipses can be O(1) wide.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

import numpy as np

from ..engine.routes import certified
from ..errors import ArgumentError
from .axes import checked_axes
from .table import Lut, plain_params

#: Models with certified tables: the isotropic microfacet lobes with F = 1.
MODELS = ("ggx", "beckmann")
#: Axes a certified table may have besides its direction axis.
PARAMETER_AXES = ("alpha",)


def check_model(model, axes: Mapping[str, object]) -> None:
    """Refuse, before any work, what has no certified table (with the reason)."""
    if model.name not in MODELS or type(model).__module__.startswith("brdfnorm.brdffile"):
        raise ArgumentError(f"no certified table for {model.name}: certified tables cover the isotropic "
                            f"{' and '.join(MODELS)} lobes with fresnel=none", where="method")
    params = model.params
    if params.get("fresnel", "none") != "none":
        raise ArgumentError(f"{model.name}: certified tables need fresnel=none (away from normal incidence the "
                            "certified route has no Fresnel)", where="method")
    if not model.isotropic:
        raise ArgumentError(f"{model.name}: certified tables need an isotropic alpha", where="method")
    if params.get("ms", "none") != "none":
        raise ArgumentError(f"{model.name}: ms={params['ms']} interpolates tables; no certified route",
                            where="method")
    for name in axes:
        if name not in ("mu", "theta", *PARAMETER_AXES):
            raise ArgumentError(f"certified tables take the axes mu or theta and alpha, not {name!r}",
                                where="axes")


def _strings(values: np.ndarray) -> list:
    return values.tolist()


def cell_tables(model, theta_flat: np.ndarray, mu_flat: np.ndarray | None, alpha_flat: np.ndarray, shape: tuple,
                digits: int, progress: Callable[[int], None] | None = None):
    """E over the cells: (tables (E, E_error, E_lower, E_upper), decimal bounds, unconverged count, working
    bits used at most, evaluations)."""
    K = theta_flat.size
    value, error = np.empty(K), np.empty(K)
    lower, upper = np.empty(K), np.empty(K)
    lower_text, upper_text = np.empty(K, dtype=object), np.empty(K, dtype=object)
    missed, bits, evaluations = 0, 0, 0
    for k in range(K):
        params = {**model.params, "alpha": float(alpha_flat[k])}
        (e,) = certified.enclose(model, float(theta_flat[k]), params, digits=digits,
                                 mu=None if mu_flat is None else float(mu_flat[k]))
        value[k], error[k], lower[k], upper[k] = e.value, e.error, e.lower_float, e.upper_float
        lower_text[k], upper_text[k] = e.lower, e.upper
        missed += not e.reached
        bits, evaluations = max(bits, e.bits), evaluations + e.evaluations
        if progress is not None:
            progress(k + 1)
    tables = {"E": value.reshape(shape), "E_error": error.reshape(shape), "E_lower": lower.reshape(shape),
              "E_upper": upper.reshape(shape)}
    decimals = {"lower": _strings(lower_text.reshape(shape)), "upper": _strings(upper_text.reshape(shape))}
    return tables, decimals, missed, bits, evaluations


def refuse_average(model) -> None:
    """E_avg has no certified route: refused, never replaced by an estimate (module docstring)."""
    raise ArgumentError(f"{model.name}: E_avg = 2∫E(μ)μdμ has no certified route yet; make the certified table "
                        "without it (--no-average, average=False) or compute E_avg with another method",
                        where="method")


def compute(model, axes: Mapping[str, Sequence[float]], *, clamp: Mapping[str, float] | None = None,
            digits: int = 12, average: bool = True, grid: str | None = None, source: str | None = None,
            progress: Callable[[int, int], None] | None = None) -> Lut:
    """Certified tables of ``model`` over ``axes`` (``mu`` or ``theta`` in radians, and ``alpha``): E, E_error,
    E_lower, E_upper and 1-E, with the decimal bounds in ``meta["certified"]`` (module docstring)."""
    from .. import __version__

    check_model(model, axes)
    digits = certified.validate_digits(digits)
    certified.require_flint()
    if average:
        refuse_average(model)
    clamp = dict(clamp or {})
    _, evaluated, direction = checked_axes(model, axes, clamp)
    names = list(evaluated)
    shape = tuple(len(evaluated[n]) for n in names)
    grids = np.meshgrid(*[evaluated[n] for n in names], indexing="ij")
    flat = {n: g.ravel() for n, g in zip(names, grids, strict=True)}
    alpha = flat.get("alpha", np.full(grids[0].size, float(model.params["alpha"])))
    mu = flat["mu"] if direction == "mu" else None
    theta = np.arccos(mu) if mu is not None else flat["theta"]
    cells = theta.size
    report = None if progress is None else (lambda done: progress(done, cells))
    tables, decimals, missed, bits, evaluations = cell_tables(model, theta, mu, alpha, shape, digits, report)
    tables["1-E"] = 1.0 - tables["E"]
    fixed = {k: v for k, v in model.params.items() if k not in axes}
    meta = {"model": source or model.name, "parameters": plain_params(fixed), "grid": grid, "clamp": clamp,
            "method": "certified", "units": {"mu": "cos theta_o", "theta": "radians"}, "brdfnorm": __version__,
            "unconverged": missed, "evaluations": evaluations,
            "certified": {"digits": digits, "working_bits_max": bits,
                          "view": ("each cell certified at the float64 mu of its axis value (after --clamp), "
                                   "exactly" if mu is not None else
                                   "each cell certified at the float64 radian of its theta axis value, exactly"),
                          "E": decimals,
                          "E_lower/E_upper": "float64 bounds rounded outward: E_lower <= E <= E_upper for the "
                                             "true E of every cell"}}
    return Lut(tables, axes, meta, {name: tuple(names) for name in tables})

