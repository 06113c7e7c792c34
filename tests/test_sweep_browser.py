"""The sweep report in a real headless browser (Debian's chromium, driven by Playwright): it loads
without errors and shows the 3D view."""

import os
from pathlib import Path

import pytest
from sweep_cases import small_sweep_report, small_sweep_result  # noqa: F401 (fixtures)

from hoseline.report.sweep_html import VIEW_ID

CHROMIUM = "/usr/bin/chromium"
CHROMIUM_ARGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update",
    "--disable-sync", "--no-first-run",
]

# on CI (.ci/run installs chromium) a missing browser is a failure, locally a skip
pytestmark = pytest.mark.skipif(
    not Path(CHROMIUM).exists() and not os.environ.get("CI"),
    reason=f"{CHROMIUM} is not installed (Debian package 'chromium'; .ci/run installs it)",
)


def test_report_loads_without_errors_and_shows_the_3d_view(small_sweep_report, tmp_path):
    sync_api = pytest.importorskip("playwright.sync_api", reason="playwright is not installed (pip install playwright)")
    errors = []
    with sync_api.sync_playwright() as playwright:
        browser = playwright.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            page = browser.new_page(viewport={"width": 1280, "height": 900})
            page.on("pageerror", lambda error: errors.append(f"page error: {error}"))
            page.on("console", lambda message: errors.append(f"console: {message.text}") if message.type == "error" else None)
            page.goto((small_sweep_report / "report.html").as_uri())
            page.wait_for_selector(f"#{VIEW_ID} .gl-container canvas", timeout=30000)
            page.wait_for_selector(f"#{VIEW_ID} .slider-container", timeout=10000)
            assert page.locator(f"#{VIEW_ID} .gl-container canvas").first.bounding_box()["height"] > 300
            assert page.get_by_text("WebGL is not supported").count() == 0
            page.locator(f"#{VIEW_ID}").screenshot(path=str(tmp_path / "view3d.png"))
        finally:
            browser.close()
    assert errors == []
