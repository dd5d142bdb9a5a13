"""``brdfnorm report``: the HTML study of the seed lobes (``make demo``), or of given models and files."""

from __future__ import annotations

import typer
from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from .application import app
from .common import DEBUG_OPTION, PARAM_OPTION, backend_option, guarded, load_model, parse_sweep


@app.command()
@backend_option
def report(
    models: list[str] = typer.Argument(None, metavar="[MODEL_OR_FILE]...",
                                       help="Built-in model names or .brdf files; none: the seed lobes."),
    param: list[str] = PARAM_OPTION,
    sweep: str = typer.Option(None, "--sweep", metavar="NAME=SPEC",
                              help="Parameter to study: V,V,..., START:STOP:COUNT or START:STOP:COUNT:log "
                                   "(default: each model's first float parameter over its range; with no "
                                   "models, the exponents n of the factor table)."),
    audit: list[str] = typer.Option([], "--audit", metavar="FILE_OR_DIR",
                                    help="Add a section auditing these .brdf files (a directory: all its .brdf "
                                         "files) with `brdfnorm check`, one row each (repeatable)."),
    output: str = typer.Option("report", "--output", "-o", metavar="DIR",
                               help="Report directory: DIR/index.html and its figures, replaced atomically."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Write an HTML report (index.html + PNG figures) studying the normalization of the seed lobes or models."""
    with guarded(debug):
        from ..report import build_report  # matplotlib loads only when a report is asked for

        loaded = [(name, load_model(name, param)) for name in models or []]
        if param and not loaded:
            typer.echo("warning: -p/--param applies to given models only; ignored for the default study",
                       err=True)
        swept = parse_sweep(sweep) if sweep else None
        console = Console(stderr=True)
        with Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                      console=console, transient=True, disable=not console.is_terminal) as progress:
            task = progress.add_task("report", total=None)

            def on_step(description: str, index: int, total: int) -> None:
                progress.update(task, description=description, completed=index, total=total)

            index = build_report(output, loaded, sweep=swept, on_step=on_step, audit=audit)
        typer.echo(f"wrote {index}", err=True)
