"""Numbers typed into the live viewer in headless Chromium, key by key, as a person types them.

A person types ``2.5e-2`` with pauses between the keys (looking up the next digit, talking to
the class): nothing is applied until Enter, then exactly the number meant; text that is not a
number brings a notification naming the field, and the old value stays in force and in the box.
Checked on a text box (the hoop's step dt) and on a slider's box (the cyclotron's kick).
"""

from __future__ import annotations

import browser
import pytest
from waiting import scaled, wait_until

pytestmark = pytest.mark.browser

PAUSE_MS = 1500  # between two keys: longer than any "typing has stopped" delay a box might use
TYPED = [("2.5e-2", 0.025), ("1E-2", 0.01), ("1e-3", 0.001), ("abc", None)]


@pytest.fixture(scope="module")
def viewer():
    with browser.open_viewer() as (app, page):
        yield app, page


def _box(page, label: str):
    row = page.locator("label", has_text=label).first
    return row.locator("xpath=ancestor::div[.//input][1]//input").first


@pytest.mark.parametrize(
    ("tab", "key", "label", "value"),
    [
        ("Hoop", "hoop.dt", "Step dt [s]", lambda app: app.exhibits["hoop"].config.dt),
        (
            "Cyclotron",
            "cyclotron.kick",
            "Kick dv [m/s]",
            lambda app: app.exhibits["cyclotron"].config.kick,
        ),
    ],
    ids=["text box", "slider box"],
)
def test_a_number_typed_key_by_key_with_pauses_is_applied_whole_on_enter(
    viewer, tab, key, label, value
):
    app, page = viewer
    page.get_by_role("tab", name=tab).click()
    box = _box(page, label)
    box.wait_for(timeout=scaled(15) * 1000)
    seen: list[float] = []  # the value in force at every frame
    hook = lambda a: seen.append(value(a))  # noqa: E731
    app.frame_hooks.append(hook)
    try:
        for text, meant in TYPED:
            old = value(app)
            seen.clear()
            app.messages.clear()
            box.click()
            box.press("Control+A")
            page.keyboard.type(text, delay=PAUSE_MS)
            # the server has the whole text, after pauses longer than a second: nothing applied
            wait_until(lambda t=text: app.w[key].value == t, 15, f"{text!r} to reach the server")
            wait_until(lambda: len(seen) > 3, 15, "frames after the typing")
            assert set(seen) == {old}, f"applied while typing {text!r}: {sorted(set(seen))}"
            box.press("Enter")
            if meant is not None:
                wait_until(lambda m=meant: value(app) == m, 15, f"{label} = {meant}")
                assert set(seen) <= {old, meant}, sorted(set(seen))
                # the box shows the value in force
                wait_until(lambda m=meant: float(box.input_value()) == m, 15, "the box to show it")
            else:
                alert = page.get_by_role("alert").filter(has_text=f"{label} must be a number")
                alert.first.wait_for(timeout=scaled(15) * 1000)
                wait_until(lambda o=old: box.input_value() == f"{o:.6g}", 15, "the old value back")
                assert value(app) == old and set(seen) == {old}
            for note in page.get_by_role("alert").all():  # close what the step left
                if "Software WebGL" not in (note.text_content() or ""):
                    note.get_by_role("button").first.click()
    finally:
        app.frame_hooks.remove(hook)
