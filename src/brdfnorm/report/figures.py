"""Figures of ``brdfnorm report``, drawn with Matplotlib's Agg canvas into PNG bytes.

Reproducibility: every figure is drawn under Matplotlib's built-in default style (a user's matplotlibrc cannot
change the page), at a fixed size and resolution, and saved with the PNG "Software" text chunk naming brdfnorm's
version (not Matplotlib's); Agg draws deterministically, so a rerun writes byte-identical files. No pyplot:
figures are plain ``Figure`` objects, never registered with a GUI backend or kept alive by a global figure manager.
"""

from __future__ import annotations

import io
from dataclasses import dataclass

import matplotlib.style
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

from ..models import closed_forms
from ..version import __version__
from .study import AlbedoCurves, Folklore, ModelStudy, PolarPanel, Seed003Fits

#: Pixels per inch of the PNG files; the page shows them at 96 CSS px per inch (1.5 image pixels per CSS
#: pixel, sharp on HiDPI screens).
DPI = 144
CSS_PER_INCH = 96
#: ``text.parse_math`` stays on: Matplotlib's own log-axis tick labels are mathtext (``$\mathdefault{10^{-1}}$``)
#: and print as raw TeX without it. Titles, axis labels, legend entries and annotations — where model names,
#: parameter names and file names go — are drawn as plain text instead (:func:`plain_text`), so a name such
#: as ``a$\foo{$b`` is never read as mathtext (the figures spell their own symbols in Unicode).
STYLE = {"font.size": 9.0, "axes.titlesize": 10.0, "legend.fontsize": 8.0, "axes.grid": True,
         "grid.alpha": 0.35, "lines.linewidth": 1.4, "figure.facecolor": "white"}
#: At most this many labelled decades on a log axis (more would overlap on the narrow panels).
LOG_TICKS = 6
CHANNEL_NAMES = ("R", "G", "B")


@dataclass(frozen=True)
class Image:
    """A rendered figure: file name, PNG bytes, display size in CSS pixels, and text for the page."""

    name: str
    png: bytes
    width: int
    height: int
    alt: str


def new_figure(width: float, height: float) -> Figure:
    """A matplotlib figure of ``width`` × ``height`` inches on the Agg canvas (no pyplot state), for every figure."""
    figure = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(figure)
    return figure


def _side_by_side(width: float, height: float):
    """A figure with two axes side by side: (figure, left, right)."""
    figure = new_figure(width, height)
    left, right = figure.subplots(1, 2)
    return figure, left, right


def render(name: str, alt: str, draw) -> Image:
    """Draw with ``draw() -> Figure`` under the fixed style and encode it as PNG."""
    with matplotlib.style.context(["default", STYLE]):
        figure = draw()
        plain_text(figure)
        for axis in figure.axes:
            readable_log_ticks(axis)
        buffer = io.BytesIO()
        # the PNG names the release that drew it (and no matplotlib version: the bytes stay reproducible)
        figure.savefig(buffer, format="png", dpi=DPI, metadata={"Software": f"brdfnorm {__version__}"})
    width, height = figure.get_size_inches()
    return Image(name, buffer.getvalue(), round(width * CSS_PER_INCH), round(height * CSS_PER_INCH), alt)


def plain_text(figure: Figure) -> None:
    """Draw every title, axis label, legend entry and annotation as plain text (no mathtext): these hold names
    a user chose. Tick labels and offset texts keep mathtext, which Matplotlib's formatters write."""
    texts: list[Text] = list(figure.texts)
    for suptitle in ("_suptitle", "_supxlabel", "_supylabel"):
        if getattr(figure, suptitle, None) is not None:
            texts.append(getattr(figure, suptitle))
    for legend in figure.legends:
        texts.extend(legend.get_texts())
    for axes in figure.axes:
        texts.extend([axes.title, axes._left_title, axes._right_title, axes.xaxis.label, axes.yaxis.label])
        texts.extend(axes.texts)
        legend = axes.get_legend()
        if legend is not None:
            texts.extend(legend.get_texts())
            texts.append(legend.get_title())
    for item in texts:
        item.set_parse_math(False)


_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


def log_label(value: float, _position=None) -> str:
    """A log-axis tick label in plain Unicode: 1, 10, 10², 10⁻³ for decades, 0.2 or 5 between them (no
    mathtext, so the label reads the same whatever ``text.parse_math`` says)."""
    if not np.isfinite(value) or value <= 0:
        return ""
    k = int(round(np.log10(value)))
    if abs(value / 10.0**k - 1.0) > 1e-9:
        return f"{value:.3g}".replace("-", "−")
    return {0: "1", 1: "10"}.get(k, "10" + str(k).translate(_SUPERSCRIPT))


def readable_log_ticks(axes) -> None:
    """On each log-scaled axis: decades labelled in Unicode (:func:`log_label`), at most :data:`LOG_TICKS` of
    them, minor ticks unlabelled — Matplotlib labels minor ticks (2×10⁰, 3×10⁰, …) on short ranges, and they
    overlap. An axis spanning less than one decade keeps a few minor labels (it has no decade to label)."""
    for axis in (axes.xaxis, axes.yaxis):
        if axis.get_scale() != "log":
            continue
        low, high = sorted(axis.get_view_interval())
        axis.set_major_locator(LogLocator(base=10.0, numticks=LOG_TICKS))
        axis.set_major_formatter(FuncFormatter(log_label))
        if low > 0 and np.floor(np.log10(high)) >= np.ceil(np.log10(low)):
            axis.set_minor_formatter(NullFormatter())
        else:
            axis.set_minor_locator(LogLocator(base=10.0, subs=(2.0, 5.0), numticks=LOG_TICKS))
            axis.set_minor_formatter(FuncFormatter(log_label))


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
        figure = new_figure(max(3.6 * len(keys), 5.0), 6.2)
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
        worst_n, worst_error = closed_forms.blinn_phong_folklore_worst()  # the one argmax the page quotes
        right.plot(worst_n, 100.0 * worst_error, "o", color="C3", markersize=4)
        right.annotate(f"{100 * worst_error:+.1f} % at n = {worst_n:.4g}",
                       (worst_n, 100.0 * worst_error), textcoords="offset points",
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
        figure = new_figure(max(3.2 * len(panels), 5.0), 2.3)
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
