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
from ..lut.splitsum import DFG_F0, DFG_F90
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
#: The lobes whose albedos the section computes by compiled kernels, as (method, name, parameters): GGX's tables by
#: the microfacet route (its kernels shared by every microfacet lobe) and the sheen (charlie) of their third DFG
#: channel (:mod:`brdfnorm.lut.cloth`) by the generic quadrature; their kernels compile ahead.
LOBES = (("microfacet", "ggx", {}), ("quadrature", "charlie", {}))


def available() -> bool:
    return "ggx" in REGISTRY


def _image_panels(name: str, alt: str, mu: np.ndarray, alpha: np.ndarray, panels: list[tuple[str, np.ndarray]]):
    def draw():
        fig = figures.new_figure(3.3 * len(panels), 3.0)
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
        fig = figures.new_figure(4.2, 3.0)
        axis = fig.add_subplot(1, 1, 1)
        axis.plot(alpha, avg, "-o", ms=3, label="E_avg(α)")
        axis.plot(alpha, 1.0 - avg, "--", label="1 − E_avg(α)")
        axis.set_xlabel("α")
        axis.legend()
        return fig

    return figures.render("microfacet-eavg.png", "E_avg(α) of GGX and the energy it loses", draw)


def furnace_residuals(quick: bool) -> dict[int, tuple[float, float]]:
    """max over μ and α of |1 − E_total| for GGX + Kulla–Conty at each table size (0: exact tables), with the
    integration error of that number: ``{size: (residual, error estimate)}``.

    E_total is integrated, never assumed: the single-scattering albedo E_ss(μ) by the engine's own quadrature
    of the ``ms=none`` lobe, plus the compensation lobe f_ms(L, V) as the model evaluates it (its tables read as
    a renderer reads them), integrated over the light hemisphere by a product rule — 3-point Gauss–Legendre on
    panels in μ_L that break at the table's nodes (where the bilinear read has kinks; exact there for the
    piecewise-quadratic (1 − E)·μ) and the periodic trapezoidal rule in φ_L. The closed-form route of
    ``albedo(..., ms=kulla-conty)`` would return 1 − 2∫(1 − E)μ dμ/(1 − E_avg) ≡ 1 for exact tables by
    construction; this one measures it. The error estimate adds the engine's estimate and the change from a
    2-point rule on the same panels.
    """
    from .. import albedo, load

    mu = grid_values(0.05, 1.0, 4 if quick else 12)
    alphas = np.array(FURNACE_ALPHAS)
    single = albedo(load("ggx", alpha=alphas[:, None]), np.arccos(mu)[None, :], rtol=RTOL)
    s = np.sqrt(1.0 - mu**2)
    views = np.stack([s, np.zeros_like(s), mu], axis=-1)[None, None, None]  # (1, 1, 1, M, 3)
    phi = np.arange(4) * (np.pi / 2)
    out = {}
    for size in FURNACE_TABLES[:2] + (0,) if quick else FURNACE_TABLES:
        model = load("ggx", ms="kulla-conty", ms_table=float(size))
        params = {**model.params, "alpha": alphas[:, None, None, None]}
        edges = np.linspace(0.0, 1.0, size if size else 33)
        rules = []
        for points in (3, 2):
            x, w = np.polynomial.legendre.leggauss(points)
            lo, hi = edges[:-1, None], edges[1:, None]
            nodes, weights = ((lo + hi) / 2 + (hi - lo) / 2 * x).ravel(), ((hi - lo) / 2 * w).ravel()
            r = np.sqrt(1.0 - nodes**2)[:, None]
            lights = np.stack(np.broadcast_arrays(r * np.cos(phi), r * np.sin(phi), nodes[:, None]), axis=-1)
            f = model.multiple_scattering(lights[None, :, :, None, :], views, params)[..., 0]  # (A, P, Φ, M)
            rules.append(np.einsum("apfm,p->am", f, weights * nodes) * (2.0 * np.pi / phi.size))
        total = single.value[..., 0] + rules[0]
        error = single.error[..., 0] + np.abs(rules[0] - rules[1])
        out[size] = (float(np.max(np.abs(1.0 - total))), float(np.max(error)))
    return out


def loss_sentence(mu: np.ndarray, alpha: np.ndarray, lut) -> str:
    """The energy single scattering loses, each number named for what it is: the worst cell of 1 − E(μ, α)
    (a grazing view) and 1 − E_avg at the roughest α of the table (the loss averaged over cosine-weighted
    views)."""
    loss = np.asarray(lut["1-E"])
    i, j = np.unravel_index(int(np.argmax(loss)), loss.shape)
    return (f"GGX (height-correlated, F = 1) loses in single scattering up to {100 * loss[i, j]:.1f} % of the "
            f"energy at one view (max over μ of 1 − E(μ, α), at μ = {mu[i]:.3g}, α = {alpha[j]:.3g}) and "
            f"{100 * (1.0 - lut['E_avg'][-1]):.1f} % averaged over views (1 − E_avg, E_avg = "
            f"{lut['E_avg'][-1]:.4f} at α = {alpha[-1]:.3g}).")


def section(ctx) -> Section:
    """Build the section (``ctx`` is :class:`brdfnorm.report.sections.Context`)."""
    from .. import load

    quick = not ctx.config.extras
    size = QUICK_GRID if quick else GRID
    mu, alpha = grid_values(0.0, 1.0, size, "texel"), grid_values(0.0, 1.0, size, "texel")
    ctx.tick(f"GGX tables {size}×{size}", 0.0)
    lut = compute(load("ggx"), {"mu": mu, "alpha": alpha}, clamp={"mu": 1e-4, "alpha": 1e-8}, rtol=RTOL,
                  channels=["dfg"], grid="texel")
    energy = ctx.image(_image_panels("microfacet-e.png", "E(μ, α) and 1 − E(μ, α) of GGX", mu, alpha,
                                     [("E(μ, α)", lut["E"]), ("1 − E(μ, α)", lut["1-E"])]))
    dfg = ctx.image(_image_panels("microfacet-dfg.png", "the split-sum DFG pair of GGX", mu, alpha,
                                  [("DFG f0 term", lut[DFG_F0]), ("DFG f90 term", lut[DFG_F90])]))
    avg = ctx.image(_avg_figure(alpha, lut["E_avg"]))
    glass_size = QUICK_GLASS_GRID if quick else GLASS_GRID
    g_mu, g_alpha = grid_values(0.0, 1.0, glass_size, "texel"), grid_values(0.0, 1.0, glass_size, "texel")
    glass = {}
    for index, eta in enumerate(GLASS_ETAS):
        ctx.tick(f"rough glass η = {eta:.4g}", 0.5 + 0.5 * index / len(GLASS_ETAS))
        glass[eta] = compute(load("ggx-dielectric", eta=eta), {"mu": g_mu, "alpha": g_alpha},
                             clamp={"mu": 1e-4, "alpha": 1e-8}, rtol=GLASS_RTOL, average=False, grid="texel")
    glass_image = ctx.image(_image_panels(
        "microfacet-glass.png", "E = R + T of rough glass (ggx-dielectric) seen from outside and inside", g_mu,
        g_alpha, [(f"E(μ, α), η = {eta:.4g}", glass[eta]["E"]) for eta in GLASS_ETAS]
        + [(f"T(μ, α), η = {GLASS_ETAS[0]:.4g}", glass[GLASS_ETAS[0]]["E_T"])]))
    residuals = furnace_residuals(quick)
    rows = [["exact" if n == 0 else f"{n}×{n}", relative(value), relative(error)]
            for n, (value, error) in residuals.items()]
    ctx.findings.append(loss_sentence(mu, alpha, lut) + (
        f" Kulla–Conty compensation, integrated over the hemisphere, leaves a white-furnace residual "
        f"max |1 − E_total| of {residuals[0][0]:.1e} with exact tables (integration error ≤ {residuals[0][1]:.1e}) "
        f"and {residuals[16][0]:.1e} with 16×16 tables."))
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
        + "} of GGX with <code>ms=kulla-conty</code>, by the size of the E and E_avg tables it interpolates. "
        "E_total is integrated, not assumed: the single-scattering albedo by the engine's quadrature plus the "
        "compensation lobe f_ms as the model evaluates it, integrated over the light hemisphere (Gauss–Legendre "
        "in μ_L on panels between the table's nodes, trapezoidal in φ_L). With exact tables the compensation is "
        "exact in theory, so that row shows the integration error.</p>\n"
        + table([["tables", "max |1 − E_total|", "integration error estimate"]], rows,
                table_id="microfacet-furnace")
        + f"<p>Rough glass: the albedo E = R + T of the GGX dielectric interface (<code>brdfnorm lut "
        f"ggx-dielectric</code>, energy form, {glass_size}×{glass_size} texels, rtol {GLASS_RTOL:g}) seen from "
        "outside (η = 1.5) and from inside (η = 1/1.5, where total internal reflection sends everything past "
        f"41.8° back), and the transmitted share T from outside. The energy single scattering loses is largest "
        f"at grazing views and high roughness: min E = {float(np.min(glass[GLASS_ETAS[0]]['E'])):.4f} (η = 1.5), "
        f"{float(np.min(glass[GLASS_ETAS[1]]['E'])):.4f} (η = 1/1.5).</p>\n"
        + figure(glass_image, "E(μ, α) of rough glass from outside and inside, and T from outside.")
    )
    return Section("microfacet", "Microfacet energy: GGX's compensation tables", body)
