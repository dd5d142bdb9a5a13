"""brdfnorm explore in a real browser (Debian's Chromium driven by Playwright; no browser is downloaded).

The page's albedo readout must equal what ``brdfnorm albedo`` prints to the digits shown; saving the watched
file must bring new numbers; a syntax error must show FILE:LINE:COL without losing the plots. The screenshot
is kept at tests/artifacts/explore.png (ignored by git).
"""

from __future__ import annotations

import json
import shutil
from decimal import Decimal
from pathlib import Path

import pytest

pytest.importorskip("starlette", reason="the explore extra (starlette, uvicorn, watchfiles) is not installed")
playwright_api = pytest.importorskip("playwright.sync_api", reason="playwright (python package) is not installed")
CHROMIUM = "/usr/bin/chromium"
pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason=f"{CHROMIUM} is missing (Debian package chromium)")

from conftest import run_cli  # noqa: E402

from brdfnorm.explore import Catalog, background  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
ARTIFACTS = Path(__file__).resolve().parent / "artifacts"
BROWSER_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
                "--disable-component-update", "--disable-sync", "--no-first-run"]
TIMEOUT_MS = 60_000
REFINED = """([view]) => {
  const readout = document.querySelector('[data-testid=readout-albedo]');
  return readout.dataset.quality === 'fine' && readout.dataset.generation === document.body.dataset.generation
    && (view === null || Number(document.querySelector('[data-testid=view-angle-value]').value) === view);
}"""


@pytest.fixture(scope="module")
def watched(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("explore") / "ggx.brdf"
    shutil.copy(ROOT / "examples" / "ggx.brdf", path)
    return path


@pytest.fixture(scope="module")
def page(watched):
    with background(Catalog.build([str(watched)])) as url, playwright_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=BROWSER_ARGS)
        page = browser.new_page(viewport={"width": 1440, "height": 1280})
        errors: list[str] = []
        page.on("pageerror", lambda error: errors.append(str(error)))
        # The page's policy allows no eval: a script that needs it would be refused, and say so here.
        page.on("console", lambda message: errors.append(message.text)
                if "Content Security Policy" in message.text else None)
        page.goto(url)
        page.errors = errors
        yield page
        browser.close()


def refined(page, view: float | None = None) -> None:
    page.wait_for_function(REFINED, arg=[view], timeout=TIMEOUT_MS, polling=50)


def cli_albedo(capsys, path: Path, roughness: float | None, view: float, *params: str) -> float | list[float]:
    options = [*(["-p", f"roughness={roughness!r}"] if roughness is not None else []), *params]
    code, out, err = run_cli(capsys, "albedo", str(path), *options, "--theta", f"{view!r}", "--json")
    assert code == 0, err
    value = json.loads(out)["results"][0]["albedo"]
    return value[0] if isinstance(value, list) and len(set(value)) == 1 else value


def assert_shows(text: str, expected: float) -> None:
    """The readout's number equals ``expected`` to the digits shown (half a unit of the last one)."""
    number = text.split(" ± ")[0]
    unit = float(10.0 ** Decimal(number).as_tuple().exponent)
    assert abs(float(number) - expected) <= 0.5 * unit * (1 + 1e-9), (text, expected)
    assert unit <= 1e-9 * abs(expected), f"only {number} shown: the refined readout should carry ~10 digits"


@pytest.mark.slow
def test_page_follows_the_slider_and_the_file(page, watched, capsys):
    refined(page)
    assert page.get_by_test_id("plot-lobe").locator(".main-svg").count() > 0
    assert page.get_by_test_id("plot-albedo").locator(".main-svg").count() > 0
    assert page.get_by_test_id("plot-3d").locator("canvas, .main-svg").count() > 0
    for testid in ("readout-factor-normal", "readout-factor-max", "view-angle", "fit-code"):
        assert page.get_by_test_id(testid).count() == 1
    before = page.get_by_test_id("readout-albedo").inner_text()

    page.get_by_test_id("param-roughness").fill("0.55")
    refined(page)
    shown = page.get_by_test_id("readout-albedo").inner_text()
    assert shown != before
    assert_shows(shown, cli_albedo(capsys, watched, 0.55, 30.0))

    page.get_by_test_id("view-angle-value").fill("60")
    page.get_by_test_id("view-angle-value").press("Enter")
    refined(page, 60.0)
    assert_shows(page.get_by_test_id("readout-albedo").inner_text(), cli_albedo(capsys, watched, 0.55, 60.0))

    # Save the file with a halved lobe: the page reloads it, keeps roughness = 0.55, and shows the new numbers.
    text = watched.read_text()
    halved = text.replace("return vec3(D * G * F / (4.0 * NdotL * NdotV));",
                          "return vec3(0.5 * D * G * F / (4.0 * NdotL * NdotV));")
    assert halved != text
    watched.write_text(halved)
    expected = cli_albedo(capsys, watched, 0.55, 60.0)
    page.wait_for_function("""([expected]) => {
      const number = Number(document.querySelector('[data-testid=readout-albedo]').textContent.split(' ± ')[0]);
      return Math.abs(number - expected) < 1e-6 * expected;
    }""", arg=[expected], timeout=TIMEOUT_MS, polling=50)
    refined(page, 60.0)
    assert page.get_by_test_id("param-roughness-value").input_value() == "0.55"
    assert_shows(page.get_by_test_id("readout-albedo").inner_text(), expected)
    good = page.get_by_test_id("readout-albedo").inner_text()

    # A syntax error: the page names FILE:LINE:COL and keeps the last good numbers and plots.
    broken = halved.replace("float a2 = alpha * alpha;\n    float d", "float a2 = alpha * alpha\n    float d")
    watched.write_text(broken)
    error = page.get_by_test_id("error")
    error.wait_for(state="visible", timeout=TIMEOUT_MS)
    line = broken[: broken.index("float a2 = alpha * alpha\n")].count("\n") + 1
    message = error.inner_text()
    assert f"{watched}:" in message
    assert any(f"{watched}:{n}:" in message for n in (line, line + 1)), message
    assert page.get_by_test_id("readout-albedo").inner_text() == good
    assert page.get_by_test_id("plot-lobe").locator(".main-svg").count() > 0

    # Fixed again: the error goes away.
    watched.write_text(halved)
    error.wait_for(state="hidden", timeout=TIMEOUT_MS)
    refined(page, 60.0)
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "explore.png"), full_page=True)
    assert page.errors == []


def test_switches_and_colour_pickers(page, capsys):
    page.get_by_test_id("model-picker").select_option("example:blinn_phong_gaussian.brdf")
    switch = page.get_by_test_id("param-normalized")
    switch.wait_for(timeout=TIMEOUT_MS)
    assert switch.is_checked()
    switch.uncheck()
    refined(page)
    view = float(page.get_by_test_id("view-angle-value").input_value())
    path = ROOT / "examples" / "blinn_phong_gaussian.brdf"
    assert_shows(page.get_by_test_id("readout-albedo").inner_text(), cli_albedo(capsys, path, None, view,
                                                                                "-p", "normalized=0"))
    page.get_by_test_id("model-picker").select_option("example:disney_diffuse.brdf")
    picker = page.get_by_test_id("param-baseColor")
    picker.wait_for(timeout=TIMEOUT_MS)
    picker.fill("#336699")  # sRGB bytes / 255, taken as the linear values BRDF Explorer's sliders give
    refined(page)
    expected = cli_albedo(capsys, ROOT / "examples" / "disney_diffuse.brdf", None, view,
                          "-p", f"baseColor={0x33 / 255!r},{0x66 / 255!r},{0x99 / 255!r}")
    shown = page.get_by_test_id("readout-albedo").inner_text().split(" · ")
    assert [part.split()[0] for part in shown] == ["R", "G", "B"]
    for part, value in zip(shown, expected, strict=True):
        assert_shows(part.split(" ", 1)[1], value)


def test_fit_panel_and_model_picker(page):
    page.get_by_test_id("model-picker").select_option("arg0")
    page.get_by_test_id("fit-parameter").wait_for(timeout=TIMEOUT_MS)
    refined(page)
    page.get_by_test_id("fit-samples").fill("8")
    page.get_by_test_id("fit-run").click()
    code = page.get_by_test_id("fit-code")
    page.wait_for_function("() => document.querySelector('[data-testid=fit-code]').textContent.includes('return')",
                           timeout=TIMEOUT_MS)
    assert "float brdfnorm_ggx_norm(float roughness)" in code.inner_text()
    assert "max relative error" in page.get_by_test_id("fit-summary").inner_text()
    assert page.get_by_test_id("fit-copy").is_enabled()

    page.get_by_test_id("model-picker").select_option("builtin:blinn-phong")
    page.get_by_test_id("param-n").wait_for(timeout=TIMEOUT_MS)
    assert page.get_by_test_id("param-n-value").input_value() == "32"  # the model's default
    page.get_by_test_id("param-n-value").fill("-5")  # a hard limit: one line in the error box, page alive
    page.get_by_test_id("param-n-value").press("Enter")
    page.get_by_test_id("error").wait_for(state="visible", timeout=TIMEOUT_MS)
    assert "parameter n" in page.get_by_test_id("error").inner_text()
    page.get_by_test_id("param-n-value").fill("100")
    page.get_by_test_id("param-n-value").press("Enter")
    page.get_by_test_id("error").wait_for(state="hidden", timeout=TIMEOUT_MS)
    refined(page)
    assert page.errors == []


def test_energy_readout_is_brdfnorm_checks_verdict(page, capsys):
    """The page's energy readout is what ``brdfnorm check --only energy`` prints at the page's values: the
    verdict, max E to the digits shown (its error never smaller than the check's) and the direction."""
    path = ROOT / "examples" / "blinn_phong_gaussian.brdf"
    page.get_by_test_id("model-picker").select_option("example:blinn_phong_gaussian.brdf")
    page.get_by_test_id("param-normalized").wait_for(timeout=TIMEOUT_MS)
    page.get_by_test_id("param-n-value").fill("150")
    page.get_by_test_id("param-n-value").press("Enter")
    for normalized, status in ((True, "fail"), (False, "pass")):
        page.get_by_test_id("param-normalized").set_checked(normalized)
        refined(page)
        readout = page.get_by_test_id("readout-energy")
        assert readout.get_attribute("data-status") == status
        argv = ["check", str(path), "--only", "energy", "-p", "n=150.0", "-p", f"normalized={int(normalized)}",
                "--budget", "2e7evals"]
        assert page.get_by_test_id("readout-energy-command").inner_text() == "same as: brdfnorm " + " ".join(argv)
        code, out, err = run_cli(capsys, *argv, "--json")
        assert code == (1 if status == "fail" else 0), err
        cli = json.loads(out)["reports"][0]["checks"]["energy"]
        assert cli["status"] == status
        text = readout.inner_text()
        assert text.startswith(f"{status} — ")
        number, rest = text.split("max E = ", 1)[1].split(" ± ", 1)
        unit = Decimal(10) ** Decimal(number).as_tuple().exponent
        assert abs(Decimal(number) - Decimal(repr(cli["value"]))) <= unit / 2, (text, cli["value"])
        assert float(rest.split()[0]) >= cli["error_estimate"]
        assert f" at θ_o = {cli['theta_deg']:.4g}°" in text
    assert page.errors == []
