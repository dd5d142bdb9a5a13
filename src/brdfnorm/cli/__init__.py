"""The ``brdfnorm`` command line (typer): one module per command group, registered below."""

from __future__ import annotations

import difflib
import os
import re
import sys

import typer

from .application import app
from .help import tidy

# isort: split
# Command modules register themselves on `app` (defined in .application, which imports none of them) when imported.
from . import audit, check, core, explore, fit, info, lut, materials, report, verify  # noqa: F401


def main(argv: list[str] | None = None) -> None:
    """Entry point: usage errors become one line (``error: ...``) with exit code 2, as project errors do."""
    command = tidy(typer.main.get_command(app))
    try:
        code = command.main(args=argv if argv is not None else sys.argv[1:], prog_name="brdfnorm",
                            standalone_mode=False)
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
