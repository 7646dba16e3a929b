"""The live viewer in headless Chromium (Debian's package, driven by playwright).

One app with its 60 Hz loop serves one page for the whole module; the tests run in order on it:
the home view draws the three exhibits, Pause stops simulated time, the method dropdown
changes the readout, an invalid parameter shows a notification. The last test switches the
environment lighting on and takes the README screenshot (saved to ``docs/img/viewer.png`` only by
``make screenshots``; ``make test`` keeps it in a temporary folder).
Skipped with the reason when no Chromium is found (a failure under MECHVIZ_REQUIRE_BROWSER=1).
"""

from __future__ import annotations

import browser
import numpy as np
import pytest
from playwright.sync_api import Error as PlaywrightError
from waiting import frames_later, scaled, wait_until

from mechviz.viz.app_commands import Present, Theme

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def viewer():
    with browser.open_viewer() as (app, page):
        yield app, page, None


def _hues(img: np.ndarray) -> dict[str, np.ndarray]:
    """x coordinates of the pixels of each exhibit's line colour (lines are blended at their
    edges, so pixels are classified by hue rather than matched exactly)."""
    img = img[:, : img.shape[1] - 350].astype(int)  # leave out the GUI panel docked on the right
    R, G, B = img[..., 0], img[..., 1], img[..., 2]
    masks = {
        "trail": (R > 190) & (G > 60) & (G < 175) & (B < 130) & (R - B > 110),  # orange
        "rim": (R < 130) & (G > 120) & (B > 130) & (np.abs(G - B) < 80) & (G - R > 60),  # cyan
        "bead": (R > 140) & (G < 120) & (B > 100) & (R - G > 80) & (B - G > 40),  # magenta
    }
    return {k: np.nonzero(m)[1] for k, m in masks.items()}


def _three_exhibits(img: np.ndarray) -> bool:
    xs = _hues(img)
    if min(len(v) for v in xs.values()) < 20:
        return False
    # the charge's trail (left) < the disk's rim (middle) < the bead's trail on the hoop (right)
    rim = xs["rim"].mean()
    return xs["trail"].mean() < rim and (xs["bead"] > rim + 150).sum() >= 15


def test_page_draws_the_three_exhibits_side_by_side(viewer):
    _, page, _ = viewer
    img = browser.wait_for_pixels(page, _three_exhibits, timeout_s=90)
    colours = len(np.unique(img.reshape(-1, 3), axis=0))
    assert colours > 1500, f"canvas looks blank ({colours} distinct colours)"


def test_pause_button_stops_simulated_time_and_play_resumes(viewer):
    app, page, _ = viewer
    page.get_by_role("button", name="Pause").click()
    page.get_by_role("button", name="Play").wait_for(timeout=scaled(10) * 1000)
    wait_until(lambda: not app.playing, 10, "the app to pause")
    frames_later(app, 1)  # a frame that began before the pause is over
    t0 = app.sim_time
    frames_later(app, 30)  # half a second of frames at 60 Hz, however long they take
    assert app.sim_time == t0
    page.get_by_text("paused", exact=False).first.wait_for(timeout=scaled(10) * 1000)
    page.get_by_role("button", name="Play").click()
    page.get_by_role("button", name="Pause").wait_for(timeout=scaled(10) * 1000)
    wait_until(lambda: app.sim_time > t0, 10, "simulated time to move on after Play")


def test_choosing_a_method_in_the_dropdown_changes_the_readout(viewer):
    app, page, _ = viewer
    page.get_by_role("tab", name="Hoop").click()
    readout = page.get_by_text("(dt=0.0166667 s)", exact=False).first
    readout.wait_for(timeout=scaled(10) * 1000)
    assert "rk4" in page.content()
    page.get_by_role("combobox", name="Method").click()
    page.get_by_role("option", name="verlet", exact=True).click()
    page.get_by_text("Stormer-Verlet", exact=False).first.wait_for(timeout=scaled(15) * 1000)
    wait_until(lambda: app.exhibits["hoop"].model.sim.method.name == "verlet", 15, "verlet to run")
    page.locator("code", has_text="verlet").first.wait_for(timeout=scaled(10) * 1000)


def _field(page, label: str):
    return browser.number_box(page, label)


def test_an_invalid_parameter_shows_a_notification_naming_the_field(viewer):
    app, page, _ = viewer
    page.get_by_role("tab", name="Hoop").click()
    sim = app.exhibits["hoop"].model.sim
    box = _field(page, "Gravity g")
    box.fill("-3")
    box.press("Enter")  # a number field is read on Enter
    page.get_by_role("alert").filter(has_text="Gravity g [m/s²] must lie between").first.wait_for(
        timeout=scaled(15) * 1000
    )
    assert app.exhibits["hoop"].model.sim is sim


def test_readme_screenshot_with_environment_lighting(viewer, tmp_path):
    app, page, _ = viewer
    app.enqueue("call", lambda a: a.server.scene.configure_environment_map(hdri="warehouse"))
    page.get_by_role("tab", name="Hoop").click()  # its chart has data
    for alert in page.get_by_role("alert").all():  # close notifications left by earlier tests
        try:
            alert.get_by_role("button").first.click(timeout=2_000)
        except PlaywrightError:
            pass  # it closed itself meanwhile (notifications auto-close)
    browser.wait_for_pixels(page, _three_exhibits, timeout_s=120)
    frames_later(app, 120)  # a couple more seconds of frames with the lighting settled
    screenshot = browser.picture_path("viewer.png", tmp_path)
    page.screenshot(path=str(screenshot), timeout=scaled(30) * 1000)
    assert screenshot.stat().st_size > 20_000


def test_readme_screenshot_of_presentation_mode(viewer, tmp_path):
    """The hoop presented alone (panel collapsed, key figures large), with the lighting of the
    screenshot before; saved as docs/img/viewer-present.png by ``make screenshots``."""
    app, page, _ = viewer
    app.enqueue("app", Present("Hoop"))
    try:
        wait_until(lambda: app.presenting == "hoop", 20, "presentation mode")
        page.get_by_role("button", name="Pause").wait_for(state="hidden", timeout=scaled(20) * 1000)
        frames_later(app, 120)  # the camera has moved and the figures are measured
        wait_until(lambda: "ω1" in app.stage_label.text, 20, "the key figures")
        # drawn: dark ink in the band above the exhibit (software WebGL draws slowly with the
        # lighting on), as many lines as the stage's words have
        label = app.stage_label

        def figures_drawn():
            img = browser.screenshot_array(page)
            # the stage's words stand right of the exhibit, below the minimized panel's title
            # bar (its "Connected" is ink too, so the band starts under it)
            lines = len(label.text.split("\n"))
            crop = img[60 : 60 + 60 * lines, int(0.68 * img.shape[1]) :].astype(int)
            rows = (crop.sum(axis=2) < 270).sum(axis=1) >= 2
            starts = np.flatnonzero(rows[1:] & ~rows[:-1])
            return len(starts) >= len(label.text.split("\n"))

        wait_until(figures_drawn, 90, "the key figures on the page", poll_s=1.0)
        screenshot = browser.picture_path("viewer-present.png", tmp_path)
        page.screenshot(path=str(screenshot), timeout=scaled(30) * 1000)
        assert screenshot.stat().st_size > 20_000
    finally:
        app.enqueue("app", Present("Off"))
        page.get_by_role("button", name="Pause").wait_for(timeout=scaled(20) * 1000)


def _chart_lines(page) -> tuple[int, int]:
    """Red and blue pixels (the energy-error and error lines) in the visible tab's chart; (0, 0)
    while no chart is laid out on the page. The chart is found, scrolled into view and measured
    in one call to the page: it is drawn anew when its time axis moves on (every quarter
    window), and a locator taken before that could point at a chart that is gone."""
    import io

    from PIL import Image

    box = page.evaluate(
        """() => new Promise(done => {
            const chart = [...document.querySelectorAll('.uplot')].find(
                e => e.getClientRects().length && e.getBoundingClientRect().width > 0);
            if (!chart) return done(null);
            // the readouts above it change height as they refresh, so playwright never sees
            // the chart "stable": scroll it into view from the page, then let it be painted
            chart.scrollIntoView({block: 'center'});
            requestAnimationFrame(() => requestAnimationFrame(() => {
                const r = chart.getBoundingClientRect();
                done({x: r.x, y: r.y, width: r.width, height: r.height});
            }));
        })"""
    )
    if not box or box["width"] < 20 or box["height"] < 20:
        return 0, 0
    try:
        png = page.screenshot(clip=box)
    except PlaywrightError:  # the page moved on while it was taken: count nothing this time
        return 0, 0
    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)
    red = (img[..., 0] > 150) & (img[..., 1] < 110) & (img[..., 2] < 110)
    blue = (img[..., 2] > 150) & (img[..., 0] < 120) & (img[..., 1] < 160)
    return int(red.sum()), int(blue.sum())


def test_a_chart_still_draws_its_lines_after_a_resize_and_three_tab_switches(viewer):
    app, page, _ = viewer
    page.get_by_role("tab", name="Hoop").click()
    hoop = app.exhibits["hoop"].model
    # an earlier test restarted the hoop: let its chart fill
    wait_until(lambda: np.ptp(hoop.history.t) >= 6.0, 30, "the hoop's chart to fill")
    wait_until(lambda: min(_chart_lines(page)) > 50, 30, "the chart's lines", poll_s=0.5)
    page.set_viewport_size({"width": 1440, "height": 900})  # as going full screen does
    for tab in ("Cyclotron", "Disk", "Hoop"):
        page.get_by_role("tab", name=tab).click()
        page.get_by_role("tab", name=tab, selected=True).wait_for(timeout=scaled(10) * 1000)
    lines_drawn = lambda: min(_chart_lines(page)) > 50  # noqa: E731
    wait_until(lines_drawn, 10, "the chart's lines after the switches", poll_s=0.5)
    page.set_viewport_size({"width": 1280, "height": 800})


def test_the_dark_theme_keeps_the_three_exhibits_visible(viewer, tmp_path):
    app, page, _ = viewer
    app.enqueue("app", Theme("dark"))
    try:
        img = browser.wait_for_pixels(page, _three_exhibits, timeout_s=90)
        assert np.median(img[:40, :400]) < 60  # the page behind the scene is dark
        screenshot = browser.picture_path("viewer-dark.png", tmp_path)
        page.screenshot(path=str(screenshot), timeout=scaled(30) * 1000)
    finally:
        app.enqueue("app", Theme("light"))
