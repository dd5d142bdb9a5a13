"""``brdfnorm check MODEL...``: the white-furnace and physics audit of :mod:`brdfnorm.check`.

The table (one row per check for one model, one summary row per model for several) or ``--json`` goes to
stdout; what each audit covered goes to stderr. Exit code 1 when a check fails, 0 otherwise (an inconclusive
verdict is reported but does not fail), 2 for bad input.
"""

from __future__ import annotations

import re
import time

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from .. import __version__
from ..check import CHECKS, DEFAULT_CHECKS, Budget, CheckReport
from ..check import check as run_check
from ..errors import ArgumentError
from ..output import STDOUT, write_file
from ..output.formats import format_error, to_json
from .application import app
from .common import (
    DEBUG_OPTION,
    PARAM_OPTION,
    At,
    Over,
    Spread,
    backend_option,
    console,
    guarded,
    load_model,
    parallel_options,
    parse_params,
    parse_sweep,
)

_BUDGET = re.compile(r"\s*([0-9.eE+-]+)\s*(s|sec|seconds|evals|evaluations)?\s*\Z")
VERDICT = {"pass": "pass", "fail": "FAIL", "inconclusive": "inconclusive"}


def parse_budget(spec: str) -> Budget:
    """``SECONDS``, ``SECONDSs`` or ``COUNTevals`` (integrand and BRDF evaluations)."""
    match = _BUDGET.match(spec)
    try:
        amount = float(match.group(1)) if match else float("nan")
    except ValueError:
        amount = float("nan")
    if not match or not np.isfinite(amount) or amount <= 0:
        raise ArgumentError(f"expected SECONDS (e.g. 20 or 20s) or COUNTevals (e.g. 5e7evals), got {spec!r}",
                            where="--budget")
    if match.group(2) in ("evals", "evaluations"):
        if amount < 1 or amount != int(amount):
            raise ArgumentError(f"an evaluation count is a whole number ≥ 1, got {spec.strip()!r}", where="--budget")
        return Budget(seconds=None, evaluations=int(amount))
    return Budget(seconds=amount)


def parse_only(spec: str) -> tuple[str, ...]:
    names = tuple(dict.fromkeys(part.strip() for part in spec.split(",") if part.strip()))
    unknown = [n for n in names if n not in CHECKS]
    if unknown or not names:
        raise ArgumentError(f"unknown check {unknown[0]!r}" if unknown else "no check named"
                            f" (known: {','.join(CHECKS)})", where="--only")
    return names


@app.command("check")
@backend_option
@parallel_options
def check_command(
    models: list[str] = typer.Argument(..., metavar="MODEL...", help="Built-in model names or .brdf files."),
    param: list[str] = PARAM_OPTION,
    sweep: list[str] = typer.Option([], "--sweep", metavar="NAME=SPEC",
                                    help="Values of a float parameter instead of its declared range (repeatable): "
                                         "V,V,..., START:STOP:n=COUNT (add :log for log spacing) or "
                                         "START:STOP:step=STEP."),
    only: str = typer.Option(None, "--only", metavar="CHECK,...",
                             help=f"Run only these checks, comma-separated ({', '.join(CHECKS)}); default: "
                                  f"{', '.join(DEFAULT_CHECKS)}, plus normalization with --normalized."),
    normalized: bool = typer.Option(False, "--normalized", help="The lobe is meant to be normalized: also check "
                                    "that its albedo at the --at direction is 1 across the parameters."),
    at: At = typer.Option(At.normal, "--at", help="Normalization convention for --normalized: normal (fixed "
                          "direction at N), max (largest over directions) or view (every direction)."),
    over: Over = typer.Option(Over.light, "--over", help="Albedo over the light (view fixed, default) or the view."),
    tolerance: float | None = typer.Option(None, "--tolerance", help="Allowed energy gain, |E − 1| for "
                                           "--normalized, and relative asymmetry for reciprocity (default 1e-6; "
                                           "float32 models such as mitsuba: 256 units of float32, 1.5e-5).",
                                           show_default=False),
    budget: str = typer.Option("20", "--budget", metavar="SECONDS|COUNTevals",
                               help="Work for the whole command, shared by the models (each gets what is left "
                                    "divided by the models still to check): seconds (default 20) or "
                                    "evaluations, e.g. 5e7evals."),
    points: int = typer.Option(48, "--points", help="Parameter points of the coarse grid (per bool combination "
                               "and swept value)."),
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object."),
    spread: Spread = None,
    debug: bool = DEBUG_OPTION,
) -> None:
    """Audit BRDFs: energy conservation (largest albedo), reciprocity, positivity, finiteness, normalization.

    Every float parameter with a declared range is searched over it (open ranges up to min + 1e4), bools take
    both values; -p NAME=VALUE holds a parameter, --sweep gives its values. With several models, one row is
    printed per model as it finishes. Exit code 1 when a check fails; 3 when none fails but the budget cut a
    search short (the verdict reads "pass (partial: k of N points)").
    The albedo integrals go through local processes or a Dask cluster like a table's cells (the same report);
    --checkpoint resumes one model's check under a budget of evaluations.
    """
    with guarded(debug):
        checks = parse_only(only) if only else DEFAULT_CHECKS + (("normalization",) if normalized else ())
        if normalized and "normalization" not in checks:
            checks = checks + ("normalization",)
        if tolerance is not None and not (np.isfinite(tolerance) and tolerance >= 0):
            raise ArgumentError(f"must be finite and ≥ 0, got {tolerance!r}", where="--tolerance")
        if points < 1:
            raise ArgumentError(f"need at least 1 point, got {points}", where="--points")
        limit = parse_budget(budget)
        sweeps = dict(parse_sweep(s) for s in sweep)
        held = list(parse_params(param))
        if spread.checkpoint is not None and len(models) > 1:
            raise ArgumentError("a checkpoint resumes the check of one model; give one MODEL", where="--checkpoint")
        loaded = [load_model(name, param) for name in models]  # every file is read before any work
        for m in loaded:
            for name in sweeps:
                m.parameter(name)
        reports = []
        stream = not json_output and len(loaded) > 1
        started, spent = time.monotonic(), 0
        for index, (name, m) in enumerate(zip(models, loaded, strict=True)):
            share = _share(limit, len(loaded) - index, time.monotonic() - started, spent)
            try:
                report = run_check(m, checks=checks, sweep=sweeps, fixed=held, tolerance=tolerance, at=at.value,
                                   over=over.value, budget=share, points=points, workers=spread.workers,
                                   scheduler=spread.dask_scheduler(), checkpoint=spread.checkpoint,
                                   chunk_cells=spread.chunk_cells)
            except ArgumentError as error:
                flags = {"sweep": "--sweep", "checks": "--only", "budget": "--budget", "points": "--points"}
                error.where = flags.get(error.where, error.where)
                raise
            spent += int(report.coverage.get("evaluations", 0))
            reports.append(report)
            typer.echo(f"{name}: {verdict_text(report)}{_failed(report)} — {coverage_text(report)}", err=True)
            if stream:  # one row per model as it finishes, not a table at the end
                console().print(row_text(report), markup=False, highlight=False, soft_wrap=True)
        if json_output:
            shown = tolerance if tolerance is not None or not reports else reports[0].tolerance
            write_file(STDOUT, to_json({"brdfnorm": __version__, "tolerance": shown, "over": over.value,
                                        "checks": list(checks),
                                        "status": _overall(reports),
                                        "reports": [{**report_json(r), "partial": _partial(r)} for r in reports]})
                       + "\n")
        elif len(reports) == 1:
            console().print(detail_table(reports[0]))
        elif any(r.failed for r in reports):
            console().print(failures_table(reports))
        if any(r.failed for r in reports):
            raise typer.Exit(1)
        if any(_partial(r) for r in reports):
            raise typer.Exit(PARTIAL_EXIT)


#: Exit status when no check failed but a budget cut a search short.
PARTIAL_EXIT = 3


def _share(total: Budget, left: int, elapsed: float, evaluations: int) -> Budget:
    """The budget of the next model: what is left of ``total`` divided by the ``left`` models still to check."""
    if total.seconds is not None:
        return Budget(seconds=max(total.seconds - elapsed, 0.0) / left or 1e-3)
    if total.evaluations is not None:
        return Budget(seconds=None, evaluations=max((total.evaluations - evaluations) // left, 1))
    return total


def _partial(report: CheckReport) -> dict | None:
    """``{"points": k, "of": N}`` when the search covered only k of its N planned parameter points."""
    c = report.coverage
    planned = c.get("parameter_points_planned")
    done = [c[key]["parameter_points"] for key in ("energy", "pairs") if key in c]
    if not planned or not done or min(done) >= planned:
        return None
    return {"points": int(min(done)), "of": int(planned)}


def verdict_text(report: CheckReport) -> str:
    """The verdict, with "(partial: k of N points)" when the budget cut the search short."""
    partial = _partial(report)
    return report.status + (f" (partial: {partial['points']} of {partial['of']} points)" if partial else "")


def row_text(report: CheckReport) -> str:
    """One model's row of a multi-model check: verdict, each check's headline, time."""
    cells = "; ".join(f"{name}: {r.status}, {cell(r)}" for name, r in report.results.items())
    return (f"{report.source or report.model}  {verdict_text(report)}  {cells}  "
            f"({report.coverage['elapsed_s']:.1f} s)")


def _failed(report: CheckReport) -> str:
    return f" ({', '.join(report.failed)})" if report.failed else ""


def _overall(reports: list[CheckReport]) -> str:
    statuses = [r.status for r in reports]
    overall = "fail" if "fail" in statuses else "inconclusive" if "inconclusive" in statuses else "pass"
    return overall + (" (partial)" if overall == "pass" and any(_partial(r) for r in reports) else "")


def coverage_text(report: CheckReport) -> str:
    """What was searched, in one line (the coverage half of the product's 'honest error bar')."""
    c = report.coverage
    parts = []
    if "energy" in c:
        e = c["energy"]
        refined = ("refinement finished" if e["refinement_finished"]
                   else f"refinement stopped by the budget after {e['refinement_rounds']} rounds")
        azimuths = f" (and 8 azimuths at the best {e['full_azimuth_points']})" if e["full_azimuth_points"] else ""
        parts.append(f"energy: {e['parameter_points']} of {e['parameter_points_planned']} parameter points × "
                     f"{e['directions']} directions{azimuths}, {refined}")
    if "pairs" in c:
        p = c["pairs"]
        parts.append(f"{p['pairs_per_point']} direction pairs at {p['parameter_points']} parameter points")
    parts.append(f"{c['evaluations']:.3g} evaluations in {c['elapsed_s']:.1f} s (budget {c['budget']})")
    if "parallel" in c:
        p = c["parallel"]
        parts.append(f"albedo integrals in {p['chunks']} chunks ({p['chunks_from_checkpoint']} from the checkpoint) "
                     f"on {p['workers']} workers ({', '.join(p['executors']) or 'none computed'})")
    return "; ".join(parts)


def report_json(report: CheckReport) -> dict:
    return {
        "model": report.model, "source": report.source, "status": report.status, "failed": report.failed,
        "tolerance": report.tolerance, "over": report.over,
        "checks": {name: {"status": r.status, "value": r.value, "error_estimate": r.error, "message": r.message,
                          "params": r.params, "L": r.L, "V": r.V, "theta_deg": r.theta_deg, "phi_deg": r.phi_deg,
                          "channel": r.channel, "share": r.share, "sampled": r.sampled}
                   for name, r in report.results.items()},
        "coverage": report.coverage,
    }


def detail_table(report: CheckReport) -> Table:
    # Names and messages come from outside (file names, parameter names): text, never rich markup.
    partial = _partial(report)
    cut = f" (partial: {partial['points']} of {partial['of']} points)" if partial else ""
    table = Table(title=escape(f"{report.source or report.model}: {VERDICT[report.status]}{cut} "
                               f"(tolerance {report.tolerance:g})"))
    for column in ("check", "verdict", "value", "details"):
        table.add_column(column, overflow="fold")
    for name, r in report.results.items():
        table.add_row(name, VERDICT[r.status], cell(r), escape(r.message))
    return table


def cell(result) -> str:
    """The headline number of one check, as the summary table shows it."""
    if result.name in ("energy", "normalization"):
        label = "max E " if result.name == "energy" else "|E−1| "
        return f"{label}{result.value:.8g} ± {format_error(result.error)}"
    if result.name == "reciprocity":
        return f"{result.value:.2g} of scale"
    return f"{100 * result.share:.3g}% of domain" if result.share else "none found"


def summary_table(reports: list[CheckReport]) -> Table:
    names = [n for n in CHECKS if any(n in r.results for r in reports)]
    table = Table(title=f"brdfnorm check: {len(reports)} models")
    for column in ("model", "verdict", *names, "time (s)"):
        table.add_column(column, overflow="fold")
    for r in reports:
        cells = [f"{VERDICT[r.results[n].status]}: {cell(r.results[n])}" if n in r.results else "—" for n in names]
        table.add_row(escape(r.source or r.model), VERDICT[r.status], *cells, f"{r.coverage['elapsed_s']:.1f}")
    return table


def failures_table(reports: list[CheckReport]) -> Table:
    """Where each failing check fails: parameter values and directions."""
    table = Table(title="failures")
    for column in ("model", "check", "details"):
        table.add_column(column, overflow="fold")
    for r in reports:
        for name in r.failed:
            table.add_row(escape(r.source or r.model), name, escape(r.results[name].message))
    return table
