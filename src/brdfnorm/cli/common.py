"""What every command shares: argument grammars, model loading, output, and the one-line error contract.

Errors are one line on stderr — ``error: WHERE: message`` — with exit code 2 for bad input or usage and 1 for
an internal error (with a hint to report it); ``--debug`` shows the traceback instead.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import sys
import tempfile
import warnings
from collections.abc import Iterator
from enum import Enum
from pathlib import Path

import numpy as np
import typer
from rich.console import Console

from ..errors import ArgumentError, BrdfnormError, OutputError
from ..models.base import Model

DEBUG_OPTION = typer.Option(False, "--debug", help="Show tracebacks instead of one-line errors.")
PARAM_OPTION = typer.Option([], "--param", "-p", metavar="NAME=VALUE",
                            help="Set a model parameter (repeatable), e.g. -p n=512 or -p baseColor=0.5,0.5,0.5.")


class At(str, Enum):
    """Normalization conventions (brdfnorm.normalize), as ``--at`` choices."""

    normal = "normal"
    max = "max"
    view = "view"


class Over(str, Enum):
    """Which direction the albedo integrates over, as ``--over`` choices."""

    light = "light"
    view = "view"


#: API argument names as the command line spells them, for error messages.
CLI_NAMES = {"theta": "--theta", "phi": "--phi", "rtol": "--rtol", "method": "--method", "sweep": "--sweep",
             "over": "--over", "digits": "--digits", "at": "--at", "nonfinite": "--nonfinite", "model": "MODEL"}


def console() -> Console:
    """A rich console that never truncates numbers (wide when stdout is not a terminal)."""
    return Console() if sys.stdout.isatty() else Console(width=160)


def fail(message: str, code: int = 2) -> typer.Exit:
    typer.echo(f"error: {message}", err=True)
    return typer.Exit(code)


@contextlib.contextmanager
def guarded(debug: bool = False) -> Iterator[None]:
    """Run a command body: project errors become one line + exit 2, anything else one line + exit 1."""

    def one_line_warning(message, category, filename, lineno, file=None, line=None):
        typer.echo(f"warning: {str(message).splitlines()[0]}", err=True)

    previous = warnings.showwarning
    warnings.showwarning = one_line_warning
    try:
        yield
    except typer.Exit:
        raise
    except BrdfnormError as error:
        if debug:
            raise
        if error.where in CLI_NAMES:
            error.where = CLI_NAMES[error.where]
        raise fail(str(error).replace("\n", " ")) from None
    except KeyboardInterrupt:
        raise fail("interrupted", 130) from None
    except Exception as error:  # noqa: BLE001 — the contract: no traceback without --debug
        if debug:
            raise
        detail = str(error).splitlines()[0] if str(error) else ""
        raise fail(f"internal error: {type(error).__name__}: {detail} (please report this, with the output of "
                   "the same command run with --debug)", 1) from None
    finally:
        warnings.showwarning = previous


def _number(text: str, option: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ArgumentError(f"not a number: {text!r}", where=option) from None
    if not math.isfinite(value):
        raise ArgumentError(f"not a finite number: {text!r}", where=option)
    return value


def parse_range(spec: str, option: str, *, allow_log: bool) -> np.ndarray:
    """``V``, ``V,V,...``, ``START:STOP:COUNT`` (inclusive) or, with ``allow_log``, ``START:STOP:COUNT:log``."""
    spec = spec.strip()
    if not spec:
        raise ArgumentError("empty value", where=option)
    if ":" in spec:
        parts = spec.split(":")
        log = allow_log and len(parts) == 4 and parts[3].strip().lower() == "log"
        if len(parts) != 3 and not log:
            form = "START:STOP:COUNT[:log]" if allow_log else "START:STOP:COUNT"
            raise ArgumentError(f"expected {form}, got {spec!r}", where=option)
        start, stop = _number(parts[0], option), _number(parts[1], option)
        try:
            count = int(parts[2])
        except ValueError:
            raise ArgumentError(f"COUNT must be a whole number, got {parts[2]!r}", where=option) from None
        if count < 1:
            raise ArgumentError(f"empty range: COUNT is {count}", where=option)
        if stop < start:
            raise ArgumentError(f"reversed range: STOP {stop:g} < START {start:g}", where=option)
        if count == 1 and stop != start:
            raise ArgumentError("COUNT 1 needs START = STOP", where=option)
        if log:
            if start <= 0:
                raise ArgumentError("a log range needs START > 0", where=option)
            return np.geomspace(start, stop, count)
        return np.linspace(start, stop, count)
    return np.array([_number(part, option) for part in spec.split(",")])


def parse_angles(spec: str, option: str = "--theta") -> np.ndarray:
    """Polar angles in degrees, each in [0, 90)."""
    degrees = parse_range(spec, option, allow_log=False)
    bad = degrees[(degrees < 0) | (degrees >= 90)]
    if bad.size:
        raise ArgumentError(f"angle {bad[0]:g}° outside [0°, 90°)", where=option)
    return degrees


def parse_azimuth(value: float, option: str = "--phi") -> float:
    if not math.isfinite(value):
        raise ArgumentError("azimuth must be finite", where=option)
    return value


def parse_sweep(spec: str, option: str = "--sweep") -> tuple[str, np.ndarray]:
    """``NAME=SPEC`` with SPEC ``V,V,...``, ``START:STOP:COUNT`` or ``START:STOP:COUNT:log``."""
    name, sep, values = spec.partition("=")
    if not sep or not name.strip():
        raise ArgumentError(f"expected NAME=SPEC, got {spec!r}", where=option)
    return name.strip(), parse_range(values, option, allow_log=True)


def parse_params(items: list[str]) -> dict[str, str]:
    params: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep or not name.strip():
            raise ArgumentError(f"expected NAME=VALUE, got {item!r}", where="-p")
        params[name.strip()] = value
    return params


def load_model(name_or_path: str, params: list[str]) -> Model:
    """A built-in model or a ``.brdf`` file, with ``-p NAME=VALUE`` overrides parsed by the parameter's kind."""
    from .. import load

    model = load(name_or_path)
    parsed = {}
    for name, text in parse_params(params).items():
        parsed[name] = model.parameter(name).parse(text)
    return model.with_params(**parsed) if parsed else model


def jsonable(value):
    """numpy scalars/arrays to plain Python; non-finite floats to None (JSON has no NaN)."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (np.bool_, bool)):
        return bool(value)
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        value = float(value)
        return value if math.isfinite(value) else None
    return value


def to_json(obj) -> str:
    return json.dumps(jsonable(obj), indent=2, ensure_ascii=False)


def print_json(obj) -> None:
    typer.echo(to_json(obj))


def channel_value(values: np.ndarray):
    """A number for single-channel models, a list for multi-channel ones."""
    values = np.asarray(values)
    return float(values[0]) if values.size == 1 else [float(v) for v in values]


def write_output_atomically(path: str | Path, data: str | bytes) -> None:
    """Write a file via a temporary sibling and rename: a failure leaves the previous file as it was."""
    path = Path(path)
    directory = path.parent if str(path.parent) else Path(".")
    if not directory.is_dir():
        raise OutputError(f"directory {str(directory)!r} does not exist", where=str(path))
    mode = "wb" if isinstance(data, bytes) else "w"
    try:
        fd, temporary = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    except OSError as error:
        raise OutputError(f"cannot write here: {error.strerror}", where=str(path)) from None
    try:
        with os.fdopen(fd, mode, **({} if mode == "wb" else {"encoding": "utf-8"})) as handle:
            handle.write(data)
        os.replace(temporary, path)
    except OSError as error:
        with contextlib.suppress(OSError):
            os.unlink(temporary)
        raise OutputError(f"cannot write: {error.strerror}", where=str(path)) from None


def stdout_is_terminal() -> bool:
    return sys.stdout.isatty()
