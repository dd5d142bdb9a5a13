"""The typer application every command module registers itself on (a module of its own, so that the command
modules import it without importing the package that imports them)."""

from __future__ import annotations

import typer

from .help import OrderedGroup

app = typer.Typer(
    name="brdfnorm",
    cls=OrderedGroup,
    help="Exact energy normalization of analytic BRDFs: albedo, normalization factors, fits, shader code.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=True,
)


def _version(value: bool) -> None:
    if value:
        from .. import __version__  # the source's own, also when run from a tree that was never installed

        typer.echo(f"brdfnorm {__version__}")
        raise typer.Exit(0)


@app.callback()
def _root(
    show_version: bool = typer.Option(False, "--version", callback=_version, is_eager=True,
                                      help="Print the version and exit."),
) -> None:
    """Exact energy normalization of analytic BRDFs: albedo, normalization factors, fits, shader code."""
