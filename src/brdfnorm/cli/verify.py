"""``brdfnorm verify``: every numerical claim of the three seed articles, formula against independent numerics.

The checks live in :mod:`brdfnorm.claims.verify`; this module parses the options and prints the table (or JSON).
Exit status 0 when every verdict is ok, 1 when some claim is not (each verdict is computed, so a failing
claim is a finding, not a crash), 2 for bad options.
"""

from __future__ import annotations

import typer
from rich.table import Table

from .. import __version__
from ..output import STDOUT, write_file
from ..output.formats import to_json
from .application import app
from .common import DEBUG_OPTION, console, guarded, parse_range


@app.command()
def verify(
    exponents: str = typer.Option(
        None, "--n", metavar="LIST",
        help="Exponents for the parametric claims: N,N,... or START:STOP:n=COUNT[:log] (default 1,10,100,512).",
    ),
    claim: list[str] = typer.Option([], "--claim", metavar="ID", help="Check only this claim (repeatable)."),
    certified: bool = typer.Option(False, "--certified",
                                   help="Also check each albedo-valued claim against a guaranteed enclosure "
                                        "(Arb ball arithmetic; needs brdfnorm[certified])."),
    digits: int = typer.Option(30, "--digits", min=1, help="With --certified: digits of the enclosures."),
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object: {\"claims\": [...]}."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Re-check the seeds' formulas (Phong and Blinn-Phong factors, seed 002's derivation, seed 003's fit).

    With --certified, every claim that is an albedo value is also checked against a guaranteed enclosure: the
    closed forms of seed 000 must lie inside it (both in ball arithmetic), seed 002's numerical procedures
    within their 1e-10 tolerance of it.
    """
    with guarded(debug):
        from ..claims import verify as checks  # mpmath and the checks load only when asked for

        n = checks.check_exponents(checks.DEFAULT_EXPONENTS if exponents is None
                                   else parse_range(exponents, "--n", allow_log=True))
        claims = checks.verify(n, only=claim or None, certified=certified, digits=digits)
        if json_output:
            write_file(STDOUT, to_json({"brdfnorm": __version__, "exponents": n,
                                        "claims": [c.as_dict() for c in claims]}) + "\n")
        else:
            groups = " and ".join(dict.fromkeys(c.group for c in claims))
            table = Table(title=f"{groups} ({sum(c.ok for c in claims)} of {len(claims)} ok)", show_lines=True)
            for column, justify in (("claim", "left"), ("source", "left"), ("statement", "left"),
                                    ("formula", "right"), ("numerics", "right"), ("rel. error", "right"),
                                    *((("certified albedo", "right"),) if certified else ()),
                                    ("verdict", "center")):  # fmt: skip
                table.add_column(column, justify=justify, overflow="fold")
            for c in claims:
                verdict = "[green]ok[/green]" if c.ok else "[red]FAIL[/red]"
                statement = f"{c.statement}\n[dim]{c.detail}[/dim]" if c.detail else c.statement
                enclosure = (_enclosure_text(c),) if certified else ()
                table.add_row(c.id, c.source.split(" (")[0], statement, f"{c.formula_value:.12g}",
                              f"{c.numeric_value:.12g}", f"{c.rel_error:.2e}", *enclosure, verdict)  # fmt: skip
            console().print(table)
        if not all(c.ok for c in claims):
            raise typer.Exit(1)


def _enclosure_text(claim) -> str:
    """The enclosure at the exponent the row shows (the claim's worst case), or why there is none."""
    if claim.certified is None:
        return "[dim]not an albedo value[/dim]"
    shown = min(zip(claim.cases, claim.certified["cases"], strict=True),
                key=lambda pair: abs(pair[0]["formula_value"] - claim.formula_value))[1]
    mark = "" if shown["inside"] else " [red](formula outside)[/red]"
    return f"n = {shown['n']:g}: [{shown['lower']}, {shown['upper']}]{mark}"
