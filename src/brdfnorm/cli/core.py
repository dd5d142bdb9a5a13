"""The core commands: ``models``, ``albedo`` and ``normalize``."""

from __future__ import annotations

import csv
import io
from enum import Enum

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from ..albedo import albedo as compute_albedo
from ..models import REGISTRY, Model
from ..normalize import NormalizationResult
from ..normalize import normalize as compute_normalize
from . import app
from .common import (
    DEBUG_OPTION,
    PARAM_OPTION,
    At,
    Over,
    channel_value,
    console,
    guarded,
    load_model,
    parse_angles,
    parse_azimuth,
    parse_sweep,
    print_json,
    stdout_is_terminal,
    to_json,
    write_output_atomically,
)


class NonFinite(str, Enum):
    raise_ = "raise"
    zero = "zero"


MODEL_ARGUMENT = typer.Argument(..., metavar="MODEL", help="A built-in model name (see `brdfnorm models`) or a "
                                "path to a BRDF Explorer .brdf file.")
METHOD_OPTION = typer.Option("auto", "--method",
                             help="auto | quadrature | closed-form | series | certified (where it applies).")
RTOL_OPTION = typer.Option(1e-10, "--rtol", help="Relative tolerance of each albedo integral (1e-14 … <1).")
OVER_OPTION = typer.Option(Over.light, "--over", help="Integrate over the light (view fixed, default) or the view.")


@app.command()
def models(debug: bool = DEBUG_OPTION) -> None:
    """List the built-in lobes with their formulas, parameters and known closed forms."""
    with guarded(debug):
        table = Table(title="built-in models")
        for column in ("name", "formula", "parameters", "closed form"):
            table.add_column(column)
        for name, cls in REGISTRY.items():
            params = ", ".join(f"{p.name}={p.default:g} {p.describe_range()}" for p in cls.parameters)
            has_closed = "normal incidence" if cls.closed_form_albedo is not Model.closed_form_albedo else "—"
            table.add_row(name, cls.formula, params, has_closed)
        console().print(table)


@app.command()
def albedo(
    model: str = MODEL_ARGUMENT,
    param: list[str] = PARAM_OPTION,
    theta: str = typer.Option("0:80:5", "--theta", metavar="SPEC",
                              help="Polar angle(s) in degrees: DEG, DEG,DEG,... or START:STOP:COUNT (inclusive)."),
    phi: float = typer.Option(0.0, "--phi", help="Azimuth in degrees."),
    over: Over = OVER_OPTION,
    method: str = METHOD_OPTION,
    rtol: float = RTOL_OPTION,
    nonfinite: NonFinite = typer.Option(NonFinite.raise_, "--nonfinite",
                                        help="raise: fail at the first NaN/Inf; zero: count them as 0 (warns)."),
    digits: int = typer.Option(None, "--digits", min=1,
                               help="With --method certified: significant digits of the enclosure (default 30)."),
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Directional albedo E = ∫ f(L,V)(N·L) dL at the given view angles (or over the view with --over view).

    With --method certified the albedo is a guaranteed enclosure [lower, upper] (Arb ball arithmetic), printed
    as decimals rounded outward; JSON carries them as strings so that no digit is lost to float parsing.
    """
    with guarded(debug):
        m = load_model(model, param)
        degrees = parse_angles(theta)
        azimuth = parse_azimuth(phi)
        result = compute_albedo(m, np.radians(degrees), np.radians(azimuth), over=over.value, rtol=rtol,
                                method=method, nonfinite=nonfinite.value, digits=digits)
        rows = [
            {"theta_deg": float(d), "phi_deg": azimuth, "albedo": channel_value(result.value[i]),
             "error_estimate": channel_value(result.error[i]), "method": result.method,
             "evaluations": int(result.evaluations[i]), "converged": bool(result.converged[i])}
            | ({} if result.lower is None else {"lower": _decimals(result.lower[i]),
                                                "upper": _decimals(result.upper[i])})
            for i, d in enumerate(degrees)
        ]
        if json_output:
            print_json({"model": m.name, "params": m.params, "over": over.value, "rtol": rtol, "results": rows})
            return
        table = Table(title=f"{m.name} albedo over the {over.value} ({_params_text(m.params)})")
        certified = result.lower is not None
        columns = ("θ (deg)", "φ (deg)", "albedo", "error estimate", "method", "evaluations")
        for column in columns + (("lower", "upper") if certified else ()):
            table.add_column(column, justify="right", overflow="fold")
        for row in rows:
            bounds = (" ".join(np.atleast_1d(row["lower"])), " ".join(np.atleast_1d(row["upper"]))) if certified else ()
            table.add_row(f"{row['theta_deg']:g}", f"{row['phi_deg']:g}", _num(row["albedo"]),
                          _num(row["error_estimate"], 3), row["method"] + ("" if row["converged"] else " (!)"),
                          str(row["evaluations"]), *bounds)
        console().print(table)


@app.command("normalize")
def normalize_command(
    model: str = MODEL_ARGUMENT,
    param: list[str] = PARAM_OPTION,
    sweep: str = typer.Option(None, "--sweep", metavar="NAME=SPEC",
                              help="Sweep a parameter: V,V,..., START:STOP:COUNT or START:STOP:COUNT:log."),
    at: At = typer.Option(At.normal, "--at", help="normal (fixed direction N), max (over all directions) or "
                          "view (per direction, see --theta)."),
    theta: str = typer.Option("0:80:9", "--theta", metavar="SPEC", help="Polar angles in degrees for --at view."),
    phi: float = typer.Option(0.0, "--phi", help="Azimuth in degrees for --at view."),
    over: Over = OVER_OPTION,
    method: str = METHOD_OPTION,
    rtol: float = RTOL_OPTION,
    json_output: bool = typer.Option(False, "--json", help="Print one JSON object."),
    csv_output: bool = typer.Option(False, "--csv", help="Print CSV."),
    output: str = typer.Option(None, "--output", "-o", help="Write the JSON/CSV/table to this file (atomically)."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Normalization factors 1/E under a convention, optionally swept over a parameter."""
    with guarded(debug):
        m = load_model(model, param)
        name, values = parse_sweep(sweep) if sweep else (None, None)
        if name is not None:
            m.parameter(name)  # unknown names fail before any work
        degrees = parse_angles(theta) if at == At.view else None
        azimuth = parse_azimuth(phi)
        show_progress = not (json_output or csv_output) and stdout_is_terminal()
        result = _normalize_with_progress(m, at.value, name, values, degrees, azimuth, over.value, rtol, method,
                                          show_progress)
        rows = _normalization_rows(m, result)
        if json_output:
            text = to_json({"model": m.name, "params": m.params, "at": at.value, "over": over.value, "rtol": rtol,
                            "results": rows})
        elif csv_output:
            text = _csv(rows)
        else:
            text = None
        if text is not None:
            if output:
                write_output_atomically(output, text + "\n")
            else:
                typer.echo(text)
            return
        table = Table(title=f"{m.name}: normalization factor 1/E at {at.value} (over the {over.value})")
        sweep_name = result.parameter
        columns = ([sweep_name] if sweep_name else []) + ["θ (deg)", "φ (deg)", "albedo", "error estimate",
                                                          "factor", "method"]
        for column in columns:
            table.add_column(column, justify="right")
        for row in rows:
            cells = ([f"{row['params'][sweep_name]:g}"] if sweep_name else []) + [
                f"{row['theta_deg']:.6g}", f"{row['phi_deg']:.6g}", _num(row["albedo"]),
                _num(row["error_estimate"], 3), _num(row["factor"]), row["method"]]
            table.add_row(*cells)
        if output:
            buffer = Console(file=io.StringIO(), width=160)
            buffer.print(table)
            write_output_atomically(output, buffer.file.getvalue())
        else:
            console().print(table)


def _normalize_with_progress(model, at, name, values, degrees, phi, over, rtol, method,
                             show_progress) -> NormalizationResult:
    theta = None if degrees is None else np.radians(degrees)
    kwargs = dict(at=at, theta=theta, phi=np.radians(phi), over=over, rtol=rtol, method=method)
    if name is None:
        return compute_normalize(model, **kwargs)
    if not show_progress or values.size < 8:
        return compute_normalize(model, sweep={name: values}, **kwargs)
    # On a terminal, long sweeps run in chunks so a progress bar can advance; each chunk is still one batch.
    chunks = np.array_split(values, min(values.size, 16))
    parts = []
    with Progress(TextColumn("{task.description}"), BarColumn(), TextColumn("{task.completed}/{task.total}"),
                  TimeElapsedColumn(), transient=True) as progress:
        task = progress.add_task(f"{model.name}: sweeping {name}", total=values.size)
        for chunk in chunks:
            parts.append(compute_normalize(model, sweep={name: chunk}, **kwargs))
            progress.advance(task, chunk.size)
    first = parts[0]
    return NormalizationResult(
        at=first.at, parameter=name, values=values,
        **{field: np.concatenate([getattr(p, field) for p in parts])
           for field in ("theta", "phi", "albedo", "error", "factor", "converged")},
        method=first.method, over=first.over,
    )


def _normalization_rows(model, result: NormalizationResult) -> list[dict]:
    rows = []
    S, T = result.theta.shape
    for s in range(S):
        params = dict(model.params)
        if result.parameter:
            params[result.parameter] = float(result.values[s])
        for t in range(T):
            rows.append({
                "params": params, "theta_deg": float(np.degrees(result.theta[s, t])),
                "phi_deg": float(np.degrees(result.phi[s, t])), "albedo": channel_value(result.albedo[s, t]),
                "error_estimate": channel_value(result.error[s, t]), "factor": channel_value(result.factor[s, t]),
                "method": result.method, "at": result.at, "converged": bool(result.converged[s, t]),
            })
    return rows


def _csv(rows: list[dict]) -> str:
    buffer = io.StringIO()
    param_names = list(rows[0]["params"]) if rows else []
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(param_names + ["theta_deg", "phi_deg", "albedo", "error_estimate", "factor", "method", "at"])
    for row in rows:
        values = [row["params"][n] for n in param_names]
        writer.writerow([_flat(v) for v in values] + [
            repr(row["theta_deg"]), repr(row["phi_deg"]), _flat(row["albedo"]), _flat(row["error_estimate"]),
            _flat(row["factor"]), row["method"], row["at"]])
    return buffer.getvalue().rstrip("\n")


def _decimals(values: np.ndarray):
    """Certified bounds (decimal strings): a string for single-channel models, a list for multi-channel ones."""
    return str(values[0]) if values.size == 1 else [str(v) for v in values]


def _flat(value) -> str:
    if isinstance(value, (list, tuple, np.ndarray)):
        return " ".join(repr(float(v)) for v in value)
    return repr(value) if isinstance(value, float) else str(value)


def _num(value, digits: int = 12) -> str:
    if isinstance(value, list):
        return ", ".join(f"{v:.{digits}g}" for v in value)
    return f"{value:.{digits}g}"


def _params_text(params: dict) -> str:
    return ", ".join(f"{k}={_flat(v) if not isinstance(v, float) else f'{v:g}'}" for k, v in params.items())
