"""Test helper: the width of a report page's tables against their boxes in headless Chromium (moved from
tests/report/test_layout.py, issue 40 item 6)."""

from __future__ import annotations

from pathlib import Path

import pytest

from helpers.paths import ARTIFACTS

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
