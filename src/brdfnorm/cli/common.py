"""What every command shares: argument grammars, model loading, output, and the one-line error contract.

Errors are one line on stderr — ``error: WHERE: message`` — with exit code 2 for bad input or usage and 1 for
an internal error (with a hint to report it); ``--debug`` shows the traceback instead.
"""

from __future__ import annotations

import contextlib
import functools
import inspect
import math
import os
import shutil
import sys
import warnings
from collections.abc import Callable, Iterator
from dataclasses import astuple, dataclass
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np
import typer

from .. import validate
from ..errors import ArgumentError, BrdfnormError
from ..models.base import Model
from ..normalization import AT
from ..output import STDOUT, write_file
from ..output.formats import render

if TYPE_CHECKING:
    from rich.console import Console

    from ..parallel.executors import Scheduler

#: Help panels of the options every computing command shares (typer's rich_help_panel), so that a long --help
#: reads as groups: what to compute (Options), where the result goes, where the work runs.
OUTPUT_PANEL = "Output"
PARALLEL_PANEL = "Parallel and resumable runs"
DEBUG_OPTION = typer.Option(False, "--debug", help="Show tracebacks instead of one-line errors.")
PARAM_OPTION = typer.Option([], "--param", "-p", metavar="NAME=VALUE",
                            help="Set a model parameter (repeatable), e.g. -p n=512 or -p baseColor=0.5,0.5,0.5.")
JSON_OPTION = typer.Option(False, "--json", help="Print one JSON object.", rich_help_panel=OUTPUT_PANEL)
CSV_OPTION = typer.Option(False, "--csv", help="Print CSV (a header row, one row per point, full precision).",
                          rich_help_panel=OUTPUT_PANEL)
OUTPUT_OPTION = typer.Option(None, "--output", "-o", metavar="FILE",
                             help="Write the table/JSON/CSV to FILE (replaced atomically; '-' is stdout).",
                             rich_help_panel=OUTPUT_PANEL)


#: Normalization conventions, as ``--at`` choices: the words of :data:`brdfnorm.normalization.AT`.
At = Enum("At", [(name, name) for name in AT], type=str)


class Over(str, Enum):
    """Which direction the albedo integrates over, as ``--over`` choices."""

    light = "light"
    view = "view"


@dataclass(frozen=True)
class Spread:
    """Where a command's albedo cells are computed (:mod:`brdfnorm.parallel`): the values of --workers,
    --scheduler, --checkpoint and --chunk-cells (None where not given)."""

    workers: int | None = None
    scheduler: str | None = None
    connect_timeout: float | None = None
    checkpoint: str | None = None
    chunk_cells: int | None = None

    def dask_scheduler(self) -> str | Scheduler | None:
        """``scheduler=`` as the library takes it: the address, with --connect-timeout's deadline where given (a
        :class:`brdfnorm.parallel.executors.Scheduler`; nothing global is set)."""
        if self.scheduler is None or self.connect_timeout is None:
            return self.scheduler
        from ..parallel.executors import Scheduler

        return Scheduler(self.scheduler, self.connect_timeout)

    def given(self) -> bool:
        return any(value is not None for value in astuple(self))


#: The parallel layer's options, declared once (:func:`parallel_options` adds them to a command).
PARALLEL_OPTIONS = {
    "workers": (int, typer.Option(None, "--workers", min=1, metavar="N",
                                  help="Local processes computing the cells (default: all cores, as threads for lut; "
                                  "1: this process).",
                                  rich_help_panel=PARALLEL_PANEL)),
    "scheduler": (str, typer.Option(None, "--scheduler", envvar="DASK_SCHEDULER_ADDRESS", metavar="tcp://HOST:PORT",
                                    help="Compute the cells on a Dask cluster (`dask scheduler`, `dask worker`) "
                                    "instead of local processes.", rich_help_panel=PARALLEL_PANEL)),
    "connect_timeout": (float, typer.Option(None, "--connect-timeout", min=0.1, max=3600, metavar="SECONDS",
                                            help="One deadline for reaching the --scheduler: connection and "
                                            "handshake (default 10).", rich_help_panel=PARALLEL_PANEL)),
    "checkpoint": (str, typer.Option(None, "--checkpoint", metavar="DIR",
                                     help="Save each finished chunk of cells in DIR; rerunning the same command "
                                     "resumes, computing only what is missing.", rich_help_panel=PARALLEL_PANEL)),
    "chunk_cells": (int, typer.Option(None, "--chunk-cells", min=1, metavar="N",
                                      help="Cells per chunk (part of the job's definition; default: sized by a "
                                      "short probe so that a chunk takes about a second).",
                                      rich_help_panel=PARALLEL_PANEL)),
}


def parallel_options(command: Callable | None = None, /, *, chunk_cells: bool = True):
    """Give a typer command the options of :data:`PARALLEL_OPTIONS` (without ``--chunk-cells`` when
    ``chunk_cells`` is False); the command receives their values as one ``spread: Spread`` argument."""
    if command is None:
        return functools.partial(parallel_options, chunk_cells=chunk_cells)
    options = {name: option for name, option in PARALLEL_OPTIONS.items() if chunk_cells or name != "chunk_cells"}
    return _option_group(command, "spread", Spread, options)


class Backend(str, Enum):
    numpy = "numpy"
    compiled = "compiled"


BACKEND_OPTION = typer.Option(None, "--backend", case_sensitive=False,
                              help="numpy (the reference) or compiled (Numba kernels; the default where Numba "
                              "imports). Also $BRDFNORM_BACKEND.")


def backend_option(command: Callable) -> Callable:
    """Give a typer command ``--backend``: where given, it sets ``$BRDFNORM_BACKEND`` for this process and the
    worker processes it starts, so every albedo the command computes, however deep, runs on that backend."""
    signature = inspect.signature(command, eval_str=True)
    parameters = list(signature.parameters.values())
    # before the parallel options where the command has them (they stay together, just before --debug)
    at = next((i for i, p in enumerate(parameters) if p.name in ("workers", "debug")), len(parameters))
    added = inspect.Parameter("backend", inspect.Parameter.POSITIONAL_OR_KEYWORD, default=BACKEND_OPTION,
                              annotation=Backend)

    @functools.wraps(command)
    def with_backend(*args, backend: Backend | None = None, **kwargs):
        if backend is not None:
            from ..engine.compiled.backend import ENVIRONMENT

            os.environ[ENVIRONMENT] = backend.value
        return command(*args, **kwargs)

    with_backend.__signature__ = signature.replace(parameters=[*parameters[:at], added, *parameters[at:]])
    return with_backend


@dataclass(frozen=True)
class ResultOutput:
    """Where and how a command writes its result records: the values of --json, --csv and -o/--output."""

    json_output: bool = False
    csv_output: bool = False
    output: str | None = None

    def write(self, records) -> None:
        """Render ``records`` as the chosen format (table, JSON or CSV) to the output file or stdout."""
        to_terminal = self.output in (None, STDOUT) and sys.stdout.isatty()
        width = shutil.get_terminal_size().columns if to_terminal else None  # a file or a pipe: nothing cut
        write_file(self.output or STDOUT, render(records, result_format(self.json_output, self.csv_output), width))


def result_options(command: Callable) -> Callable:
    """Give a typer command --json, --csv and -o/--output; it receives them as one ``result: ResultOutput``."""
    return _option_group(command, "result", ResultOutput,
                         {"json_output": (bool, JSON_OPTION), "csv_output": (bool, CSV_OPTION),
                          "output": (str, OUTPUT_OPTION)})


def _option_group(command: Callable, argument: str, group: type, options: dict[str, tuple[type, object]]):
    """``command`` with ``options`` (name -> (type, typer option)) in place of its parameter ``argument``, just
    before ``--debug``: typer reads the new signature, and the command receives ``group(**values)``."""
    signature = inspect.signature(command, eval_str=True)
    parameters = [p for p in signature.parameters.values() if p.name != argument]
    at = next((i for i, p in enumerate(parameters) if p.name == "debug"), len(parameters))
    added = [inspect.Parameter(name, inspect.Parameter.POSITIONAL_OR_KEYWORD, default=option, annotation=kind)
             for name, (kind, option) in options.items()]

    @functools.wraps(command)
    def with_group(*args, **kwargs):
        values = group(**{name: kwargs.pop(name) for name in options})
        return command(*args, **{argument: values}, **kwargs)

    with_group.__signature__ = signature.replace(parameters=[*parameters[:at], *added, *parameters[at:]])
    return with_group


#: API argument names as the command line spells them, for error messages.
CLI_NAMES = {"theta": "--theta", "phi": "--phi", "rtol": "--rtol", "method": "--method", "sweep": "--sweep",
             "over": "--over", "at": "--at", "nonfinite": "--nonfinite", "model": "MODEL", "language": "--emit",
             "form": "--form", "metric": "--metric", "target": "--target", "max_coefficients": "--max-coefficients",
             "output": "--output", "n": "--n", "claim": "--claim", "digits": "--digits", "workers": "--workers",
             "scheduler": "--scheduler", "connect_timeout": "--connect-timeout", "checkpoint": "--checkpoint",
             "chunk_cells": "--chunk-cells", "backend": "--backend",
             "axes": "--axis", "clamp": "--clamp", "channels": "--channels", "tables": "--table", "half": "--half",
             "grid": "--grid", "format": "--format",
             # the audit and lut libraries' arguments (audit(), read_table(), fit_table(), layout.parse())
             "pins": "--as", "channel": "--channel", "scale": "--scale", "shape": "--shape",
             "fmt": "--format", "dtype": "--dtype", "order": "--order", "offset": "--offset", "fix": "--fix",
             "formula": "--formula", "function": "--function", "args": "--args", "bindings": "--args",
             "quantities": "--quantity", "table": "--table", "lut": "--lut", "layout": "--layout",
             "certified": "--certified"}


@functools.cache
def _console_class() -> type[Console]:
    """rich's Console with a closed pipe treated as every other write is (rich imported here, where a command prints
    through it: ~0.1 s that ``lut`` and other commands printing plain lines do not pay)."""
    from rich.console import Console

    class _Console(Console):
        def on_broken_pipe(self) -> None:
            """rich exits 1 when stdout's reader goes away; a closed pipe is the reader's choice, not an error,
            so it goes the way of every other write (:func:`guarded`: exit 0)."""
            raise BrokenPipeError

    return _Console


def console(*, stderr: bool = False) -> Console:
    """A rich console on stdout (or stderr) that never truncates numbers (wide when not a terminal)."""
    stream = sys.stderr if stderr else sys.stdout
    kind = _console_class()
    return kind(stderr=stderr) if stream.isatty() else kind(stderr=stderr, width=160)


def _maybe_terminal() -> bool:
    """False where rich's ``Console(stderr=True).is_terminal`` is False for sure, told without importing rich: stderr
    is no terminal and neither ``TTY_COMPATIBLE=1`` nor ``FORCE_COLOR`` says otherwise (rich's own rule)."""
    try:
        terminal = sys.stderr.isatty()
    except (AttributeError, ValueError):  # replaced by an object without it, or closed
        terminal = False
    return terminal or os.environ.get("TTY_COMPATIBLE") == "1" or "FORCE_COLOR" in os.environ


def fail(message: str, code: int = 2) -> typer.Exit:
    """One ``error:`` line on stderr, at most :data:`~brdfnorm.inputs.limits.MAX_ERROR_LINE` characters (a long
    name elided in the middle)."""
    from ..inputs import shorten
    from ..inputs.limits import MAX_ERROR_LINE

    typer.echo(f"error: {shorten(message, MAX_ERROR_LINE)}", err=True)
    return typer.Exit(code)


@contextlib.contextmanager
def guarded(debug: bool = False, names: dict[str, str] | None = None) -> Iterator[None]:
    """Run a command body: project errors become one line + exit 2, anything else one line + exit 1.

    An error's ``where`` (an API argument name) is shown as the command's flag: ``names`` (this command's own
    spellings, e.g. audit's ``--model``), else :data:`CLI_NAMES`."""
    flags = {**CLI_NAMES, **(names or {})}

    def one_line_warning(message, category, filename, lineno, file=None, line=None):
        typer.echo(f"warning: {str(message).splitlines()[0]}", err=True)

    previous = warnings.showwarning
    warnings.showwarning = one_line_warning
    try:
        yield
    except typer.Exit:
        raise
    except BrokenPipeError:  # the reader went away (`brdfnorm info F | head -1`): done, nothing to report
        raise typer.Exit(0) from None
    except BrdfnormError as error:
        if debug:
            raise
        if error.where in flags:
            error.where = flags[error.where]
        raise fail(str(error).replace("\n", " ")) from None
    except ModuleNotFoundError as error:  # an optional package imported deeper down: the install hint, exit 2
        from ..extras import missing_extra

        hint = missing_extra(error)
        if debug:
            raise
        if hint is None:
            raise _internal(error) from None
        raise fail(str(hint)) from None
    except KeyboardInterrupt as interrupt:  # Ctrl-C, or SIGTERM while a table's cells run (brdfnorm.parallel)
        signal_name = f" by {interrupt.args[0]}" if interrupt.args else ""
        raise fail(f"interrupted{signal_name}", 143 if signal_name else 130) from None
    except Exception as error:  # noqa: BLE001 — the contract: no traceback without --debug
        if debug:
            raise
        raise _internal(error) from None
    finally:
        warnings.showwarning = previous


def _internal(error: Exception) -> typer.Exit:
    """An unexpected exception: one line and exit 1."""
    detail = str(error).splitlines()[0] if str(error) else ""
    return fail(f"internal error: {type(error).__name__}: {detail} (please report this, with the output of "
                "the same command run with --debug)", 1)


def _number(text: str, option: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise ArgumentError(f"not a number: {validate.short_repr(text)}", where=option) from None
    if not math.isfinite(value):
        raise ArgumentError(f"not a finite number: {validate.short_repr(text)}", where=option)
    return value


#: The spellings of a range, as the help texts and error messages give them.
RANGE_FORMS = "START:STOP:n=COUNT, START:STOP:step=STEP or START:STOP:COUNT"


def parse_range(spec: str, option: str, *, allow_log: bool) -> np.ndarray:
    """``V``, ``V,V,...`` or an inclusive range: ``START:STOP:n=COUNT`` (COUNT values), ``START:STOP:step=STEP``
    (START, START + STEP, ... up to STOP) or the older ``START:STOP:COUNT`` (the same as ``n=COUNT``); with
    ``allow_log``, ``:log`` after a count spaces the values geometrically (``1:1e4:n=9:log``)."""
    spec = spec.strip()
    if not spec:
        raise ArgumentError("empty value", where=option)
    if ":" in spec:
        parts = [part.strip() for part in spec.split(":")]
        log = allow_log and len(parts) == 4 and parts[3].lower() == "log"
        if len(parts) != 3 and not log:
            form = RANGE_FORMS + (" (a count may end in :log)" if allow_log else "")
            raise ArgumentError(f"expected {form}; got {spec!r}", where=option)
        start, stop = _number(parts[0], option), _number(parts[1], option)
        if stop < start:
            raise ArgumentError(f"reversed range: STOP {stop:g} < START {start:g}", where=option)
        key, sep, third = parts[2].partition("=")
        key = key.strip().lower() if sep else "n"
        third = third if sep else parts[2]
        if key == "step":
            if log:
                raise ArgumentError("a log range takes a count (n=COUNT), not a step", where=option)
            return _stepped(start, stop, _number(third, option), option)
        if key != "n":
            raise ArgumentError(f"expected n=COUNT or step=STEP after START:STOP, got {parts[2]!r}", where=option)
        count = validate.count(third.strip(), option)
        if count == 1 and stop != start:
            raise ArgumentError("n=1 needs START = STOP", where=option)
        if log:
            if start <= 0:
                raise ArgumentError("a log range needs START > 0", where=option)
            return np.geomspace(start, stop, count)
        return np.linspace(start, stop, count)
    return np.array([_number(part, option) for part in spec.split(",")])


def _stepped(start: float, stop: float, step: float, option: str) -> np.ndarray:
    """START, START + STEP, ... while ≤ STOP (STOP itself where it is a whole number of steps, to rounding)."""
    if step <= 0:
        raise ArgumentError(f"step must be > 0, got {step:g}", where=option)
    steps = (stop - start) / step
    whole = math.floor(steps + 1e-9 * max(1.0, steps))
    count = validate.count(str(whole + 1), option)  # bounded like any other range
    return np.minimum(start + step * np.arange(count), stop)  # 0:1:step=0.1 ends at 1, not 1.0000000000000002


def parse_angles(spec: str, option: str = "--theta") -> np.ndarray:
    """Polar angles in degrees, each in [0, 90) (checked in radians by the API's own validator)."""
    degrees = parse_range(spec, option, allow_log=False)
    validate.polar_angles(np.radians(degrees), where=option)
    return degrees


def parse_azimuth(value: float, option: str = "--phi") -> float:
    """An azimuth in degrees (any finite value)."""
    return validate.real_number(value, option)


def parse_sweep(spec: str, option: str = "--sweep") -> tuple[str, np.ndarray]:
    """``NAME=SPEC`` with SPEC ``V,V,...`` or a range of :func:`parse_range` (``:log`` allowed)."""
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
        target = model.aliases[name][0] if name in model.aliases else name  # roughness parses as alpha does
        parsed[name] = model.parameter(target).parse(text)
    return model.with_params(**parsed) if parsed else model


def result_format(json_output: bool, csv_output: bool) -> str:
    """The result format (:data:`brdfnorm.output.formats.FORMATS`) that ``--json``/``--csv`` choose."""
    if json_output and csv_output:
        raise ArgumentError("choose one of --json and --csv", where="--csv")
    return "json" if json_output else "csv" if csv_output else "table"


@contextlib.contextmanager
def progress_bar(description: str, *, enabled: bool = True) -> Iterator[Callable[[int, int], None] | None]:
    """An ``on_progress(done, total)`` callback drawing a rich bar on stderr — None (no chunking, no bar)
    unless ``enabled`` and stderr is a terminal."""
    if not (enabled and _maybe_terminal()):
        yield None
        return
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    stderr = Console(stderr=True)
    if not stderr.is_terminal:
        yield None
        return
    with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                  console=stderr, transient=True) as progress:
        task = progress.add_task(description, total=None)

        def on_progress(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        yield on_progress


def compute_cells(job, label: str, spread: Spread):
    """:func:`brdfnorm.parallel.albedo_cells` where ``spread`` says, with a progress bar on stderr when it is a
    terminal, then a one-line summary there (for more than one cell)."""
    from ..parallel import albedo_cells

    with progress_bar(label, enabled=job.size > 1) as on_progress:
        record = albedo_cells(job, workers=spread.workers, scheduler=spread.dask_scheduler(),
                              checkpoint=spread.checkpoint, on_progress=on_progress)
    if job.size > 1:
        reused = record.chunks - record.chunks_computed
        typer.echo(f"{label}: {job.size} cells in {_count(record.chunks, 'chunk')} ({reused} from the checkpoint) "
                   f"on {_count(record.workers, 'worker')} ({record.executor}) in {record.seconds:.2f} s", err=True)
    return record


def _count(number: int, noun: str) -> str:
    return f"{number} {noun}{'' if number == 1 else 's'}"
