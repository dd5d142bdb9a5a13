"""``brdfnorm lut``: energy-compensation tables over a grid (:mod:`brdfnorm.lut`), written in an engine's format.

``brdfnorm lut ggx --axis mu=0:1:32 --axis alpha=0:1:32 --clamp mu=1e-4 --clamp alpha=1e-8 -o E.npz``
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import typer

from .. import validate
from ..errors import ArgumentError, OutputError
from ..extras import require
from ..lut import formats
from ..lut.axes import DIRECTION_AXES, VIEW_AZIMUTH_AXIS, axis_parameter
from ..lut.table import GRIDS, Lut, compute, grid_values
from ..output import write_file
from ..output.formats import format_error
from ..validate import DEFAULT_RTOL
from .application import app
from .common import (
    DEBUG_OPTION,
    PARAM_OPTION,
    Spread,
    backend_option,
    guarded,
    load_model,
    parallel_options,
    parse_range,
    progress_bar,
)

AXIS_HELP = ("An axis NAME=SPEC (repeatable; the tables are indexed in this order): mu (cos θ_o), theta "
             "(degrees) or a float parameter; SPEC is START:STOP:n=COUNT (spaced by --grid), "
             "START:STOP:step=STEP or V,V,...")


def parse_axis(spec: str, grid: str) -> tuple[str, np.ndarray]:
    """``NAME=START:STOP:n=COUNT`` (node or texel grid) or ``NAME=V,V,...`` (as given)."""
    name, sep, values = spec.partition("=")
    name = name.strip()
    if not sep or not name:
        raise ArgumentError(f"expected NAME=SPEC, got {spec!r}", where="--axis")
    parsed = parse_range(values, f"--axis {name}", allow_log=False)
    if ":" in values:
        parsed = grid_values(parsed[0], parsed[-1], parsed.size, grid)
    return name, parsed


def parse_clamp(spec: str) -> tuple[str, float]:
    name, sep, value = spec.partition("=")
    if not sep or not name.strip():
        raise ArgumentError(f"expected NAME=MIN, got {spec!r}", where="--clamp")
    (minimum,) = parse_range(value, f"--clamp {name.strip()}", allow_log=False)[:1]
    return name.strip(), float(minimum)


def missed_cells(result: Lut, shown: int = 8) -> str:
    """The cells that missed their tolerance (``meta["converged_mask"]``), named by their axis values: the first
    ``shown`` of them, and how many more."""
    names = []
    for table, mask in result.meta.get("converged_mask", {}).items():
        axes = result.table_axes[table]
        for index in np.argwhere(~np.asarray(mask, dtype=bool)):
            where = ", ".join(f"{a}={float(result.axes[a][i]):.6g}" for a, i in zip(axes, index, strict=True))
            names.append(where if table == "E" else f"{table} at {where}" if where else table)
    more = f" and {len(names) - shown} more" if len(names) > shown else ""
    return "; ".join(names[:shown]) + more


def stage_lines(name: str, axes: dict, channels: list[str], average: bool):
    """Where stderr is not a terminal: a progress callback that writes one line per finished stage (E, E_avg and
    the DFG channels), with its time."""
    cells = int(np.prod([len(v) for v in axes.values()]))
    others = [len(v) for a, v in axes.items() if a not in DIRECTION_AXES]
    stages = [("E", cells)] + ([("E_avg", int(np.prod(others)))] if average else [])
    stages += [(f"DFG_{c}", cells) for c in ("f0", "f90", "cloth")] if "dfg" in channels else []
    ends = np.cumsum([size for _, size in stages])
    state = {"stage": 0, "start": time.perf_counter(), "from": 0}

    def on_progress(done: int, total: int) -> None:
        while state["stage"] < len(stages) and done >= ends[state["stage"]]:
            label, size = stages[state["stage"]]
            now = time.perf_counter()
            typer.echo(f"{name}: {label}: {size} {'values' if label == 'E_avg' else 'cells'} in "
                       f"{now - state['start']:.2f} s", err=True)
            state.update(stage=state["stage"] + 1, start=now)

    return on_progress


def in_degrees(result: Lut, degrees: np.ndarray, clamp: float | None) -> Lut:
    """The lut with its θ axis (and θ clamp) in degrees as the command line gave them; ``meta["units"]`` says so."""
    meta = dict(result.meta)
    meta["units"] = {**meta.get("units", {}), "theta": "degrees"}
    if clamp is not None:
        meta["clamp"] = {**meta["clamp"], "theta": clamp}
    axes = {name: degrees if name == "theta" else values for name, values in result.axes.items()}
    return Lut(dict(result), axes, meta, result.table_axes)


@app.command("lut")
@backend_option
@parallel_options(chunk_cells=False)
def lut_command(
    model: str = typer.Argument(..., metavar="MODEL", help="A built-in model name, a .brdf file, "
                                "mitsuba:PLUGIN or a Mitsuba .xml file."),
    param: list[str] = PARAM_OPTION,
    axis: list[str] = typer.Option(..., "--axis", metavar="NAME=SPEC", help=AXIS_HELP),
    grid: str = typer.Option("node", "--grid", help="node: START + i/(N−1)·(STOP − START) (default); texel: "
                             "START + (i + ½)/N·(STOP − START), where a GPU samples an N-texel texture."),
    clamp: list[str] = typer.Option([], "--clamp", metavar="NAME=MIN", help="Evaluate an axis at max(value, MIN) "
                                    "(repeatable), e.g. --clamp mu=1e-4 --clamp alpha=1e-8; the file keeps the "
                                    "grid's values and records the clamps."),
    channels: list[str] = typer.Option([], "--channels", help="dfg: add the split-sum pair DFG_f0 = ∫ f cos "
                                       "(1 − (1 − V·H)⁵), DFG_f90 = ∫ f cos (1 − V·H)⁵, Fresnel off."),
    table: list[str] = typer.Option([], "--tables", "--table", metavar="NAMES", help="Write only these tables "
                                    "(comma list, repeatable). Default: all in .npz, .json, .csv; the values (E, "
                                    "E_avg, DFG_*) in images and headers."),
    layout: str = typer.Option(None, "--layout", metavar="SPEC", help="x=AXIS, y=AXIS, v=down|up: the axes along "
                               "an image's columns and rows; row 0 holds the first y (down) or the last (up). "
                               "Default: x = mu or theta, y = roughness or alpha, v=down in images and headers; "
                               "'axes' (the --axis order) in .npz, .json, .csv."),
    channel_names: str = typer.Option("rgba", "--channel-names", metavar="NAMING", help="rgba: image channels R, "
                                      "G, B, A in the order of the tables (mapping in the metadata); brdfnorm: "
                                      "the table names (.exr)."),
    broadcast_average: bool = typer.Option(False, "--broadcast-average", help="Repeat E_avg along μ in the "
                                           "grid's image (.exr, .png), not as its own one-row image."),
    prefix: str = typer.Option("lut_", "--prefix", help="Start of every identifier in .h, .glsl, .hlsl."),
    no_average: bool = typer.Option(False, "--no-average", help="Skip E_avg = 2∫ E(μ) μ dμ."),
    rtol: float = typer.Option(None, "--rtol", help="Relative tolerance of every cell (and of E_avg); default 1e-10 "
                               "(1e-6 with --anisotropy)."),
    method: str = typer.Option("auto", "--method", help="Albedo method (auto picks the model's best)."),
    digits: int = typer.Option(None, "--digits", min=1, help="With --method certified: every cell's enclosure has a "
                               "relative radius ≤ 10^-DIGITS (default 12)."),
    allow_unconverged: bool = typer.Option(False, "--allow-unconverged",
                                           help="Exit 0, not 3, if some cells miss --rtol (written either way)."),
    strict: bool = typer.Option(False, "--strict", help="Write nothing (exit 1) if any cell misses --rtol."),
    output: str = typer.Option(..., "--output", "-o", metavar="FILE",
                               help=f"The table file; the extension picks the format (.{', .'.join(formats.FORMATS)})"
                                    "; - writes a text format to stdout (with --format)."),
    fmt: str = typer.Option(None, "--format", help="Format when it is not the extension's (needed for -o -)."),
    anisotropy: str = typer.Option(None, "--anisotropy", metavar="PARAMETERIZATION", help="ggx, beckmann: an "
                                   "anisotropy axis (--axis anisotropy=0:1:16) mapped to (alpha_x, alpha_y) as aspect, "
                                   "burley, materialx or openpbr do; E averaged over the view azimuth unless --axis "
                                   "phi_v=DEGREES (docs/anisotropy.md)."),
    half: bool = typer.Option(False, "--half", help="float16 channels in .exr."),
    spread: Spread = None,
    debug: bool = DEBUG_OPTION,
) -> None:
    """Energy-compensation tables: E, its error, E_avg and 1 − E (and DFG) over the axes, one file."""
    with guarded(debug):
        if grid not in GRIDS:
            raise ArgumentError(f"unknown grid {grid!r} (known: {', '.join(GRIDS)})", where="--grid")
        to_stdout = output == "-"
        if to_stdout and fmt is None:
            raise ArgumentError("-o - writes to stdout: give --format (json, csv, h, glsl or hlsl)", where="--format")
        name = formats.format_of(output if not to_stdout else "", fmt, where="--format" if fmt else "--output")
        if to_stdout and name not in formats.TEXT_FORMATS:
            raise ArgumentError(f"{name} is binary; stdout takes {', '.join(formats.TEXT_FORMATS)}", where="--format")
        if half and name != "exr":
            raise ArgumentError("--half applies to .exr only", where="--half")
        if name == "exr":  # the optional extra the writer needs: one line before the work, not after it
            require("OpenEXR", "exr", where=".exr format")
        axes: dict[str, np.ndarray] = {}
        for spec in axis:
            axis_name, values = parse_axis(spec, grid)
            if axis_name in axes:
                raise ArgumentError(f"axis {axis_name} given twice", where="--axis")
            axes[axis_name] = values
        validate.batch_size(tuple(len(v) for v in axes.values()), where="--axis")  # before any grid is built
        if spread.checkpoint is not None:  # DIR holds one checkpoint per table, and nothing else
            from ..parallel.checkpoint import check_root

            check_root(spread.checkpoint)
        if anisotropy is None and VIEW_AZIMUTH_AXIS in axes:
            raise ArgumentError("a phi_v axis needs --anisotropy", where="--axis phi_v")
        azimuth_degrees = axes.get(VIEW_AZIMUTH_AXIS)
        if azimuth_degrees is not None:
            axes[VIEW_AZIMUTH_AXIS] = np.radians(azimuth_degrees)
        if "theta" in axes:
            if np.any(axes["theta"] < 0) or np.any(axes["theta"] >= 90):
                raise ArgumentError("theta must lie in [0°, 90°)", where="--axis theta")
            degrees = axes["theta"]
            axes["theta"] = np.radians(degrees)
        clamps = dict(parse_clamp(c) for c in clamp)
        clamp_degrees = clamps.get("theta")
        if "theta" in clamps:
            clamps["theta"] = float(np.radians(clamps["theta"]))
        for c in channels:
            if c not in ("dfg",):
                raise ArgumentError(f"unknown channel set {c!r} (known: dfg)", where="--channels")
        m = load_model(model, param)
        # (the anisotropic and certified routes imported only where asked: 0.1–0.2 s of a table's start)
        if anisotropy is not None:
            from ..lut import anisotropy as anisotropic_tables

            if method != "auto" or digits is not None:
                raise ArgumentError("anisotropic tables are computed by their own route (no --method, --digits)",
                                    where="--anisotropy")
            anisotropic_tables.lobe_of(m)
            anisotropic_tables.PARAMETERIZATIONS.validate(anisotropy)
        for axis_name in axes if anisotropy is None else ():
            if axis_name not in DIRECTION_AXES:
                m.parameter(axis_parameter(m, axis_name, np.array([0.5]))[0])  # unknown: one line, before any work
        if not to_stdout and not Path(output).parent.is_dir():  # fail before the work, not after it
            raise OutputError(f"directory {str(Path(output).parent)!r} does not exist", where=output)
        table_names = formats.layouts.split_tables(table)
        spec = formats.layouts.parse(layout)
        for key in ("x", "y"):  # an axis the layout names must be one of the table's: fail before the work
            if spec and spec.get(key) is not None and spec[key] not in axes:
                raise ArgumentError(f"{key}={spec[key]}: no axis of that name (axes: {', '.join(axes)})",
                                    where="--layout")
        if digits is not None and method != "certified":
            raise ArgumentError("--digits applies to --method certified only", where="--digits")
        if rtol is None:
            rtol = DEFAULT_RTOL if anisotropy is None else 1e-6
        with progress_bar(f"{m.name}: table cells") as bar:
            progress = bar or stage_lines(m.name, axes, channels, not no_average)
            if anisotropy is not None:
                result = anisotropic_tables.compute(m, axes, anisotropy=anisotropy, clamp=clamps, rtol=rtol,
                                                    average=not no_average, grid=grid, source=model,
                                                    workers=spread.workers, scheduler=spread.dask_scheduler(),
                                                    channels=channels, checkpoint=spread.checkpoint)
            elif method == "certified":
                from ..lut import certified as certified_tables

                if spread.given():
                    raise ArgumentError("certified tables are computed in this process", where="--workers")
                result = certified_tables.compute(m, axes, clamp=clamps, digits=12 if digits is None else digits,
                                                  average=not no_average, grid=grid, source=model,
                                                  progress=progress)
            else:
                result = compute(m, axes, clamp=clamps, rtol=rtol, method=method, channels=channels,
                                 average=not no_average, grid=grid, source=model, progress=progress,
                                 workers=spread.workers, scheduler=spread.dask_scheduler(),
                                 checkpoint=spread.checkpoint)
        if "theta" in axes:  # the file's θ axis in the degrees it was given in (the API's is in radians)
            result = in_degrees(result, degrees, clamp_degrees)
        if azimuth_degrees is not None:
            result = Lut(dict(result), {n: azimuth_degrees if n == VIEW_AZIMUTH_AXIS else v
                                        for n, v in result.axes.items()},
                         {**result.meta, "units": {**result.meta["units"],
                                                   VIEW_AZIMUTH_AXIS: "degrees"}},
                         result.table_axes)
        data = formats.dumps(result, name, tables=table_names, half=half, layout=spec, prefix=prefix,
                             channel_names=channel_names, broadcast_average=broadcast_average)
        unconverged = result.meta["unconverged"]
        goal = f"--digits {result.meta['certified']['digits']}" if method == "certified" else f"--rtol {rtol:g}"
        if unconverged and strict:
            typer.echo(f"error: {unconverged} cells did not reach {goal}; nothing written (--strict)", err=True)
            raise typer.Exit(1)
        write_file(output, data)
        cells = int(np.prod([len(v) for v in axes.values()]))
        worst = float(np.max(result["E_error"])) if result["E_error"].size else 0.0
        typer.echo(f"{m.name}: {cells} cells, max error estimate {format_error(worst, 3)}, {unconverged} unconverged"
                   + ("" if to_stdout else f"; wrote {output}"), err=True)
        if unconverged:
            typer.echo(f"warning: {unconverged} cells did not reach {goal}, written with their error estimates "
                       f"(meta converged_mask): {missed_cells(result)}", err=True)
            if not allow_unconverged:
                raise typer.Exit(3)
