"""``brdfnorm info FILE``: what a ``.brdf`` file (or built-in model) declares, and whether it is reciprocal.

Reciprocity f(L, V) = f(V, L) (Helmholtz) is checked on random direction pairs with
:func:`brdfnorm.brdffile.reciprocity_check`; it decides whether the albedo over the light equals the albedo
over the view (``--over``), e.g. not for the original Phong lobe (seed 000: 2π/(n+1) against 2π/(n+2)).
"""

from __future__ import annotations

import typer
from rich.markup import escape
from rich.table import Table

from .. import __version__
from ..brdffile import BrdfModel, reciprocity_check
from ..errors import ArgumentError
from ..output import STDOUT, write_file
from ..output.formats import format_value, to_json
from .application import app
from .common import DEBUG_OPTION, PARAM_OPTION, console, guarded, load_model


@app.command()
def info(
    model: str = typer.Argument(..., metavar="FILE", help="A BRDF Explorer .brdf file (or a built-in model name)."),
    param: list[str] = PARAM_OPTION,
    samples: int = typer.Option(4096, "--samples", help="Random direction pairs for the reciprocity check."),
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Parameters (kind, range, default), channels, reciprocity on a sample of pairs, and whether a .brdf file
    has an isFunc (importance-sampling) section."""
    with guarded(debug):
        if samples < 1:
            raise ArgumentError(f"need at least 1 pair, got {samples}", where="--samples")
        m = load_model(model, param)
        check = reciprocity_check(m, samples=samples, seed=0)
        is_file = isinstance(m, BrdfModel)
        bound = m.params
        parameters = [
            {
                **p.declaration(),  # the declaration models and explore read: kind, channels, integer, range…
                "min": p.minimum,
                "max": p.maximum,
                "value": bound[p.name],
                "range_is_slider": not p.strict,
            }
            for p in m.parameters
        ]
        data = {
            "model": m.name,
            "source": m.source_path,
            "channels": m.channels,
            "isotropic": m.isotropic,
            "parameters": parameters,
            "reciprocity": {
                "reciprocal": check.reciprocal,
                "max_relative_asymmetry": check.max_relative,
                "tolerance": check.tolerance,
                "worst_L": check.L,
                "worst_V": check.V,
                "samples": check.samples,
                "nonfinite_pairs": check.nonfinite,
            },
            "isFunc": m.has_is_func if is_file else False,
        }
        if json_output:
            write_file(STDOUT, to_json({"brdfnorm": __version__, **data}) + "\n")
            return
        out = console()
        title = f"{m.name}" + (f" ({m.source_path})" if m.source_path else " (built-in)")
        table = Table(title=escape(title))  # a file name is text, not rich markup
        for column in ("parameter", "kind", "range", "default", "value"):
            table.add_column(column)
        for p in m.parameters:
            kind_range = "R,G,B " + p.describe_range() if p.kind == "color" else p.describe_range()  # a|b|c choices
            if not p.strict and p.kind in ("float", "int", "spectrum"):
                kind_range += " (slider)"
            table.add_row(escape(p.name), p.kind, kind_range, format_value(p.default, 6),
                          format_value(bound[p.name], 6))
        out.print(table)
        out.print(f"channels: {m.channels}")
        verdict = "yes" if check.reciprocal else "no"
        out.print(
            f"reciprocal: {verdict} (max relative asymmetry |f(L,V) - f(V,L)| / max {check.max_relative:.3g} "
            f"on {check.samples} random pairs)"
        )
        if check.nonfinite:
            out.print(f"non-finite values at {check.nonfinite} of the {check.samples} pairs (skipped)")
        out.print(f"isFunc section: {'yes' if data['isFunc'] else 'no'}")
