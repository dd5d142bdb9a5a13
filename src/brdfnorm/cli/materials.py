"""``brdfnorm furnace`` and ``brdfnorm reference``: the white furnace of a material, and reference values for
engines' CI (:mod:`brdfnorm.materials.furnace`, :mod:`brdfnorm.materials.reference`)."""

from __future__ import annotations

import numpy as np
import typer

from ..errors import ArgumentError
from ..output import STDOUT, write_file
from .application import app
from .common import DEBUG_OPTION, console, guarded, load_model, parse_range

PARAM_OPTION = typer.Option([], "--param", "-p", metavar="NAME=VALUE", help="Set a model parameter (repeatable).")


@app.command()
def furnace(
    model: str = typer.Argument(..., help="A material: openpbr or a material file (.toml, .json)."),
    param: list[str] = PARAM_OPTION,
    theta: str = typer.Option(None, "--theta", metavar="DEGREES", help="View angles: V,V,... or START:STOP:COUNT "
                              "(default 0…89.9°, 30 views)."),
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object instead of the table."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """White furnace of a material: E(θ) − 1 with its largest residual and view, E_avg, reciprocity error."""
    with guarded(debug):
        from ..materials.furnace import furnace as run

        m = load_model(model, param)
        angles = None if theta is None else np.radians(parse_range(theta, "--theta", allow_log=False))
        result = run(m, angles)
        L, V = result.reciprocity_at
        summary = {"model": m.name, "source": m.source_path, "max_residual": result.max_residual,
                   "argmax_theta_deg": float(np.degrees(result.argmax_theta)), "E_avg": result.average.tolist(),
                   "E_avg_error": result.average_error.tolist(), "reciprocity_error": result.reciprocity,
                   "reciprocity_argmax": {"L": L.tolist(), "V": V.tolist()}, "views": result.rows()}
        if json_output:
            import json

            write_file(STDOUT, json.dumps(summary, indent=1) + "\n")
            return
        out = console()
        for row in summary["views"]:
            out.print(f"θ {row['theta_deg']:8.3f}°  E " + ", ".join(f"{x:.12f}" for x in row["E"])
                          + f"  ± {max(row['error_estimate']):.2e}")
        out.print(f"largest |E − 1|: {result.max_residual:.3e} at θ = {summary['argmax_theta_deg']:g}°; "
                      f"E_avg " + ", ".join(f"{x:.12f}" for x in result.average)
                      + f" ± {result.average_error.max():.1e}; reciprocity error {result.reciprocity:.3e} of the "
                      f"lobe's scale at L={np.round(L, 6).tolist()}, V={np.round(V, 6).tolist()}")


@app.command()
def reference(
    model: str = typer.Argument(..., help="A material: openpbr or a material file (.toml, .json)."),
    param: list[str] = PARAM_OPTION,
    grid: list[str] = typer.Option([], "--grid", metavar="NAME=SPEC", help="A grid axis over a float parameter "
                                   "(repeatable): V,V,... or START:STOP:COUNT, e.g. coat_weight=0:1:3."),
    mu: str = typer.Option("0.05:1:20", "--mu", metavar="SPEC", help="View cosines μ: V,V,... or START:STOP:COUNT."),
    csv_output: bool = typer.Option(False, "--csv", help="CSV (one row per grid point and μ) instead of JSON."),
    output: str = typer.Option("-", "--output", "-o", help="Output file ('-': stdout)."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Reference E(μ), E_avg and furnace residual of a material over a parameter grid, for engines' CI."""
    with guarded(debug):
        from ..materials import reference as ref

        m = load_model(model, param)
        axes = {}
        for item in grid:
            name, sep, spec = item.partition("=")
            if not sep or not name.strip():
                raise ArgumentError(f"expected NAME=SPEC, got {item!r}", where="--grid")
            axes[name.strip()] = parse_range(spec, "--grid", allow_log=False).tolist()
        document = ref.reference(m, axes, parse_range(mu, "--mu", allow_log=False))
        write_file(STDOUT if output == "-" else output, ref.to_csv(document) if csv_output else ref.to_json(document))
        if output != "-":
            console(stderr=True).print(f"{len(document['points'])} grid points × {len(document['mu'])} views; "
                                       f"wrote {output}")
