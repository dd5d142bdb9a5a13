"""The report's "microfacet energy" section: GGX's energy-compensation tables (:mod:`brdfnorm.lut`).

Kulla & Conty (2017, "Revisiting physically based shading at Imageworks") compensate the energy a single-
scattering microfacet lobe loses with f_ms = (1 − E(μ_L))(1 − E(μ_V)) / (π (1 − E_avg)), built from the albedo
E(μ, α) and its average E_avg(α) = 2∫ E(μ) μ dμ; Karis (2013) splits the Schlick-Fresnel lobe's integral into
the "DFG" pair. This section shows E and 1 − E over (μ, α), E_avg(α), the DFG pair, and the white-furnace
residual max |1 − E_total| of GGX with ``ms=kulla-conty`` as the tables it interpolates grow (16, 32, 64, and
exact — that one by the hemisphere cubature of the compensated lobe), and the rough-glass albedo E = R + T of
``ggx-dielectric`` for η = 1.5 and 1/1.5. It runs when the built-in ``ggx`` model is registered.
"""

from __future__ import annotations

import numpy as np

from ..lut import compute, grid_values
from ..models import REGISTRY
from . import figures
from .html import Section, figure, number, relative, table

#: Table grid (μ × α) of the full report, and of the quick configuration (tests).
GRID, QUICK_GRID = 32, 8
#: The rough-glass tables (ggx-dielectric, reflection + transmission) seen from outside and from inside.
GLASS_ETAS = (1.5, 1 / 1.5)
GLASS_GRID, QUICK_GLASS_GRID, GLASS_RTOL = 10, 4, 1e-6
#: Kulla–Conty table sizes whose furnace residual is shown (0: exact E and E_avg, no interpolation).
FURNACE_TABLES = (16, 32, 64, 0)
FURNACE_ALPHAS = (0.1, 0.5, 1.0)
RTOL = 1e-8


def available() -> bool:
    return "ggx" in REGISTRY


def _image_panels(name: str, alt: str, mu: np.ndarray, alpha: np.ndarray, panels: list[tuple[str, np.ndarray]]):
    def draw():
        fig = figures._new(3.3 * len(panels), 3.0)
        for index, (title, values) in enumerate(panels, start=1):
            axis = fig.add_subplot(1, len(panels), index)
            shown = axis.imshow(values.T, origin="lower", aspect="auto", cmap="viridis",
                                extent=(mu[0], mu[-1], alpha[0], alpha[-1]))
            axis.set_xlabel("μ = cos θ_o")
            axis.set_ylabel("α")
            axis.set_title(title)
            axis.grid(False)
            fig.colorbar(shown, ax=axis)
        return fig

    return figures.render(name, alt, draw)


def _avg_figure(alpha: np.ndarray, avg: np.ndarray):
    def draw():
        fig = figures._new(4.2, 3.0)
        axis = fig.add_subplot(1, 1, 1)
        axis.plot(alpha, avg, "-o", ms=3, label="E_avg(α)")
        axis.plot(alpha, 1.0 - avg, "--", label="1 − E_avg(α)")
        axis.set_xlabel("α")
        axis.legend()
        return fig

    return figures.render("microfacet-eavg.png", "E_avg(α) of GGX and the energy it loses", draw)


def furnace_residuals(quick: bool) -> dict[int, float]:
    """max over μ and α of |1 − E_total| for GGX + Kulla–Conty at each table size (0: exact tables)."""
    from .. import albedo, load

    mu = grid_values(0.05, 1.0, 4 if quick else 12)
    alphas = np.array(FURNACE_ALPHAS)[:, None]
    out = {}
    for size in FURNACE_TABLES[:2] + (0,) if quick else FURNACE_TABLES:
        model = load("ggx", ms="kulla-conty", ms_table=float(size), alpha=alphas)
        # Exact tables: the hemisphere cubature of the compensated lobe, which does not assume the 1 (the albedo
        # methods' closed form for ∫ f_ms cos would return it by construction); interpolated tables: that form.
        result = albedo(model, np.arccos(mu)[None, :], rtol=RTOL, method="quadrature" if size == 0 else "auto")
        out[size] = float(np.max(np.abs(1.0 - result.value[..., 0])))
    return out


def section(ctx) -> Section:
    """Build the section (``ctx`` is :class:`brdfnorm.report.sections.Context`)."""
    from .. import load

    quick = not ctx.config.extras
    size = QUICK_GRID if quick else GRID
    mu, alpha = grid_values(0.0, 1.0, size, "texel"), grid_values(0.0, 1.0, size, "texel")
    lut = compute(load("ggx"), {"mu": mu, "alpha": alpha}, clamp={"mu": 1e-4, "alpha": 1e-8}, rtol=RTOL,
                  channels=["dfg"], grid="texel")
    energy = ctx.image(_image_panels("microfacet-e.png", "E(μ, α) and 1 − E(μ, α) of GGX", mu, alpha,
                                     [("E(μ, α)", lut["E"]), ("1 − E(μ, α)", lut["1-E"])]))
    dfg = ctx.image(_image_panels("microfacet-dfg.png", "the split-sum DFG pair of GGX", mu, alpha,
                                  [("DFG f0 term", lut["DFG_f0"]), ("DFG f90 term", lut["DFG_f90"])]))
    avg = ctx.image(_avg_figure(alpha, lut["E_avg"]))
    glass_size = QUICK_GLASS_GRID if quick else GLASS_GRID
    g_mu, g_alpha = grid_values(0.0, 1.0, glass_size, "texel"), grid_values(0.0, 1.0, glass_size, "texel")
    glass = {eta: compute(load("ggx-dielectric", eta=eta), {"mu": g_mu, "alpha": g_alpha},
                          clamp={"mu": 1e-4, "alpha": 1e-8}, rtol=GLASS_RTOL, average=False, grid="texel")
             for eta in GLASS_ETAS}
    glass_image = ctx.image(_image_panels(
        "microfacet-glass.png", "E = R + T of rough glass (ggx-dielectric) seen from outside and inside", g_mu,
        g_alpha, [(f"E(μ, α), η = {eta:.4g}", glass[eta]["E"]) for eta in GLASS_ETAS]
        + [(f"T(μ, α), η = {GLASS_ETAS[0]:.4g}", glass[GLASS_ETAS[0]]["E_T"])]))
    residuals = furnace_residuals(quick)
    rows = [["exact" if n == 0 else f"{n}×{n}", relative(value)] for n, value in residuals.items()]
    worst_loss = float(np.max(lut["1-E"]))
    ctx.findings.append(
        f"GGX (height-correlated, F = 1) loses up to {100 * worst_loss:.1f} % of the energy in single scattering "
        f"(E_avg = {lut['E_avg'][-1]:.4f} at α = {alpha[-1]:.3g}); Kulla–Conty compensation with exact tables "
        f"leaves a furnace residual of {residuals[0]:.1e}, with 16×16 tables {residuals[16]:.1e}.")
    avg_rows = [[number(a, 4), number(e, 12), relative(err)]
                for a, e, err in zip(alpha, lut["E_avg"], lut["E_avg_error"], strict=True)]
    body = (
        f"<p>The energy-compensation tables of <code>brdfnorm lut ggx</code> on a {size}×{size} texel grid "
        f"(μ clamped to ≥ 1e-4, α to ≥ 1e-8, rtol {RTOL:g}; the largest error estimate of a cell is "
        f"{float(np.max(lut['E_error'])):.1e}). E_avg is the integral 2∫E(μ)μ dμ by its own quadrature, not a "
        "sum over the table.</p>\n"
        + figure(energy, "E(μ, α) and the energy lost in single scattering, 1 − E.")
        + figure(avg, "E_avg(α) and 1 − E_avg(α).")
        + table([["α", "E_avg", "error estimate"]], avg_rows, table_id="microfacet-eavg")
        + figure(dfg, "The split-sum pair: ∫ f cos (1 − (1 − V·H)⁵) and ∫ f cos (1 − V·H)⁵ (Fresnel off).")
        + "<p>White furnace: max |1 − E_total| over μ ∈ [0.05, 1] and α ∈ {"
        + ", ".join(f"{a:g}" for a in FURNACE_ALPHAS)
        + "} of GGX with <code>ms=kulla-conty</code>, by the size of the E and E_avg tables it interpolates.</p>\n"
        + table([["tables", "max |1 − E_total|"]], rows, table_id="microfacet-furnace")
        + f"<p>Rough glass: the albedo E = R + T of the GGX dielectric interface (<code>brdfnorm lut "
        f"ggx-dielectric</code>, energy form, {glass_size}×{glass_size} texels, rtol {GLASS_RTOL:g}) seen from "
        "outside (η = 1.5) and from inside (η = 1/1.5, where total internal reflection sends everything past "
        f"41.8° back), and the transmitted share T from outside. The energy single scattering loses is largest "
        f"at grazing views and high roughness: min E = {float(np.min(glass[GLASS_ETAS[0]]['E'])):.4f} (η = 1.5), "
        f"{float(np.min(glass[GLASS_ETAS[1]]['E'])):.4f} (η = 1/1.5).</p>\n"
        + figure(glass_image, "E(μ, α) of rough glass from outside and inside, and T from outside.")
    )
    return Section("microfacet", "Microfacet energy: GGX's compensation tables", body)
