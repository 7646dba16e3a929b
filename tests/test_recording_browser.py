"""Recordings in a real browser: each demo's DEMO.html, opened from file:// in headless Chromium,
draws its scene (non-blank canvas) and shows viser's playback bar. The still of each demo taken
here goes to docs/img/demos/NAME.png for the README under ``make screenshots``, to a temporary
folder under ``make test``.

One Chromium serves every demo (pages are reloaded, not relaunched). SwiftShader draws the first
frame of a lit scene in 4-8 s on an idle machine, several times that
under load; locator clicks wait for animation frames, so the bar is driven with the mouse.
"""

from __future__ import annotations

import os

import browser
import numpy as np
import pytest
from waiting import scaled, wait_until

from mechviz.viz import record as rec

pytestmark = pytest.mark.browser

WIDTH, HEIGHT = 960, 600
DURATION = 4.0  # seconds of playback recorded per demo
SEEK = "3.5"  # where the still is taken [s]
# One demo per exhibit keeps `make test` inside CI's time budget (each lit scene costs tens of
# seconds in software WebGL); MECHVIZ_ALL_DEMOS=1 checks every demo and retakes every still.
DEMOS = (
    rec.demo_names()
    if os.environ.get("MECHVIZ_ALL_DEMOS") == "1"
    else [n for n in ("helix", "driven-disk", "hoop-mode1") if n in rec.demo_names()]
)


@pytest.fixture(scope="module")
def recordings(tmp_path_factory):
    browser.require_browser()
    out = tmp_path_factory.mktemp("html")
    for name in DEMOS:
        demo = rec.load_demo(name)
        # long enough for the demo's scripted events (a kick at t = 5 s) to be in the recording
        last = max((e.t / demo.speed for e in demo.events), default=0.0)
        rec.record(demo.with_overrides(duration=max(DURATION, last + 1.0)), out)
    return out


@pytest.fixture(scope="module")
def page(recordings):
    first = (recordings / f"{DEMOS[0]}.html").resolve().as_uri()
    with browser.open_page(first, width=WIDTH, height=HEIGHT, wait_connected=False) as pg:
        yield pg


def _drawn(img: np.ndarray) -> bool:
    """More than a background: many distinct colours and some pixels far from the corner's."""
    colours = len(np.unique(img[::2, ::2].reshape(-1, 3), axis=0))
    bg = img[2, 2].astype(int)
    far = (np.abs(img.astype(int) - bg).max(axis=-1) > 60).mean()
    return colours > 150 and far > 0.003


@pytest.mark.parametrize("name", DEMOS)
def test_demo_html_plays_from_file_url_with_its_playback_bar(recordings, page, name, tmp_path):
    page.goto((recordings / f"{name}.html").resolve().as_uri())
    page.wait_for_function("() => window.__VISER_EMBED_DATA__ !== undefined")
    browser.canvas(page).wait_for(timeout=scaled(60) * 1000)
    img = browser.wait_for_pixels(page, _drawn, timeout_s=120.0)
    assert _drawn(img)
    # The playback bar along the bottom: play/pause button, time box, scrubber, speed selector.
    time_box = page.get_by_role("textbox").first
    time_box.wait_for(timeout=30_000)
    assert page.get_by_role("combobox").count() >= 1
    t0 = float(time_box.input_value())
    page.mouse.click(22, HEIGHT - 20)  # pause
    alert = page.get_by_role("alert").filter(has_text="Software WebGL")
    if alert.count():
        alert.first.get_by_role("button").first.click(force=True, timeout=10_000)
    time_box.fill(SEEK)
    time_box.press("Enter")
    sought = float(SEEK)
    wait_until(
        lambda: float(time_box.input_value()) == pytest.approx(sought),
        10,
        "the seek to show in the time box (paused)",
    )
    assert t0 >= 0.0
    browser.wait_for_pixels(page, _drawn, timeout_s=60.0)
    still = browser.picture_path(f"demos/{name}.png", tmp_path)
    page.screenshot(path=str(still))
    assert still.stat().st_size > 5_000
