"""The report's tables fit its 1240 px page in Chromium (issue 43: the factor table was 1 394 px wide in a
1 240 px box, the blinn-phong-gaussian columns hidden at every window width), and the report's progress.

The quick test renders the two widest tables of the default study — the factor table (12 columns of numbers)
and the claims table — through the report's own section code with every number at full length (17 significant
digits in, the widest the page can show), so it needs no integration; the slow tier checks the real default
report in tests/report/test_study.py's fixture the same way.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from helpers.paths import ARTIFACTS

from brdfnorm.claims import Claim
from brdfnorm.output.directories import Stage
from brdfnorm.report import StudyConfig, sections, study
from brdfnorm.report.html import page

CHROMIUM = "/usr/bin/chromium"
PAGE_WIDTH = 1240

MEASURE = """() => Array.from(document.querySelectorAll('table')).map(t => {
  const box = t.closest('.scroll') || t.parentElement;
  return {id: t.id, table: Math.ceil(t.getBoundingClientRect().width), box: box.clientWidth,
          scrolls: box.scrollWidth > box.clientWidth, body: document.body.clientWidth};
})"""


def measure(html: Path, width: int = PAGE_WIDTH, screenshot: Path | None = None) -> list[dict]:
    """Every table's width against its box, in headless Chromium at a ``width`` px window."""
    playwright_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed")
    if not Path(CHROMIUM).exists():
        pytest.skip(f"{CHROMIUM} is missing (Debian package chromium)")
    with playwright_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=["--headless", "--no-sandbox", "--disable-gpu"])
        try:
            tab = browser.new_page(viewport={"width": width, "height": 1000})
            tab.goto(html.as_uri())
            found = tab.evaluate(MEASURE)
            if screenshot is not None:
                screenshot.parent.mkdir(exist_ok=True)
                tab.screenshot(path=str(screenshot), full_page=True)
        finally:
            browser.close()
    return found


def assert_tables_fit(html: Path, name: str) -> None:
    found = measure(html, screenshot=ARTIFACTS / f"{name}-{PAGE_WIDTH}px.png")
    assert found, "no tables on the page"
    for t in found:
        assert not t["scrolls"] and t["table"] <= t["box"], (name, t)


def _wide_factor_table(config: StudyConfig) -> study.FactorTable:
    n = np.asarray(config.table_n, dtype=float)
    wide = {lobe: np.full(n.size, 1.0 / 3.0) * (1 + 1e-12 * k) for k, lobe in enumerate(study.SEED_LOBES)}
    closed = {lobe: wide[lobe] for lobe in study.SEED_LOBES if lobe in study.CLOSED_FORM_OF}
    return study.FactorTable(n, closed, wide, {lobe: np.full(n.size, -1.2345e-13) for lobe in wide},
                             {lobe: np.zeros(n.size) for lobe in wide}, {lobe: np.zeros(n.size) for lobe in wide},
                             None)


def _claims(only: list[str]) -> list[Claim]:
    (claim_id,) = only
    return [Claim(claim_id, "seed 000 (Phong normalization)", "(n+8)/8π is not the Blinn-Phong factor (an "
                  "approximation; error quantified)", -1.0 / 3.0, 2.0 / 3.0, 0.0752, True,
                  "max relative error 0.0752 at n = 8.764 over n ∈ [0.01, 1e4]; " * 3,
                  relation="differ", criterion="|A − B| / |B| > 1e-6 (and the exact factor confirmed to 1e-12)")]


def test_the_widest_tables_fit_the_page(tmp_path, monkeypatch):
    config = StudyConfig()
    monkeypatch.setattr(study, "factor_table", lambda config, tick=None: _wide_factor_table(config))
    ctx = sections.Context(config, Stage(tmp_path))
    built = [sections.factor_section(ctx), sections.verify_section(_claims)(ctx)]
    html = tmp_path / "index.html"
    html.write_text(page("layout", "", built, ""), encoding="utf-8")
    cells = html.read_text(encoding="utf-8")
    assert 'data-value="0.3333333333333333"' in cells  # every digit kept for machines
    assert_tables_fit(html, "report-tables")


def test_progress_moves_within_sections(monkeypatch, tmp_path):
    # The sections report their parts; a step that takes minutes no longer sits at "0/7".
    calls: list[tuple[str, float, int]] = []
    monkeypatch.setattr(study, "normalize", _fake_normalize)
    monkeypatch.setattr(study, "certified_factors", lambda *args, **kwargs: None)
    config = StudyConfig.quick()
    ctx = sections.Context(config, Stage(tmp_path))
    ctx.tick = lambda detail, fraction: calls.append((detail, fraction, 1))
    study.factor_table(config, ctx.tick)
    fractions = [fraction for _, fraction, _ in calls]
    assert len(calls) == 2 * len(study.SEED_LOBES) + 1 and fractions == sorted(fractions)
    assert 0.0 <= fractions[0] and fractions[-1] < 1.0 and not math.isclose(fractions[1], fractions[0])


def _fake_normalize(model, at, sweep, **kwargs):
    n = np.asarray(sweep["n"], dtype=float)
    ones = np.ones((n.size, 1, 1))
    return type("Result", (), {"factor": ones, "albedo": ones, "error": 1e-12 * ones, "theta": np.zeros((n.size, 1))})


def test_report_prints_one_line_per_section_when_not_a_terminal(monkeypatch, run_cli):
    import brdfnorm.report

    def fake(output, models, sweep=None, on_step=None, audit=()):
        for i, description in enumerate(["one", "two"]):
            on_step(description, i, 2)
            for k in range(3):
                on_step(description + ": part", i + k / 3, 2)
        on_step("done", 2, 2)
        return f"{output}/index.html"

    monkeypatch.setattr(brdfnorm.report, "build_report", fake)
    code, out, err = run_cli("report", "-o", "somewhere")
    assert code == 0 and out == "", err
    lines = err.splitlines()
    assert [line.split(" (")[0] for line in lines[:-1]] == ["report [1/2] one", "report [2/2] two"], lines
    assert lines[-1] == "wrote somewhere/index.html"


def test_one_folklore_argmax_quoted_everywhere(tmp_path, monkeypatch):
    import mpmath as mp

    from brdfnorm.claims.seed000 import blinn_phong_folklore
    from brdfnorm.models import closed_forms

    with mp.workdps(30):  # the root of d/dn of (n+8)(2^(−n/2)+n)/((n+2)(n+4)) − 1: an independent argmax
        g = lambda n: (n + 8) * (2 ** (-n / 2) + n) / ((n + 2) * (n + 4)) - 1  # noqa: E731
        true_n = float(mp.findroot(lambda n: mp.diff(g, n), 8.7))
    worst_n, worst_error = closed_forms.blinn_phong_folklore_worst()
    assert abs(worst_n - true_n) < 1e-6 and abs(worst_error - 0.0752011614585) < 1e-12
    quoted = f"n = {true_n:.4g}"  # 8.764, in the findings, the figure and the claims table alike
    assert quoted in blinn_phong_folklore(np.array([1.0, 10.0, 100.0, 512.0])).detail
    config = StudyConfig.quick()
    ctx = sections.Context(config, Stage(tmp_path))
    ctx.results["factors"] = _wide_factor_table(config)
    texts = []
    monkeypatch.setattr("matplotlib.axes.Axes.annotate", lambda self, text, *a, **k: texts.append(text))
    sections.folklore_section(ctx)
    assert any(quoted in finding for finding in ctx.findings), ctx.findings
    assert any(quoted in text for text in texts), texts
