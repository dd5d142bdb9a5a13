"""Declared model parameters: name, kind, range and default, and validation of user values.

Kinds (:data:`KINDS`): ``float`` (one number), ``int`` (a whole number: table sizes), ``spectrum`` (per-channel
numbers: one value for every channel or R,G,B, each within the declared range — an index of refraction η,
an extinction k, a reflectance f0; never a colour clamped to [0, 1] or quantized), ``color`` (an R,G,B colour in
a .brdf file or a Mitsuba reflectance), ``bool`` and ``choice``. :meth:`Parameter.declaration` is the one
description that ``brdfnorm models``, ``info``, ``check`` and the explorer read.

Built-in lobes declare *hard* ranges (a negative Phong exponent is meaningless and refused); `.brdf` files
declare *slider* ranges (BRDF Explorer's UI limits), so values outside them are accepted with a warning.
"""

from __future__ import annotations

import difflib
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .errors import ParameterError, ParameterTypeError
from .validate import real_array, short_repr

Kind = Literal["float", "int", "spectrum", "bool", "color", "choice"]
KINDS: tuple[str, ...] = ("float", "int", "spectrum", "bool", "color", "choice")
#: Kinds that hold one number per colour channel (an array's last axis of length CHANNELS).
PER_CHANNEL = ("spectrum", "color")
#: Kinds that a lookup-table axis, a sweep or a search may vary (one number per cell; a spectrum gets it in every
#: channel).
NUMERIC = ("float", "int", "spectrum")
CHANNELS = 3


@dataclass(frozen=True)
class Parameter:
    """One declared parameter of a model."""

    name: str
    kind: Kind = "float"
    default: float | bool | tuple[float, float, float] | str = 0.0
    minimum: float | None = None
    maximum: float | None = None
    description: str = ""
    strict: bool = True  # True: range is a hard limit; False: slider range, warn only
    choices: tuple[str, ...] = ()  # the allowed values of a ``kind="choice"`` parameter

    @property
    def per_channel(self) -> bool:
        """Whether a value holds one number per colour channel (``spectrum``, ``color``)."""
        return self.kind in PER_CHANNEL

    def declaration(self) -> dict:
        """The declaration as plain data: name, kind, channels (3 per-channel numbers, else 1), integer, default,
        minimum, maximum (per channel for a spectrum), strict (hard range) or slider, choices, description, and
        the range and default as the command line spells them."""
        default = self.default
        if isinstance(default, tuple):
            default = [float(v) for v in default]
        elif self.kind == "int":
            default = int(default)  # type: ignore[arg-type]
        elif self.kind == "float":
            default = float(default)  # type: ignore[arg-type]
        return {"name": self.name, "kind": self.kind, "channels": CHANNELS if self.per_channel else 1,
                "integer": self.kind == "int", "default": default, "minimum": self.minimum,
                "maximum": self.maximum, "strict": self.strict, "choices": list(self.choices),
                "description": self.description, "range": self.describe_range(),
                "default_text": self.describe_default()}

    def describe_range(self) -> str:
        if self.kind == "bool":
            return "0 or 1"
        if self.kind == "choice":
            return "|".join(self.choices)
        lo = "-inf" if self.minimum is None else f"{self.minimum:g}"
        hi = "inf" if self.maximum is None else f"{self.maximum:g}"
        whole = " whole" if self.kind == "int" else ""
        each = " per channel (1 or 3 numbers)" if self.kind == "spectrum" else ""
        return f"[{lo}, {hi}]{whole}{each}"

    def describe_outside(self, array: np.ndarray) -> str:
        """The first value of ``array`` outside the range, as a user would type it, and how many there are
        (not a numpy dump: ``0 (1 of 8 values)``)."""
        flat = np.asarray(array, dtype=float).ravel()
        outside = ((flat < self.minimum) if self.minimum is not None else np.zeros(flat.size, dtype=bool)) | (
            (flat > self.maximum) if self.maximum is not None else np.zeros(flat.size, dtype=bool))
        first = f"{flat[np.argmax(outside)]:.10g}"
        return first if flat.size == 1 else f"{first} ({np.count_nonzero(outside)} of {flat.size} values)"

    def parse(self, text: str) -> float | bool | tuple[float, float, float]:
        """Parse a command-line value (``n=512``, ``normalized=0``, ``baseColor=0.5,0.5,0.5``)."""
        text = text.strip()
        if self.kind == "choice":
            return self._choose(text)
        try:
            if self.kind == "bool":
                lowered = text.lower()
                if lowered in ("1", "true", "yes", "on"):
                    return True
                if lowered in ("0", "false", "no", "off"):
                    return False
                raise ValueError
            if self.kind == "int":
                number = float(text)
                if not number.is_integer():
                    raise ValueError
                return int(number)  # type: ignore[return-value]
            if self.per_channel:
                parts = [float(p) for p in text.split(",")]
                if len(parts) == 1:
                    parts = parts * 3
                if len(parts) != 3:
                    raise ValueError
                return tuple(parts)  # type: ignore[return-value]
            return float(text)
        except ValueError:
            expected = {"bool": "0 or 1", "color": "R,G,B (three numbers)", "float": "a number",
                        "int": "a whole number", "spectrum": "a number or R,G,B (one per channel)"}[self.kind]
            raise ParameterError(f"expected {expected}, got {text!r}", where=f"parameter {self.name}") from None

    def validate(self, value: object) -> float | bool | tuple[float, float, float] | np.ndarray:
        """Check type and range; returns the value in canonical form (arrays allowed for sweeps)."""
        where = f"parameter {self.name}"
        if self.kind == "choice":
            return self._choose(value)
        if isinstance(value, str):
            value = self.parse(value)
        if self.kind == "bool":
            if isinstance(value, (bool, np.bool_)) or (isinstance(value, (int, float)) and value in (0, 1)):
                return bool(value)
            raise ParameterError(f"expected 0 or 1, got {value!r}", where=where)
        array = real_array(value, where, error=ParameterError, type_error=ParameterTypeError)
        if self.per_channel and array.ndim == 0:
            array = np.full(CHANNELS, float(array))
        if self.per_channel and array.shape[-1:] != (CHANNELS,):
            raise ParameterError(f"expected 3 components (R,G,B), got {value!r}", where=where)
        if self.kind == "int" and not np.all(array == np.rint(array)):
            raise ParameterError(f"expected a whole number, got {short_repr(value)}", where=where)
        low = self.minimum is not None and np.any(array < self.minimum)
        high = self.maximum is not None and np.any(array > self.maximum)
        if low or high:
            message = f"value {self.describe_outside(array)} outside {self.describe_range()}"
            if self.strict:
                raise ParameterError(message, where=where)
            warnings.warn(f"{where}: {message} (the file's slider range; evaluating anyway)", stacklevel=3)
        if array.ndim == 0:
            return int(array) if self.kind == "int" else float(array)
        if self.per_channel and array.ndim == 1:
            return tuple(float(c) for c in array)  # type: ignore[return-value]
        return array


    def _choose(self, value: object) -> str:
        if isinstance(value, str) and value.strip() in self.choices:
            return value.strip()
        raise ParameterError(f"expected one of {', '.join(self.choices)}; got {short_repr(value)}",
                             where=f"parameter {self.name}")

    def describe_default(self) -> str:
        """The default as the command line would spell it."""
        if self.kind == "choice":
            return str(self.default)
        if self.kind == "bool":
            return str(int(bool(self.default)))
        if self.kind == "int":
            return str(int(self.default))  # type: ignore[arg-type]
        return ",".join(f"{v:g}" for v in np.atleast_1d(np.asarray(self.default, dtype=float)))


def resolve(parameters: tuple[Parameter, ...], values: Mapping[str, object], *, where: str = "",
            aliases: tuple[str, ...] = ()) -> dict:
    """Defaults overridden by ``values``; unknown names are refused with the closest known name ("did you
    mean") and the list of known ones (``aliases``: other names the model accepts)."""
    known = {p.name: p for p in parameters}
    for name in values:
        if name not in known:
            names = ", ".join([*known, *aliases]) or "none"
            close = difflib.get_close_matches(str(name), [*known, *aliases], n=1, cutoff=0.6)
            hint = f"; did you mean {close[0]!r}?" if close else ""
            raise ParameterError(f"unknown parameter {name!r}{hint} (known: {names})", where=where or None)
    resolved = {}
    for p in parameters:
        resolved[p.name] = p.validate(values[p.name]) if p.name in values else p.default
    return resolved
