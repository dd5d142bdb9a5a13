"""``brdfnorm report``: the HTML study of the seed lobes (``make demo``), or of given models and files."""

from __future__ import annotations

import time

import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Column

from .application import app
from .common import DEBUG_OPTION, PARAM_OPTION, backend_option, guarded, load_model, parse_sweep


@app.command()
@backend_option
def report(
    models: list[str] = typer.Argument(None, metavar="MODEL_OR_FILE",
                                       help="Built-in model names or .brdf files; none: the seed lobes."),
    param: list[str] = PARAM_OPTION,
    sweep: str = typer.Option(None, "--sweep", metavar="NAME=SPEC",
                              help="Parameter to study: V,V,..., START:STOP:n=COUNT (add :log for log spacing) "
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
    with guarded(debug, names={"audit": "--audit"}):
        from ..report import build_report  # matplotlib loads only when a report is asked for

        loaded = [(name, load_model(name, param)) for name in models or []]
        if param and not loaded:
            typer.echo("warning: -p/--param applies to given models only; ignored for the default study",
                       err=True)
        swept = parse_sweep(sweep) if sweep else None
        console = Console(stderr=True)
        if console.is_terminal:
            # A bar that moves within a section (the sections report their parts), the part named beside it; the
            # description column is bounded, so that bar, section and time stay on one 80-column line.
            what = TextColumn("{task.description}", table_column=Column(no_wrap=True, overflow="ellipsis",
                                                                        max_width=48))
            with Progress(what, BarColumn(bar_width=16), TextColumn("{task.fields[section]}"),
                          TimeElapsedColumn(), console=console, transient=True) as progress:
                task = progress.add_task("report", total=None, section="")
                current = [""]

                def on_step(description: str, position: float, total: int) -> None:
                    # a section's start names it; its parts ("SECTION: part") show the part, which changes
                    if description.startswith(current[0] + ": ") and current[0]:
                        description = description[len(current[0]) + 2:]
                    else:
                        current[0] = description
                    section = f"{min(int(position) + 1, total)}/{total}"
                    progress.update(task, description=description, completed=position, total=total,
                                    section=section)

                index = build_report(output, loaded, sweep=swept, on_step=on_step, audit=audit)
        else:
            # Not a terminal (a log, CI): one line as each section starts, and none within it.
            started, announced = time.monotonic(), set()

            def on_line(description: str, position: float, total: int) -> None:
                if int(position) not in announced and position < total:  # a section's first call names it
                    announced.add(int(position))
                    typer.echo(f"report [{int(position) + 1}/{total}] {description} "
                               f"({time.monotonic() - started:.0f} s)", err=True)

            index = build_report(output, loaded, sweep=swept, on_step=on_line, audit=audit)
        typer.echo(f"wrote {index}", err=True)
