"""``brdfnorm fit``: fit a cheap formula to a model's normalization factor and emit it as shader code (issue 4).

Samples are the normalization factor 1/E over a parameter sweep (as :func:`brdfnorm.normalization.normalize` computes
it, spread over cores or a Dask cluster by :mod:`brdfnorm.parallel`; with ``--at view`` also over the polar angles of
``--theta``, fitted in the two variables (x, cos θ_o)); the fitting is
:func:`brdfnorm.fit.fit`, the code :func:`brdfnorm.fit.codegen.emit`. Seed 003's check:
``brdfnorm fit blinn-phong-gaussian --sweep n=1:512:512 --form linear --metric abs-lsq --at normal --json``.
"""

from __future__ import annotations

from enum import Enum
from pathlib import Path

import numpy as np
import typer
from rich.markup import escape
from rich.table import Table

from .. import __version__
from ..errors import ArgumentError, EvaluationError, OutputError
from ..fit import METRICS, FitResult, fit, parse_form
from ..fit.codegen import LANGUAGES, emit, fit_context
from ..fit.exact import EXACT, exact_form
from ..output import STDOUT, write_file
from ..output.formats import to_json
from ..parallel.results import normalization_result, sweep_job
from ..validate import DEFAULT_RTOL
from .application import app
from .common import (
    DEBUG_OPTION,
    PARAM_OPTION,
    At,
    Spread,
    backend_option,
    compute_cells,
    console,
    guarded,
    load_model,
    parallel_options,
    parse_angles,
    parse_sweep,
)

SECOND_VARIABLE = "cos_theta_o"


class Metric(str, Enum):
    abs_lsq = "abs-lsq"
    rel_lsq = "rel-lsq"
    minimax_rel = "minimax-rel"
    minimax_abs = "minimax-abs"


assert tuple(m.value for m in Metric) == METRICS


def _factor_channel(factor: np.ndarray) -> np.ndarray:
    """Channel 0 of the (S, T, C) factors; several channels only if they are all equal."""
    if factor.shape[-1] > 1 and not np.allclose(factor, factor[..., :1], rtol=1e-12, atol=0.0):
        raise ArgumentError(f"the model has {factor.shape[-1]} channels with different factors; fit one "
                            "channel at a time (e.g. set the color parameters equal)", where="MODEL")
    return factor[..., 0]


def _plot(path: str, result: FitResult, x: np.ndarray, t: np.ndarray | None, y: np.ndarray, name: str) -> None:
    """α(x), the fit, and the relative error (one curve per θ for a two-variable fit)."""
    import io

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(7, 7), sharex=True)
    columns = [slice(None)] if t is None else [np.s_[:, j] for j in range(y.shape[1])]
    X = x if t is None else np.broadcast_to(x[:, None], y.shape)
    for j, col in enumerate(columns):
        xs, ys = X[col], y[col]
        ts = None if t is None else t[col]
        fitted = result(xs, ts)
        label = "" if t is None else f" θ={np.degrees(np.arccos(np.clip(ts[0], -1, 1))):.3g}°"
        top.plot(xs, ys, ".", ms=3, color=f"C{j % 10}", label=f"α{label}" if j < 8 else None)
        top.plot(xs, fitted, "-", lw=1, color=f"C{j % 10}", label=f"fit{label}" if j < 8 else None)
        bottom.plot(xs, fitted / ys - 1.0, "-", lw=1, color=f"C{j % 10}")
    top.set_ylabel("normalization factor α")
    top.set_title(f"{result.form} ({result.metric}): max rel. error {result.max_rel_error:.3g}")
    top.legend(fontsize=7)
    bottom.set_ylabel("relative error (fit/α − 1)")
    bottom.set_xlabel(name)
    bottom.axhline(0.0, color="k", lw=0.5)
    if x.min() > 0 and x.max() / x.min() > 100:
        for axis in (top, bottom):
            axis.set_xscale("log")
        top.set_yscale("log")
    from ..report.figures import plain_text, readable_log_ticks

    plain_text(fig)  # the parameter name is the user's: never mathtext
    for axis in (top, bottom):
        readable_log_ticks(axis)
    fig.tight_layout()
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110, metadata={"Software": f"brdfnorm {__version__}"})
    plt.close(fig)
    write_file(path, buffer.getvalue())


@app.command("fit")
@backend_option
@parallel_options
def fit_command(
    model: str = typer.Argument(None, metavar="MODEL", help="A built-in model name or a .brdf file (not with --lut)."),
    param: list[str] = PARAM_OPTION,
    sweep: str = typer.Option(None, "--sweep", metavar="NAME=SPEC",
                              help="The fitted parameter: NAME=START:STOP:n=COUNT (add :log for log spacing) "
                                   "or NAME=V,V,..."),
    lut: str = typer.Option(None, "--lut", metavar="FILE", help="Fit a table of `brdfnorm lut` over its two axes "
                            "(e.g. E(μ, α)) instead of a normalization factor; prints the Pareto front "
                            "(coefficients vs max absolute error; an entry beats every smaller fit by ≥ 1 %; "
                            "candidates proved unable to enter it are skipped, listed in --json) on stderr. "
                            "--target is then absolute "
                            "(default 5e-3) and --max-coefficients defaults to 16."),
    lut_table: str = typer.Option("E", "--table", metavar="NAME", help="The table fitted with --lut."),
    form: str = typer.Option("auto", "--form", help="closed-form | linear | hyperbola | poly:D | rational:P/Q | "
                             "rational-sqrt:P/Q | auto (which prefers closed-form where the model has one: "
                             "phong, modified-phong and blinn-phong over n at normal); with --at view add @D "
                             "(degree in cos θ_o) and "
                             "optionally ~tau, e.g. rational-sqrt:4/2@3~tau. With --lut of a (mu, alpha) "
                             "table also smith:P/Q@D or smith:P/Q@D/DQ, E = 1 − s·(N + ln s·L)/Q in "
                             "s = μ/√(μ² + α²(1 − μ²)) with Q of degree DQ in α², e.g. smith:1/1@1/2 (GGX to "
                             "5e-3, 11 coefficients)."),
    metric: Metric = typer.Option(None, "--metric", help="What the fit minimizes (default minimax-rel; with "
                                  "--lut minimax-abs)."),
    at: At = typer.Option(At.normal, "--at", help="Normalization convention (view: fit in n and cos θ_o)."),
    theta: str = typer.Option(None, "--theta", metavar="SPEC",
                              help="Polar angles in degrees for --at view (START:STOP:n=COUNT, "
                                   "START:STOP:step=STEP or a list)."),
    target: float = typer.Option(None, "--target", help="Max relative error that --form auto aims for (default "
                                 "1e-3; with --lut the max absolute error, default 5e-3)."),
    max_coefficients: int = typer.Option(None, "--max-coefficients",
                                         help="Largest coefficient count --form auto tries (default 10; 40 "
                                              "in two variables)."),
    rtol: float = typer.Option(DEFAULT_RTOL, "--rtol", help="Relative tolerance of each albedo integral."),
    emit_language: str = typer.Option(None, "--emit", metavar="LANG", help="glsl | hlsl | c | python."),
    output: str = typer.Option(None, "--output", "-o", metavar="FILE", help="Write the emitted code here."),
    plot: str = typer.Option(None, "--plot", metavar="FILE.png", help="Plot α, the fit and its error."),
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object."),
    verbose: bool = typer.Option(False, "--verbose", "-v", help="Also print the forms --form auto tried."),
    allow_poor_fit: bool = typer.Option(False, "--allow-poor-fit",
                                        help="With --lut: write the code even when the fit's relative error "
                                             "exceeds 100 % (refused otherwise: the table is then rarely the "
                                             "one meant)."),
    anisotropic_fix: bool = typer.Option(False, "--anisotropic-fix", help="ggx, beckmann: fit the effective "
                                         "roughness alpha_eff(mu, alpha_x, alpha_y) at which an isotropic E table "
                                         "gives the anisotropic lobe's albedo averaged over the view azimuth "
                                         "(instead of sqrt(alpha_x alpha_y)); its max error in E over the domain "
                                         "is printed and in the code (docs/anisotropy.md)."),
    spread: Spread = None,
    debug: bool = DEBUG_OPTION,
) -> None:
    """Fit a cheap formula (the fewest coefficients for --target with --form auto) to the normalization factor."""
    with guarded(debug):
        if emit_language is not None:
            LANGUAGES.validate(emit_language)
        if output == STDOUT and json_output:
            raise ArgumentError("--json prints to stdout: '-o -' would put the code before it", where="--output")
        if output is not None and emit_language is None:
            raise ArgumentError("-o/--output writes the emitted code: give --emit LANG too", where="--output")
        if anisotropic_fix:
            _fit_anisotropic(model, param, emit_language, output, json_output)
            return
        if lut is not None:
            if model is not None or sweep is not None or at is not At.normal or theta is not None:
                raise ArgumentError("--lut fits a table file: give no MODEL, --sweep, --at or --theta", where="--lut")
            _fit_lut(lut, lut_table, form, (metric or Metric.minimax_abs).value, 5e-3 if target is None else target,
                     max_coefficients or 16, emit_language, output, json_output, allow_poor_fit)
            return
        if model is None or sweep is None:
            raise ArgumentError("give MODEL and --sweep NAME=SPEC (or --lut FILE)", where="--sweep")
        target = 1e-3 if target is None else target
        metric = metric or Metric.minimax_rel
        if at is At.view and theta is None:
            raise ArgumentError("--at view fits over the view angle: give --theta SPEC", where="--theta")
        if at is not At.view and theta is not None:
            raise ArgumentError("--theta applies only with --at view", where="--theta")
        if max_coefficients is not None and max_coefficients < 2:
            raise ArgumentError(f"need at least 2, got {max_coefficients}", where="--max-coefficients")
        if plot is not None and not plot.lower().endswith(".png"):
            raise ArgumentError(f"the plot is a PNG file: {plot!r}", where="--plot")
        if form.strip() not in ("auto", "closed-form"):
            parse_form(form, two_d=at is At.view)  # a bad --form is reported before any integration
        if output is not None and not Path(output).parent.is_dir():
            raise OutputError(f"directory {str(Path(output).parent)!r} does not exist", where=output)
        name, values = parse_sweep(sweep)
        degrees = parse_angles(theta) if theta is not None else None
        m = load_model(model, param)
        m.parameter(name)  # an unknown swept parameter is a one-line error before any integration
        exact = exact_form(m.name, name, at.value)
        if form.strip() == "closed-form" and exact is None:
            raise ArgumentError(f"{m.name} has no closed-form factor over {name} at {at.value}; closed forms: "
                                f"{', '.join(EXACT)} over n at normal", where="--form")
        if exact is not None and form.strip() in ("auto", "closed-form"):
            form = exact  # the exact formula: cheaper and more accurate than any fit
        job = sweep_job(m, at.value, name, values, None if degrees is None else np.radians(degrees), rtol=rtol,
                        chunk_cells=spread.chunk_cells)
        samples = compute_cells(job, f"{m.name}: sampling the factor over {name}", spread)
        result = normalization_result(job, at.value, name, samples)
        y = _factor_channel(result.factor)
        if not np.all(np.isfinite(y)) or np.any(y <= 0):
            raise EvaluationError("the normalization factor is not finite and positive at every sample "
                                  "(an albedo of 0?)", where="--sweep")
        x = result.values
        t = None
        if at is At.view:
            t = np.cos(result.theta)
            fitted = fit(np.broadcast_to(x[:, None], y.shape), y, t, form=form, metric=metric.value,
                         target=target, max_coefficients=max_coefficients, names=(name, SECOND_VARIABLE))
        else:
            fitted = fit(x, y[:, 0], form=form, metric=metric.value, target=target,
                         max_coefficients=max_coefficients, names=(name, SECOND_VARIABLE))
        code = emit(fitted, emit_language, m.name, variable=name,
                    context=fit_context(m, name, at.value, job.settings.over)) if emit_language else None
        if output is not None:
            write_file(output, code)
        if plot is not None:
            _plot(plot, fitted, x, t, y if t is not None else y[:, 0], name)
        if json_output:
            data = {"model": m.name, "at": at.value, "parameter": name, **fitted.to_dict()}
            if at is At.view:
                data["argmax"] = {**data["argmax"],
                                  "theta_deg": float(np.degrees(np.arccos(fitted.argmax[SECOND_VARIABLE])))}
            if code is not None:
                data["language"] = emit_language
                data["code"] = code
            write_file(STDOUT, to_json({"brdfnorm": __version__, **data}) + "\n")
            return
        if code is not None and output is None:
            write_file(STDOUT, code)  # the code alone on stdout, so `> f.glsl` compiles; the summary on stderr
        _summary(fitted, m.name, at.value, output, to_stderr=code is not None and output in (None, STDOUT),
                 verbose=verbose)


def _fit_anisotropic(model: str | None, param: list[str], emit_language: str | None, output: str | None,
                     json_output: bool) -> None:
    """``fit ggx|beckmann --anisotropic-fix``: :func:`brdfnorm.lut.anisotropy_fix.fit_alpha_fix`."""
    from ..lut.anisotropy import lobe_of
    from ..lut.anisotropy_fix import fit_alpha_fix

    if model is None:
        raise ArgumentError("give the lobe: ggx or beckmann", where="MODEL")
    if emit_language is not None and emit_language not in ("glsl", "hlsl", "c", "python"):
        raise ArgumentError(f"unknown language {emit_language!r} (known: glsl, hlsl, c, python)", where="--emit")
    if output is not None and output != STDOUT and not Path(output).parent.is_dir():
        raise OutputError(f"directory {str(Path(output).parent)!r} does not exist", where=output)
    distribution, shadowing = lobe_of(load_model(model, param))
    fix = fit_alpha_fix(distribution, shadowing)
    code = fix.emit(emit_language) if emit_language else None
    if output is not None:
        write_file(output, code)
    if json_output:
        data = {"model": distribution, "shadowing": shadowing, "degree": fix.degree,
                "coefficients": [float(c) for c in fix.coefficients], "domain": fix.domain,
                "max_error": fix.max_error, "geometric_mean_error": fix.geometric_mean_error, **fix.validation}
        if code is not None:
            data["language"], data["code"] = emit_language, code
        write_file(STDOUT, to_json(data) + "\n")
        return
    if code is not None and output is None:
        write_file(STDOUT, code)
    typer.echo(f"{distribution} alpha_eff: {fix.coefficients.size} coefficients, max |E_iso(alpha_eff) - E| "
               f"{fix.max_error:.2g} over the domain (the geometric mean: {fix.geometric_mean_error:.2g})"
               + ("" if output in (None, STDOUT) else f"; wrote {output}"), err=True)


#: ``fit --lut`` refuses a fit whose relative error exceeds this (unless --allow-poor-fit): a fit that far off
#: means the table is not the one meant (issue 31: the README's E.npz held another lobe's table).
POOR_FIT = 1.0


def _fit_lut(path: str, table: str, form: str, metric: str, target: float, max_coefficients: int,
             emit_language: str | None, output: str | None, json_output: bool, allow_poor_fit: bool = False) -> None:
    """``fit --lut``: a two-axis table fitted by :func:`brdfnorm.lut.fitting.fit_table`; the Pareto front on
    stderr, the code (or the expression) alone on stdout."""
    from ..lut import load
    from ..lut.fitting import fit_table

    if form.strip() != "auto":
        parse_form(form, two_d=True)
    if output not in (None, STDOUT) and not Path(output).parent.is_dir():
        raise OutputError(f"directory {str(Path(output).parent)!r} does not exist", where=output)
    data = load(path)
    result = fit_table(data, table=table, form=form, metric=metric, target=target,
                       max_coefficients=max_coefficients)
    best, (x, t) = result.best, result.variables
    source = str(data.meta.get("model", "table"))
    if best.max_rel_error > POOR_FIT and not allow_poor_fit:
        raise ArgumentError(f"the best fit ({best.form}) of table {table} of {source} is off by up to "
                            f"{100 * best.max_rel_error:.0f} % relative error; is this the table you meant? "
                            "(--allow-poor-fit writes it anyway)", where=path)
    code = (emit(best, emit_language, source, variable=x, second=t, quantity=f"Table {table}",
                 suffix=table) if emit_language else None)
    if output is not None:
        write_file(output, code)
    if json_output:
        # the table's candidates, not the chosen FitResult's own (empty) ``tried``, which used to overwrite them
        write_file(STDOUT, to_json({"brdfnorm": __version__, "lut": path, "table": table, "variables": [x, t],
                                    **best.to_dict(),
                                    "front": result.front, "tried": result.tried,
                                    **({"language": emit_language, "code": code} if code else {})}) + "\n")
        return
    err = console(stderr=True)
    front = Table(title=f"Pareto front: {escape(table)}({x}, {t}) of {escape(source)}")
    for column in ("coefficients", "form", "max abs. error", "max rel. error"):
        front.add_column(column)
    for entry in result.front:
        front.add_row(str(entry["coefficients"]), entry["form"], f"{entry['max_abs_error']:.3g}",
                      f"{entry['max_rel_error']:.3g}")
    err.print(front)
    err.print(f"chosen: {best.form} ({len(best.coefficients)} coefficients), max absolute error "
              f"{best.max_abs_error:.4g}, max relative error {best.max_rel_error:.4g}", highlight=False, markup=False)
    for warning in best.warnings:
        err.print(f"warning: {warning}", highlight=False, markup=False)
    if code is not None and output is None:
        write_file(STDOUT, code)
    elif code is None:
        write_file(STDOUT, best.expression + "\n")


def _summary(result: FitResult, model: str, at: str, output: str | None, *, to_stderr: bool,
             verbose: bool = False) -> None:
    out = console(stderr=to_stderr)
    how = "exact, seed 000" if result.form == "closed-form" else result.metric
    out.print(f"[bold]{escape(model)}[/bold] normalization factor at {at}: [bold]{result.form}[/bold] "
              f"({how}, {result.samples} samples)")
    out.print(f"  α ≈ {result.expression}", highlight=False, markup=False)
    where = ", ".join(f"{k} = {v:.6g}" for k, v in result.argmax.items())
    out.print(f"  max relative error {result.max_rel_error:.4g} at {where}; max absolute error "
              f"{result.max_abs_error:.4g}", markup=False)
    ops = ", ".join(f"{n} {c}" for n, c in result.operations.items() if c)
    out.print("  range: " + "; ".join(f"{k} ∈ [{lo:.6g}, {hi:.6g}]" for k, (lo, hi) in result.range.items())
              + f"; operations: {ops or 'none'}", markup=False)
    for warning in result.warnings:
        out.print(f"  [yellow]warning:[/yellow] {escape(warning)}")
    if result.tried and verbose:
        table = Table(title="forms tried (auto)")
        for column in ("form", "coefficients", "max rel. error", "pole/degenerate"):
            table.add_column(column)
        for entry in result.tried:
            table.add_row(entry["form"], str(entry["coefficients"]), f"{entry['max_rel_error']:.3g}",
                          "yes" if entry["pole"] else "")
        out.print(table)
    if output not in (None, STDOUT):
        console(stderr=True).print(f"code written to {output}", markup=False, highlight=False)

