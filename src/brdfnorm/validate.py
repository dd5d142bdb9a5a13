"""The one place where arguments from outside are checked: numbers, angles, tolerances, counts, directions.

Every public function (albedo, normalize, series, fit, verify, the parameters of a model) and the command line
validate through these helpers, so an argument means the same and fails the same way everywhere. Errors name the
API argument (``where="theta"``); the CLI alone maps API names to its flags. Nothing is cast silently: strings,
``None``, complex numbers, dates and other objects are refused (:class:`~brdfnorm.errors.ArgumentTypeError`,
both a TypeError and a ValueError), as are numbers float64 cannot hold (``10**400``) and non-finite values.
"""

from __future__ import annotations

import numbers
import os

import numpy as np

from .errors import ArgumentError, ArgumentTypeError, BrdfnormError

#: Largest number of points a range (``START:STOP:COUNT``) may ask for.
MAX_COUNT = 1_000_000
#: Largest number of albedo integrals one call may batch (angles × parameter values).
MAX_INTEGRALS = 10_000_000
#: Largest numpy array one argument may be (directions, angles, parameter values, samples): 64 Mi values.
MAX_ARRAY_VALUES = 64 * 1024**2
#: Finest relative tolerance float64 quadrature can honour.
RTOL_FLOOR = 1e-14
#: The relative tolerance an albedo integral gets when none is asked for (the API's and the CLI's ``rtol``).
DEFAULT_RTOL = 1e-10
#: The integrand evaluations one albedo integral may spend before it stops unconverged (``max_evaluations``).
DEFAULT_MAX_EVALUATIONS = 20_000_000
HALF_PI = np.pi / 2


def short_repr(value: object) -> str:
    """``repr(value)`` cut to 40 characters: what an error message quotes of a value from outside."""
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def real_array(value: object, where: str, *, error: type[BrdfnormError] = ArgumentError,
               type_error: type[BrdfnormError] = ArgumentTypeError) -> np.ndarray:
    """``value`` (a real number or an array of them) as finite float64, or an error naming ``where``.

    Accepted: Python ints and floats, numpy integer and floating scalars and arrays, nested sequences of them; a
    numpy array of more than :data:`MAX_ARRAY_VALUES` values is refused from its shape, before its data is touched (a
    ``np.broadcast_to`` view of 10¹⁰ values took 67 s and 19.6 GB to be refused once).
    Refused: bool (a flag is not a number), str/bytes, None, complex, datetime/timedelta, other objects, values
    beyond float64's range and NaN/inf. ``error`` and ``type_error`` are the classes raised (a model's
    parameters raise :class:`~brdfnorm.errors.ParameterError` and its TypeError twin).
    """
    if isinstance(value, (str, bytes)) or value is None or isinstance(value, (bool, np.bool_)):
        raise type_error(f"expected a number, got {type(value).__name__} {short_repr(value)}", where=where)
    size = np.size(value) if isinstance(value, np.ndarray) else None  # metadata: a broadcast view stays a view
    if size is not None and size > MAX_ARRAY_VALUES:
        raise error(f"an array of shape {np.shape(value)} holds {size} values, more than the {MAX_ARRAY_VALUES} one "
                    "argument may hold", where=where)
    try:
        array = np.asarray(value)
    except (TypeError, ValueError, OverflowError):
        raise type_error(f"expected a number or an array of numbers, got {short_repr(value)}",
                         where=where) from None
    if array.dtype.kind == "O":
        flat = array.ravel()
        if not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in flat):
            raise type_error(f"expected real numbers, got {short_repr(value)}", where=where)
        try:
            array = np.array([float(v) for v in flat], dtype=float).reshape(array.shape)
        except OverflowError:
            raise error(f"{short_repr(value)} is beyond float64's range", where=where) from None
    if array.dtype.kind not in "iuf":
        kind = {"c": "complex", "M": "a date", "m": "a time span", "U": "text", "S": "bytes", "b": "a bool"}.get(
            array.dtype.kind, f"dtype {array.dtype}")
        raise type_error(f"expected real numbers, got {kind}: {short_repr(value)}", where=where)
    array = array.astype(float, copy=False)
    if not np.all(np.isfinite(array)):
        raise error(f"must be finite, got {short_repr(value)}", where=where)
    return array


def choice(value: object, choices: tuple[str, ...], where: str) -> str:
    """One of a few fixed words (``over``, ``at``, ``nonfinite``)."""
    if not isinstance(value, str):
        raise ArgumentTypeError(f"expected one of {', '.join(choices)}, got {type(value).__name__}", where=where)
    if value not in choices:
        raise ArgumentError(f"expected one of {', '.join(choices)}, got {short_repr(value)}", where=where)
    return value


def real_number(value: object, where: str) -> float:
    """One finite real number (see :func:`real_array`)."""
    array = real_array(value, where)
    if array.ndim:
        raise ArgumentTypeError(f"expected one number, got an array of shape {array.shape}", where=where)
    return float(array)


def polar_angles(theta: object, where: str = "theta", *, horizon: bool = False) -> np.ndarray:
    """Polar angles in radians, in [0, π/2) — or [0, π/2] with ``horizon`` (where a method allows 90°)."""
    theta = real_array(theta, where)
    outside = (theta < 0) | ((theta > HALF_PI) if horizon else (theta >= HALF_PI))
    if np.any(outside):
        bad = float(theta[outside].flat[0])
        limit = "90°]" if horizon else "90°)"
        raise ArgumentError(f"polar angle {np.degrees(bad):.6g}° ({bad:.6g} rad) outside [0°, {limit} "
                            f"(radians [0, π/2{']' if horizon else ')'} in the API)", where=where)
    return theta


def angles(theta: object, phi: object = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """Polar angles in [0, π/2) and finite azimuths (radians), as the API's ``theta`` and ``phi``."""
    return polar_angles(theta), real_array(phi, "phi")


def tolerances(rtol: object, atol: object = 0.0, *, floor: float = RTOL_FLOOR) -> tuple[float, float]:
    """``rtol`` in [floor, 1) or 0 and ``atol`` ≥ 0, not both 0."""
    rtol, atol = real_number(rtol, "rtol"), real_number(atol, "atol")
    if rtol < 0:
        raise ArgumentError(f"must be ≥ 0, got {rtol:g}", where="rtol")
    if atol < 0:
        raise ArgumentError(f"must be ≥ 0, got {atol:g}", where="atol")
    if rtol == 0 and atol == 0:
        raise ArgumentError("rtol and atol are both 0: no tolerance can be met", where="rtol")
    if rtol and rtol < floor:
        raise ArgumentError(f"{rtol:g} is below what float64 quadrature can honour (≥ {floor:g})",
                            where="rtol")
    if rtol >= 1:
        raise ArgumentError(f"{rtol:g} is not a relative tolerance (it must be < 1)", where="rtol")
    return rtol, atol


def count(value: object, where: str, *, minimum: int = 1, maximum: int = MAX_COUNT) -> int:
    """A whole number of points in [minimum, maximum] (a clear limit rather than a MemoryError)."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Integral, str)):
        raise ArgumentTypeError(f"expected a whole number, got {short_repr(value)}", where=where)
    try:
        number = int(value)
    except ValueError:
        raise ArgumentError(f"expected a whole number, got {short_repr(value)}", where=where) from None
    if number < minimum:
        raise ArgumentError(f"must be at least {minimum}, got {number}", where=where)
    if number > maximum:
        raise ArgumentError(f"{number} is more than the limit of {maximum:,} points", where=where)
    return number


def memory_limit() -> int:
    """Bytes this process may hold: the machine's physical memory, or less where an address-space limit
    (``ulimit -v``, ``RLIMIT_AS``) is set."""
    try:
        physical = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        physical = 1 << 62
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
    except (ImportError, OSError, ValueError):
        soft = -1
    return min(physical, soft) if soft > 0 else physical


def _bytes_text(count: float) -> str:
    for unit, scale in (("TiB", 1024**4), ("GiB", 1024**3), ("MiB", 1024**2)):
        if count >= scale:
            return f"{count / scale:.3g} {unit}"
    return f"{count / 1024:.3g} KiB"


def batch_size(shape: tuple[int, ...], where: str = "theta", *, bytes_per_integral: int | None = None) -> int:
    """The number of integrals a broadcast batch holds, refused beyond :data:`MAX_INTEGRALS` — and, where the
    caller says what one integral costs while the batch is integrated at once, refused up front when the batch
    cannot fit in :func:`memory_limit` (rather than a MemoryError, or the kernel's OOM killer, minutes later)."""
    size = int(np.prod(shape, dtype=object))
    if size > MAX_INTEGRALS:
        raise ArgumentError(f"{size:,} albedo integrals in one call is more than the limit of "
                            f"{MAX_INTEGRALS:,}; split the work", where=where)
    if bytes_per_integral is not None and size * bytes_per_integral > memory_limit():
        raise ArgumentError(f"{size:,} albedo integrals in one call would need about "
                            f"{_bytes_text(size * bytes_per_integral)} (about {_bytes_text(bytes_per_integral)} "
                            f"each while they are integrated together), more than the "
                            f"{_bytes_text(memory_limit())} this process may use; split the work into smaller "
                            "calls (or use `brdfnorm lut`, which computes in chunks)", where=where)
    return size


def directions(value: object, where: str) -> np.ndarray:
    """An array of 3-vectors (..., 3), finite and real (directions need not be normalized)."""
    array = real_array(value, where)
    if array.ndim == 0 or array.shape[-1] != 3:
        raise ArgumentError(f"expected directions of shape (..., 3), got shape {array.shape}", where=where)
    return array
