"""Directional albedo of a model over many directions (and parameter values) at once.

E(V) = ∫_H f(L, V)(N·L) dL — seed 002's energy-normalization integral, the light integrated with the view
fixed (``over="light"``, the default). ``over="view"`` is the other reading: the light fixed and
∫_H f(L, V)(N·V) dV; the two differ for non-reciprocal lobes such as the original Phong (2π/(n+1) against
2π/(n+2) at normal incidence).

Methods (a registry, colour-science style): ``"quadrature"`` (:mod:`brdfnorm.engine.routes.quadrature`, any model),
``"closed-form"`` (only where the model declares one — e.g. normal incidence — and an error elsewhere, never
substituted silently), the exact routes of particular lobes (:mod:`brdfnorm.engine.routes`), ``"material"`` for
OpenPBR (declared by where it lives, :class:`brdfnorm.registry.Reference`: :mod:`brdfnorm.materials` lies above
the engine), and those a user adds with :func:`register_method`. ``"auto"`` takes the first applicable of
:data:`AUTO_ORDER`.

This module is the front door only: it turns angles and parameter values into a :class:`Problem`, picks the
method, and builds the public :class:`AlbedoResult` from the route's
:class:`brdfnorm.engine.machinery.result.RouteResult` (:func:`albedo_result`).

(The module is ``brdfnorm.engine.methods`` so that the function ``brdfnorm.albedo`` does not shadow it.)
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from decimal import Decimal

import numpy as np

from .. import validate
from ..errors import ArgumentError, ArgumentTypeError
from ..models.base import Model, Over
from ..models.blinn_phong import BlinnPhong
from ..models.dielectric import MicrofacetDielectric
from ..models.microfacet import MicrofacetModel
from ..output.formats import Column, Records, channel_value, degrees, format_value
from ..registry import Reference, Registry
from ..validate import DEFAULT_MAX_EVALUATIONS, DEFAULT_RTOL
from .compiled import backend as compiled_backend
from .machinery.result import RouteResult
from .routes import azimuthal, certified, quadrature
from .routes.dielectric import albedo_method as _dielectric
from .routes.hemisphere import NonFinitePolicy
from .routes.microfacet import azimuthal_method as _azimuthal_method
from .routes.microfacet import halfvector_method as _microfacet
from .routes.series import albedo_method as _series


@dataclass(frozen=True)
class AlbedoResult:
    """Albedo over a batch of directions: arrays of the broadcast shape S of (theta, phi, parameters)."""

    value: np.ndarray  # (*S, C)
    error: np.ndarray  # (*S, C) error estimate (absolute)
    evaluations: np.ndarray  # (*S,) integrand evaluations
    converged: np.ndarray  # (*S,) bool
    method: str
    theta: np.ndarray  # (*S,) radians
    phi: np.ndarray  # (*S,) radians
    over: Over
    params: dict = field(default_factory=dict)  # parameter values broadcast to S (colors: (*S, 3))
    nonfinite_fraction: np.ndarray | None = None  # (*S,) share of the hemisphere zeroed (nonfinite="zero")
    lower: np.ndarray | None = None  # (*S, C) decimal strings, a guaranteed lower bound (method "certified")
    upper: np.ndarray | None = None  # (*S, C) decimal strings, a guaranteed upper bound (method "certified")
    #: (*S,) str: "" where converged, else why not — "rounding-limited" (the integrand's float64 noise exceeds
    #: the tolerance), "stalled" (the estimate stopped improving) or "budget" (max_evaluations ran out).
    reason: np.ndarray | None = None
    reflected: np.ndarray | None = None  # (*S, C) the upper hemisphere's share, for models that transmit (BSDFs)
    transmitted: np.ndarray | None = None  # (*S, C) the lower hemisphere's share; value = reflected + transmitted
    model: str = ""  # the model's name
    bound: dict = field(default_factory=dict)  # the model's parameter values as bound (before broadcasting)
    rtol: float = 0.0

    def records(self) -> Records:
        """One row per direction (θ, φ in degrees), for :mod:`brdfnorm.output.formats`."""
        rows = [
            {"theta_deg": degrees(self.theta[i]), "phi_deg": degrees(self.phi[i]),
             "albedo": channel_value(self.value[i]), "error_estimate": channel_value(self.error[i]),
             "method": self.method, "evaluations": int(self.evaluations[i]), "converged": bool(self.converged[i]),
             "reason": "" if self.reason is None else str(self.reason[i])}
            | ({} if self.reflected is None else {"reflected": channel_value(self.reflected[i]),
                                                  "transmitted": channel_value(self.transmitted[i])})
            | ({} if self.lower is None else {"lower": _decimals(self.lower[i]), "upper": _decimals(self.upper[i]),
                                              # the enclosure is for this float64 radian, exactly (theta_deg is
                                              # for display, 12 digits): shortest round trip and exact decimal
                                              "theta_rad": float(self.theta[i]),
                                              "theta_rad_exact": str(Decimal(float(self.theta[i])))})
            for i in np.ndindex(self.converged.shape)
        ]
        bounds = () if self.lower is None else (Column("theta_rad", "θ (rad, certified)", None),
                                                Column("lower", "lower", None), Column("upper", "upper", None))
        parts = () if self.reflected is None else (Column("reflected", "reflected"),
                                                   Column("transmitted", "transmitted"))
        params = ", ".join(f"{k}={format_value(v, 6)}" for k, v in self.bound.items())
        return Records(
            title=f"{self.model} albedo over the {self.over} ({params})",
            meta={"model": self.model, "params": self.bound, "over": self.over, "rtol": self.rtol},
            columns=(Column("theta_deg", "θ (deg)", 6), Column("phi_deg", "φ (deg)", 6), Column("albedo", "albedo"))
            + parts
            + (Column("error_estimate", "error estimate", 3, bound=True), Column("method", "method", None),
                     Column("evaluations", "evaluations", None), Column("converged", "converged", None),
                     Column("reason", "reason", None))
            + bounds,
            rows=rows,
        )


def _decimals(values: np.ndarray) -> str | list[str]:
    """Certified bounds (decimal strings): a string for single-channel models, a list for multi-channel ones."""
    return str(values.ravel()[0]) if values.size == 1 else [str(v) for v in values.ravel()]


#: Working memory of one albedo integral while a batch is integrated at once (the adaptive cubature's nodes and
#: values for every case): measured 25 KiB (lambert), 41 KiB (phong) and 92 KiB (ggx-dielectric, both hemispheres)
#: per integral at 4 000 angles; a BSDF counts twice. A batch that cannot fit is refused up front.
BYTES_PER_INTEGRAL = 48 * 1024


@dataclass(frozen=True)
class Problem:
    """A batch of albedo integrals, flattened: K cases with their fixed direction and parameter values."""

    model: Model
    shape: tuple[int, ...]
    theta: np.ndarray  # (*S,)
    phi: np.ndarray  # (*S,)
    fixed: np.ndarray  # (K, 3)
    params: dict  # per parameter: shared by all cases, or one value per case (names in ``per_case``)
    per_case: frozenset
    broadcast_params: dict  # per parameter, broadcast to S for reporting
    over: Over
    #: The compiled integrand (:class:`brdfnorm.engine.compiled.drivers.NativeIntegrand`) under the compiled
    #: backend, where the model has a compiled lobe; None: numpy evaluates.
    native: object = None
    #: Whether the compiled backend was asked for (the routes with kernels of their own read it).
    compiled: bool = False

    def case_params(self, case: np.ndarray) -> dict:
        """Parameter values for a vector of case indices (shared values stay shared)."""
        return {name: value[case] if name in self.per_case else value for name, value in self.params.items()}

    def integrand(self, omega: np.ndarray, case: np.ndarray) -> np.ndarray:
        """f·cos over the free direction ω for the cases given, shape (M, C)."""
        if self.native is not None:
            return self.native(omega, case)
        fixed = self.fixed[case]
        params = self.case_params(case)
        with np.errstate(all="ignore"):
            if self.over == "light":
                return self.model.projected(omega, fixed, params)
            return self.model.evaluate(fixed, omega, params) * omega[:, 2:3]


def _directions(theta: np.ndarray, phi: np.ndarray) -> np.ndarray:
    st = np.sin(theta)
    return np.stack([st * np.cos(phi), st * np.sin(phi), np.cos(theta)], axis=-1)


def check_model(model: object) -> Model:
    """``model`` if it is a :class:`Model` (what :func:`brdfnorm.load` returns)."""
    if not isinstance(model, Model):
        raise ArgumentTypeError(f"expected a model (brdfnorm.load(...)), got {type(model).__name__}", where="model")
    return model


def make_problem(model: Model, theta, phi=0.0, over: Over = "light") -> Problem:
    """Broadcast angles and (possibly array-valued) parameters into a flat batch of cases."""
    check_model(model)
    validate.choice(over, ("light", "view"), "over")
    theta, phi = validate.angles(theta, phi)
    bound = model.params
    batch_shapes = []
    for p in model.parameters:
        value = np.asarray(bound[p.name])
        batch_shapes.append(() if p.kind == "choice" else value.shape[:-1] if p.per_channel else value.shape)
    try:
        shape = np.broadcast_shapes(theta.shape, phi.shape, *batch_shapes)
    except ValueError:
        raise ArgumentError(f"shapes do not broadcast: theta {theta.shape}, phi {phi.shape}, parameters "
                            f"{', '.join(str(b) for b in batch_shapes)}", where="theta") from None
    sides = 2 if getattr(model, "transmits", False) else 1
    validate.batch_size(shape, bytes_per_integral=BYTES_PER_INTEGRAL * sides)
    theta_b, phi_b = np.broadcast_to(theta, shape), np.broadcast_to(phi, shape)
    params, broadcast = {}, {}
    for p, batch in zip(model.parameters, batch_shapes, strict=True):
        value = bound[p.name]
        if p.kind == "choice":  # a choice is one value for the whole batch (never swept)
            params[p.name] = broadcast[p.name] = value
            continue
        tail = (3,) if p.per_channel else ()
        broadcast[p.name] = np.broadcast_to(np.asarray(value, dtype=float), shape + tail)
        params[p.name] = broadcast[p.name].reshape((-1,) + tail) if batch else value
    fixed = _directions(theta_b, phi_b).reshape(-1, 3)
    per_case = frozenset(p.name for p, batch in zip(model.parameters, batch_shapes, strict=True) if batch)
    return Problem(model, shape, theta_b, phi_b, fixed, params, per_case, broadcast, over)


def with_native(problem: Problem, backend: str) -> Problem:
    """``problem`` with its compiled integrand under the ``"compiled"`` backend, where Numba imports (checked only
    here: the routes that never sample the lobe do not pay for importing it) and the model has a compiled lobe
    (:meth:`brdfnorm.models.base.Model.native_kernel`) that compiles."""
    if backend != "compiled" or not compiled_backend.numba_available():
        return problem
    return replace(problem, native=_native(problem))


def _native(problem: Problem):
    """The compiled integrand of ``problem`` (None where the model has no compiled lobe or it does not compile)."""
    from .compiled.drivers import native_integrand

    kernel = problem.model.native_kernel()
    if kernel is None:
        return None
    K = problem.fixed.shape[0]
    if problem.per_case:  # one packing per distinct parameter set
        rows = [kernel.pack(problem.case_params(np.array([k]))) for k in range(K)]
    else:
        rows = [kernel.pack(problem.params)] * K
    return native_integrand(kernel, problem.fixed, [np.asarray(r, dtype=float).ravel() for r in rows],
                            problem.over == "light")


# -- methods ----------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Method:
    """An albedo method: ``applies(model, over)`` says where it can be used; ``run`` computes it."""

    name: str
    applies: Callable[[Model, Over], bool]
    #: ``run(problem, rtol=, atol=, nonfinite=, max_evaluations=, **options)`` -> a :class:`RouteResult` of the
    #: K cases, value and error (K, C); its ``reason`` None where it gives none ("budget" where unconverged), and
    #: its extras further result fields: ``nonfinite_fraction`` (K,), ``reflected``/``transmitted`` (K, C), the
    #: certified ``lower``/``upper`` bounds (K, C).
    run: Callable[..., RouteResult]
    description: str = ""
    #: Keyword options of :func:`albedo` this method takes besides the tolerances (e.g. ``digits``).
    options: tuple[str, ...] = ()


def _closed_form(problem: Problem, **_: object):
    K = problem.fixed.shape[0]
    value = problem.model.closed_form_albedo(problem.fixed, problem.case_params(np.arange(K)), problem.over)
    value = np.broadcast_to(value, (K, problem.model.channels))
    if np.any(np.isnan(value)):
        raise ArgumentError(
            f"no closed form for {problem.model.name} (over the {problem.over}) at the requested directions; "
            "closed forms hold at normal incidence (theta 0) — use method 'quadrature'", where="method")
    error = 4.0 * np.finfo(float).eps * np.abs(value)  # a few roundings in the formula
    return RouteResult(value, error, np.zeros(K, dtype=np.int64), np.ones(K, dtype=bool))


def _has_closed_form(model: Model, over: Over) -> bool:
    return type(model).closed_form_albedo is not Model.closed_form_albedo


def _reciprocal_microfacet(applies):
    """``applies`` except for ms=turquin over the view: that lobe is not reciprocal (its factor depends on V), and
    the microfacet methods integrate at the fixed direction as if it were; the generic quadrature takes it."""
    return lambda model, over: applies(model, over) and not (over == "view" and model.params.get("ms") == "turquin")


_MATERIAL_APPLIES = Reference("brdfnorm.materials.route:applies").call()


def _material_applies(model: Model, over: Over) -> bool:
    """Whether the method "material" applies: asked of a model whose class derives from one of
    :mod:`brdfnorm.materials` only, so that "auto" for any other model does not import the materials (a ``.brdf``
    table's start: docs/performance.md, eighth round)."""
    return any(c.__module__.startswith("brdfnorm.materials.") for c in type(model).__mro__) and \
        _MATERIAL_APPLIES(model, over)


#: The albedo methods. Besides the generic quadrature and the closed forms: seed 002's hypergeometric form for the
#: built-in Blinn-Phong lobe (reciprocal, so over the light and the view alike; exact to 1e-12 and far faster);
#: isotropic GGX and Beckmann with F = 1 (the lobes of energy-compensation tables) by a 1-D integral with the azimuth
#: in closed form; the microfacet lobes over the half vector with the distribution as the measure (exact to the
#: mirror limit, where the hemisphere coordinates fail); rough dielectrics (BSDFs), reflection and refraction over
#: the facet normal, both parts reported; and rigorous enclosures by Arb ball arithmetic (python-flint, an
#: optional extra), never chosen by "auto": slower, and a different question (a guaranteed interval).
METHODS: Registry[Method] = Registry("method", "method", {
    "quadrature": Method("quadrature", lambda model, over: True, quadrature.albedo_method,
                         "adaptive Gauss-Kronrod cubature in lobe-aligned coordinates"),
    "closed-form": Method("closed-form", _has_closed_form, _closed_form, "exact formula, normal incidence"),
    "series": Method("series", lambda model, over: type(model) is BlinnPhong, _series,
                     "seed 002's 2F1 form as a Legendre function; 1-D adaptive Gauss-Legendre"),
    "azimuthal": Method("azimuthal", _reciprocal_microfacet(azimuthal.applies), _azimuthal_method,
                        "isotropic GGX or Beckmann, F = 1: the azimuth in closed form; 1-D adaptive Gauss-Legendre"),
    "microfacet": Method("microfacet",
                         _reciprocal_microfacet(lambda model, over: isinstance(model, MicrofacetModel)), _microfacet,
                         "half-vector cubature, the slope distribution's CDF as coordinates"),
    "dielectric": Method("dielectric", lambda model, over: isinstance(model, MicrofacetDielectric), _dielectric,
                         "reflection + refraction over the facet normal, the slope distribution as measure"),
    "certified": Method("certified", certified.applies, certified.albedo_method,
                        "guaranteed enclosure by Arb ball arithmetic (1-D reductions)", options=("digits",)),
    # brdfnorm.materials lies above the engine: its method is declared by where it lives, imported on first use
    "material": Method("material", _material_applies,
                       Reference("brdfnorm.materials.route:albedo_method").call(),
                       "a material term by term: its lobes' exact albedos through the layering factors"),
})
#: What ``method="auto"`` tries, in order (the first applicable wins); closed forms are never chosen silently.
AUTO_ORDER: list[str] = ["material", "series", "azimuthal", "microfacet", "dielectric", "quadrature"]


def register_method(method: Method, *, auto_priority: int | None = None) -> None:
    """Add an albedo method; with ``auto_priority`` it is also tried by ``method="auto"`` at that position."""
    METHODS.register(method.name, method)
    if auto_priority is not None and method.name not in AUTO_ORDER:
        AUTO_ORDER.insert(auto_priority, method.name)


def resolve_method(model: Model, over: Over, method: str) -> Method:
    """The method named (``"auto"``: the first applicable of :data:`AUTO_ORDER`), refused where it does not apply."""
    METHODS.validate(method, extra=("auto",))
    if method == "auto":
        for name in AUTO_ORDER:
            if METHODS[name].applies(model, over):
                return METHODS[name]
    chosen = METHODS[method]
    if not chosen.applies(model, over):
        raise ArgumentError(f"method {method!r} does not apply to {model.name} over the {over}", where="method")
    return chosen


def warn_about(name: str, rtol: float, converged: np.ndarray, reason: np.ndarray | None,
               nonfinite_fraction: np.ndarray | None, *, stacklevel: int) -> None:
    """The warnings of a batch of albedos, once for the batch: how many did not converge and why (the reasons
    the integrals gave; "budget" where a method gives none), and the share of non-finite values counted as 0."""
    if not np.all(converged):
        reason = np.where(converged, "", "budget") if reason is None else np.asarray(reason, dtype=str)
        why = ", ".join(f"{np.count_nonzero(reason == r)} {r}" for r in np.unique(reason[~converged]))
        warnings.warn(f"{name}: {np.count_nonzero(~converged)} of {converged.size} albedo integrals did not "
                      f"reach rtol={rtol:g} ({why}); see the error estimates", stacklevel=stacklevel)
    if nonfinite_fraction is not None and np.any(nonfinite_fraction > 0):
        warnings.warn(f"{name}: non-finite BRDF values counted as 0 on up to {100 * nonfinite_fraction.max():.3g}% "
                      "of the hemisphere's solid angle", stacklevel=stacklevel)


def check_settings(model: Model, *, over: Over = "light", rtol: float = DEFAULT_RTOL, atol: float = 0.0,
                   method: str = "auto", nonfinite: NonFinitePolicy = "raise",
                   max_evaluations: int = DEFAULT_MAX_EVALUATIONS, digits: int | None = None
                   ) -> tuple[float, float, Method]:
    """The settings of an albedo computation checked once, for :func:`albedo` and for a table job before its work
    is sent out (:class:`brdfnorm.parallel.job.AlbedoSettings`): (rtol, atol) as floats and the method chosen
    (``"auto"`` resolved for this model and ``over``). Raises :class:`ArgumentError` naming the API argument."""
    rtol, atol = validate.tolerances(rtol, atol)
    validate.count(max_evaluations, "max_evaluations", maximum=10**12)
    validate.choice(nonfinite, ("raise", "zero"), "nonfinite")
    check_model(model)
    validate.choice(over, ("light", "view"), "over")
    if over == "view" and getattr(model, "transmits", False):
        raise ArgumentError(f"{model.name} transmits: its albedo is defined over the light (the view fixed), "
                            "as the energy form of the BSDF states; over='view' is not implemented for BSDFs",
                            where="over")
    chosen = resolve_method(model, over, method)
    for name, given in {"digits": digits}.items():
        if given is not None and name not in chosen.options:
            raise ArgumentError(f"{name} applies to method 'certified' only, not {chosen.name!r}", where=name)
    return rtol, atol, chosen


def albedo(
    model: Model,
    theta,
    phi=0.0,
    *,
    over: Over = "light",
    rtol: float = DEFAULT_RTOL,
    atol: float = 0.0,
    method: str = "auto",
    nonfinite: NonFinitePolicy = "raise",
    max_evaluations: int = DEFAULT_MAX_EVALUATIONS,
    digits: int | None = None,
    backend: str | None = None,
) -> AlbedoResult:
    """Directional albedo of ``model`` at polar angles ``theta`` and azimuths ``phi`` (radians, broadcast).

    Parameter values bound to the model may be arrays (a sweep); they broadcast with ``theta`` and ``phi``.
    Returns values of shape (*S, C) with an absolute error estimate; a point that did not reach the
    tolerance within ``max_evaluations`` has ``converged`` False and triggers a warning.
    ``digits`` (method ``"certified"`` only, default 30) is the number of significant digits asked of the
    enclosure; the result then also carries ``lower`` and ``upper``. ``backend`` ("numpy" or "compiled"; default
    ``$BRDFNORM_BACKEND``, else "compiled" where Numba imports) chooses how the integrand and the cubature's inner
    loops run (:mod:`brdfnorm.engine.compiled`); the answers agree within their error estimates.
    """
    rtol, atol, chosen = check_settings(model, over=over, rtol=rtol, atol=atol, method=method, nonfinite=nonfinite,
                                        max_evaluations=max_evaluations, digits=digits)
    options = {"digits": digits}
    problem = make_problem(model, theta, phi, over)
    backend = compiled_backend.requested(backend)
    if chosen.name == "quadrature":  # the only method that samples the model's own lobe
        problem = with_native(problem, backend)
    problem = replace(problem, compiled=backend == "compiled")
    result = chosen.run(problem, rtol=rtol, atol=atol, nonfinite=nonfinite, max_evaluations=max_evaluations,
                        **{name: given for name, given in options.items() if given is not None})
    return albedo_result(result, problem, chosen.name, rtol)


def albedo_result(result: RouteResult, problem: Problem, method: str, rtol: float) -> AlbedoResult:
    """The public :class:`AlbedoResult` of a method's :class:`RouteResult` over ``problem``'s batch: reshaped to
    the batch's shape, every estimate at least the final rounding (:func:`with_final_rounding`), the batch's
    warnings given once."""
    value, error = result.value, result.error
    if method != "certified":  # a certified error is the enclosure's radius: it bounds the rounding already
        error = with_final_rounding(value, error)
    extras = dict(result.extras)
    bad = extras.pop("nonfinite_fraction", None)
    reason = result.reasons()
    S, C = problem.shape, value.shape[-1]
    warn_about(problem.model.name, rtol, result.converged, reason, bad, stacklevel=4)
    return AlbedoResult(
        value=value.reshape(S + (C,)), error=error.reshape(S + (C,)), evaluations=result.evaluations.reshape(S),
        converged=result.converged.reshape(S), method=method, theta=problem.theta, phi=problem.phi,
        over=problem.over, params=problem.broadcast_params, nonfinite_fraction=None if bad is None else bad.reshape(S),
        reason=reason.reshape(S), **{name: part.reshape(S + (C,)) for name, part in extras.items()},
        model=problem.model.name, bound=problem.model.params, rtol=rtol,
    )


#: The float64 value returned is itself a rounding of the albedo, and the last operations of every route (a sum of
#: panels, a product with 2π) round again: no estimate is smaller than this many units in the last place of it.
FINAL_ROUNDING_ULPS = 4.0


def with_final_rounding(value: np.ndarray, error: np.ndarray) -> np.ndarray:
    """The error estimate, at least :data:`FINAL_ROUNDING_ULPS` units in the last place of the value.

    Every method's result passes through here (the front door, :func:`albedo`), so a printed estimate bounds the
    true error including the rounding of the result itself: a route whose own estimate is below that (a
    difference of two rules that agree to the last bit) would otherwise claim more than float64 holds.
    """
    value = np.asarray(value, dtype=float)
    with np.errstate(invalid="ignore"):
        floor = FINAL_ROUNDING_ULPS * np.spacing(np.abs(value))
        return np.where(np.isfinite(floor), np.maximum(error, floor), error)


def sweep_model(model: Model, sweep: Mapping[str, object] | None) -> tuple[Model, str | None, np.ndarray]:
    """Bind a one-parameter sweep to the model as an array of shape (S, 1) (broadcasting against angles)."""
    check_model(model)
    if sweep is None:
        return model, None, np.zeros(1)
    if not isinstance(sweep, Mapping):
        raise ArgumentTypeError(f"expected a mapping {{name: values}}, got {type(sweep).__name__}", where="sweep")
    if not sweep:
        return model, None, np.zeros(1)
    if len(sweep) != 1:
        raise ArgumentError("sweep one parameter at a time", where="sweep")
    (name, values), = sweep.items()
    if not isinstance(name, str):
        raise ArgumentTypeError(f"a parameter name is text, got {type(name).__name__}", where="sweep")
    parameter = model.parameter(name)
    if parameter.kind != "float":
        raise ArgumentError(f"only float parameters can be swept; {name} is {parameter.kind}", where="sweep")
    values = validate.real_array(values, "sweep").ravel()
    if values.size == 0:
        raise ArgumentError(f"the sweep over {name} is empty", where="sweep")
    return model.with_params(**{name: values[:, None]}), name, values
