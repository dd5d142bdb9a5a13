"""The ``brdfnorm`` command line (typer): one module per command group, registered below."""

from __future__ import annotations

import sys

import typer

app = typer.Typer(
    name="brdfnorm",
    help="Exact energy normalization of analytic BRDFs: albedo, normalization factors, fits, shader code.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)

# Command modules register themselves on `app` when imported.
from . import core, explore, fit, info, report, verify  # noqa: E402,F401


def main(argv: list[str] | None = None) -> None:
    """Entry point: usage errors become one line (``error: ...``) with exit code 2, as project errors do."""
    command = typer.main.get_command(app)
    try:
        code = command.main(args=argv if argv is not None else sys.argv[1:], prog_name="brdfnorm",
                            standalone_mode=False)
    except typer.Exit as done:
        raise SystemExit(done.exit_code) from None
    except typer.Abort:
        typer.echo("error: aborted", err=True)
        raise SystemExit(130) from None
    except typer.TyperException as error:  # click-style usage errors (typer vendors click)
        context = getattr(error, "ctx", None)
        if type(error).__name__ == "NoArgsIsHelpError":  # typer has printed the help already
            raise SystemExit(0) from None
        command_path = context.command_path if context is not None else "brdfnorm"
        typer.echo(f"error: {error.format_message()} (see '{command_path} --help')", err=True)
        raise SystemExit(getattr(error, "exit_code", 2)) from None
    if isinstance(code, int) and code:
        raise SystemExit(code)
