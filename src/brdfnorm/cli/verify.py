"""``brdfnorm verify``: every numerical claim of the three seed articles, formula against independent numerics.

The checks live in :mod:`brdfnorm.verify`; this module parses the options and prints the table (or JSON).
Exit status 0 when every verdict is ok, 1 when some claim is not (each verdict is computed, so a failing
claim is a finding, not a crash), 2 for bad options.
"""

from __future__ import annotations

import typer
from rich.table import Table

from ..output import STDOUT, write_file
from ..output.formats import to_json
from . import app
from .common import DEBUG_OPTION, console, guarded, parse_range


@app.command()
def verify(
    exponents: str = typer.Option(
        None, "--n", metavar="LIST",
        help="Exponents for the parametric claims: N,N,... or START:STOP:COUNT[:log] (default 1,10,100,512).",
    ),
    claim: list[str] = typer.Option([], "--claim", metavar="ID", help="Check only this claim (repeatable)."),
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object: {\"claims\": [...]}."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Re-check the seeds' formulas (Phong and Blinn-Phong factors, seed 002's derivation, seed 003's fit)."""
    with guarded(debug):
        from .. import verify as checks  # mpmath and the checks load only when asked for

        n = checks.check_exponents(checks.DEFAULT_EXPONENTS if exponents is None
                                   else parse_range(exponents, "--n", allow_log=True))
        claims = checks.verify(n, only=claim or None)
        if json_output:
            write_file(STDOUT, to_json({"exponents": n, "claims": [c.as_dict() for c in claims]}) + "\n")
        else:
            table = Table(title=f"seed claims ({sum(c.ok for c in claims)} of {len(claims)} ok)", show_lines=True)
            for column, justify in (("claim", "left"), ("source", "left"), ("statement", "left"),
                                    ("formula", "right"), ("numerics", "right"), ("rel. error", "right"),
                                    ("verdict", "center")):  # fmt: skip
                table.add_column(column, justify=justify, overflow="fold")
            for c in claims:
                verdict = "[green]ok[/green]" if c.ok else "[red]FAIL[/red]"
                statement = f"{c.statement}\n[dim]{c.detail}[/dim]" if c.detail else c.statement
                table.add_row(c.id, c.source.split(" (")[0], statement, f"{c.formula_value:.12g}",
                              f"{c.numeric_value:.12g}", f"{c.rel_error:.2e}", verdict)  # fmt: skip
            console().print(table)
        if not all(c.ok for c in claims):
            raise typer.Exit(1)
