"""The typer application every command module registers itself on (a module of its own, so that the command
modules import it without importing the package that imports them)."""

from __future__ import annotations

import typer

app = typer.Typer(
    name="brdfnorm",
    help="Exact energy normalization of analytic BRDFs: albedo, normalization factors, fits, shader code.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,
)
