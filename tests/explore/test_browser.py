"""brdfnorm explore in a real browser (Debian's Chromium driven by Playwright; no browser is downloaded).

The page's albedo readout must equal what ``brdfnorm albedo`` prints to the digits shown; saving the watched
file must bring new numbers; a syntax error must show FILE:LINE:COL without losing the plots. The screenshot
is kept at tests/artifacts/explore.png (ignored by git).
"""

from __future__ import annotations

import json
import math
import shutil
from decimal import Decimal
from pathlib import Path

import pytest
from helpers.paths import ARTIFACTS, REPO

pytest.importorskip("starlette", reason="the explore extra (starlette, uvicorn, watchfiles) is not installed")
playwright_api = pytest.importorskip("playwright.sync_api", reason="playwright (python package) is not installed")
CHROMIUM = "/usr/bin/chromium"
pytestmark = pytest.mark.skipif(not Path(CHROMIUM).exists(), reason=f"{CHROMIUM} is missing (Debian package chromium)")



from brdfnorm.explore import Catalog, background  # noqa: E402

ROOT = REPO
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
def browser():
    with playwright_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=BROWSER_ARGS)
        yield browser
        browser.close()


def open_page(browser, url: str, width: int, height: int):
    """A page at ``url``; its script errors (and refusals by the page's policy) are collected in ``errors``."""
    page = browser.new_page(viewport={"width": width, "height": height})
    errors: list[str] = []
    page.on("pageerror", lambda error: errors.append(str(error)))
    # The page's policy allows no eval: a script that needs it would be refused, and say so here.
    page.on("console", lambda message: errors.append(message.text)
            if "Content Security Policy" in message.text else None)
    page.goto(url)
    page.errors = errors
    return page


@pytest.fixture(scope="module")
def page(watched, browser):
    with background(Catalog.build([str(watched)])) as url:
        page = open_page(browser, url, 1440, 1280)
        yield page
        page.close()


def refined(page, view: float | None = None) -> None:
    page.wait_for_function(REFINED, arg=[view], timeout=TIMEOUT_MS, polling=50)


def cli_albedo(run_cli, path: Path, roughness: float | None, view: float, *params: str) -> float | list[float]:
    options = [*(["-p", f"roughness={roughness!r}"] if roughness is not None else []), *params]
    code, out, err = run_cli("albedo", str(path), *options, "--theta", f"{view!r}", "--json")
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
def test_page_follows_the_slider_and_the_file(page, watched, run_cli):
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
    assert_shows(shown, cli_albedo(run_cli, watched, 0.55, 30.0))

    page.get_by_test_id("view-angle-value").fill("60")
    page.get_by_test_id("view-angle-value").press("Enter")
    refined(page, 60.0)
    assert_shows(page.get_by_test_id("readout-albedo").inner_text(), cli_albedo(run_cli, watched, 0.55, 60.0))

    # Save the file with a halved lobe: the page reloads it, keeps roughness = 0.55, and shows the new numbers.
    text = watched.read_text()
    halved = text.replace("return vec3(D * G * F / (4.0 * NdotL * NdotV));",
                          "return vec3(0.5 * D * G * F / (4.0 * NdotL * NdotV));")
    assert halved != text
    watched.write_text(halved)
    expected = cli_albedo(run_cli, watched, 0.55, 60.0)
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


def test_switches_and_colour_pickers(page, run_cli):
    page.get_by_test_id("model-picker").select_option("example:blinn_phong_gaussian.brdf")
    switch = page.get_by_test_id("param-normalized")
    switch.wait_for(timeout=TIMEOUT_MS)
    assert switch.is_checked()
    switch.uncheck()
    refined(page)
    view = float(page.get_by_test_id("view-angle-value").input_value())
    path = ROOT / "examples" / "blinn_phong_gaussian.brdf"
    assert_shows(page.get_by_test_id("readout-albedo").inner_text(), cli_albedo(run_cli, path, None, view,
                                                                                "-p", "normalized=0"))
    page.get_by_test_id("model-picker").select_option("example:disney_diffuse.brdf")
    picker = page.get_by_test_id("param-baseColor")
    picker.wait_for(timeout=TIMEOUT_MS)
    picker.fill("#336699")  # sRGB bytes / 255, taken as the linear values BRDF Explorer's sliders give
    refined(page)
    expected = cli_albedo(run_cli, ROOT / "examples" / "disney_diffuse.brdf", None, view,
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


def test_energy_readout_is_brdfnorm_checks_verdict(page, run_cli):
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
        code, out, err = run_cli(*argv, "--json")
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


# -- numbers per channel, withdrawn readouts, log scale, raw f, φ_o, the overlay, switches, 900 px ---------------

def select(page, model_id: str, probe: str) -> None:
    """Pick a model and wait for its controls (``probe``: a test id only that model's controls have)."""
    page.get_by_test_id("model-picker").select_option(model_id)
    page.get_by_test_id(probe).wait_for(timeout=TIMEOUT_MS)


def enter(page, testid: str, value: object) -> None:
    box = page.get_by_test_id(testid)
    box.fill(str(value))
    box.press("Enter")


def assert_channels(text: str, expected: list[float]) -> None:
    shown = text.split(" · ")
    assert [part.split()[0] for part in shown] == ["R", "G", "B"], text
    for part, value in zip(shown, expected, strict=True):
        assert_shows(part.split(" ", 1)[1], value)


def test_eta_k_f0_take_numbers_per_channel(page, run_cli):
    """η, k, f0 and f90 are three numeric inputs each (no colour picker): η = 1.33/1.5/1.7 can be set, and f0
    keeps all its digits (a colour picker would round 0.0123456789 to 3/255)."""
    select(page, "builtin:ggx", "param-eta-R")
    for name in ("eta", "k", "f0", "f90"):
        for c in "RGB":
            assert page.get_by_test_id(f"param-{name}-{c}").get_attribute("type") == "number"
    assert page.locator("#params input[type=color]").count() == 0
    assert "[0.001, 1000]" in page.locator(".control", has=page.get_by_test_id("param-eta-R")).inner_text()
    page.get_by_test_id("param-fresnel").select_option("dielectric")
    for c, eta in zip("RGB", ("1.33", "1.5", "1.7"), strict=True):
        enter(page, f"param-eta-{c}", eta)
    refined(page)
    view = float(page.get_by_test_id("view-angle-value").input_value())
    expected = cli_albedo(run_cli, "ggx", None, view, "-p", "fresnel=dielectric", "-p", "eta=1.33,1.5,1.7")
    assert_channels(page.get_by_test_id("readout-albedo").inner_text(), expected)

    page.get_by_test_id("param-fresnel").select_option("schlick")
    enter(page, "param-f0-R", "0.0123456789")
    refined(page)
    expected = cli_albedo(run_cli, "ggx", None, view, "-p", "fresnel=schlick", "-p", "f0=0.0123456789,0.04,0.04")
    assert_channels(page.get_by_test_id("readout-albedo").inner_text(), expected)
    assert page.get_by_test_id("param-f0-R").input_value() == "0.0123456789"
    page.get_by_test_id("param-fresnel").select_option("none")
    refined(page)
    assert page.errors == []


READOUT_IDS = ("readout-albedo", "readout-factor-normal", "readout-factor-max", "readout-factor-view",
               "readout-energy")


def test_an_input_error_withdraws_the_numbers_and_the_verdict(page):
    """After a refused input no number of the previous inputs stays on screen, nor the energy verdict."""
    select(page, "builtin:blinn-phong", "param-n-value")
    enter(page, "param-n-value", "64")
    refined(page)
    assert page.get_by_test_id("readout-energy").get_attribute("data-status") in ("pass", "fail", "inconclusive")
    enter(page, "param-n-value", "-5")
    page.get_by_test_id("error").wait_for(state="visible", timeout=TIMEOUT_MS)
    page.wait_for_function("() => document.querySelector('[data-testid=readout-albedo]').textContent === '—'",
                           timeout=TIMEOUT_MS, polling=50)
    for testid in READOUT_IDS:
        readout = page.get_by_test_id(testid)
        assert readout.inner_text() == "—", testid
        assert readout.get_attribute("data-value") is None and readout.get_attribute("data-quality") == "none"
    assert page.get_by_test_id("readout-energy").get_attribute("data-status") == "withdrawn"
    assert page.get_by_test_id("readout-energy-command").inner_text() == ""
    assert "refined" not in page.locator("#quality").inner_text()
    assert "refined" not in page.get_by_test_id("status").inner_text()
    assert page.get_by_test_id("plots").get_attribute("data-stale") == "true"
    enter(page, "param-n-value", "100")
    page.get_by_test_id("error").wait_for(state="hidden", timeout=TIMEOUT_MS)
    refined(page)
    assert page.get_by_test_id("readout-energy").get_attribute("data-status") in ("pass", "fail", "inconclusive")
    assert page.get_by_test_id("plots").get_attribute("data-stale") is None
    assert page.errors == []


LOBE_TRACES = """() => document.getElementById('plot-lobe').data.filter((t) => t.meta)
  .map((t) => ({ meta: t.meta, name: t.name, r: t.x.map((x, i) => x === null ? null : Math.hypot(x, t.y[i])) }))"""


CURRENT = """() => {
  const readout = document.querySelector('[data-testid=readout-albedo]');
  return readout.dataset.generation === document.body.dataset.generation && readout.dataset.quality !== 'none';
}"""


def test_log_scale_raw_f_and_view_azimuth(page, run_cli):
    """The raw f is drawn beside the normalized lobe; the log scale draws decades below the peak (a narrow
    lobe's tails show) and puts E on a log axis; φ_o turns V (an anisotropic lobe's albedo is the command
    line's at --phi)."""
    select(page, "builtin:ggx", "param-eta-R")
    enter(page, "param-alpha-value", "0.05")
    refined(page)
    data = page.evaluate("() => state.lastData")
    traces = {t["meta"]: t for t in page.evaluate(LOBE_TRACES)}
    assert set(traces) == {"normalized", "raw"}
    for meta, values in (("normalized", data["lobe"]["r"]), ("raw", data["lobe"]["raw"])):
        for drawn, value in zip(traces[meta]["r"], values, strict=True):
            assert abs(drawn - value) <= 1e-9 * max(values)
    page.get_by_test_id("raw-f").uncheck()
    assert page.get_by_test_id("raw-f-state").inner_text() == "off"
    assert {t["meta"] for t in page.evaluate(LOBE_TRACES)} == {"normalized"}

    page.get_by_test_id("log-scale").check()
    assert page.get_by_test_id("log-scale-state").inner_text() == "on"
    layout = page.evaluate("() => document.getElementById('plot-albedo').layout")
    assert layout["yaxis"]["type"] == layout["yaxis2"]["type"] == "log"
    r, t = data["lobe"]["r"], data["lobe"]["t_deg"]
    peak = max(r)
    drawn = {t["meta"]: t for t in page.evaluate(LOBE_TRACES)}["normalized"]["r"]
    for shown, value in zip(drawn, r, strict=True):
        decades = max(0.0, 5 + math.log10(value / peak)) if value > 0 else 0.0
        assert abs(shown - decades) <= 1e-9
    assert max(drawn) == pytest.approx(5.0)

    def span(radii: list[float], limit: float) -> float:  # degrees of the plane where the curve is drawn beyond limit
        inside = [angle for angle, radius in zip(t, radii, strict=True) if radius > limit]
        return max(inside) - min(inside)

    assert span(drawn, 0.1 * 5) > 3 * span(r, 0.1 * peak)  # the narrow lobe's shape and tails show
    page.get_by_test_id("log-scale").uncheck()
    page.get_by_test_id("raw-f").check()

    enter(page, "param-alpha-value", "0.5")
    refined(page)

    # φ_o = 90°: an anisotropic lobe seen along Y. Only the coarse pass is awaited: the refined pass's energy
    # check searches φ at length (~30 s here), and the next move cancels it.
    path = ROOT / "examples" / "ward_anisotropic.brdf"
    select(page, "example:ward_anisotropic.brdf", "param-rho_s-value")
    enter(page, "view-azimuth-value", "90")
    page.wait_for_function(CURRENT, timeout=TIMEOUT_MS, polling=50)
    data = page.evaluate("() => state.lastData")
    assert data["phi_deg"] == 90.0 and abs(data["surface"]["view"][0]) < 1e-12 and data["surface"]["view"][1] > 0
    view = float(page.get_by_test_id("view-angle-value").input_value())
    expected = cli_albedo(run_cli, path, None, view, "--phi", "90")
    readout = data["readouts"]["albedo"]
    assert abs(readout["value"][0] - expected) <= readout["error"][0] + 1e-9 * expected
    across = cli_albedo(run_cli, path, None, view, "--phi", "0")
    assert abs(across - expected) > 100 * readout["error"][0]  # φ_o matters here
    enter(page, "view-azimuth-value", "0")
    page.wait_for_function(CURRENT, timeout=TIMEOUT_MS, polling=50)
    assert page.errors == []


def test_a_second_lobe_is_overlaid_and_labelled(page, run_cli):
    select(page, "builtin:ggx", "param-eta-R")
    page.get_by_test_id("overlay-on").check()
    page.get_by_test_id("overlay-model").select_option("builtin:phong")
    page.get_by_test_id("overlay-param-n-value").wait_for(timeout=TIMEOUT_MS)
    enter(page, "overlay-param-n-value", "50")
    refined(page)
    names = page.evaluate("() => document.getElementById('plot-lobe').data.map((t) => t.name)")
    for name in ("α·f·(N·L): ggx", "α·f·(N·L): phong", "f: ggx", "f: phong"):
        assert name in names, names
    legend = page.get_by_test_id("plot-lobe").locator(".legendtext").evaluate_all(
        "(nodes) => nodes.map((n) => n.textContent)")
    assert "α·f·(N·L): ggx" in legend and "α·f·(N·L): phong" in legend
    albedo_names = page.evaluate("() => document.getElementById('plot-albedo').data.map((t) => t.name)")
    assert "E(θ_o): phong" in albedo_names
    text = page.get_by_test_id("readout-overlay").inner_text()
    assert text.startswith("phong: E(θ_o) = ")
    view = float(page.get_by_test_id("view-angle-value").input_value())
    shown = text.split("E(θ_o) = ", 1)[1].split(",", 1)[0]
    assert_shows(shown, cli_albedo(run_cli, "phong", None, view, "-p", "n=50"))
    page.get_by_test_id("overlay-on").uncheck()
    refined(page)
    names = page.evaluate("() => document.getElementById('plot-lobe').data.map((t) => t.name)")
    assert not any("phong" in name for name in names)
    assert page.get_by_test_id("readout-overlay").inner_text() == "—"
    assert page.errors == []


def test_switches_are_labelled_with_their_names_and_state(page):
    select(page, "example:blinn_phong_gaussian.brdf", "param-normalized")
    switch = page.get_by_role("switch", name="normalized")
    assert switch.count() == 1
    label = page.locator("label.switch", has=switch)
    assert "normalized" in label.inner_text()
    state = page.get_by_test_id("param-normalized-state")
    before = switch.is_checked()
    assert state.inner_text() == ("on" if before else "off")
    label.get_by_text("normalized", exact=True).click()  # the name is part of the switch
    assert switch.is_checked() != before
    assert state.inner_text() == ("off" if before else "on")
    refined(page)
    switch.set_checked(before)
    refined(page)
    for name in ("log scale", "raw f beside", "second lobe"):
        assert page.get_by_role("switch", name=name).count() == 1


@pytest.fixture(scope="module")
def narrow(browser):
    """The README's ``brdfnorm explore examples/ggx.brdf`` in a 900 × 800 window."""
    with background(Catalog.build([str(ROOT / "examples" / "ggx.brdf")])) as url:
        page = open_page(browser, url, 900, 800)
        yield page
        page.close()


def test_usable_at_900_px_and_each_model_listed_once(narrow):
    page = narrow
    page.wait_for_function(CURRENT, timeout=TIMEOUT_MS, polling=50)  # the layout, not the refined numbers
    options = page.eval_on_selector_all("#model option", "(os) => os.map((o) => o.textContent)")
    assert len(options) == len(set(options)), options
    assert sum(o.startswith("ggx.brdf") for o in options) == 1
    for model, probe in (("arg0", "param-roughness-value"), ("builtin:ggx", "param-eta-R")):
        select(page, model, probe)
        if model == "builtin:ggx":
            page.get_by_test_id("overlay-on").check()  # the second lobe's controls take room too
            page.locator("#overlay-params .control").first.wait_for(timeout=TIMEOUT_MS)
        page.wait_for_function(CURRENT, timeout=TIMEOUT_MS, polling=50)
        assert page.evaluate("() => document.documentElement.scrollWidth") <= 900
        assert page.evaluate("() => document.body.scrollWidth") <= 900
        for testid in ("model-picker", "convention", probe, "view-angle-value", "view-azimuth-value", "log-scale",
                       "raw-f", "status"):
            box = page.get_by_test_id(testid).bounding_box()
            assert box is not None and page.get_by_test_id(testid).is_visible(), testid
            assert box["x"] >= 0 and box["x"] + box["width"] <= 900 and box["y"] + box["height"] <= 800, (testid, box)
        lobe = page.get_by_test_id("plot-lobe").bounding_box()
        assert lobe["y"] < 800 and lobe["width"] >= 400 and lobe["x"] + lobe["width"] <= 900
    ARTIFACTS.mkdir(exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "explore-900.png"))
    assert page.errors == []
