"""``brdfnorm report``: page content checked against independent routes, determinism, atomic output, CLI errors,
and a headless-Chromium render that every image loads.

Independent routes: the L = N albedo of each seed lobe is a 1-D integral (in t = cos θ) evaluated by mpmath at
30 digits — it shares nothing with the closed forms' derivation or with brdfnorm's 2-D hemisphere cubature.
"""

from __future__ import annotations

import filecmp
import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path

import mpmath as mp
import numpy as np
import pytest
from helpers.paths import EXAMPLES
from helpers.references import phong_like_reference

from brdfnorm import __version__
from brdfnorm.errors import OutputError
from brdfnorm.output.directories import MARKER
from brdfnorm.report import StudyConfig, build_report, sections, study

BRDFNORM = Path(sys.executable).parent / "brdfnorm"


# -- independent references -----------------------------------------------------------------------------------

def reference_albedo(lobe: str, n: float) -> mp.mpf:
    """E at L = N by a 1-D mpmath integral over t = cos θ of the light (or view) direction.

    phong: 2π∫t^n dt; modified: 2π∫t^(n+1) dt; Blinn-Phong: N·H = cos(θ/2) = √((1+t)/2), so
    2π∫((1+t)/2)^(n/2) t dt; Gaussian Blinn-Phong (seed 003): 2π∫exp(−((√((1+t)/2) − 1)/(c − 1))²) t dt with
    c = 0.04^(1/n). The integrands peak at t = 1; the interval is split at a few widths of the peak.
    """
    with mp.workdps(30):
        n = mp.mpf(n)
        if lobe == "phong":
            f = lambda t: t**n  # noqa: E731
            width = 1 / (n + 1)
        elif lobe == "modified-phong":
            f = lambda t: t ** (n + 1)  # noqa: E731
            width = 1 / (n + 2)
        elif lobe == "blinn-phong":
            f = lambda t: ((1 + t) / 2) ** (n / 2) * t  # noqa: E731
            width = 4 / (n + 2)
        else:
            c = mp.mpf("0.04") ** (1 / n)
            f = lambda t: mp.exp(-(((mp.sqrt((1 + t) / 2) - 1) / (c - 1)) ** 2)) * t  # noqa: E731
            width = 4 * (1 - c)
        points = sorted({mp.mpf(0), mp.mpf(1)} | {1 - k * width for k in (1, 3, 10, 30, 100) if k * width < 1})
        return 2 * mp.pi * mp.quad(f, points)


# -- parsing the page ---------------------------------------------------------------------------------------

class Page(HTMLParser):
    """Tables (by id: rows of (text, data-value) cells) and image sources of a report page."""

    def __init__(self, text: str) -> None:
        super().__init__()
        self.tables: dict[str, list[list[tuple[str, float | None]]]] = {}
        self.images: list[dict] = []
        self.section_ids: list[str] = []
        self._table: str | None = None
        self._row: list | None = None
        self._cell: list | None = None
        self._in_body = False
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "section":
            self.section_ids.append(attrs["id"])
        elif tag == "table":
            self._table = attrs.get("id", "")
            self.tables[self._table] = []
        elif tag == "tbody":
            self._in_body = True
        elif tag == "tr" and self._in_body:
            self._row = []
        elif tag == "td" and self._row is not None:
            value = attrs.get("data-value")
            self._cell = [[], None if value is None else float(value)]
        elif tag == "img":
            self.images.append(attrs)

    def handle_data(self, data):
        if self._cell is not None:
            self._cell[0].append(data)

    def handle_endtag(self, tag):
        if tag == "td" and self._cell is not None:
            self._row.append(("".join(self._cell[0]), self._cell[1]))
            self._cell = None
        elif tag == "tr" and self._row is not None:
            self.tables[self._table].append(self._row)
            self._row = None
        elif tag == "tbody":
            self._in_body = False


def shown(cell: tuple[str, float | None]) -> float:
    """The number as displayed (U+2212 minus back to ASCII)."""
    return float(cell[0].replace("−", "-").replace("%", "").strip())


# -- fixtures -------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def default_report(tmp_path_factory) -> Path:
    """The default study (what `make demo` writes), built once for the module."""
    out = tmp_path_factory.mktemp("default") / "report"
    build_report(out)
    return out


@pytest.fixture(scope="module")
def quick_report(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("quick") / "report"
    build_report(out, config=StudyConfig.quick())
    return out


# -- content ------------------------------------------------------------------------------------------------

@pytest.mark.slow
def test_default_study_sections_and_images(default_report):
    page = Page((default_report / "index.html").read_text(encoding="utf-8"))
    assert page.section_ids == ["factors", "albedo", "folklore", "fits", "polar", "microfacet", "verify"]
    sources = [image["src"] for image in page.images]
    assert sources == ["albedo.png", "folklore.png", "fits.png", "polar.png", "microfacet-e.png",
                       "microfacet-eavg.png", "microfacet-dfg.png", "microfacet-glass.png"]
    for image in page.images:
        data = (default_report / image["src"]).read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n"
        # The IHDR chunk: pixel size = display size × 1.5 (144 dpi shown at 96 CSS px per inch).
        width, height = int.from_bytes(data[16:20], "big"), int.from_bytes(data[20:24], "big")
        assert abs(width - 1.5 * int(image["width"])) <= 2 and abs(height - 1.5 * int(image["height"])) <= 2
        # The Software text chunk names brdfnorm's version, not matplotlib's (the bytes stay reproducible).
        assert b"Software\x00brdfnorm " + __version__.encode() in data and image["alt"]
    assert (default_report / MARKER).is_file()
    assert sorted(p.name for p in default_report.iterdir()) == sorted([MARKER, "index.html", *sources])


@pytest.mark.slow
def test_factor_table_matches_independent_integrals(default_report):
    """Every number of the factor table: closed form and quadrature against mpmath 1-D integrals."""
    page = Page((default_report / "index.html").read_text(encoding="utf-8"))
    rows = page.tables["factor-table"]
    assert [shown(row[0]) for row in rows] == list(StudyConfig().table_n)
    for row in rows:
        n = row[0][1]
        cells = iter(row[1:])
        for lobe in study.SEED_LOBES:
            reference = 1 / reference_albedo(lobe, n)
            if lobe in study.CLOSED_FORM_OF:
                closed, quad, diff = next(cells), next(cells), next(cells)
                assert float(abs(closed[1] / reference - 1)) < 1e-14, (lobe, n)
                assert diff[1] == quad[1] / closed[1] - 1.0
                assert abs(shown(diff) - diff[1]) <= 0.01 * abs(diff[1])
            else:
                quad, error = next(cells), next(cells)
                assert 0 < error[1] < 1e-11
            assert float(abs(quad[1] / reference - 1)) < 2e-12, (lobe, n)
            # The shown text is the value to 10 significant digits (so that the table fits the page; issue 43),
            # the data-value all of them.
            assert abs(shown(quad) / quad[1] - 1) < 1e-9
        assert next(cells, None) is None
    for row in page.tables["max-table"]:
        assert all(cell[1] == 0.0 for cell in row[1:])  # seed 000's premise: the albedo peaks at L = N


@pytest.mark.slow
def test_folklore_table(default_report):
    page = Page((default_report / "index.html").read_text(encoding="utf-8"))
    for n_cell, exact, quad, folk, error in page.tables["folklore-table"]:
        n = n_cell[1]
        reference = 1 / reference_albedo("blinn-phong", n)
        assert float(abs(exact[1] / reference - 1)) < 1e-14
        assert float(abs(quad[1] / reference - 1)) < 2e-12
        assert folk[1] == pytest.approx((n + 8) / (8 * np.pi), rel=1e-15)
        assert error[1] == pytest.approx(folk[1] / exact[1] - 1, rel=1e-12)
    # n = 8, near the worst case: (16/8π)/((10·12)/(8π(1/16 + 8))) − 1 = 16·8.0625/120 − 1 = 0.075 exactly.
    row = next(r for r in page.tables["folklore-table"] if r[0][1] == 8.0)
    assert row[4][1] == pytest.approx(0.075, rel=1e-13) and row[4][0] == "+7.50 %"


@pytest.mark.slow
def test_fit_table_reproduces_seed_003(default_report):
    page = Page((default_report / "index.html").read_text(encoding="utf-8"))
    rows = {row[0][0]: row for row in page.tables["fit-table"]}
    assert set(rows) == {"seed 003 line", "least-squares line", "hyperbola (minimax)", "auto fit (minimax)"}
    # The least-squares line through the exact factor at n = 1…512 gives back the seed's coefficients.
    c0, c1 = (float(v) for v in re.findall(r"[-+]?\d*\.\d+(?:e[-+]?\d+)?", rows["least-squares line"][1][0]))
    assert c0 == pytest.approx(0.17287429, rel=1e-6) and c1 == pytest.approx(0.01388682, rel=1e-6)
    # The seed line's largest error (at n = 1) against the independent integral at n = 1.
    exact = 1 / reference_albedo("blinn-phong-gaussian", 1.0)
    assert rows["seed 003 line"][2][1] == pytest.approx(float(abs((0.17287429 + 0.01388682) / exact - 1)),
                                                        rel=1e-9)
    assert rows["auto fit (minimax)"][2][1] < 1.1e-3  # fit's default target 1e-3 (on the subset), whole grid


@pytest.mark.slow
def test_verify_table(default_report):
    """Columns mean the same on every row: A (the seed's side), B (independent), |A − B| / |B| recomputed from
    them, the claimed relation (a claimed failure says by how much it fails), the criterion, the verdict, and each
    claim's explaining line under its statement."""
    from brdfnorm.claims import RELATIONS
    from brdfnorm.claims.verify import verify

    page = Page((default_report / "index.html").read_text(encoding="utf-8"))
    rows = page.tables["verify-table"]
    claims = verify()
    assert [row[0][0] for row in rows] == [claim.id for claim in claims]
    for row, claim in zip(rows, claims, strict=True):
        _, _, statement, relation, a, b, difference, criterion, verdict = row
        assert statement[0] == claim.statement + claim.detail  # the explaining line is in the cell
        assert relation[0] == RELATIONS[claim.relation] and criterion[0] == claim.criterion != ""
        assert a[1] == claim.formula_value and b[1] == claim.numeric_value
        assert difference[1] == pytest.approx(abs(a[1] - b[1]) / abs(b[1]), rel=1e-12, abs=1e-300)
        assert verdict[0] == ("✔ confirmed" if claim.ok else "✘ refuted")
    by_id = {row[0][0]: row for row in rows}
    # The negative claims read as failures, with the size of the failure in the difference column.
    stokes = by_id["stokes-z-cubed-fails"]
    assert stokes[3][0].startswith("A ≠ B") and stokes[6][1] == pytest.approx(1.0)
    small_n = by_id["gaussian-fit-small-n-error"]
    assert small_n[3][0].startswith("A ≠ B") and small_n[6][1] == pytest.approx(0.42, abs=0.01)
    assert by_id["gaussian-hyperbola-beats-line"][3][0] == "A < B"
    # A difference is never shown as 0 beside values that differ (issue 31: 0.00 beside a 1.4e-7 difference).
    for row in rows:
        if row[4][1] != row[5][1]:
            assert row[6][1] > 0 and float(row[6][0]) > 0


@pytest.mark.slow
def test_furnace_residual_is_integrated(monkeypatch):
    """The Kulla–Conty furnace residual comes from integrating the compensated lobe: with exact tables it is
    not 0 by construction but the integration error (small, nonzero), and for 16×16 tables it agrees with the
    engine's adaptive hemisphere cubature of the whole lobe (method="quadrature", a second route)."""
    from brdfnorm import albedo, load
    from brdfnorm.report import microfacet

    monkeypatch.setattr(microfacet, "FURNACE_ALPHAS", (0.5,))
    residuals = microfacet.furnace_residuals(quick=True)
    value, error = residuals[0]
    assert 0.0 < value < 1e-6 and 0.0 < error
    mu = microfacet.grid_values(0.05, 1.0, 4)
    total = albedo(load("ggx", ms="kulla-conty", ms_table=16.0, alpha=0.5), np.arccos(mu), method="quadrature",
                   rtol=1e-7).value[..., 0]
    assert residuals[16][0] == pytest.approx(float(np.max(np.abs(1.0 - total))), rel=1e-4)
    assert residuals[16][0] > 1e-4


def test_microfacet_loss_sentence_names_its_numbers():
    """"loses up to X %" is the max over (μ, α) of 1 − E; 1 − E_avg is named as the average (issue 31: 68.2 %
    beside E_avg = 0.416)."""
    from brdfnorm.report.microfacet import loss_sentence

    mu, alpha = np.array([0.0, 0.5, 1.0]), np.array([0.5, 1.0])
    lut = {"1-E": np.array([[0.3, 0.682], [0.1, 0.2], [0.01, 0.05]]), "E_avg": np.array([0.8, 0.416])}
    sentence = loss_sentence(mu, alpha, lut)
    assert "up to 68.2 % of the energy at one view (max over μ of 1 − E(μ, α), at μ = 0, α = 1)" in sentence
    assert "58.4 % averaged over views (1 − E_avg, E_avg = 0.4160 at α = 1)" in sentence


@pytest.mark.slow
def test_grazing_table_against_independent_integrals(quick_report):
    """The "energy kept" cells are E(θ_o)/E(0) − 1; for the Phong lobes E(θ_o) has a 1-D integral (conftest)."""
    config = StudyConfig.quick()
    degrees = np.degrees(config.theta)
    picks = sorted({int(np.argmin(np.abs(degrees - g))) for g in sections.GRAZING})
    page = Page((quick_report / "index.html").read_text(encoding="utf-8"))
    checked = 0
    for row in page.tables["grazing-table"]:
        lobe, n = row[0][0], row[1][1]
        if lobe not in ("phong", "modified-phong"):
            continue
        original = lobe == "phong"
        normal = 2 * np.pi / (n + (1 if original else 2))
        for cell, i in zip(row[2:], picks, strict=True):
            reference = phong_like_reference(n, config.theta[i], original=original) / normal - 1
            assert cell[1] == pytest.approx(reference, abs=1e-7), (lobe, n, degrees[i])
            checked += 1
    assert checked == 2 * len(config.curve_n) * len(picks)


# -- determinism and atomicity ------------------------------------------------------------------------------

@pytest.mark.slow
def test_rebuild_is_byte_identical(quick_report, tmp_path):
    again = tmp_path / "again"
    build_report(again, config=StudyConfig.quick())
    names = sorted(p.name for p in quick_report.iterdir())
    assert names == sorted(p.name for p in again.iterdir())
    match, mismatch, errors = filecmp.cmpfiles(quick_report, again, names, shallow=False)
    assert mismatch == [] and errors == [] and match == names


@pytest.mark.slow
def test_failed_run_keeps_the_old_report(quick_report, tmp_path, monkeypatch):
    target = tmp_path / "report"
    shutil.copytree(quick_report, target)
    before = {p.name: p.read_bytes() for p in target.iterdir()}

    def broken(config, tick=None):
        raise FloatingPointError("simulated failure in the middle of the study")

    monkeypatch.setattr(study, "albedo_curves", broken)
    with pytest.raises(FloatingPointError):
        build_report(target, config=StudyConfig.quick())
    assert {p.name: p.read_bytes() for p in target.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]  # no staging directory left behind
    # And with no previous report, nothing at all is left.
    with pytest.raises(FloatingPointError):
        build_report(tmp_path / "fresh", config=StudyConfig.quick())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


@pytest.mark.slow
def test_replaces_a_previous_report_but_not_other_directories(quick_report, tmp_path):
    target = tmp_path / "report"
    shutil.copytree(quick_report, target)
    (target / "stale.png").write_bytes(b"old")
    build_report(target, config=StudyConfig.quick())
    assert not (target / "stale.png").exists() and (target / "index.html").is_file()
    precious = tmp_path / "notes"
    precious.mkdir()
    (precious / "keep.txt").write_text("mine")
    with pytest.raises(OutputError, match="not empty"):
        build_report(precious, config=StudyConfig.quick())
    assert (precious / "keep.txt").read_text() == "mine"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes", "report"]


# -- models and files ----------------------------------------------------------------------------------------

def test_model_study_of_a_builtin_over_a_sweep(tmp_path):
    out = tmp_path / "bp"
    build_report(out, ["blinn-phong"], sweep=("n", np.array([2.0, 50.0, 700.0])), config=StudyConfig.quick())
    page = Page((out / "index.html").read_text(encoding="utf-8"))
    rows = page.tables["model1-table"]
    assert [row[0][1] for row in rows] == [2.0, 50.0, 700.0]
    for row in rows:
        n = row[0][1]
        reference = 1 / reference_albedo("blinn-phong", n)
        # columns: n, E, factor at N, closed-form factor, relative difference, θmax, φmax, factor at max, excess
        assert float(abs(row[2][1] / reference - 1)) < 1e-8
        assert float(abs(row[3][1] / reference - 1)) < 1e-14
        assert row[5][1] == 0.0 and row[6][0] == "—" and row[8][0] == "at L = N"
        assert row[7][1] == pytest.approx(row[2][1], rel=1e-6)
    assert [image["src"] for image in page.images] == ["model1-factors.png", "model1-albedo.png",
                                                       "model1-polar.png"]


def test_brdf_file_study_over_its_first_float_parameter(tmp_path):
    """examples/lambert.brdf: its albedo is its reflectance at every angle, so every factor is 1/reflectance."""
    out = tmp_path / "lambert"
    build_report(out, [str(EXAMPLES / "lambert.brdf")], config=StudyConfig.quick())
    page = Page((out / "index.html").read_text(encoding="utf-8"))
    rows = page.tables["model1-table"]
    values = np.array([row[0][1] for row in rows])
    assert values.size == StudyConfig.quick().sweep_count
    assert values[0] == 0.0 and rows[0][2][0] == "∞"  # the slider range starts at a black surface
    for row in rows[1:]:
        rho = row[0][1]
        assert row[1][1] == pytest.approx(rho, rel=1e-8)
        assert row[2][1] == pytest.approx(1 / rho, rel=1e-8)
        assert row[5][1] == pytest.approx(1 / rho, rel=1e-6)  # factor at the maximum: the same
    assert len(page.images) == 3


# -- command line -------------------------------------------------------------------------------------------

def run_cli(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([str(BRDFNORM), "report", *args], capture_output=True, text=True, timeout=120,
                          cwd=cwd)


@pytest.mark.slow
@pytest.mark.parametrize("make_target", [
    lambda tmp: tmp / "missing" / "report",  # parent does not exist
    lambda tmp: (tmp / "file.txt").write_text("x") and tmp / "file.txt",  # a file, not a directory
])
def test_cli_bad_output_directory(tmp_path, make_target):
    target = make_target(tmp_path)
    result = run_cli("-o", str(target))
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(target) in lines[0]
    assert result.stdout == ""


@pytest.mark.slow
def test_cli_bad_sweep_and_model(tmp_path):
    result = run_cli("blinn-phong", "--sweep", "roughness=1,2", "-o", str(tmp_path / "r"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and "roughness" in result.stderr
    result = run_cli("no-such-lobe", "-o", str(tmp_path / "r"))
    assert result.returncode == 2 and result.stderr.count("\n") == 1 and "no-such-lobe" in result.stderr
    assert not (tmp_path / "r").exists()


def test_cli_writes_a_report(tmp_path):
    result = run_cli("modified-phong", "--sweep", "n=4,40", "-o", "out", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""  # messages for people: on stderr; not a terminal: one line per section, no bar
    lines = result.stderr.strip().splitlines()
    assert re.fullmatch(r"report \[1/1\] modified-phong: factors, albedo curves, polar plots \(\d+ s\)", lines[0])
    assert lines[1:] == [f"wrote {Path('out') / 'index.html'}"]
    page = Page((tmp_path / "out" / "index.html").read_text(encoding="utf-8"))
    for row in page.tables["model1-table"]:
        assert row[2][1] == pytest.approx((row[0][1] + 2) / (2 * np.pi), rel=1e-8)


# -- headless Chromium -----------------------------------------------------------------------------------------

PROBE = """<script>
window.addEventListener("load", () => {
  const out = document.createElement("pre");
  out.id = "image-probe";
  out.textContent = Array.from(document.images).map(
    (img) => `${img.getAttribute("src")} ${img.complete} ${img.naturalWidth} ${img.naturalHeight}`).join("\\n");
  document.body.appendChild(out);
});
</script>"""


@pytest.mark.slow
def test_every_image_loads_in_chromium(default_report, tmp_path):
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    if chromium is None:
        pytest.skip("chromium is not installed (Debian package 'chromium'); the page was not rendered")
    page_dir = tmp_path / "page"
    shutil.copytree(default_report, page_dir)
    index = page_dir / "index.html"
    index.write_text(index.read_text(encoding="utf-8").replace("</body>", PROBE + "</body>"), encoding="utf-8")
    command = [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
               "--disable-background-networking", "--disable-component-update", "--disable-sync",
               f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=5000", "--dump-dom",
               index.as_uri()]
    result = subprocess.run(command, capture_output=True, text=True, timeout=60,
                            env={**os.environ, "HOME": str(tmp_path)})
    assert result.returncode == 0, result.stderr[-2000:]
    probe = re.search(r'<pre id="image-probe">(.*?)</pre>', result.stdout, re.S)
    assert probe is not None, "the probe script did not run"
    lines = probe.group(1).strip().splitlines()
    expected = [image["src"] for image in Page(index.read_text(encoding="utf-8")).images]
    assert [line.split()[0] for line in lines] == expected and len(expected) == 8
    for line in lines:
        src, complete, width, height = line.split()
        assert complete == "true" and int(width) > 0 and int(height) > 0, line


@pytest.mark.slow
def test_tables_fit_the_page_in_chromium(default_report):
    # issue 43: the factor table was 1 394 px wide in the 1 240 px page
    from report.test_layout import assert_tables_fit

    assert_tables_fit(default_report / "index.html", "default-report")
