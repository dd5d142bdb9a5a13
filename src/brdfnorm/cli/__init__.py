"""The ``brdfnorm`` command line (typer): one module per command group, registered on :data:`app` when imported.

A run imports only the module of the command it names (:data:`COMMANDS`): ``brdfnorm lut ...`` does not import
the fit, audit, check and report commands and what they use. The root's help, an unknown command (its "did you
mean" needs every name) and shell completion import them all, as does ``brdfnorm.cli.app`` (PEP 562), which
holds every command.
"""

from __future__ import annotations

import atexit
import difflib
import gc
import importlib
import os
import re
import sys
import threading
from collections.abc import Callable
from typing import NoReturn

import typer

from . import application
from .help import tidy

#: Each command's name -> the module of this package that defines it (tests/cli/test_command_start.py keeps the
#: two in step); in the order the modules were imported before (the order typer lists commands not in help.ORDER).
COMMANDS = {
    "audit": "audit", "check": "check", "models": "core", "albedo": "core", "normalize": "core",
    "explore": "explore", "fit": "fit", "info": "info", "lut": "lut", "furnace": "materials",
    "reference": "materials", "report": "report", "verify": "verify",
}


def register(names: list[str] | None = None) -> typer.Typer:
    """The application with the commands ``names`` registered (their modules imported; None: every command)."""
    for module in dict.fromkeys(COMMANDS[n] for n in (COMMANDS if names is None else names)):
        importlib.import_module(f"{__name__}.{module}")
    return application.app


def __getattr__(name: str) -> object:
    if name == "app":  # the whole application (tests, documentation tools): every command registered
        return register()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def chosen(argv: list[str]) -> list[str] | None:
    """The command ``argv`` runs, as a list of one name, or None where every command must be registered: no
    command (the root's help), one not known (the "did you mean" of the error), shell completion."""
    if any(key.startswith("_BRDFNORM_COMPLETE") or key == "_TYPER_COMPLETE_ARGS" for key in os.environ):
        return None
    for arg in argv:
        if arg == "--":
            return None
        if not arg.startswith("-"):  # the root takes no option with a value: the first word is the command
            return [arg] if arg in COMMANDS else None
    return None


def main(argv: list[str] | None = None) -> None:
    """Entry point: usage errors become one line (``error: ...``) with exit code 2, as project errors do.

    Called as the process's command line (``argv`` None: the ``brdfnorm`` script, ``python -m brdfnorm``), the
    process also starts and ends faster (:func:`_started`, :func:`_leave`); called with ``argv`` (tests, other
    programs), it only raises SystemExit as click does."""
    if argv is not None:
        _run(list(argv), started=lambda: None)
        return
    _one_blas_thread()
    gc.disable()  # (re-enabled by _started once the command's modules are imported)
    try:
        _run(sys.argv[1:], started=_started)
    except SystemExit as done:
        _leave(done.code)
    finally:
        gc.enable()
    _leave(0)


#: The variables by which a user sets the BLAS library's threads (OpenBLAS reads the first three, MKL the last two).
BLAS_THREADS = ("OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")


def _one_blas_thread() -> None:
    """One BLAS thread for the command-line process and its children, where the user sets none (before numpy is
    imported: the BLAS library reads them as it loads). Its default, a thread per core, spins after each call on
    the cores the table's own threads compute on: ``lut examples/ggx.brdf`` took 3.42 CPU s (2.21 s wall) with it,
    3.14 (2.10 s) without (docs/performance.md); the commands' arrays are too small for BLAS threads to pay."""
    if "numpy" in sys.modules or any(name in os.environ for name in BLAS_THREADS):
        return
    os.environ["OPENBLAS_NUM_THREADS"] = os.environ["MKL_NUM_THREADS"] = "1"


def _started() -> None:
    """The command's modules imported: the collector back on, with what the imports made frozen (never scanned
    again: modules, functions and classes live as long as the process). Without the collector during the imports,
    and with them frozen, the start of ``lut examples/ggx.brdf`` takes ~0.08 CPU s less (docs/performance.md)."""
    gc.freeze()
    gc.enable()


def _leave(code: object) -> NoReturn:
    """End the command-line process with ``code`` (as ``sys.exit`` reads it) without the interpreter's teardown:
    its streams flushed and its ``atexit`` functions run first, as at a normal exit. The teardown — every module's
    dictionary cleared and Numba's and LLVM's objects destroyed one by one — took ~0.2 s after a table
    (docs/performance.md). Where another thread that is no daemon still runs, or a child process of
    :mod:`multiprocessing`, or where a profiler or tracer watches the process (``python -m cProfile -o FILE -m
    brdfnorm ...`` writes its file after ``main()`` returns; coverage), the interpreter's own exit is taken."""
    others = [t for t in threading.enumerate() if t is not threading.main_thread() and t.is_alive() and not t.daemon]
    processes = sys.modules.get("multiprocessing")
    watched = sys.getprofile() is not None or sys.gettrace() is not None
    if others or watched or (processes is not None and processes.active_children()):
        raise SystemExit(code)
    status = 0 if code is None else code if isinstance(code, int) else 1
    if not isinstance(code, int | None):
        print(code, file=sys.stderr)  # (sys.exit's rule for other objects: printed, status 1)
    atexit._run_exitfuncs()  # noqa: SLF001 — what a normal exit runs (logging's flush, handlers of libraries)
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):  # a reader that went away, or a closed stream: nothing more to write
            pass
    os._exit(status)


def _run(args: list[str], started: Callable[[], None]) -> None:
    """The command line ``args`` run (the application with the commands it needs; ``started`` called once their
    modules are imported), its errors mapped to the exit statuses and lines of :func:`main`."""
    command = tidy(typer.main.get_command(register(chosen(args))))
    started()
    try:
        code = command.main(args=args, prog_name="brdfnorm", standalone_mode=False)
        sys.stdout.flush()
    except typer.Exit as done:
        if done.exit_code == 0:
            _quiet_broken_pipe()
        raise SystemExit(done.exit_code) from None
    except BrokenPipeError:
        _quiet_broken_pipe()
        raise SystemExit(0) from None
    except typer.Abort:
        typer.echo("error: aborted", err=True)
        raise SystemExit(130) from None
    except typer.TyperException as error:  # click-style usage errors (typer vendors click)
        context = getattr(error, "ctx", None)
        if type(error).__name__ == "NoArgsIsHelpError":  # typer has printed the help already
            raise SystemExit(0) from None
        command_path = context.command_path if context is not None else "brdfnorm"
        typer.echo(f"error: {usage_message(error)} (see '{command_path} --help')", err=True)
        raise SystemExit(getattr(error, "exit_code", 2)) from None
    if isinstance(code, int) and code:
        raise SystemExit(code)


def usage_message(error) -> str:
    """A usage error's text in the product's words: without the validation library's "Value error, " prefix,
    and, for a choice, the closest choice ("did you mean 'max'?")."""
    message = error.format_message().replace("Value error, ", "")
    wanted = re.search(r"Input should be (?:a valid |an? )?([\w ]+?)(?:,.*)?$", message)
    if wanted:  # pydantic's words for a bad number: say what was given and what is expected
        cause = error.__cause__
        given = cause.errors()[0].get("input") if hasattr(cause, "errors") else None
        shown = "" if given is None else f"{given!r} is not "
        message = message[:wanted.start()] + f"{shown or 'expected '}a{'n' if wanted.group(1)[0] in 'aeiou' else ''} " \
            f"{wanted.group(1)}"
    param, value = getattr(error, "param", None), None
    kind = getattr(param, "type_descriptor", None) or getattr(param, "type", None)
    choices = [str(getattr(c, "value", c)) for c in getattr(kind, "choices", None) or ()]
    found = re.search(r"'([^']*)' is not one of", message)
    if found:
        value = found.group(1)
    close = difflib.get_close_matches(value, choices, n=1, cutoff=0.4) if value and choices else []
    if close:
        message = message.rstrip(".") + f"; did you mean {close[0]!r}?"
    return message


def _quiet_broken_pipe() -> None:
    """After the reader of stdout went away, point stdout at /dev/null so the interpreter's final flush of
    what is still buffered cannot fail again (the recipe of Python's documentation on SIGPIPE)."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        with open(os.devnull, "wb") as devnull:  # noqa: PTH123 — a raw descriptor for dup2
            os.dup2(devnull.fileno(), sys.stdout.fileno())
    except (OSError, ValueError):  # stdout is not a real file (captured in tests): nothing to flush
        pass
