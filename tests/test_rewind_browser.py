"""Pause, then scrub back, in the live viewer in headless Chromium, as a lecturer does: typed
into the Rewind box, the time on the page goes back by that much and the exhibits move back (the
canvas changes while the simulation stands still); Play goes on from the moment shown."""

from __future__ import annotations

import re

import browser
import numpy as np
import pytest
from waiting import scaled, wait_until

pytestmark = [pytest.mark.browser, pytest.mark.slow]


def _box(page, label: str):
    return browser.number_box(page, label)


def _page_time(page) -> float | None:
    """The simulated time the cyclotron's readout (the first tab's) shows on the page [s]."""
    shown = page.locator("strong:visible", has_text=re.compile(r"^t = [0-9.]+ s$")).first
    m = re.search(r"t = ([0-9.]+) s", shown.inner_text())
    return float(m.group(1)) if m else None


def test_pausing_and_scrubbing_back_moves_the_time_and_the_exhibits_back():
    with browser.open_viewer() as (app, page):
        wait_until(lambda: app.sim_time > 8.0, 120, "eight simulated seconds")
        page.get_by_role("button", name="Pause").click()
        page.get_by_role("button", name="Play").wait_for(timeout=scaled(15) * 1000)
        wait_until(lambda: not app.playing, 15, "the app to pause")
        t_paused, cyc = app.sim_time, app.exhibits["cyclotron"].model
        t_shown = cyc.t
        wait_until(lambda: _page_time(page) == round(t_shown, 2), 15, "the page's paused time")
        before = browser.screenshot_array(page)
        box = _box(page, "Rewind [s]")
        box.click()
        box.press("Control+A")
        page.keyboard.type("-5")
        box.press("Enter")  # at once: the Enter travels in the box's text, after the 5
        wait_until(
            lambda: (t := _page_time(page)) is not None and abs(t - (t_shown - 5.0)) < 0.05,
            15,
            "the page's time to go 5 s back",
        )
        assert not app.playing
        hoop = app.exhibits["hoop"].model
        assert hoop.scrubbed == pytest.approx(5.0, abs=0.02)
        # the hoop's readout on its tab says the same time
        page.get_by_role("tab", name="Hoop").click()
        page.locator("strong:visible", has_text=f"t = {hoop.t:.2f} s").first.wait_for(
            timeout=scaled(15) * 1000
        )

        def moved(img: np.ndarray) -> bool:
            changed = np.abs(img.astype(int) - before.astype(int)).max(axis=-1) > 40
            return int(changed.sum()) > 200

        browser.wait_for_pixels(page, moved, timeout_s=30)
        assert app.sim_time == t_paused  # nothing advanced: the exhibits were taken back
        # Play: on from the moment shown (the time of the first frame played, seen by a hook)
        resumed: list[float] = []
        app.frame_hooks.append(lambda a: a.playing and not resumed and resumed.append(a.sim_time))
        page.get_by_role("button", name="Play").click()
        wait_until(lambda: resumed, 15, "a frame played")
        assert resumed[0] == pytest.approx(t_paused - 5.0, abs=0.5)
        wait_until(lambda: box.input_value() == "0", 15, "the Rewind box back at 0")
