"""One exhibit on stage at a time, in headless Chromium at 1280x800, 1920x1080 and 800x1000.

For each exhibit's stage, chosen with its button at the top of the panel: no node of another
exhibit is visible (their root frames are hidden, and every node an exhibit makes is under its
root); the exhibit's box, projected through the camera the browser reports, fills at least 75 %
of the page's height or 90 % of the width the panel leaves (at 800x1000: 50 % of the height);
every label is at least 3 % of the page's height (the size viser draws a label at, per unit of
scale, and the tallest line of ink of the stage's words measured on the screenshot). Home
shows the three again. Presenting is left by the Escape key.
"""

from __future__ import annotations

import browser
import numpy as np
import pytest
from waiting import scaled, wait_until

from mechviz.viz.app_commands import Present, Stage

pytestmark = pytest.mark.browser

SIZES = [(1280, 800), (1920, 1080), (800, 1000)]


@pytest.fixture(scope="module", params=SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
def viewer(request):
    with browser.open_viewer(*request.param) as (app, page):
        yield app, page, request.param


def _framed(app):
    """What the app last framed the page's camera for (to tell a new framing from it)."""
    client = next(iter(app.server.get_clients().values()))
    return app.framed.get(client.client_id)


def _arrived(app, before=None):
    """The browser's camera once it is where the app last framed it, a framing other than
    ``before`` (the one before the change): (position, look_at, fov)."""
    client = next(iter(app.server.get_clients().values()))

    def there():
        framed = app.framed.get(client.client_id)
        cam = client.camera
        return (
            framed is not None
            and framed is not before
            # both: a camera reported between the two would frame another view
            and np.allclose(cam.look_at, framed[1], atol=1e-3)
            and np.allclose(cam.position, framed[0], atol=1e-3)
            and cam
        )

    cam = wait_until(there, 30, "the camera to arrive where the stage frames it")
    return np.array(cam.position), np.array(cam.look_at), float(cam.fov)


def _panel_left(page, width: int) -> float:
    """Where the panel begins on the page (its width if the panel is minimized)."""
    button = page.get_by_role("button", name="Reset all")
    if not button.count() or not button.first.is_visible():  # minimized: no wait for it
        return width
    box = button.first.bounding_box()
    return width if box is None else box["x"] - 20


def _ink_lines(img: np.ndarray) -> list[int]:
    """Heights [px] of the runs of rows holding dark ink (the lines of a text)."""
    rows = (img.astype(int).sum(axis=2) < 3 * 90).sum(axis=1) >= 2
    heights, run = [], 0
    for dark in [*rows, False]:
        if dark:
            run += 1
        elif run:
            heights.append(run)
            run = 0
    return heights


@pytest.mark.parametrize("view", ["Cyclotron", "Disk", "Hoop"])
def test_each_stage_shows_its_exhibit_alone_large_with_words_for_a_hall(viewer, view, tmp_path):
    from mechviz.viz.scene import framing
    from mechviz.viz.views import LABEL_INK_PX, VIEWS

    app, page, (width, height) = viewer
    key = VIEWS[view]
    before = _framed(app)
    button = page.get_by_role("button", name=view, exact=True)
    if button.is_visible():
        button.click()
    else:  # a narrow page has its panel minimized on a stage: what the button sends
        app.enqueue("app", Stage(view))
    wait_until(lambda: app.stage == key, 15, f"the {view} stage")
    position, target, fov = _arrived(app, before)
    for other, ex in app.exhibits.items():
        root = ex.nodes[ex.root]
        assert root.visible == (other == key), other
        assert all(name.startswith(ex.root) for name in ex.nodes)
    # the box on the page, through the browser's own camera, for the page's CSS size
    share, x0, x1, y0, y1 = framing.share(
        *app.exhibits[key].bounds, position, target, width, height, fov
    )
    free = min(_panel_left(page, width), width)
    wide = (x1 - x0) / free
    print(f"{view} at {width}x{height}: height {share:.0%}, width {wide:.0%} of {free:.0f} px")
    if height > width:
        assert share >= 0.5, f"{share:.0%} of the height"
    else:
        assert share >= 0.75 or wide >= 0.9, f"{share:.0%} of the height, {wide:.0%} of the width"
    assert -1 <= x0 and x1 <= free + 1 and -1 <= y0 and y1 <= height + 1
    # every label of the scene that is shown: at least 3 % of the page's height
    shown = [h for h in app.exhibits[key].labels() if h.visible and h.text]
    shown.append(app.stage_label)
    sizes = [h.font_screen_scale * LABEL_INK_PX for h in shown]
    assert min(sizes) >= 0.03 * min(height, 1080), sizes
    # and the stage's words drawn so: the tallest line of ink in the band or column
    words = app.stage_label.text
    assert app.stage_label.visible and app.exhibits[key].model.title in words

    # the words' columns: beside the stage's chart where it stands beside them
    xy = framing.project(app.charts[key].world_corners(), position, target, width, height, fov)
    left, right = 0, int(free)
    if xy[:, 1].min() < height / 2:
        cx0, cx1 = xy[:, 0].min(), xy[:, 0].max()
        # the chart at the page's left edge has the words right of it, else left
        left, right = (0, int(cx0)) if cx0 > 0.1 * free else (int(cx1), int(free))

    def drawn():
        img = browser.screenshot_array(page)
        # runs of ink a line of text tall (the exhibit's own dark parts run taller)
        heights = [h for h in _ink_lines(img[: height // 2, left:right]) if h < 0.07 * height]
        lines = min(len(words.splitlines()), 3)
        return len(heights) >= lines and max(heights) >= 0.03 * height and heights

    heights = wait_until(drawn, 60, "the stage's words on the page", poll_s=0.5)
    print(f"  words' ink lines {heights} px; {len(words.splitlines())} lines")
    page.screenshot(path=str(tmp_path / f"stage-{view}-{width}x{height}.png"))


def test_home_shows_the_three_again(viewer):
    app, page, _ = viewer
    before = _framed(app)
    button = page.get_by_role("button", name="Home", exact=True)
    if button.is_visible():
        button.click()
    else:  # a narrow page has its panel minimized on a stage: what the button sends
        app.enqueue("app", Stage("Home"))
    wait_until(lambda: app.stage is None, 15, "home")
    _arrived(app, before)
    assert all(ex.nodes[ex.root].visible for ex in app.exhibits.values())
    assert not app.stage_label.visible


def test_escape_leaves_presentation_mode(viewer):
    app, page, (width, _) = viewer
    if width != 1280:
        pytest.skip("once is enough")
    app.enqueue("app", Present("Hoop"))
    wait_until(lambda: app.presenting == "hoop", 15, "presentation mode")
    button = page.get_by_role("button", name="Leave presentation (Esc)")
    button.wait_for(timeout=scaled(15) * 1000)
    browser.canvas(page).click(position={"x": 20, "y": 20})  # the scene has the focus
    page.keyboard.press("Escape")
    wait_until(lambda: app.presenting is None, 15, "Escape to leave presentation mode")
    assert app.stage is None


def test_a_page_that_changes_shape_is_framed_again(viewer):
    from mechviz.viz.scene import framing

    app, page, (width, height) = viewer
    if width != 1280:
        pytest.skip("once is enough")
    framed = _framed(app)
    page.get_by_role("button", name="Disk", exact=True).click()
    wait_until(lambda: app.stage == "disk", 15, "the disk's stage")
    before = _arrived(app, framed)
    try:
        page.set_viewport_size({"width": 1920, "height": 1080})  # as going full screen does
        client = next(iter(app.server.get_clients().values()))
        wait_until(
            lambda: not np.allclose(app.framed[client.client_id][1], before[1], atol=1e-3),
            30,
            "the stage framed for the new shape",
        )
        position, target, fov = _arrived(app)
        share, x0, x1, *_ = framing.share(
            *app.exhibits["disk"].bounds, position, target, 1920, 1080, fov
        )
        free = _panel_left(page, 1920)
        assert share >= 0.75 or x1 - x0 >= 0.9 * free, f"{share:.0%} after the resize"
    finally:
        page.set_viewport_size({"width": width, "height": height})
