"""The core commands: ``models``, ``albedo`` and ``normalize``."""

from __future__ import annotations

from enum import Enum

import numpy as np
import typer
from rich.table import Table

from ..engine.methods import METHODS
from ..errors import ArgumentError
from ..models import REGISTRY, Model
from ..normalization import normalize as compute_normalize
from ..parallel import CellsJob
from ..parallel.results import albedo_result, normalization_result, sweep_job
from ..validate import DEFAULT_RTOL
from .application import app
from .common import (
    DEBUG_OPTION,
    PARAM_OPTION,
    At,
    Over,
    ResultOutput,
    Spread,
    backend_option,
    compute_cells,
    console,
    guarded,
    load_model,
    parallel_options,
    parse_angles,
    parse_azimuth,
    parse_sweep,
    result_options,
)


class NonFinite(str, Enum):
    raise_ = "raise"
    zero = "zero"


MODEL_ARGUMENT = typer.Argument(..., metavar="MODEL", help="A built-in model name (see `brdfnorm models`), a "
                                "path to a BRDF Explorer .brdf file, mitsuba:PLUGIN or a Mitsuba .xml file.")
METHOD_OPTION = typer.Option("auto", "--method",
                             help=" | ".join(("auto", *METHODS)) + " (where it applies; auto takes the first that "
                                  "does, never certified; azimuthal: isotropic ggx and beckmann without Fresnel, "
                                  "a 1-D integral; microfacet: ggx and beckmann over the half vector).")
RTOL_OPTION = typer.Option(DEFAULT_RTOL, "--rtol",
                           help="Relative tolerance of each albedo integral (at least 1e-14, below 1).")
OVER_OPTION = typer.Option(Over.light, "--over", help="Integrate over the light (view fixed, default) or the view.")


@app.command()
def models(debug: bool = DEBUG_OPTION) -> None:
    """List the built-in lobes with their formulas, parameters and known closed forms."""
    with guarded(debug):
        table = Table(title="built-in models")
        for column in ("name", "formula", "parameters", "closed form", "energy"):
            table.add_column(column)
        for name, cls in REGISTRY.items():
            declared = [p.declaration() for p in cls.parameters]  # the one declaration info and explore read
            params = ", ".join(f"{d['name']}={d['default_text']} {d['kind']} {d['range']}" for d in declared)
            has_closed = cls.closed_form_domain if cls.closed_form_albedo is not Model.closed_form_albedo else "—"
            table.add_row(name, cls.formula, params, has_closed, cls.energy or "—")
        console().print(table)


@app.command()
@backend_option
@parallel_options
@result_options
def albedo(
    model: str = MODEL_ARGUMENT,
    param: list[str] = PARAM_OPTION,
    theta: str = typer.Option("0:80:n=5", "--theta", metavar="SPEC",
                              help="Polar angle(s) in degrees: DEG, DEG,DEG,..., START:STOP:n=COUNT or "
                                   "START:STOP:step=STEP (inclusive; START:STOP:COUNT is n=COUNT)."),
    phi: float = typer.Option(0.0, "--phi", help="Azimuth in degrees."),
    over: Over = OVER_OPTION,
    method: str = METHOD_OPTION,
    rtol: float = RTOL_OPTION,
    nonfinite: NonFinite = typer.Option(NonFinite.raise_, "--nonfinite",
                                        help="raise: fail at the first NaN/Inf; zero: count them as 0 (warns)."),
    digits: int = typer.Option(None, "--digits", min=1,
                               help="With --method certified: significant digits of the enclosure (default 30)."),
    result: ResultOutput = None,
    spread: Spread = None,
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
        job = CellsJob.of(m, np.radians(degrees), np.radians(azimuth), over=over.value, rtol=rtol, method=method,
                          nonfinite=nonfinite.value, digits=digits, chunk_cells=spread.chunk_cells)
        cells = compute_cells(job, f"{m.name}: albedo", spread)
        result.write(albedo_result(job, cells).records())


@app.command("normalize")
@backend_option
@parallel_options
@result_options
def normalize_command(
    model: str = MODEL_ARGUMENT,
    param: list[str] = PARAM_OPTION,
    sweep: str = typer.Option(None, "--sweep", metavar="NAME=SPEC",
                              help="Sweep a parameter: V,V,..., START:STOP:n=COUNT (add :log for log "
                                   "spacing) or START:STOP:step=STEP."),
    at: At = typer.Option(At.normal, "--at", help="normal (fixed direction N), max (over all directions) or "
                          "view (per direction, see --theta)."),
    theta: str = typer.Option("0:80:n=9", "--theta", metavar="SPEC", help="Polar angles in degrees for --at view."),
    phi: float = typer.Option(0.0, "--phi", help="Azimuth in degrees for --at view."),
    over: Over = OVER_OPTION,
    method: str = METHOD_OPTION,
    rtol: float = RTOL_OPTION,
    result: ResultOutput = None,
    spread: Spread = None,
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
        kwargs = dict(theta=None if degrees is None else np.radians(degrees), phi=np.radians(azimuth),
                      over=over.value, rtol=rtol, method=method)
        if name is None:
            if spread.given():
                raise ArgumentError("--workers, --scheduler, --checkpoint and --chunk-cells spread a --sweep's "
                                    "cells; there is no sweep", where="--sweep")
            factors = compute_normalize(m, at=at.value, **kwargs)
        else:
            job = sweep_job(m, at.value, name, values, **kwargs, chunk_cells=spread.chunk_cells)
            cells = compute_cells(job, f"{m.name}: sweeping {name}", spread)
            factors = normalization_result(job, at.value, name, cells)
        result.write(factors.records())
