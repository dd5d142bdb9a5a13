"""The sections of ``brdfnorm report``: each computes its numbers (:mod:`.study`), draws its figures
(:mod:`.figures`) into the staging directory and returns its HTML (:mod:`.html`) plus one-line findings for the
summary at the top of the page.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from html import escape

import numpy as np

from ..models import closed_forms
from ..output.directories import Stage
from ..output.formats import format_value
from . import figures, study
from .figures import Image
from .html import Cell, Section, figure, number, percent, relative, table, text

#: Quadrature against a closed form is flagged when the relative difference exceeds this many × rtol.
AGREEMENT = 10.0
#: The view angles (degrees) of the "energy kept" table, taken at the nearest point of the θ grid.
GRAZING = (60.0, 80.0, 85.0, 89.0)

FACTOR_FORMULA = {"phong": "(n+1)/2π", "modified-phong": "(n+2)/2π",
                  "blinn-phong": "(n+2)(n+4)/8π(2^(−n/2)+n)"}


@dataclass
class Context:
    """What every section shares: the configuration, the staging directory, and results passed along."""

    config: study.StudyConfig
    stage: Stage
    findings: list[str] = field(default_factory=list)
    results: dict = field(default_factory=dict)
    #: Progress within the running section (study.Tick); build_report points it at its on_step.
    tick: study.Tick = study.quiet_progress

    def image(self, image: Image) -> Image:
        self.stage.write(image.name, image.png)
        return image


Step = tuple[str, Callable[[Context], Section]]


# -- default study -----------------------------------------------------------------------------------------

def _certified_line(data) -> str:
    """The factor table's certification, in one sentence (or why there is none)."""
    cert = data.certified
    if cert is None:
        return ("Not certified: python-flint is not installed (pip install 'brdfnorm[certified]' adds guaranteed "
                "enclosures by Arb ball arithmetic).")
    worst = max(float(np.max(r)) for r in cert.radius.values())
    inside = all(bool(np.all(v)) for v in cert.closed_inside.values())
    covered = all(bool(np.all(v)) for v in cert.quadrature_covered.values())
    return (f"Certified to {cert.digits} digits: every albedo of this table lies in a guaranteed enclosure (Arb ball "
            f"arithmetic, brdfnorm's method 'certified') of relative radius ≤ {worst:.1e}; seed 000's closed forms "
            f"lie {'inside' if inside else 'OUTSIDE'} their enclosures, and the quadrature's error estimates "
            f"{'cover' if covered else 'DO NOT cover'} their distance to them.")


def factor_section(ctx: Context) -> Section:
    config = ctx.config
    data = study.factor_table(config, ctx.tick)
    ctx.results["factors"] = data
    tolerance = AGREEMENT * config.table_rtol
    top: list[Cell | str] = [Cell("n", rowspan=2)]
    sub: list[Cell | str] = []
    for lobe in study.SEED_LOBES:
        if lobe in data.closed:
            top.append(Cell(f"{lobe}: {FACTOR_FORMULA[lobe]}", colspan=3))
            sub += ["closed form", "quadrature", "relative difference"]
        else:
            top.append(Cell(lobe + " (no closed form)", colspan=2))
            sub += ["quadrature", "error estimate (relative)"]
    rows = []
    for s, n in enumerate(data.n):
        row: list[Cell | str] = [number(n, 6)]
        for lobe in study.SEED_LOBES:
            if lobe in data.closed:
                # 10 digits shown (the relative difference says how far they agree; data-value keeps all 17),
                # so that the 12 columns fit the page's 1240 px
                row += [number(data.closed[lobe][s], 10), number(data.quadrature[lobe][s], 10),
                        relative(data.relative_difference(lobe)[s], tolerance)]
            else:
                row += [number(data.quadrature[lobe][s], 10), relative(data.error[lobe][s])]
        rows.append(row)
    worst = max(float(np.max(np.abs(data.relative_difference(lobe)))) for lobe in data.closed)
    ctx.findings.append(
        f"Adaptive quadrature reproduces seed 000's closed-form factors to {worst:.1e} (largest relative "
        f"difference over {len(data.closed) * data.n.size} values, rtol {config.table_rtol:g}).")
    certified_line = _certified_line(data)

    # Seeds 000 and 003 assume (without proof) that the albedo is largest at normal incidence; it is searched.
    search_rows = []
    for lobe in study.SEED_LOBES:
        search_rows.append([text(lobe)] + [number(np.degrees(t), 4) for t in data.theta_max[lobe]])
    off_normal = [(lobe, n) for lobe in study.SEED_LOBES for n, t in zip(data.n, data.theta_max[lobe], strict=True)
                  if t > 0]
    if off_normal:
        where = ", ".join(f"{lobe} at n = {n:g}" for lobe, n in off_normal)
        verdict = (f"The albedo peaks away from normal incidence for {where}: the L = N factor is not "
                   "conservative there.")
    else:
        verdict = ("For every lobe and every n in the table, the largest albedo over θ ∈ [0°, 89.9°] is at normal "
                   "incidence: the seeds' assumption holds, and the L = N factor is the energy-conserving one.")
    ctx.findings.append(verdict)
    body = (
        "<p>Normalization factor 1/E at L = N (the fixed direction at the normal) for each seed lobe over the "
        "exponent n: seed 000's closed forms against adaptive Gauss-Kronrod quadrature of the albedo integral "
        f"E = ∫ f(L,V)(N·L) dL (<code>brdfnorm.normalize</code>, rtol {config.table_rtol:g}). Relative "
        f"difference = quadrature/closed form − 1, green within {tolerance:g}. The Gaussian Blinn-Phong lobe of "
        "seed 003 has no closed form; its column gives the quadrature and its error estimate.</p>\n"
        + table([top, sub], rows, table_id="factor-table")
        + f'\n<p id="factor-certified">{escape(certified_line)}</p>\n'
        + "\n<h3>Where is the albedo largest?</h3>\n<p>θ (degrees) of the largest albedo over the view angle "
        f"θ ∈ [0°, 89.9°], found by a grid and golden-section search (<code>normalize(at=\"max\")</code>, rtol "
        f"{config.search_rtol:g}). {escape(verdict)}</p>\n"
        + table([["lobe"] + [Cell(f"n = {n:g}") for n in data.n]], search_rows, table_id="max-table")
    )
    return Section("factors", "Normalization factors: closed form against quadrature", body)


def albedo_section(ctx: Context) -> Section:
    config = ctx.config
    curves = study.albedo_curves(config, ctx.tick)
    image = ctx.image(figures.albedo_figure(curves, "albedo.png"))
    degrees = np.degrees(curves.theta)
    picks = sorted({int(np.argmin(np.abs(degrees - g))) for g in GRAZING})
    header = [["lobe", "n"] + [Cell(f"θ_o = {degrees[i]:.3g}°") for i in picks]]
    rows = []
    for lobe in study.SEED_LOBES:
        kept = curves.normalized(lobe)[..., 0]
        for k, n in enumerate(curves.values[lobe]):
            rows.append([text(lobe), number(n, 6)] + [percent(kept[k, i] - 1.0, 1) for i in picks])
    # The headline: the lobe and exponent losing the most at the most grazing angle of the table.
    last = picks[-1]
    lobe, k = min(((lobe, k) for lobe in study.SEED_LOBES for k in range(curves.values[lobe].size)),
                  key=lambda item: curves.normalized(item[0])[item[1], last, 0])
    kept = curves.normalized(lobe)[k, last, 0]
    ctx.findings.append(
        f"Normalized at L = N, {lobe} with n = {curves.values[lobe][k]:g} reflects only {100 * kept:.2g} % of the "
        f"incoming energy at θ_o = {degrees[last]:.3g}°: a constant factor cannot conserve energy at every angle.")
    body = (
        "<p>Directional albedo E(θ_o) = ∫ f(L,V)(N·L) dL for the view at θ_o (top, log scale), and the same "
        "curves times the L = N factor (bottom): the share of the incoming energy that the normalized lobe "
        "reflects. 1 at normal incidence by construction; everything below 1 is energy lost towards grazing "
        f"views (seed 002's open problem). Quadrature at rtol {config.plot_rtol:g}.</p>\n"
        + figure(image, "Albedo against view angle: raw (top), normalized at L = N (bottom).")
        + "\n<p>Energy kept by the normalized lobe, E(θ_o)·factor − 1:</p>\n"
        + table(header, rows, table_id="grazing-table")
    )
    return Section("albedo", "Albedo against view angle, with and without normalization", body)


def folklore_section(ctx: Context) -> Section:
    config = ctx.config
    data = study.folklore(config, ctx.results["factors"])
    image = ctx.image(figures.folklore_figure(data, "folklore.png"))
    exact_at_table = 1.0 / closed_forms.blinn_phong_albedo_normal(data.table_n)
    folk_at_table = closed_forms.blinn_phong_folklore_factor(data.table_n)
    rows = [[number(n, 6), number(exact_at_table[s]), number(data.quadrature[s]), number(folk_at_table[s]),
             percent(folk_at_table[s] / exact_at_table[s] - 1.0)] for s, n in enumerate(data.table_n)]
    header = [["n", "α(n) exact (seed 000)", "α(n) quadrature", "folklore (n+8)/8π", "folklore error"]]
    error = data.relative_error
    worst_n, worst_error = closed_forms.blinn_phong_folklore_worst()
    large = data.n >= 100
    ctx.findings.append(
        f"The folklore Blinn-Phong factor (n+8)/8π is off by up to {100 * abs(worst_error):.1f} % (at "
        f"n = {worst_n:.4g}); for n ≥ 100 by at most {100 * np.max(np.abs(error[large])):.2f} %.")
    body = (
        "<p>Seed 000 derives the exact Blinn-Phong normalization at L = N, α(n) = (n+2)(n+4)/(8π(2^(−n/2)+n)), "
        "and notes it is <em>not</em> the widely used (n+8)/8π. Left: both against n, with quadrature values; "
        "right: the folklore factor's relative error. The two agree asymptotically (both ≈ n/8π) and differ "
        "most at moderate n.</p>\n"
        + figure(image, "Blinn-Phong α(n) against the folklore (n+8)/8π.")
        + table(header, rows, table_id="folklore-table")
    )
    return Section("folklore", "Blinn-Phong: exact α(n) against the folklore (n+8)/8π", body)


def fit_section(fit: Callable) -> Callable[[Context], Section]:
    def build(ctx: Context) -> Section:
        data = study.seed003_fits(ctx.config, fit, ctx.tick)
        image = ctx.image(figures.fit_figure(data, "fits.png"))
        steep = data.n >= 16
        rows = []
        for f in data.fits:
            error = np.abs(data.relative_error(f))
            rows.append([text(f.label), Cell(f.expression, css="num"), percent(error.max(), signed=False),
                         percent(error[steep].max(), signed=False) if np.any(steep) else text("—")])
        seed, best = data.fits[0], min(data.fits[1:], key=lambda f: np.abs(data.relative_error(f)).max())
        seed_error = np.abs(data.relative_error(seed))
        ctx.findings.append(
            f"Seed 003's line {closed_forms.SEED_003_TEXT} misses the Gaussian Blinn-Phong factor by up to "
            f"{100 * seed_error.max():.1f} % over n ∈ [1, 512] ({100 * seed_error[steep].max():.2f} % for "
            f"n ≥ 16); the {best.label} <code>{escape(best.expression)}</code> stays within "
            f"{100 * np.abs(data.relative_error(best)).max():.2g} %.")
        body = (
            f"<p>Seed 003 normalizes its Gaussian Blinn-Phong lobe by {closed_forms.SEED_003_TEXT}, a line "
            "fitted numerically over n ∈ [1, 512] (\"not accurate for small specular power values\"); a "
            "commenter suggests a scaled hyperbola √(x² + 1) instead. Here the factor 1/E(L = N) is computed "
            f"by quadrature at {data.n.size} values of n in that range (rtol {ctx.config.table_rtol:g}) and "
            "refitted with <code>brdfnorm.fit</code>: a least-squares line through all of them (the seed's "
            "method, which should give back the seed's coefficients), and, minimizing the largest relative "
            f"error on {ctx.config.fit_samples} geometrically spaced n, the hyperbola and the automatic "
            "choice of form (target 10⁻³). Errors are measured on the whole grid.</p>\n"
            + figure(image, "Seed 003's linear fit and refits of the Gaussian Blinn-Phong factor, with their "
                     "relative errors.")
            + table([["fit", "expression", "max |error|, n ∈ [1, 512]", "max |error|, n ∈ [16, 512]"]], rows,
                    table_id="fit-table")
        )
        return Section("fits", "Seed 003: the linear fit against refits", body)

    return build


def polar_section(ctx: Context) -> Section:
    config = ctx.config
    panels = study.polar_lobes(config, ctx.tick)
    image = ctx.image(figures.polar_figure(panels, "polar.png"))
    views = ", ".join(f"{v:g}°" for v in config.polar_views)
    body = (
        f"<p>Each lobe at n = {config.polar_n:g}, normalized at L = N, drawn in the plane of incidence: the "
        f"radius is f(L,V)(N·L)·factor for the light L at polar angle t (N up), for views V at θ_v = {views} "
        "(thin rays, on the right; the reflection lobes appear on the left, around the mirror direction). The "
        "original Phong lobe keeps its shape and is cut by the horizon; the half-vector lobes flatten and "
        "shrink towards grazing views.</p>\n"
        + figure(image, "The seed lobes in the plane of incidence at several view angles.")
    )
    return Section("polar", "The lobes in the plane of incidence", body)


def verify_section(verify: Callable) -> Callable[[Context], Section]:
    def build(ctx: Context) -> Section:
        from ..claims import RELATIONS
        from ..claims.verify import CHECKS

        claims = []
        for index, claim_id in enumerate(CHECKS):  # one claim at a time, so that the progress moves
            ctx.tick(claim_id, index / len(CHECKS))
            claims += verify(only=[claim_id])
        rows = []
        for claim in claims:
            # The difference column is recomputed here from the two values shown, so that it means
            # |A − B| / |B| on every row (a claim's own rel_error may be another measure, e.g. a ratio).
            a, b = float(claim.formula_value), float(claim.numeric_value)
            difference = abs(a - b) / abs(b) if b != 0 else (0.0 if a == b else float("inf"))
            rows.append([text(str(claim.id)), text(str(claim.source).split(" (")[0]),
                         Cell(str(claim.statement), detail=str(claim.detail)),
                         text(RELATIONS.get(claim.relation, claim.relation)), _value_cell(claim.formula_value),
                         _value_cell(claim.numeric_value), Cell(f"{difference:.2e}", difference, "num"),
                         text(claim.criterion or "—"),
                         Cell("✔ confirmed" if claim.ok else "✘ refuted", css="good" if claim.ok else "bad")])
        failed = [str(c.id) for c in claims if not c.ok]
        ctx.findings.append(
            f"{len(claims) - len(failed)} of {len(claims)} checked claims (the seed articles' and the field's "
            "published numbers) are confirmed"
            + (f"; refuted: {', '.join(failed)}." if failed else "."))
        body = (
            "<p>Claims of the seed articles (formulas, fits, folklore, and steps a seed shows failing) and the "
            "field's published numbers (EON, Kulla-Conty's F_avg, GGX furnace values), each "
            "recomputed independently by <code>brdfnorm verify</code>. On every row A is the seed's side (its "
            "formula, fit or stated value) and B the independent computation; the line under each claim says "
            "what A and B are. <em>Claimed relation</em> is what the seed states about them: most claims state "
            "A = B, a claimed failure or error states A ≠ B, and then |A − B| / |B| is by how much it fails. "
            "The verdict applies the criterion to the difference: ✔ confirmed means the seed's statement, "
            "equality or failure, is reproduced.</p>\n"
            + table([["id", "source", "claim, and how it was checked", "claimed relation", "A (seed)",
                      "B (independent)", "|A − B| / |B|", "criterion", "verdict"]], rows, table_id="verify-table")
        )
        return Section("verify", "The seeds' claims, verified", body)

    return build


def _value_cell(value) -> Cell:
    if value is None:
        return text("—")
    if isinstance(value, (int, float, np.floating, np.integer)):
        return number(value)
    return Cell(str(value), css="num")


# -- any model ---------------------------------------------------------------------------------------------

def model_section(model, label: str, sweep, index: int) -> Callable[[Context], Section]:
    def build(ctx: Context) -> Section:
        data = study.model_study(model, label, sweep, ctx.config, ctx.tick)
        prefix = f"model{index}"
        shown = [ctx.image(figures.factor_figure(data, f"{prefix}-factors.png"))] if data.parameter else []
        curves = ctx.image(figures.albedo_figure(data.curves, f"{prefix}-albedo.png"))
        polar = ctx.image(figures.polar_figure(data.polar, f"{prefix}-polar.png"))
        name = data.parameter or "—"
        header = [[name, "albedo E (L = N)", "factor at L = N"]
                  + (["closed form factor", "relative difference"] if data.closed_albedo is not None else [])
                  + ["θ of max E", "φ of max E", "factor at the maximum", "max / L = N − 1"]]
        rows = []
        with np.errstate(divide="ignore", invalid="ignore"):
            normal_factor = 1.0 / data.normal_albedo
            max_factor = 1.0 / data.max_albedo
            excess = data.max_albedo.max(axis=-1) / data.normal_albedo.max(axis=-1) - 1.0
        for s, value in enumerate(data.values):
            row = [number(value, 6) if data.parameter else text("—"), _channel_cell(data.normal_albedo[s]),
                   _channel_cell(normal_factor[s])]
            if data.closed_albedo is not None:
                closed = 1.0 / data.closed_albedo[s]
                row += [_channel_cell(closed), relative(float(np.max(np.abs(normal_factor[s] / closed - 1.0))),
                                                        AGREEMENT * ctx.config.model_rtol)]
            if data.max_theta[s] > 0:
                row += [number(np.degrees(data.max_theta[s]), 4), number(np.degrees(data.max_phi[s]), 4),
                        _channel_cell(max_factor[s]), percent(excess[s], 3)]
            else:  # the maximum is the L = N integral itself (φ is meaningless at the pole)
                row += [number(0.0), text("—"), _channel_cell(max_factor[s]), text("at L = N")]
            rows.append(row)
        off = data.max_theta > 0
        what = f"{escape(label)}" + (f" over {escape(name)}" if data.parameter else "")
        if np.any(off):
            worst = int(np.argmax(excess))
            ctx.findings.append(
                f"{what}: the albedo peaks away from L = N for {np.count_nonzero(off)} of {off.size} values; "
                f"normalized at L = N, the lobe then reflects up to {1 + excess[worst]:.4g} times the energy it "
                f"receives (at θ = {np.degrees(data.max_theta[worst]):.3g}°, {name} = {data.values[worst]:.4g}); "
                "the factor at the maximum is the energy-conserving one.")
        else:
            ctx.findings.append(f"{what}: the albedo is largest at L = N for every value studied.")
        finite = normal_factor[np.isfinite(normal_factor)]
        if data.parameter and finite.size:
            ctx.findings.append(f"{what}: the factor at L = N ranges from {finite.min():.4g} to {finite.max():.4g} "
                                "(1 would mean the lobe is already normalized).")
        sweep_text = (f"the sweep over <code>{escape(name)}</code> ({data.values.size} values from "
                      f"{data.values.min():.4g} to {data.values.max():.4g})" if data.parameter else
                      "its bound parameters (no float parameter to sweep)")
        formula = f"<p><code>{escape(model.formula)}</code></p>" if getattr(model, "formula", "") else ""
        params = ", ".join(f"{k} = {format_value(v, 6)}" for k, v in model.params.items()) or "none"
        body = (
            f"{formula}<p>{escape(model.name)} ({escape(label)}; parameters {escape(params)}) over {sweep_text}. "
            "Factors 1/E at L = N and at the maximum of E over directions (<code>normalize(at=\"max\")</code>: the "
            "smallest factor that keeps the lobe energy-conserving everywhere); albedo curves and polar plots at "
            f"{data.curves.values[label].size} of the values. Albedo method: {escape(data.method)}.</p>\n"
            + "".join(figure(image, "Normalization factors over the sweep, and where the albedo peaks.")
                      for image in shown)
            + figure(curves, "Albedo against view angle: raw (top), normalized at L = N (bottom).")
            + figure(polar, "The lobe in the plane of incidence, normalized at L = N, at several view angles.")
            + table(header, rows, table_id=f"{prefix}-table")
        )
        return Section(prefix, f"{label}", body)

    return build


def _channel_cell(values: np.ndarray) -> Cell:
    values = np.asarray(values, dtype=float)
    if values.size == 1 or np.allclose(values, values[0], rtol=1e-12, atol=0.0):
        return number(values[0])
    return Cell(", ".join(number(v).text for v in values), None, "num")


