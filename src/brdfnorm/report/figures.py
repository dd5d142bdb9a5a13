"""Figures of ``brdfnorm report``, drawn with Matplotlib's Agg canvas into PNG bytes.

Reproducibility: every figure is drawn under Matplotlib's built-in default style (a user's matplotlibrc cannot
change the page), at a fixed size and resolution, and saved without the PNG "Software" text chunk; Agg draws
deterministically, so a rerun writes byte-identical files. No pyplot: figures are plain ``Figure`` objects,
never registered with a GUI backend or kept alive by a global figure manager.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import matplotlib.style
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from .study import AlbedoCurves, Folklore, ModelStudy, PolarPanel, Seed003Fits

#: Pixels per inch of the PNG files; the page shows them at 96 CSS px per inch (1.5 image pixels per CSS
#: pixel, sharp on HiDPI screens).
DPI = 144
CSS_PER_INCH = 96
#: ``text.parse_math`` off: model names and file names are drawn as text — a name such as ``a$\foo{$b`` is not
#: mathtext (the figures spell their symbols in Unicode).
STYLE = {"font.size": 9.0, "axes.titlesize": 10.0, "legend.fontsize": 8.0, "axes.grid": True,
         "grid.alpha": 0.35, "lines.linewidth": 1.4, "figure.facecolor": "white", "text.parse_math": False}
CHANNEL_NAMES = ("R", "G", "B")


@dataclass(frozen=True)
class Image:
    """A rendered figure: file name, PNG bytes, display size in CSS pixels, and text for the page."""

    name: str
    png: bytes
    width: int
    height: int
    alt: str


def _new(width: float, height: float) -> Figure:
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _side_by_side(width: float, height: float):
    """A figure with two axes side by side: (figure, left, right)."""
    figure = _new(width, height)
    left, right = figure.subplots(1, 2)
    return figure, left, right


def render(name: str, alt: str, draw) -> Image:
    """Draw with ``draw() -> Figure`` under the fixed style and encode it as PNG."""
    with matplotlib.style.context(["default", STYLE]):
        figure = draw()
        buffer = io.BytesIO()
        figure.savefig(buffer, format="png", dpi=DPI, metadata={"Software": None})
    width, height = figure.get_size_inches()
    return Image(name, buffer.getvalue(), round(width * CSS_PER_INCH), round(height * CSS_PER_INCH), alt)


def channels(values: np.ndarray) -> list[tuple[str, np.ndarray]]:
    """Split (..., C) into labelled channels; a colour model whose channels agree is drawn once."""
    values = np.asarray(values)
    if values.shape[-1] == 1 or np.allclose(values, values[..., :1], rtol=1e-12, atol=0.0, equal_nan=True):
        return [("", values[..., 0])]
    return [(f" ({CHANNEL_NAMES[c] if c < 3 else c})", values[..., c]) for c in range(values.shape[-1])]


_LINESTYLES = ("-", "--", ":")
_FIT_STYLES = ("-", "--", ":", "-.")


def albedo_figure(curves: AlbedoCurves, name: str) -> Image:
    """Top row: E(θ_o), log scale. Bottom row: E(θ_o)·factor(L = N), the share of energy kept."""
    keys = list(curves.albedo)
    degrees = np.degrees(curves.theta)

    def draw() -> Figure:
        figure = _new(max(3.6 * len(keys), 5.0), 6.2)
        axes = figure.subplots(2, len(keys), squeeze=False, sharex=True)
        for j, key in enumerate(keys):
            top, bottom = axes[0, j], axes[1, j]
            for k, value in enumerate(curves.values[key]):
                color = f"C{k}"
                label = f"{curves.parameter} = {value:.4g}" if curves.parameter else "E"
                for c, (suffix, raw) in enumerate(channels(curves.albedo[key][k])):
                    style = _LINESTYLES[c % 3]
                    top.plot(degrees, raw, style, color=color, label=label + suffix)
                    bottom.plot(degrees, channels(curves.normalized(key)[k])[c][1], style, color=color,
                                label=label + suffix)
            top.set_yscale("log")
            top.set_title(curves.title[key])
            bottom.axhline(1.0, color="0.3", linewidth=0.8)
            bottom.set_xlabel("view angle θ_o (degrees)")
            bottom.set_xlim(0, 90)
            bottom.set_xticks(np.arange(0, 91, 15))
            if j == 0:
                top.set_ylabel("albedo E(θ_o)")
                bottom.set_ylabel("E(θ_o) × factor at L = N")
            top.legend(loc="lower left")
        return figure

    return render(name, "Directional albedo against view angle, raw and normalized at L = N", draw)


def _label(axis, xlabel: str, ylabel: str, title: str, legend: str | None = None) -> None:
    """Axis labels and title, and a legend at ``legend`` (a matplotlib location) if given."""
    axis.set_xlabel(xlabel)
    axis.set_ylabel(ylabel)
    axis.set_title(title)
    if legend is not None:
        axis.legend(loc=legend)


def folklore_figure(data: Folklore, name: str) -> Image:
    def draw() -> Figure:
        figure, left, right = _side_by_side(10.0, 3.8)
        left.loglog(data.n, data.exact, color="C0", label="exact α(n) = (n+2)(n+4) / 8π(2^(−n/2)+n)")
        left.loglog(data.n, data.folklore, "--", color="C3", label="folklore (n+8) / 8π")
        left.loglog(data.table_n, data.quadrature, "o", color="C0", markersize=4, mfc="none",
                    label="quadrature (L = N)")
        _label(left, "exponent n", "normalization factor α(n)", "Blinn-Phong normalization at L = N", "upper left")
        right.semilogx(data.n, 100.0 * data.relative_error, color="C3")
        right.axhline(0.0, color="0.3", linewidth=0.8)
        worst = int(np.argmax(np.abs(data.relative_error)))
        right.plot(data.n[worst], 100.0 * data.relative_error[worst], "o", color="C3", markersize=4)
        right.annotate(f"{100 * data.relative_error[worst]:+.1f} % at n = {data.n[worst]:.3g}",
                       (data.n[worst], 100.0 * data.relative_error[worst]), textcoords="offset points",
                       xytext=(8, -4), fontsize=8)
        _label(right, "exponent n", "(n+8)/8π relative to α(n)  (%)", "Error of the folklore factor")
        return figure

    return render(name, "Blinn-Phong normalization factor against the folklore (n+8)/8π", draw)


def fit_figure(data: Seed003Fits, name: str) -> Image:
    def draw() -> Figure:
        figure, left, right = _side_by_side(10.0, 3.8)
        left.loglog(data.n, data.factor, color="k", linewidth=3.0, alpha=0.25, label="quadrature factor")
        for k, fit in enumerate(data.fits):
            # The least-squares refit reproduces the seed's line: drawn dashed over it, so both stay visible.
            style = dict(linestyle=_FIT_STYLES[k % 4], color=f"C{k}", linewidth=2.6 if k == 0 else 1.4,
                         alpha=0.6 if k == 0 else 1.0, label=fit.label)
            left.loglog(data.n, fit.prediction, **style)
            right.loglog(data.n, np.abs(data.relative_error(fit)), **style)
        _label(left, "exponent n", "factor 1 / E(L = N)", "Gaussian Blinn-Phong (seed 003): factor and fits",
               "upper left")
        _label(right, "exponent n", "|relative error|", "Error of each fit", "best")
        return figure

    return render(name, "Seed 003's linear fit against refits, with their relative errors", draw)


def polar_figure(panels: list[PolarPanel], name: str) -> Image:
    """One half-disc per panel: N up, L on the left of N when it lies opposite V; V drawn as a thin ray."""

    def draw() -> Figure:
        figure = _new(max(3.2 * len(panels), 5.0), 2.3)
        axes = figure.subplots(1, len(panels), subplot_kw={"projection": "polar"}, squeeze=False)[0]
        for ax, panel in zip(axes, panels, strict=True):
            ax.set_theta_zero_location("N")
            ax.set_theta_direction(-1)
            ax.set_thetamin(-90)
            ax.set_thetamax(90)
            top = np.nanmax(panel.radiance) if np.any(np.isfinite(panel.radiance)) else 1.0
            for w, view in enumerate(panel.views):
                color = f"C{w}"
                for c, (suffix, value) in enumerate(channels(panel.radiance[w])):
                    ax.plot(panel.t, value, _LINESTYLES[c % 3], color=color,
                            label=f"θ_v = {np.degrees(view):.0f}°{suffix}")
                ax.plot([view, view], [0, top], color=color, linewidth=0.7, alpha=0.6)
            ax.set_rmin(0.0)
            ax.set_rmax(top * 1.05 if top > 0 else 1.0)
            ax.set_title(panel.title, pad=2)
            ax.yaxis.set_major_locator(MaxNLocator(3))
            ax.tick_params(labelsize=7)
        axes[-1].legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), fontsize=7)
        return figure

    return render(name, "Polar plots of the lobes in the plane of incidence", draw)


def factor_figure(study: ModelStudy, name: str) -> Image:
    """Factors at L = N and at the maximum over directions against the swept parameter."""

    def draw() -> Figure:
        figure, left, right = _side_by_side(10.0, 3.6)
        x = study.values
        with np.errstate(divide="ignore"):
            normal, highest = 1.0 / study.normal_albedo, 1.0 / study.max_albedo
        for c, (suffix, value) in enumerate(channels(normal)):
            left.plot(x, value, _LINESTYLES[c % 3], color="C0", marker=".", label="at L = N" + suffix)
        for c, (suffix, value) in enumerate(channels(highest)):
            left.plot(x, value, _LINESTYLES[c % 3], color="C3", label="at the maximum" + suffix)
        if study.closed_albedo is not None:
            with np.errstate(divide="ignore"):
                left.plot(x, 1.0 / study.closed_albedo[:, 0], "o", color="C2", mfc="none", markersize=4,
                          label="closed form (L = N)")
        right.plot(x, np.degrees(study.max_theta), color="C3", marker=".")
        if _wide(x):
            left.set_xscale("log")
            right.set_xscale("log")
        if _wide(normal[np.isfinite(normal)]):
            left.set_yscale("log")
        _label(left, study.parameter, "normalization factor 1/E", "Factor over the sweep", "best")
        _label(right, study.parameter, "θ of the largest albedo (degrees)", "Where the albedo is largest")
        right.set_ylim(-2, 92)
        return figure

    return render(name, f"Normalization factor of {study.label} over {study.parameter}", draw)


def _wide(values: np.ndarray) -> bool:
    values = np.asarray(values, dtype=float)
    return values.size > 1 and np.all(values > 0) and values.max() / values.min() >= 20
