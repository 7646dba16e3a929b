"""Numbers typed into the live viewer in headless Chromium, key by key, as a person types them.

A person types ``2.5e-2`` with pauses between the keys (looking up the next digit, talking to
the class) and presses Enter: exactly the number meant is applied, never a part of it, however
busy the machine; text that is not a number, or a number outside the field's range, brings a
notification naming the field and changes nothing. The box a person is typing in is never
rewritten under their fingers; once they move on it shows the value in force.

The long test enters 100 values into the speed, kick, step and mass boxes, each right after
another change (a kick, the beam, play/pause, the method), with two busy loops taking both
cores. Pauses between keys are drawn as 3 s x u^4 (u uniform in 0..1): every pause from 0 to
3 s occurs, but most are short (mean 0.6 s, one in ten over 2 s), to keep the run near ten
minutes on a machine with two free cores. The seed is printed; ``MECHVIZ_TYPING_SEED`` replays a
run, ``MECHVIZ_TYPING_ENTRIES`` sets how many entries (100).
"""

from __future__ import annotations

import contextlib
import os
import random
import subprocess
import sys
import time

import browser
import pytest
from waiting import wait_until

from mechviz.viz.model.commands import Set
from mechviz.viz.scene.fields import number_text

pytestmark = pytest.mark.browser

MAX_PAUSE = 3.0  # s between two keys at most


@pytest.fixture(scope="module")
def viewer():
    with browser.open_viewer() as (app, page):
        yield app, page


@contextlib.contextmanager
def busy_loops(n: int = 2):
    """``n`` processes spinning on a core each, stopped (by their own ids) on exit."""
    procs = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(n)]
    try:
        yield procs
    finally:
        for p in procs:
            p.kill()
        for p in procs:
            p.wait(timeout=30)


def _box(page, label: str):
    return browser.number_box(page, label, exact=True)  # each exhibit's tab has its own


def _close_notes(page) -> None:
    for note in page.get_by_role("alert").all():
        with contextlib.suppress(Exception):  # it may close on its own meanwhile
            if "Software WebGL" not in (note.text_content(timeout=500) or ""):
                note.get_by_role("button").first.click(timeout=1000)


def _type(page, text: str, pause) -> None:
    """Type ``text`` key by key, ``pause()`` seconds before each key and before Enter."""
    for ch in text:
        time.sleep(pause())
        page.keyboard.type(ch)
    time.sleep(pause())
    page.keyboard.press("Enter")


# ----------------------------------------------------------------------------- the boxes
CYC = "cyclotron"
BOXES = {  # name: (label, value in force, good texts, bad texts)
    "speed": (
        "Speed [×]",
        lambda app: app.speed,
        ["2.5", "0.5", "1e0", "3E-1", "7.25", "1.5e+0", ".75", "10", "0.1", "4"],
        ["abc", "20", "0.05", "-1", "1e", "2.5.", "−2", "nan"],
    ),
    "kick": (
        "Kick dv [m/s]",
        lambda app: app.exhibits[CYC].model.config.kick,
        ["-0.3", "−0.45", "2.5e-1", "-1E-1", ".75", "0.05", "1", "-1", "+0.4", "-.2"],
        ["1.5", "-2", "1e1", "-", "--3", "1.2.3", "e5", "0x10"],
    ),
    "dt": (
        "Step dt [s]",
        lambda app: app.exhibits[CYC].model.config.dt,
        ["0.02", "2.5e-2", "1E-2", "0.005", ".03", "5e-3", "0.0125", "4E-2"],
        # 1e4 s: longer than a turn of the charge at every mass entered (2 pi x 250 s at most)
        ["0", "-0.01", "1e4", "1e", "abc", "inf", "0.0.1"],
    ),
    "mass": (
        "Mass m [kg]",
        lambda app: app.exhibits[CYC].model.config.params["mass"],
        ["2", "0.5", "1.5e1", "3E+0", "250", "0.75", "1", "12.5"],
        ["0", "-1", "2000", "1e-4", "m", "1,5", "2e"],
    ),
}


def _plan(rng: random.Random, n: int) -> list[tuple[str, str, bool]]:
    """``n`` entries ``(box, text, good)``: about seven in ten good, each box in turn at random."""
    out = []
    for _ in range(n):
        box = rng.choice(tuple(BOXES))
        good = rng.random() < 0.7
        pool = BOXES[box][2] if good else BOXES[box][3]
        out.append((box, rng.choice(pool), good))
    return out


# ----------------------------------------------------------------------------- other changes
def _other_change(app, page, rng: random.Random) -> str:
    """Make one change elsewhere in the panel, as a person does before typing, and wait until
    the viewer has applied it; returns what it was."""
    ex = app.exhibits[CYC]
    what = rng.choice(("kick", "beam", "play", "method"))
    if what == "kick":
        motion = ex.model.motion
        page.get_by_role("button", name="Kick", exact=True).click()
        wait_until(lambda: app.exhibits[CYC].model.motion is not motion, 20, "the kick given")
    elif what == "beam":
        beam = ex.model.config.beam
        page.get_by_role("checkbox", name="Beam").click()
        wait_until(lambda: app.exhibits[CYC].model.config.beam != beam, 20, "the beam toggled")
    elif what == "play":
        playing = app.playing
        page.get_by_role("button", name="Pause" if playing else "Play", exact=True).click()
        wait_until(lambda: app.playing != playing, 20, "play/pause")
    else:
        method = "rk4" if ex.model.config.method == "boris" else "boris"
        page.get_by_role("combobox", name="Method", exact=True).click()
        page.get_by_role("option", name=method, exact=True).click()
        wait_until(lambda: app.exhibits[CYC].model.config.method == method, 20, f"method {method}")
    return what


# ----------------------------------------------------------------------------- the tests
def test_a_hundred_numbers_typed_key_by_key_under_load_are_each_applied_exactly_or_refused(viewer):
    app, page = viewer
    seed = int(os.environ.get("MECHVIZ_TYPING_SEED", random.randrange(2**31)))
    print(f"typing seed {seed} (MECHVIZ_TYPING_SEED={seed} replays it)")
    rng = random.Random(seed)

    def pause() -> float:
        return MAX_PAUSE * rng.random() ** 4

    app.enqueue(CYC, Set(fields={"method": "boris"}))  # a fixed step: the step box shows
    wait_until(lambda: app.exhibits[CYC].model.config.method == "boris", 20, "boris")
    page.get_by_role("tab", name="Cyclotron").click()
    seen: dict[str, list[float]] = {name: [] for name in BOXES}  # every value in force, in order

    def watch(a) -> None:
        for name, (_, value, _, _) in BOXES.items():
            v = value(a)
            if not seen[name] or seen[name][-1] != v:
                seen[name].append(v)

    app.frame_hooks.append(watch)
    entered: dict[str, list[float]] = {name: [] for name in BOXES}  # good values, in order
    misread = []
    plan = _plan(rng, int(os.environ.get("MECHVIZ_TYPING_ENTRIES", "100")))
    try:
        with busy_loops(2):
            for k, (name, text, good) in enumerate(plan):
                label, value, _, _ = BOXES[name]
                meant = float(text.replace("−", "-")) if good else None
                if good and value(app) == meant:  # the same again would show nothing
                    continue
                _other_change(app, page, rng)
                box = _box(page, label)
                # a person types into the box as they see it: showing the value in force
                wait_until(
                    lambda v=value, b=box: b.input_value() == number_text(v(app)),
                    20,
                    f"{label} to show the value in force",
                )
                old = value(app)
                n_messages = len(app.messages)
                box.click()
                box.press("Control+A")
                _type(page, text, pause)
                if good:
                    try:
                        wait_until(lambda m=meant, v=value: v(app) == m, 20, f"{label} = {text}")
                    except TimeoutError:
                        misread.append((k, label, text, value(app), app.messages[n_messages:]))
                        print(f"{k:3d} {label}: {text!r} MISREAD {misread[-1]}", flush=True)
                        continue
                    entered[name].append(meant)
                else:

                    def refused(n=n_messages, lab=label):
                        return any(
                            title.startswith("Invalid value") and body.startswith(lab)
                            for title, body in app.messages[n:]
                        )

                    try:
                        wait_until(refused, 20, f"{text!r} refused in {label}")
                    except TimeoutError:
                        misread.append((k, label, text, value(app), app.messages[n_messages:]))
                        continue
                    if value(app) != old:
                        misread.append((k, label, text, value(app), "changed although refused"))
                _close_notes(page)
                print(f"{k:3d} {label}: {text!r} {'applied' if good else 'refused'}", flush=True)
            # the last values shown by every frame: one more frame after the last entry
            frame = app.frame
            wait_until(lambda: app.frame > frame + 2, 20, "a frame")
    finally:
        app.frame_hooks.remove(watch)
    assert not misread, misread
    for name, values in entered.items():
        # the values in force, in order, were the start's and then exactly those entered: no
        # half-typed value was ever applied, not even for a frame
        assert seen[name][1:] == values, (name, seen[name], values)
    assert sum(len(v) for v in entered.values()) >= len(plan) // 2


def test_a_box_typed_in_keeps_its_text_and_shows_the_value_in_force_once_left(viewer):
    """Refused text stays in the box while the person is there (nothing is written under their
    fingers); touching another control puts the value in force back, and text left without
    Enter is not applied, with a notification saying so."""
    app, page = viewer
    # an earlier test may have left refused text in a box (kept while the person is there):
    # the person moves on first, as a click on any other control would
    app.typing.left()
    page.get_by_role("tab", name="Cyclotron").click()
    box = _box(page, "Kick dv [m/s]")
    kick = app.exhibits[CYC].model.config.kick
    wait_until(lambda: box.input_value() == number_text(kick), 20, "the kick shown")
    box.click()
    box.press("Control+A")
    n = len(app.messages)
    page.keyboard.type("1.2.3", delay=150)
    page.keyboard.press("Enter")
    wait_until(lambda: any("Kick dv" in b for _, b in app.messages[n:]), 20, "the refusal")
    frame = app.frame
    wait_until(lambda: app.frame > frame + 10, 20, "frames after the refusal")
    assert box.input_value() == "1.2.3\n"  # kept: the person may be about to correct it
    page.keyboard.type("0.35", delay=150)  # typed on, no Enter
    wait_until(lambda: app.w[f"{CYC}.kick"].value == "1.2.3\n0.35", 20, "the text at the server")
    n = len(app.messages)
    page.get_by_role("button", name="Kick", exact=True).click()  # moved on
    wait_until(lambda: box.input_value() == number_text(kick), 20, "the value in force back")
    assert app.exhibits[CYC].model.config.kick == kick
    assert any("not entered" in body for _, body in app.messages[n:]), app.messages[n:]
    _close_notes(page)


def test_a_stepper_moves_a_number_to_the_next_value_of_its_series(viewer):
    app, page = viewer
    page.get_by_role("tab", name="Cyclotron").click()
    ex = app.exhibits[CYC]
    app.enqueue(CYC, Set(params={"mass": 1.0}))
    wait_until(lambda: ex.model.config.params["mass"] == 1.0, 20, "mass 1")
    box = _box(page, "Mass m [kg]")
    stepper = box.locator("xpath=following::button[normalize-space()='+'][1]")
    stepper.click()
    wait_until(lambda: app.exhibits[CYC].model.config.params["mass"] == 2.0, 20, "mass 2")
    wait_until(lambda: box.input_value() == "2", 20, "the box to show 2")
    box.locator("xpath=following::button[normalize-space()='−'][1]").click()
    box.locator("xpath=following::button[normalize-space()='−'][1]").click()
    wait_until(lambda: app.exhibits[CYC].model.config.params["mass"] == 0.5, 20, "mass 0.5")
    wait_until(lambda: box.input_value() == "0.5", 20, "the box to show 0.5")
