"""The report's figures as a reader sees them: every figure of a report is drawn, its tick labels read back
from the canvas. Decade labels must be plain text (no raw TeX such as ``$\\mathdefault{10^{-1}}$``), tick
labels of one axis must not overlap, and names a user chose must never be read as mathtext."""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg

from brdfnorm.report import StudyConfig, build_report, figures


def _boxes_overlap(a, b) -> bool:
    return a.x0 < b.x1 - 0.5 and b.x0 < a.x1 - 0.5 and a.y0 < b.y1 - 0.5 and b.y0 < a.y1 - 0.5


def check_figure(figure) -> list[str]:
    """Every visible tick label of every axis: (no TeX, no overlap) checked; returns the labels read."""
    canvas = figure.canvas
    assert isinstance(canvas, FigureCanvasAgg)
    canvas.draw()
    renderer = canvas.get_renderer()
    read = []
    for axes in figure.axes:
        for axis in (axes.xaxis, axes.yaxis):
            labels = [t for t in axis.get_ticklabels() + axis.get_ticklabels(minor=True)
                      if t.get_visible() and t.get_text()]
            lo, hi = sorted(axis.get_view_interval())
            labels = [t for t, v in zip(labels, [*axis.get_majorticklocs(), *axis.get_minorticklocs()],
                                        strict=False) if lo <= v <= hi] or labels
            for label in labels:
                text = label.get_text()
                read.append(text)
                assert "$" not in text and "mathdefault" not in text, text
            boxes = [label.get_window_extent(renderer) for label in labels]
            for i in range(len(boxes)):
                for j in range(i + 1, len(boxes)):
                    assert not _boxes_overlap(boxes[i], boxes[j]), (labels[i].get_text(), labels[j].get_text())
    return read


@pytest.fixture
def drawn(monkeypatch):
    """Capture every Figure that report.figures.render draws."""
    captured = []
    original = figures.render

    def capture(name, alt, draw):
        def keep():
            figure = draw()
            captured.append((name, figure))
            return figure
        return original(name, alt, keep)

    monkeypatch.setattr(figures, "render", capture)
    return captured


@pytest.mark.slow
def test_quick_report_figures_have_readable_ticks(drawn, tmp_path):
    build_report(tmp_path / "r", config=StudyConfig.quick())
    names = [name for name, _ in drawn]
    assert {"albedo.png", "folklore.png", "polar.png", "microfacet-eavg.png"} <= set(names)
    decades = []
    for _name, figure in drawn:
        decades += [t for t in check_figure(figure) if t.startswith("10")]
    assert any("⁻" in t for t in decades)  # the log axes are labelled, in Unicode superscripts


@pytest.mark.slow
def test_fit_figure(drawn):
    """The fits figure (not in the quick report): log axes on both panels."""
    from brdfnorm.fit import fit
    from brdfnorm.report import study

    figures.fit_figure(study.seed003_fits(StudyConfig.quick(), fit), "fits.png")
    (_, figure), = drawn
    assert all(axes.get_xscale() == "log" for axes in figure.axes)
    check_figure(figure)


@pytest.mark.slow
def test_model_figures_over_a_wide_sweep(drawn, tmp_path):
    build_report(tmp_path / "r", ["blinn-phong"], sweep=("n", np.geomspace(1.0, 1e4, 5)),
                 config=StudyConfig.quick())
    assert len(drawn) == 3
    for _name, figure in drawn:
        check_figure(figure)


@pytest.mark.parametrize("low, high", [(1.0, 3e4), (2.0, 9.0), (0.3, 700.0), (1e-9, 1.0)])
def test_log_axis_spans(low, high):
    """Short spans (no decade inside) keep a few labels; long ones are thinned to at most LOG_TICKS decades."""
    def draw():
        figure = figures.new_figure(3.0, 2.0)  # a narrow panel, as in the report's side-by-side figures
        axes = figure.subplots()
        x = np.geomspace(low, high, 50)
        axes.loglog(x, x)
        return figure

    image = figures.render("t.png", "t", draw)
    assert image.png[:4] == b"\x89PNG"
    figure = draw()
    figures.plain_text(figure)
    figures.readable_log_ticks(figure.axes[0])
    labels = check_figure(figure)
    assert labels, "a log axis with no label at all"
    assert sum(t.startswith("10") or t == "1" for t in labels) <= 2 * figures.LOG_TICKS


def test_user_names_are_not_mathtext():
    """A name that is broken mathtext draws as itself: parsing it would raise at draw time."""
    name = r"a$\foo{$b"

    def draw():
        figure = figures.new_figure(3.0, 2.0)
        axes = figure.subplots()
        axes.semilogx([1, 10, 100], [1, 2, 3], label=name)
        axes.set_title(name)
        axes.set_xlabel(name)
        axes.legend()
        return figure

    image = figures.render("t.png", "t", draw)
    assert image.png[:4] == b"\x89PNG"


def test_log_label():
    assert [figures.log_label(v) for v in (1e-3, 0.1, 1.0, 10.0, 100.0, 0.2, 5.0)] == [
        "10⁻³", "10⁻¹", "1", "10", "10²", "0.2", "5"]
