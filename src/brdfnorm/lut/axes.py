"""A table's axes: which model parameter each sets (an alias such as ``roughness`` sets α = roughness², an ``f0``
axis sets η on a dielectric), the axes checked against the model before any cell is computed, and the clamp
that fixes an axis starting outside its parameter's range.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

import numpy as np

from .. import validate
from ..errors import ArgumentError, ParameterError
from ..models.base import Model
from ..parameters import CHANNELS as COLOUR_CHANNELS
from ..parameters import NUMERIC, resolve

#: Axes that give the view direction: μ = cos θ_o, or θ_o itself (radians in the API).
DIRECTION_AXES = ("mu", "theta")
#: The view azimuth axis of anisotropic tables (:mod:`brdfnorm.lut.anisotropy`; here so that the ``lut`` command
#: checks its axes without importing the anisotropic route).
VIEW_AZIMUTH_AXIS = "phi_v"


def per_cell(model: Model, values: Mapping[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Per-cell values as the parameters take them: a spectrum (η, k, f0) gets each cell's number in every channel."""
    kinds = {p.name: p for p in model.parameters}
    return {n: np.repeat(np.asarray(v)[..., None], COLOUR_CHANNELS, -1) if n in kinds and kinds[n].per_channel else v
            for n, v in values.items()}


def axis_parameter(model: Model, name: str, values: np.ndarray) -> tuple[str, np.ndarray]:
    """The model parameter an axis sets, and its values. An ``f0`` axis sets ``eta`` on a model that has an
    index but no ``f0`` (the dielectrics): η = (1 + √F0)/(1 − √F0), F0 the reflectance at normal incidence —
    it spreads η where materials are."""
    if name == "f0" and "f0" not in {p.name for p in model.parameters} and "eta" in {p.name for p in model.parameters}:
        if np.any(values <= 0) or np.any(values >= 1):
            raise ArgumentError("f0 must lie in (0, 1) (η = (1 + √F0)/(1 − √F0))", where="axes")
        root = np.sqrt(values)
        return "eta", (1.0 + root) / (1.0 - root)
    if name in model.aliases and name not in {p.name for p in model.parameters}:
        target, mapping, _ = model.aliases[name]  # e.g. a roughness axis sets alpha = roughness²
        return target, mapping(np.asarray(values, dtype=float))
    return name, values


def _clamp_hint(model: Model, name: str, array: np.ndarray) -> str:
    """``; clamp it, e.g. --clamp NAME=MIN``: the smallest axis value the parameter it sets accepts (found by
    bisection through an alias's mapping, e.g. roughness = √α_min), where the axis starts below it; else ''."""
    target, _ = axis_parameter(model, name, np.array([1.0]))
    minimum = model.parameter(target).minimum
    if minimum is None or axis_parameter(model, name, np.array([float(array.min())]))[1][0] >= minimum:
        return ""
    high = _first_mapped_to(model, name, minimum, float(array.min()), max(float(array.max()), 1.0))
    return f"; clamp it, e.g. --clamp {name}={float(f'{high:.2g}') if high < 1 else high:g}"


def _first_mapped_to(model: Model, name: str, minimum: float, low: float = 0.0, high: float = 1.0) -> float:
    """The smallest value of axis ``name`` whose parameter value is ≥ ``minimum``, by bisection in [low, high]
    (the axis' mapping, e.g. α = roughness², is monotone)."""
    for _ in range(200):
        middle = 0.5 * (low + high)
        inside = axis_parameter(model, name, np.array([middle]))[1][0] >= minimum
        low, high = (low, middle) if inside else (middle, high)
    return high


def checked_axes(model: Model, axes: Mapping[str, Sequence[float]],
                 clamp: Mapping[str, float]) -> tuple[dict, dict, str]:
    """The table's axes checked against ``model`` (one direction axis, the others its parameters, the clamps
    applied): the axes' values as given, as evaluated (clamped), and the direction axis's name."""
    if not axes:
        raise ArgumentError("give at least one axis", where="axes")
    names = list(axes)
    direction = [n for n in names if n in DIRECTION_AXES]
    if len(direction) != 1:
        raise ArgumentError(f"exactly one of the axes must give the view direction ({' or '.join(DIRECTION_AXES)}"
                            f"); got {direction or 'none'}", where="axes")
    sizes = {name: int(np.size(axes[name])) for name in names}  # from the shapes, before any data is touched
    if math.prod(sizes.values()) > validate.MAX_INTEGRALS:
        shown = " × ".join(f"{sizes[n]:,}" for n in names) + " = " if len(names) > 1 else ""
        raise ArgumentError(f"{shown}{math.prod(sizes.values()):,} albedo integrals in one call is more than the "
                            f"limit of {validate.MAX_INTEGRALS:,}; split the work", where="axes")
    values: dict[str, np.ndarray] = {}
    for name in names:
        array = np.asarray(axes[name], dtype=float)
        if array.ndim != 1 or array.size == 0 or not np.all(np.isfinite(array)):
            raise ArgumentError(f"axis {name!r} needs a non-empty list of finite numbers", where="axes")
        if name not in DIRECTION_AXES:
            parameter = model.parameter(axis_parameter(model, name, np.array([0.5]))[0])
            if parameter.kind not in NUMERIC:
                raise ArgumentError(f"only numeric parameters ({', '.join(NUMERIC)}) can be axes; {name} is "
                                    f"{parameter.kind}", where="axes")
        values[name] = array
    for name, minimum in clamp.items():
        if name not in values:
            setters = [axis for axis in names if axis in model.aliases and model.aliases[axis][0] == name]
            hint = (f"; the {setters[0]} axis sets it ({model.aliases[setters[0]][2]}): clamp it instead, e.g. "
                    f"--clamp {setters[0]}={_first_mapped_to(model, setters[0], minimum):.3g}" if setters else "")
            raise ArgumentError(f"{name}: no axis of that name (the axes: {', '.join(names)}){hint}", where="clamp")
        if not np.isfinite(minimum):
            raise ArgumentError(f"clamp for {name} must be finite", where="clamp")
    evaluated = {name: np.maximum(v, clamp[name]) if name in clamp else v for name, v in values.items()}
    (dname,) = direction
    if dname == "mu":
        mu = evaluated["mu"]
        if np.any(mu <= 0) or np.any(mu > 1):
            raise ArgumentError("mu = cos θ_o must lie in (0, 1]: μ = 0 is the horizon, where the albedo is not "
                                "defined; clamp it, e.g. --clamp mu=1e-4", where="axes")
    else:
        theta = evaluated["theta"]
        if np.any(theta < 0) or np.any(theta >= np.pi / 2):
            raise ArgumentError("theta must lie in [0, π/2) radians ([0°, 90°) on the command line)", where="axes")
    for name, array in evaluated.items():
        if name not in DIRECTION_AXES:
            try:
                resolve(model.parameters, per_cell(model, dict([axis_parameter(model, name, array)])),
                        where=f"axis {name}")
            except ParameterError as error:
                hint = _clamp_hint(model, name, array)
                raise ParameterError(error.message + hint, where=error.where) from None
    return values, evaluated, dname
