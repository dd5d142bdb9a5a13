"""What the explorer computes for one view of one model, at a coarse or a fine tolerance, cancellably.

For a model bound to the page's parameter values and a view direction V at polar angle θ_o and azimuth φ_o
(φ_o = 0: the X–N plane), :func:`evaluate_view` returns, as JSON-ready data:

* the albedo curve E(θ_o) = ∫ f(L, V)(N·L) dL over θ_o ∈ [0°, 89.9°] at the azimuth φ_o, with its error estimate
  (:func:`brdfnorm.albedo`), and the normalized curve α·E(θ_o) — the energy kept under the chosen convention;
* the readouts: E at the current view, the factors α = 1/E at ``normal``, ``max`` and ``view``
  (:func:`brdfnorm.normalize`), and the energy verdict of :func:`brdfnorm.check.check` (``checks=("energy",)``,
  every parameter held at the page's value, so only directions are searched) — in the fine pass; the coarse pass
  shows the albedo grid's maximum as a pending verdict;
* the normalized lobe α·f(L, V)(N·L) and the raw f(L, V) for L in the plane of incidence (polar plots) and the
  normalized one over the hemisphere (a 3-D surface, in polar coordinates about the mirror direction so a narrow
  lobe is resolved) — :mod:`.lobes`;
* optionally a second model's (the overlay's) lobe, albedo curve and factor, under the same convention, for
  comparison (no energy check of its own).

The coarse pass (``quality="coarse"``) is what a slider move waits for; the fine pass refines every number in the
background. Both are *cancellable*: the model's ``evaluate``/``projected`` are wrapped on a private copy so that
the integrator's next batch raises :class:`Superseded` once the client has moved on (``check``).

Errors of factors: with |E − Ê| ≤ ε, |1/E − 1/Ê| ≤ ε/(Ê(Ê − ε)) — a bound, not a first-order estimate.
"""

from __future__ import annotations

import math
import shlex
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Callable, Hashable
from dataclasses import dataclass

import numpy as np

from .. import albedo, normalize
from ..check import Budget
from ..check import check as check_model
from ..errors import (
    ArgumentError,
    ArgumentTypeError,
    BrdfnormError,
    EvaluationError,
    ParameterError,
    ParameterTypeError,
)
from ..fit import fit
from ..fit.codegen import emit, fit_context
from ..models.base import Model
from ..normalization import THETA_MAX
from ..output.formats import format_with_error
from ..validate import DEFAULT_MAX_EVALUATIONS, choice, count, real_array, real_number, short_repr
from .catalog import control_of
from .lobes import finite as _finite
from .lobes import plane_lobe, surface_lobe

CONVENTIONS = ("normal", "max", "view")
FIT_LANGUAGES = ("glsl", "hlsl")
#: Tolerance of the factors the fit panel samples: far below the fit's 1e-3 target, and reachable in float64
#: even for the narrowest lobes (GGX at roughness 0.01 cannot reach 1e-9).
FIT_RTOL = 1e-7
#: Slider upper end for a parameter declared without one (the built-in exponents: n ≥ 0, usable to 1e5).
UNBOUNDED_SLIDER_MAX = 1e4
#: The energy check's work bound, in integrand evaluations rather than seconds: a time budget caps the integrals
#: by the rate measured so far, so its verdict would vary with the machine's load; this one is reproducible —
#: the page shows what ``brdfnorm check MODEL --only energy -p … --budget 2e7evals`` prints. The built-ins and
#: examples/ take at most 3.5e6 at their defaults (measured), so it rarely binds; a stale check is cancelled.
ENERGY_EVALUATIONS = DEFAULT_MAX_EVALUATIONS
#: Energy gained beyond which a lobe fails (the check's, and the command line's, default ``--tolerance``).
ENERGY_TOLERANCE = 1e-6
#: A view angle of 90° is the horizon, where the albedo integral degenerates (as in ``normalize``).
VIEW_MAX_DEG = float(np.degrees(THETA_MAX))


class Superseded(Exception):  # noqa: N818 — not an error: the client asked for something newer
    """The client has sent a newer request; this computation is abandoned."""


@dataclass(frozen=True)
class Quality:
    curve_points: int
    curve_rtol: float
    point_rtol: float
    max_rtol: float | None  # None: the max is the curve's grid maximum (a lower bound), not searched
    max_evaluations: int


QUALITIES = {
    "coarse": Quality(curve_points=19, curve_rtol=1e-3, point_rtol=1e-6, max_rtol=None, max_evaluations=2_000_000),
    "fine": Quality(curve_points=61, curve_rtol=1e-8, point_rtol=1e-10, max_rtol=1e-8, max_evaluations=2_000_000),
}


# -- parameters ---------------------------------------------------------------------------------------------

def describe_parameters(model: Model) -> list[dict]:
    """Declared parameters with the slider each gets (log scale where the range spans decades)."""
    described = []
    for p in model.parameters:
        entry = p.declaration() | {"control": control_of(p)}  # kind, channels, integer, range, default …
        if not entry["choices"]:
            del entry["choices"]
        if entry["control"] == "slider":
            low = p.minimum if p.minimum is not None else min(0.0, float(p.default))
            high = p.maximum if p.maximum is not None else max(UNBOUNDED_SLIDER_MAX, float(p.default))
            low, high = float(low), float(high)
            log = high > 0 and (p.maximum is None or (low > 0 and high / low >= 1e3))
            if log:  # a slider spans at most six decades (α ≥ 1e-12 is a limit, not a useful place to drag to)
                low = max(low, high * 1e-6) if low > 0 else max(1.0, high * 1e-6)
            entry["slider"] = {"low": low, "high": high, "log": log,
                               "step": 1 if str(p.kind) in ("int", "integer") else "any"}
        described.append(entry)
    return described


def bind_parameters(model: Model, raw: object) -> Model:
    """The model bound to the page's values: one number per float, [R, G, B] (or one number) per colour or
    per-channel number, true/false, a choice's name. Arrays are refused where one number is meant (a sweep from
    a request would multiply the work); the ranges, colour components and choices are checked by the parameters
    themselves."""
    if raw is None:
        return model
    if not isinstance(raw, dict):
        raise ArgumentTypeError("params must be an object of name: value", where="params")
    values: dict[str, object] = {}
    for name, value in raw.items():
        p = model.parameter(str(name)[:80])
        where = f"parameter {p.name}"
        control = control_of(p)
        if control == "slider":
            number = real_array(value, where, error=ParameterError, type_error=ParameterTypeError)
            if number.ndim:
                raise ParameterTypeError(f"expected one number, got {short_repr(value)}", where=where)
            value = float(number)
        elif control in ("channels", "colour"):
            scalar = not isinstance(value, list)
            if not scalar and len(value) != 3:
                raise ParameterTypeError(f"expected [R, G, B] or one number, got {short_repr(value)}", where=where)
            numbers = real_array(value, where, error=ParameterError, type_error=ParameterTypeError)
            value = float(numbers) if scalar else tuple(numbers.tolist())
        elif control == "switch" and not isinstance(value, bool):
            raise ParameterTypeError(f"expected true or false, got {short_repr(value)}", where=where)
        elif control == "menu" and not isinstance(value, str):  # a choice: its name
            raise ParameterTypeError(f"expected one of the choices, got {short_repr(value)}", where=where)
        values[p.name] = value
    return model.with_params(**values)


def view_angle(raw: object) -> float:
    """The page's view angle θ_o in degrees, checked: [0°, 89.9°]."""
    degrees = real_number(raw, "view")
    if not 0.0 <= degrees <= VIEW_MAX_DEG:
        raise ArgumentError(f"view angle must be in [0, {VIEW_MAX_DEG:g}] degrees, got {degrees:g}", where="view")
    return degrees


def view_azimuth(raw: object) -> float:
    """The page's view azimuth φ_o in degrees (absent: 0), checked: [0°, 360°]."""
    if raw is None:
        return 0.0
    degrees = real_number(raw, "phi")
    if not 0.0 <= degrees <= 360.0:
        raise ArgumentError(f"view azimuth must be in [0, 360] degrees, got {degrees:g}", where="phi")
    return degrees


# -- cancellation -------------------------------------------------------------------------------------------

def cancellable(model: Model, check: Callable[[], None]) -> Model:
    """A private copy of ``model`` whose evaluations first call ``check`` (which raises :class:`Superseded`).

    The wrappers are instance attributes, so the copy keeps its class (method selection such as Blinn-Phong's
    ``series`` is unchanged) and ``with_params`` copies carry them along.
    """
    copy = model.with_params()
    evaluate, projected = copy.evaluate, copy.projected

    def checked_evaluate(L, V, params):
        check()
        return evaluate(L, V, params)

    def checked_projected(L, V, params):
        check()
        return projected(L, V, params)

    copy.evaluate = checked_evaluate  # type: ignore[method-assign]
    copy.projected = checked_projected  # type: ignore[method-assign]
    return copy


def _readout(values: np.ndarray, errors: np.ndarray) -> dict:
    """Per-channel numbers and one text (a single number where the channels agree)."""
    values, errors = np.atleast_1d(values).astype(float), np.atleast_1d(errors).astype(float)
    same = bool(np.all(values == values[0]))
    if same:
        text = format_with_error(float(values[0]), float(errors.max()))
    else:
        text = " · ".join(f"{c} {format_with_error(float(v), float(e))}" for c, v, e in zip("RGB", values, errors,
                                                                                                 strict=False))
    return {"value": values.tolist(), "error": errors.tolist(), "text": text}


def factor_bound(E: np.ndarray, error: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """α = 1/E and a bound on its error (infinite where the error could reach E)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        factor = 1.0 / E
        bound = np.where(E > error, error / (np.abs(E) * (np.abs(E) - error)), np.inf)
    return factor, bound


# -- the view -----------------------------------------------------------------------------------------------

ENERGY_VERDICTS = {"pass": "conserves energy", "fail": "gains energy",
                   "inconclusive": "at the limit (max E within its error of 1 + tolerance)"}


def grid_verdict(E_max: float, error: float, theta_deg: float) -> dict:
    """The coarse pass's pending verdict: the albedo grid's maximum, a lower bound on max E (gains energy for
    sure when even that exceeds 1 beyond its error; otherwise the check in the fine pass decides)."""
    where = f"grid max E = {format_with_error(E_max, error)} at θ_o = {theta_deg:.3g}°"
    verdict = "gains energy" if E_max - error > 1.0 + ENERGY_TOLERANCE else "pending"
    return {"verdict": verdict, "status": None, "source": "grid",
            "text": f"{verdict}: {where} (brdfnorm check runs in the refined pass)"}


def check_command(source: str, model: Model) -> str:
    """The command line whose energy verdict the page shows: every parameter held at its bound value."""
    held = []
    for p in model.parameters:
        value = model.params[p.name]
        if p.kind == "float":
            text = repr(float(value))
        elif p.kind == "int":
            text = str(int(value))
        elif p.kind == "bool":
            text = "1" if value else "0"
        elif isinstance(value, str):
            text = value
        else:  # a colour or numbers per channel
            text = ",".join(repr(float(c)) for c in np.atleast_1d(value))
        held += ["-p", f"{p.name}={text}"]
    return shlex.join(["brdfnorm", "check", source, "--only", "energy", *held,
                       "--budget", f"{ENERGY_EVALUATIONS:.0e}".replace("e+0", "e") + "evals"])


class Verdicts:
    """The last energy verdicts by (model, parameter values): the check does not depend on the view angle or the
    convention, and its evaluation budget makes it reproducible, so a view-angle move reuses it."""

    def __init__(self, size: int = 256) -> None:
        self.size = size
        self.lock = threading.Lock()
        self.found: OrderedDict[Hashable, dict] = OrderedDict()

    def get(self, key: Hashable) -> dict | None:
        with self.lock:
            if key not in self.found:
                return None
            self.found.move_to_end(key)
            return {**self.found[key], "cached": True, "elapsed_ms": 0.0}

    def put(self, key: Hashable, verdict: dict) -> None:
        with self.lock:
            self.found[key] = verdict
            while len(self.found) > self.size:
                self.found.popitem(last=False)


def energy_check(model: Model, source: str, verdicts: Verdicts | None = None,
                 model_key: Hashable | None = None) -> dict:
    """The verdict of :func:`brdfnorm.check.check` (energy only) for the lobe as bound, and where max E is;
    from ``verdicts`` when this model (``model_key``: the caller's name for its version) was checked at these
    parameter values before."""
    key = (model_key, source, repr(sorted(model.params.items())))
    if verdicts is not None and model_key is not None and (found := verdicts.get(key)) is not None:
        return found
    started = time.perf_counter()
    report = check_model(model, checks=("energy",), fixed="all", tolerance=ENERGY_TOLERANCE,
                         budget=Budget(seconds=None, evaluations=ENERGY_EVALUATIONS))
    r = report.results["energy"]
    where = f"θ_o = {r.theta_deg:.4g}°" + ("" if model.isotropic else f", φ_o = {r.phi_deg:.4g}°")
    # The check's notes (non-finite values, a search cut short by the budget) follow its headline after "; ".
    notes = "".join(f"; {note}" for note in r.message.split("; ")[1:])
    text = f"{r.status} — {ENERGY_VERDICTS[r.status]}: max E = {format_with_error(r.value, r.error)} at {where}"
    verdict = {"verdict": ENERGY_VERDICTS[r.status], "status": r.status, "source": "check", "text": text + notes,
               "value": [r.value], "error": [r.error], "theta_deg": r.theta_deg, "phi_deg": r.phi_deg,
               "message": r.message, "tolerance": report.tolerance, "command": check_command(source, model),
               "evaluations": report.coverage["evaluations"], "elapsed_ms": 1e3 * (time.perf_counter() - started),
               "cached": False}
    if verdicts is not None and model_key is not None:
        verdicts.put(key, verdict)
    return verdict


@dataclass
class Albedos:
    """The albedos one view needs: at V and at N, the curve over θ_o at φ_o, and the largest E (searched in the
    fine pass, the curve's grid maximum — a lower bound — in the coarse one)."""

    view: tuple[np.ndarray, np.ndarray]
    normal: tuple[np.ndarray, np.ndarray]
    curve: object  # brdfnorm.AlbedoResult over grid_deg
    grid_deg: np.ndarray
    max: tuple[np.ndarray, np.ndarray]
    theta_max: float
    searched: bool

    def factor(self, convention: str) -> np.ndarray:
        """α under ``convention`` (per channel); for ``view``, α = 1/E(V) (the lobe's normalization)."""
        return factor_bound(*{"normal": self.normal, "max": self.max, "view": self.view}[convention])[0]


def albedos(m: Model, theta_v: float, phi_v: float, q: Quality) -> Albedos:
    kwargs = dict(max_evaluations=q.max_evaluations)
    points = albedo(m, np.array([theta_v, 0.0]), np.array([phi_v, 0.0]), rtol=q.point_rtol, **kwargs)
    grid_deg = np.linspace(0.0, VIEW_MAX_DEG, q.curve_points)
    curve = albedo(m, np.radians(grid_deg), phi_v, rtol=q.curve_rtol, **kwargs)
    if q.max_rtol is None:  # the grid's maximum: a lower bound on the true one
        i = int(np.argmax(curve.value.max(axis=-1)))
        E_max, theta_max, searched = (curve.value[i], curve.error[i]), float(grid_deg[i]), False
    else:
        result = normalize(m, at="max", rtol=q.max_rtol)
        E_max, theta_max = (result.albedo[0, 0], result.error[0, 0]), float(np.degrees(result.theta[0, 0]))
        searched = True
    return Albedos((points.value[0], points.error[0]), (points.value[1], points.error[1]), curve, grid_deg,
                   E_max, theta_max, searched)


def evaluate_view(model: Model, view_deg: float, convention: str, quality: str,
                  check: Callable[[], None] = lambda: None, params: object = None, source: str | None = None,
                  verdicts: Verdicts | None = None, model_key: Hashable | None = None, phi_deg: float = 0.0,
                  overlay: tuple[Model, object, str] | None = None) -> dict:
    """Everything the page shows for one state; see the module docstring.

    ``params`` are the page's values (:func:`bind_parameters`), bound here so that their warnings (a value
    outside a file's slider range) are reported with the computation's own; ``source`` is how the command line
    names the model (a built-in's name or the file's path; the model's name if not given); ``verdicts`` keeps
    energy verdicts across calls for the model called ``model_key`` (which must change when the model does);
    ``overlay`` is a second (model, page values, label) drawn beside the first.
    """
    choice(convention, CONVENTIONS, "convention")
    choice(quality, tuple(QUALITIES), "quality")
    q = QUALITIES[quality]
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        model = bind_parameters(model, params)
        second = _bind_overlay(*overlay) if overlay is not None else None
        m = cancellable(model, check)
        theta_v, phi_v = math.radians(view_deg), math.radians(phi_deg)
        a = albedos(m, theta_v, phi_v, q)
        check()
        alpha = a.factor(convention) if convention != "view" else None
        lobe_alpha = a.factor(convention)
        plane = plane_lobe(m, theta_v, phi_v, lobe_alpha)
        surface = surface_lobe(m, theta_v, phi_v, lobe_alpha)
        drawn = _overlay(cancellable(second, check), overlay[2], theta_v, phi_v, convention, q) if second else None
        # Last: the lobe's numbers are all computed when the (longer) search starts, and a move cancels it.
        energy = energy_check(m, source or model.name, verdicts, model_key) if a.searched else None
    (E_view, err_view), (E_max, err_max) = a.view, a.max
    readouts = {"albedo": {**_readout(E_view, err_view), "theta_deg": view_deg, "phi_deg": phi_deg}}
    for name, (E, err) in (("normal", a.normal), ("max", a.max), ("view", a.view)):
        readouts[f"factor_{name}"] = _readout(*factor_bound(E, err))
    max_channel = int(np.argmax(E_max))
    if not a.searched:  # the grid's largest channel is a lower bound of the true maximum: its factor an upper one
        lower = float(E_max[max_channel] - err_max[max_channel])
        channel = f"{'RGB'[max_channel]}, " if len(set(np.atleast_1d(E_max).tolist())) > 1 else ""
        readouts["factor_max"]["text"] = (f"≤ {1.0 / lower:.6g} ({channel}grid max, refining)" if lower > 0
                                          else "refining…")
    readouts["factor_max"]["theta_deg"] = a.theta_max
    readouts["energy"] = energy or grid_verdict(float(E_max[max_channel]), float(err_max[max_channel]), a.theta_max)
    curve = a.curve
    normalized = (curve.value * alpha) if alpha is not None else np.ones_like(curve.value)
    messages = sorted({str(w.message).splitlines()[0] for w in caught})
    return {
        "quality": quality, "convention": convention, "view_deg": view_deg, "phi_deg": phi_deg,
        "channels": model.channels, "method": curve.method,
        "curve": {"theta_deg": a.grid_deg.tolist(), "value": _columns(curve.value), "error": _columns(curve.error),
                  "normalized": _columns(normalized), "rtol": q.curve_rtol},
        "readouts": readouts, "lobe": plane, "surface": surface, "overlay": drawn, "warnings": messages,
    }


def _bind_overlay(model: Model, params: object, label: str) -> Model:
    """The second lobe bound to its values; an error says it is the second lobe's (the page shows one line)."""
    try:
        return bind_parameters(model, params)
    except BrdfnormError as error:
        error.where = f"second lobe ({label})" + (f": {error.where}" if error.where else "")
        raise


def _overlay(m: Model, label: str, theta_v: float, phi_v: float, convention: str, q: Quality) -> dict:
    """The second lobe: its plane lobe (normalized by its own factor under ``convention``, and raw), its
    albedo curve and that factor."""
    a = albedos(m, theta_v, phi_v, q)
    E, err = {"normal": a.normal, "max": a.max, "view": a.view}[convention]
    factor = a.factor(convention)
    normalized = a.curve.value * factor if convention != "view" else np.ones_like(a.curve.value)
    return {"label": label, "model": m.name, "lobe": plane_lobe(m, theta_v, phi_v, factor),
            "curve": {"theta_deg": a.grid_deg.tolist(), "value": _columns(a.curve.value),
                      "error": _columns(a.curve.error), "normalized": _columns(normalized)},
            "factor": _readout(*factor_bound(E, err)), "albedo": _readout(*a.view)}


def _columns(values: np.ndarray) -> list[list]:
    """(T, C) to one list per channel (a single one where all channels are equal)."""
    values = np.asarray(values, dtype=float)
    if values.ndim == 1:
        values = values[:, None]
    if np.all(values == values[:, :1]):
        values = values[:, :1]
    return [_finite(values[:, c]) for c in range(values.shape[1])]


# -- the fit panel ------------------------------------------------------------------------------------------

def fit_factor(model: Model, parameter: object, low: object, high: object, samples: object, at: object,
               language: object, scale: object = "linear", form: object = "auto",
               check: Callable[[], None] = lambda: None, params: object = None) -> dict:
    """Fit α(x) = 1/E over a float parameter's range (:func:`brdfnorm.fit.fit`, ``auto`` form by default) and
    emit it (:func:`brdfnorm.fit.codegen.emit`); the other parameters at the page's values ``params``."""
    p = model.parameter(str(parameter)[:80])
    if p.kind != "float":
        raise ArgumentError(f"only float parameters can be fitted; {p.name} is {p.kind}", where="parameter")
    low, high = real_number(low, "low"), real_number(high, "high")
    if not low < high:
        raise ArgumentError(f"the range needs low < high, got [{low:g}, {high:g}]", where="range")
    samples = count(samples, "samples", minimum=4, maximum=64)
    choice(at, ("normal", "max"), "at")
    choice(language, FIT_LANGUAGES, "language")
    choice(scale, ("linear", "log"), "scale")
    if scale == "log" and low <= 0:
        raise ArgumentError("a log scale needs low > 0", where="scale")
    if not isinstance(form, str) or len(form) > 40:
        raise ArgumentError("form must be a form name such as auto or rational:2/1", where="form")
    values = np.geomspace(low, high, samples) if scale == "log" else np.linspace(low, high, samples)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        m = cancellable(bind_parameters(model, params), check)
        result = normalize(m, at=at, sweep={p.name: values}, rtol=FIT_RTOL)
        factor = result.factor[:, 0, :]
        if not np.allclose(factor, factor[:, :1], rtol=1e-12, atol=0.0):
            raise ArgumentError("the channels have different factors; set the colour parameters equal to fit",
                                where="parameter")
        y = factor[:, 0]
        if not np.all(np.isfinite(y)) or np.any(y <= 0):
            raise EvaluationError("the factor is not finite and positive at every sample (an albedo of 0?)",
                                  where="range")
        check()
        fitted = fit(values, y, form=form, metric="minimax-rel", target=1e-3, names=(p.name, "cos_theta_o"))
        code = emit(fitted, language, model.name, variable=p.name, context=fit_context(m, p.name, at))
    return {"code": code, "form": fitted.form, "expression": fitted.expression,
            "max_rel_error": fitted.max_rel_error, "samples": fitted.samples, "at": at, "parameter": p.name,
            "range": [float(values[0]), float(values[-1])], "language": language,
            "warnings": fitted.warnings + sorted({str(w.message).splitlines()[0] for w in caught})}
