"""The sweep report in a real headless browser (Debian's chromium, driven by Playwright): it loads
without errors (plotly.js unpacked from its compressed copy), shows the 3D view and the plots, and
the slider's frames move the hose where the sweep put it."""

import os
from pathlib import Path

import numpy as np
import pytest
from sweep_cases import small_sweep_report, small_sweep_result  # noqa: F401 (fixtures)

from hoseline.report.sweep_figures import shown_poses
from hoseline.report.sweep_html import PLOTS_ID, VIEW_ID

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


HOSE = (f"document.getElementById('{VIEW_ID}')._fullData"
        ".find(function (t) { return t.name === 'hose (both ends clamped)'; })")


def test_report_loads_without_errors_and_shows_the_3d_view(small_sweep_report, small_sweep_result, tmp_path):
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
            page.wait_for_selector(f"#{PLOTS_ID} .main-svg", timeout=10000)
            page.locator(f"#{VIEW_ID}").screenshot(path=str(tmp_path / "view3d.png"))
            # a frame sends only the coordinates: the hose moves to that pose and keeps the rest (its hover data)
            lines = small_sweep_result.centerlines
            far = max(shown_poses(small_sweep_result), key=lambda k: np.abs(lines[k] - lines[0]).max())  # unlike pose 0
            middle = lines.shape[1] // 2
            page.evaluate(f"Plotly.animate('{VIEW_ID}', ['{far}'], {{mode: 'immediate', frame: {{duration: 0}}, "
                          "transition: {duration: 0}})")
            page.wait_for_function(f"Math.abs({HOSE}.z[{middle}] - {float(lines[far, middle, 2])}) < 1e-3",
                                   timeout=10000)
            shown = np.array(page.evaluate(f"[Array.from({HOSE}.x), Array.from({HOSE}.y), Array.from({HOSE}.z)]")).T
            np.testing.assert_allclose(shown, lines[far], atol=1e-3)  # single precision
            assert page.evaluate(f"{HOSE}.customdata.length") == small_sweep_result.s.size
        finally:
            browser.close()
    assert errors == []
