"""``brdfnorm audit``: how wrong a shipped table or fitted formula is, in which convention; ``--fix`` writes the
exact replacement (:mod:`brdfnorm.audit`).

``brdfnorm audit ltc.js --model ggx --array g_ltc_2 --shape 64,64,4 --channel 0``
``brdfnorm audit dfg.js --model ggx --dtype float16 --shape 16,16,2 --fix -o dfg_fixed.js``
``brdfnorm audit --formula "0.806495*exp(-1.98712*r*r)+0.199531" --quantity E_avg --model ggx``

Exit status: 0 only when every cell of every audited channel is within the tolerance of the convention named; 1
otherwise (wrong cells, a channel whose meaning cannot be named, no convention fitting most cells); 2 for bad input.
"""

from __future__ import annotations

import json

import numpy as np
import typer

from ..errors import ArgumentError
from ..output import write_file
from .application import app
from .common import DEBUG_OPTION, PARAM_OPTION, backend_option, guarded, load_model


@app.command("audit")
@backend_option
def audit_command(
    file: str = typer.Argument(None, metavar="FILE", help="The table: .npz .exr .png .csv .json .h/.glsl/.hlsl/.js "
                               "array literals, or raw binary (.bin with --shape, --dtype)."),
    model: str = typer.Option("ggx", "--model", "-m", help="The lobe the table is of (a microfacet model)."),
    param: list[str] = PARAM_OPTION,
    array: str = typer.Option(None, "--array", help="Which array of a file with several."),
    shape: str = typer.Option(None, "--shape", help="Shape of a flat array, e.g. 64,64 or 64,64,4 (channels last)."),
    dtype: str = typer.Option(None, "--dtype", help="Storage type: float16 (half bit patterns in 16-bit integers), "
                              "float32, float64, uint8, uint16, ..."),
    channels_last: bool = typer.Option(None, "--channels/--no-channels", help="Whether the last axis holds "
                                       "channels (default: a last axis of at most 4 after larger ones does)."),
    order: str = typer.Option("C", "--order", help="C: last index fastest; F: first index fastest."),
    offset: int = typer.Option(0, "--offset", min=0, help="Raw binary: bytes to skip before the values."),
    byte_order: str = typer.Option("little", "--byte-order", help="Raw binary: little or big endian."),
    channel: str = typer.Option(None, "--channel", help="Audit one channel, by name or index."),
    scale: float = typer.Option(None, "--scale", help="Stored value = table value × SCALE (default: an integer "
                                "type's maximum, 1 for floats)."),
    fmt: str = typer.Option(None, "--format", help="Format when the extension does not say it (e.g. text, raw)."),
    pin: list[str] = typer.Option([], "--as", metavar="KEY=VALUE", help="\n\n".join([
        "Pin part of the convention (repeatable); KEY=VALUE is one of:",
        "axes=mu,alpha (the axes in array order)",
        "direction= mu-node, mu-texel, theta-node, theta-texel or ltc",
        "roughness= alpha-node, alpha-texel, r2-node or r2-texel",
        "flip= 0 or 1",
        "shadowing= height-correlated or separable (rough dielectrics also height-correlated/refraction= "
        "reflection-form or separable)",
        "mu_floor=1e-4, alpha_floor=1e-8",
        "channels=DFG_f0,DFG_f90, each a meaning: E, 1-E, DFG_f0, DFG_f90, E_f0, E_avg, 1-E_avg, E_dielectric, "
        "E_f0_dielectric, DFG_cloth, E_schlick, E_conductor, or F_avg (a Fresnel average over r,g, f0 or eta)",
        "eta=1.5 (of E_dielectric), schlick_f0=0.04 (of E_schlick)",
        "eta=0.2 and k=3.9 (a conductor's eta + ik, of E_conductor)"])),
    axis: list[str] = typer.Option([], "--axis", metavar="NAME=SPEC", help="Give an axis's values outright, as in "
                                   "lut: mu, theta (degrees), alpha, r (alpha = r^2) or f0 = START:STOP:n=COUNT "
                                   "(spaced by --grid) or V,V,... in array order."),
    grid: str = typer.Option("node", "--grid", help="node or texel: how --axis START:STOP:n=COUNT is spaced."),
    tolerance: float = typer.Option(None, "--tolerance", metavar="TOL", help="Absolute tolerance a cell must be "
                                    "within (default: from the storage precision, the reference's error and the "
                                    "table's noise; printed)."),
    json_out: bool = typer.Option(False, "--json", help="Machine-readable result on stdout."),
    report: str = typer.Option(None, "--report", metavar="DIR", help="Write error maps and plots (PNG) there."),
    fix: bool = typer.Option(False, "--fix", help="Write the exact table in the input's format and layout (-o)."),
    output: str = typer.Option(None, "--output", "-o", metavar="FILE", help="Where --fix writes."),
    no_dense: bool = typer.Option(False, "--no-interpolation", help="Skip the interpolation error."),
    no_sweep: bool = typer.Option(False, "--no-sweep", help="Skip the error against resolution."),
    formula: str = typer.Option(None, "--formula", help="A fitted formula: an expression in mu, r, alpha, theta, "
                                "or a .glsl file with --function."),
    function: str = typer.Option(None, "--function", help="The GLSL function of --formula FILE.glsl."),
    args: str = typer.Option(None, "--args", help="GLSL arguments: NAME=mu|r|alpha|theta|NUMBER, comma-separated."),
    quantity: str = typer.Option(None, "--quantity", help="What the formula approximates, one per component: E, "
                                 "1-E, DFG_f0, DFG_f90, E_avg (default E, or E_avg without mu)."),
    debug: bool = DEBUG_OPTION,
) -> None:
    """Audit a table or a fitted formula against exact values; name its convention; optionally fix it."""
    with guarded(debug, names={"model": "--model"}):
        m = load_model(model, param)
        if report is not None:  # before the work: a directory that cannot be written is refused now
            from ..output.directories import check_target

            check_target(report, "--report")
        if formula is not None:
            _formula(m, formula, function, args, quantity, json_out, report)
            return
        if file is None:
            raise ArgumentError("give a table FILE or --formula", where="audit")
        if fix and not output:
            raise ArgumentError("--fix needs -o FILE", where="--fix")
        from ..audit import audit
        from ..audit.readers import parse_shape

        if byte_order not in ("little", "big"):
            raise ArgumentError(f"{byte_order[:20]!r}: little or big", where="--byte-order")
        read = {"fmt": fmt, "array": array, "shape": parse_shape(shape), "dtype": dtype, "order": order,
                "scale": scale, "channels": channels_last, "offset": offset, "byteorder": byte_order}
        pins = dict(p.partition("=")[::2] for p in pin)
        if "shadowing" in m.params and any(p.partition("=")[0].strip() == "shadowing" for p in param):
            pins.setdefault("shadowing", str(m.params["shadowing"]))  # -p shadowing=... pins it
        axes = {}
        for spec in axis:
            from .lut import parse_axis

            name, values = parse_axis(spec, grid)
            axes[name] = np.radians(values) if name == "theta" else values
        if tolerance is not None and not (np.isfinite(tolerance) and tolerance > 0):
            raise ArgumentError("must be a positive number", where="--tolerance")
        result = audit(file, m, channel=channel, dense=not no_dense, sweep=not no_sweep, fix=fix, read=read,
                       axes=axes, pins=pins, tolerance=tolerance)
        payload = result.to_json()
        if report is not None:
            from ..audit.report import figures

            payload["figures"] = figures(result, report)
        refused = None
        if fix:
            if result.unnamed or result.fixed is None:  # never a half-fixed file
                refused = (f"--fix: nothing written: the meaning of channel{'s' if len(result.unnamed) > 1 else ''} "
                           f"{', '.join(result.unnamed)} cannot be named (pin it with --as channels=..., '-' "
                           "keeps a channel as read)" if result.unnamed else
                           f"--fix: nothing written: channel {', '.join(result.unfixable)} has more wrong cells "
                           "than an audit computes exactly (their exact values were interpolated)")
            else:
                from ..audit.fix import write

                write_file(output, write(result.source, result.fixed, output, result.fix_meta()))
                payload["fixed"] = output
        if json_out:
            typer.echo(json.dumps(payload, default=float))
        else:
            from ..audit.report import text

            typer.echo(text(payload))
            if fix and refused is None:
                changed = sum(info["count"] for info in result.wrong_cells.values())
                typer.echo(f"wrote {output} ({changed} cell{'s' if changed != 1 else ''} replaced)", err=True)
        if refused is not None:
            typer.echo(f"error: {refused}", err=True)
        if not result.passes or refused is not None:
            raise typer.Exit(1)


def _formula(m, formula: str, function: str | None, args: str | None, quantity: str | None, json_out: bool,
             report: str | None) -> None:
    from ..audit.formula import ARGUMENTS, audit_formula, compile_expression, compile_glsl, parse_args
    from ..audit.reference import Reference

    if function is not None:
        bindings = parse_args(args)
        evaluate = compile_glsl(formula, function, bindings)
        uses = {v for v in bindings.values() if isinstance(v, str)}
    else:
        if args is not None:
            raise ArgumentError("--args binds a GLSL function's arguments; an expression uses mu, r, alpha, theta "
                                "directly", where="--args")
        evaluate = compile_expression(formula, ARGUMENTS)
        import ast

        uses = {n.id for n in ast.walk(ast.parse(formula.strip(), mode="eval")) if isinstance(n, ast.Name)}
    quantities = [q.strip() for q in quantity.split(",")] if quantity else (
        ["E"] if uses & {"mu", "theta"} else ["E_avg"])
    arrays: dict = {}
    rows = audit_formula(evaluate, uses, quantities, Reference(m),
                         shadowing=str(m.params.get("shadowing", "height-correlated")), arrays=arrays)
    figures = []
    if report is not None:
        from ..audit.report import formula_figures

        figures = formula_figures(arrays, report)
    if json_out:
        typer.echo(json.dumps({"formula": formula, "function": function, "model": m.name, "results": rows,
                               "figures": figures}))
        return
    for row in rows:
        at = ", ".join(f"{k}={v:.4g}" for k, v in row["at"].items())
        typer.echo(f"{row['quantity']}: max error {row['max']:.3g} at {at}; RMS {row['rms']:.3g} over "
                   f"{row['points']} points (reference error ≤ {row['reference_error']:.1g})")
