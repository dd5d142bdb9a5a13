"""``brdfnorm report``: an HTML study of the seed lobes (or of given models), with figures.

With no models, the page studies the seed articles' lobes — phong, modified-phong, blinn-phong and
blinn-phong-gaussian: normalization factors against seed 000's closed forms, albedo curves with and without
normalization (seed 002), Blinn-Phong's α(n) against the folklore (n+8)/8π (seed 000), seed 003's linear fit
against refits (:mod:`brdfnorm.fit`), polar plots of the lobes, and the table of the seeds' claims checked by
:mod:`brdfnorm.claims.verify`. Given models (built-in names or ``.brdf`` files)
get the same study over one float parameter each.

The report is a directory: ``index.html`` and PNG figures beside it. It is built in a temporary sibling
directory and renamed into place only when complete (:mod:`brdfnorm.output.directories`), and it is
deterministic: the same inputs give byte-identical files.

>>> from brdfnorm.report import build_report, StudyConfig
>>> build_report("report", config=StudyConfig.quick())  # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from .. import __version__, load
from ..claims import published
from ..claims.verify import verify
from ..errors import ArgumentError
from ..fit import fit
from ..models.base import Model
from ..output.directories import check_target, staged
from ..parallel import warm
from . import microfacet, sections
from .html import page
from .study import SEED_LOBES, StudyConfig

__all__ = ["StudyConfig", "build_report", "plan"]

#: Called before each step with (description, index, total), within a long step with ("step: detail",
#: index + fraction done, total), and once more with ("done", total, total).
OnStep = Callable[[str, float, int], None]


def plan(models: Sequence[Model | str | tuple[str, Model]] = (), sweep: tuple[str, np.ndarray] | None = None,
         config: StudyConfig | None = None) -> tuple[StudyConfig, list[sections.Step], list[warm.Need]]:
    """The configuration, the steps of the page, and the models it computes albedos of, each with the method that
    integrates it ((method, model), :data:`brdfnorm.parallel.warm.Need`), in the order it first needs them (their
    kernels compile ahead, :mod:`brdfnorm.parallel.warm`)."""
    config = config or StudyConfig()
    if not models:
        if sweep is not None:
            name, values = sweep
            if name != "n":
                raise ArgumentError(f"the default study sweeps the exponent n, not {name!r}", where="sweep")
            if np.any(np.asarray(values) <= 0):
                raise ArgumentError("the default study needs exponents n > 0", where="sweep")
            config = dataclasses.replace(config, table_n=tuple(float(v) for v in values))
        lobes = [("quadrature", name, {}) for name in SEED_LOBES]
        steps: list[sections.Step] = [
            ("factors at L = N: closed form vs quadrature; search for the maximum", sections.factor_section),
            ("albedo curves E(θ_o)", sections.albedo_section),
            ("Blinn-Phong α(n) vs (n+8)/8π", sections.folklore_section),
        ]
        if config.extras:
            steps.append(("seed 003: fits of the Gaussian Blinn-Phong factor", sections.fit_section(fit)))
        steps.append(("polar plots of the lobes", sections.polar_section))
        if microfacet.available():
            steps.append(("microfacet energy: GGX's compensation tables", microfacet.section))
            lobes += microfacet.LOBES
        if config.extras:
            steps.append(("verifying the seeds' claims", sections.verify_section(verify)))
            lobes += [("quadrature", name, params) for name, params in published.LOBES]
        return config, steps, [(method, load(name, **params)) for method, name, params in lobes]
    steps, loaded = [], []
    for index, item in enumerate(models, start=1):
        if isinstance(item, tuple):
            label, model = item
        else:
            model, label = (item, item.name) if isinstance(item, Model) else (load(item), str(item))
        loaded.append(model)
        if sweep is not None:
            model.parameter(sweep[0])  # an unknown name fails now, before any work
        steps.append((f"{label}: factors, albedo curves, polar plots",
                      sections.model_section(model, label, sweep, index)))
    return config, steps, loaded


def build_report(out_dir: str | Path, models: Sequence[Model | str | tuple[str, Model]] = (), *,
                 sweep: tuple[str, np.ndarray] | None = None, config: StudyConfig | None = None,
                 on_step: OnStep | None = None, audit: Sequence[str | Path] = ()) -> Path:
    """Compute the study, write ``out_dir/index.html`` with its figures atomically; returns the index path.

    ``audit``: ``.brdf`` files or directories to audit with ``brdfnorm check`` (:mod:`.audit`), one row each.
    """
    check_target(out_dir)  # a bad -o fails before minutes of work
    config, steps, lobes = plan(models, sweep, config)
    if audit:
        from .audit import audit_section

        steps.append(("auditing the .brdf files (brdfnorm check)", audit_section(audit)))
    report = (lambda *args: None) if on_step is None else on_step
    with staged(out_dir, f"brdfnorm {__version__}\n") as stage, warm.ahead(lobes):
        ctx = sections.Context(config, stage)
        built = []
        for index, (description, step) in enumerate(steps):
            report(description, index, len(steps))
            ctx.tick = (lambda detail, fraction, description=description, index=index:
                        report(f"{description}: {detail}", index + min(max(fraction, 0.0), 0.99), len(steps)))
            built.append(step(ctx))
        report("done", len(steps), len(steps))
        title = ("brdfnorm: energy normalization of the seed lobes" if not models
                 else "brdfnorm: " + ", ".join(s.title for s in built))
        stage.write("index.html", page(title, _intro(models, config, ctx.findings), built, _footer()))
    return Path(out_dir) / "index.html"


def _intro(models, config: StudyConfig, findings: list[str]) -> str:
    what = ("the seed articles' lobes (Phong, modified Phong, Blinn-Phong and seed 003's Gaussian Blinn-Phong)"
            if not models else "the models given on the command line")
    parts = [
        f"<p>How much energy do analytic specular lobes reflect, and how good are the usual normalization "
        f"factors? This page studies {what}. The directional albedo is E = ∫ f(L,V)(N·L) dL over the upper "
        "hemisphere, computed by adaptive quadrature with error estimates; a normalization factor is 1/E for "
        "the direction held fixed (L = N unless stated otherwise). Angles in degrees.</p>",
        "<h2>Findings</h2>",
        '<ul class="findings">' + "".join(f"<li>{f}</li>" for f in findings) + "</ul>",
    ]
    if models:
        tolerances = (f"factors at L = N rtol {config.model_rtol:g}, maximum search {config.model_search_rtol:g} "
                      f"on {config.model_search_points} view angles then golden section")
    else:
        tolerances = f"factor tables rtol {config.table_rtol:g}, maximum search {config.search_rtol:g}"
    parts.append(f'<p class="note">Tolerances: {tolerances}, curves {config.plot_rtol:g}.</p>')
    return "\n".join(parts)


def _footer() -> str:
    return (f"Written by <code>brdfnorm report</code> (brdfnorm {__version__}). Table cells carry their "
            "full-precision values in <code>data-value</code> attributes. The same command writes "
            "byte-identical files.")
