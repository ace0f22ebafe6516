"""Calibration in the session, in a real browser: the panel's file control loads the
demo touches, the status lists the calibrated frames, the viewer draws the nominal and
the calibrated flange paths side by side, and "Use calibrated values" moves the
controls to the calibrated frames and re-plans."""

import pytest
from test_browser import TIMEOUT_MS, session, status  # noqa: F401  (the fixture)

from browser import WEBGL_ARGS, require_chromium
from conftest import CELLS

pytestmark = pytest.mark.slow
TOUCHES = CELLS / "calibration" / "seal_plate_kr16_touches.csv"


def test_touches_in_the_browser(session):  # noqa: F811
    pytest.importorskip("playwright.sync_api", reason="pip install playwright (the test extras)")
    from playwright.sync_api import expect, sync_playwright

    folder, cell, url, process = session
    port = int(url.split(":")[2].split("/")[0])
    with sync_playwright() as playwright:
        browser = playwright.chromium.launch(
            executable_path=require_chromium(), args=["--no-sandbox", *WEBGL_ARGS[:2]]
        )
        page = browser.new_page(viewport={"width": 1400, "height": 900})
        page.goto(url)
        expect(page.locator("#status")).to_have_class("feasible", timeout=TIMEOUT_MS)
        assert page.locator("#use-calibration").is_disabled()

        page.set_input_files("#touches", str(TOUCHES))
        lines = page.locator("#calibration-lines")
        expect(lines).to_contain_text("X_IT  tool tip [mm]", timeout=TIMEOUT_MS)
        expect(lines).to_contain_text("the planned path on the part moves up to")
        found = status(page)["calibration"]
        assert found["file"] == TOUCHES.name and not found["applied"]

        viewer = next(f for f in page.frames if f.url.startswith(f"http://localhost:{port + 1}"))
        viewer.wait_for_function("typeof viewer !== 'undefined'", timeout=TIMEOUT_MS)
        for name in ("nominal", "calibrated"):
            viewer.wait_for_function(
                "name => viewer.scene_tree.find(['session', 'calibration', name, 'path'])"
                ".object.children.length > 0",
                arg=name,
                timeout=TIMEOUT_MS,
            )

        page.click("#use-calibration")
        expect(page.locator("#use-calibration")).to_be_disabled(timeout=TIMEOUT_MS)
        now = status(page)
        assert now["calibration"]["applied"]
        assert now["values"]["X_IT.x"] != 1000.0  # the calibrated tool stand
        expect(page.locator("#status")).to_have_class("feasible", timeout=TIMEOUT_MS)
        browser.close()
    assert process.poll() is None
