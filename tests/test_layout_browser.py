"""How large the exhibits are on a 1280 x 800 page in headless Chromium, as a lecture hall sees it.

The camera each view leaves the page with is read back from the browser (viser reports it to
the server) and the exhibit's box is projected through it onto the page: home shows all three
left of the panel (measured in the page: the panel's left edge), staggered down the page so
that together they span more of its height (45 %) and none is below 26 % of it (each stage is
measured in ``test_stage_browser``). Presentation mode collapses the panel, frames the exhibit
to 75 % of the height (or 90 % of the width) and draws its words at least 28 pixels high
(measured on the screenshot: the height of the dark ink of each line of the stage's label).
"""

from __future__ import annotations

import browser
import numpy as np
import pytest
from waiting import scaled, wait_until

from mechviz.viz.model.commands import Set

pytestmark = pytest.mark.browser

PAGE = (1280, 800)


@pytest.fixture(scope="module")
def viewer():
    with browser.open_viewer(*PAGE) as (app, page):
        yield app, page


def _camera(app, view):
    """The browser's camera once it looks where preset ``view`` puts it (a look-at point: the
    one it has now), for the page size the client reports now, which the app framed it for
    (the browser draws a loaded page smaller): (position, look_at, fov)."""
    from mechviz.viz.views import page_size

    client = next(iter(app.server.get_clients().values()))

    def target():
        if not isinstance(view, str):
            return np.asarray(view, float)
        return app.camera_preset(view, *page_size(client))[1]

    def arrived():
        cam = client.camera
        return np.allclose(cam.look_at, target(), atol=1e-3) and cam

    try:
        cam = wait_until(arrived, 20, f"the camera to look where {view!r} puts it")
    except TimeoutError as exc:
        raise TimeoutError(
            f"{exc}: {target()} for a page of {page_size(client)}; it looks at "
            f"{client.camera.look_at}"
        ) from None
    assert cam.image_width * PAGE[1] == cam.image_height * PAGE[0]  # drawn at some scale of it
    return np.array(cam.position), np.array(cam.look_at), float(cam.fov)


def _panel_left(page) -> float:
    return page.get_by_role("button", name="Pause").bounding_box()["x"] - 20


def test_home_shows_the_three_left_of_the_panel_down_the_page(viewer):
    from mechviz.viz.scene import framing

    app, page = viewer
    page.get_by_role("button", name="Home", exact=True).click()
    free = _panel_left(page)
    position, target, fov = _camera(app, "Home")
    shares, spans = {}, []
    for key, ex in app.exhibits.items():
        share, x0, x1, y0, y1 = framing.share(*ex.home_bounds, position, target, *PAGE, fov)
        assert 0 <= x0 and x1 <= free and 0 <= y0 and y1 <= PAGE[1], key
        shares[key] = share
        spans.append((y0, y1))
    union = (max(y for _, y in spans) - min(y for y, _ in spans)) / PAGE[1]
    # three round-ish exhibits in a 940 x 800 part of the page cannot each be large: staggered
    # in depth, seen from above the front left, they go down the page as well as across it
    print(f"home: {', '.join(f'{k} {s:.1%}' for k, s in shares.items())}; union {union:.1%}")
    assert union >= 0.45, f"home's exhibits span {union:.0%} of the height"
    assert min(shares.values()) >= 0.26, shares


@pytest.mark.parametrize("mode", ["driven", "released"])
def test_no_two_labels_overlap_on_the_page_at_any_preset(viewer, mode):
    """The labels' boxes and the chaos map's on the page, for the camera the browser has at
    each preset: none overlaps another in the part of the page left of the panel, while the
    disk turns (driven) or tumbles (released, with the Poinsot picture's names)."""
    import screen

    from mechviz.viz.scene import atlas_map

    app, page = viewer
    app.enqueue("disk", Set(fields={"mode": mode}))
    wait_until(lambda: app.exhibits["disk"].model.config.mode == mode, 15, f"the {mode} disk")
    free = _panel_left(page)
    names = set()
    for view in ("Home", "Cyclotron", "Disk", "Hoop", "Top"):
        if view == "Top":  # looking down on the cyclotron's stage
            page.get_by_role("button", name="Cyclotron", exact=True).click()
            wait_until(lambda: app.stage == "cyclotron", 15, "the cyclotron's stage")
        page.get_by_role("button", name=view, exact=True).click()
        position, target, _ = _camera(app, view)
        t0 = app.exhibits["disk"].model.t
        for _ in range(4):  # over a second of the motion: the moving labels move
            camera = (position, target)
            boxes = [
                b
                for b in screen.label_boxes(app.scene_nodes(), camera, *PAGE)
                + screen.image_boxes(app.scene_nodes(), camera, *PAGE)
                if b.x0 < free and b.y0 < PAGE[1]
            ]
            assert not screen.overlapping(boxes), (view, app.exhibits["disk"].model.t)
            names |= {b.text for b in boxes}
            wait_until(
                lambda t=app.exhibits["disk"].model.t: app.exhibits["disk"].model.t > t + 0.3,
                15,
                "time",
            )
        assert app.exhibits["disk"].model.t > t0
    expected = {
        "mode 1",
        "mode 2",
        atlas_map.MAP_AND_SQUARE_TITLE,
        "image /hoop/chaos_map",
    }
    if mode == "released":
        expected.add("Poinsot: inertia ellipsoid + polhode,\ninvariable plane (⊥ L) + herpolhode")
    assert expected <= names, expected - names
    assert any("\nprincipal moments about" in t for t in names)


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


def test_presentation_mode_collapses_the_panel_and_draws_the_key_figures_large(viewer):
    from mechviz.viz.scene import framing

    app, page = viewer
    page.get_by_role("combobox", name="Present").click()
    page.get_by_role("option", name="Hoop", exact=True).click()
    wait_until(lambda: app.presenting == "hoop", 15, "presentation mode")
    page.get_by_role("button", name="Pause").wait_for(state="hidden", timeout=scaled(15) * 1000)
    label = app.stage_label
    wait_until(lambda: "ω1" in label.text, 15, "the key figures")
    client = next(iter(app.server.get_clients().values()))
    wait_until(
        lambda: np.allclose(client.camera.look_at, app.framed[client.client_id][1], atol=1e-3),
        15,
        "the presentation camera",
    )
    position, target, fov = _camera(app, client.camera.look_at)
    share, x0, x1, *_ = framing.share(*app.exhibits["hoop"].bounds, position, target, *PAGE, fov)
    assert share >= 0.75 or x1 - x0 >= 0.9 * PAGE[0], f"presented: {share:.0%} of the height"
    lines = len(label.text.split("\n"))

    def drawn():
        # the stage's words stand right of the exhibit, below the minimized panel's title bar
        # (its "Connected" is ink too, so the band starts under it)
        img = browser.screenshot_array(page)
        img = img[60 : 60 + 60 * lines, int(0.68 * img.shape[1]) :]
        heights = _ink_lines(img)
        return len(heights) >= lines and heights

    heights = wait_until(drawn, 30, "the key figures on the page", poll_s=0.5)
    # the tallest ink of a line ("(", "ω", digits) is about the font's size
    assert max(heights) >= 28, heights
    print(f"key figures: ink heights {heights} px; presented exhibit {share:.0%} of the height")
    page.get_by_role("button", name="Leave presentation (Esc)").click()
    page.get_by_role("button", name="Pause").wait_for(timeout=scaled(15) * 1000)
    wait_until(lambda: app.presenting is None and app.stage is None, 15, "home again")


def _red_pixels(page) -> int:
    """Pixels of the energy-error line (red) in the visible tab's chart."""
    import io

    from PIL import Image

    # The client mounts the chart anew as its data change, so no element handle lasts: the
    # visible chart is found, scrolled into the panel's view and measured in one call, and the
    # page's picture cropped there (a new chart takes the old one's place).
    box = page.evaluate(
        """() => {
            const u = [...document.querySelectorAll('.uplot')].find(e => e.offsetParent);
            if (!u) return null;
            u.scrollIntoView({block: 'center'});
            const r = u.getBoundingClientRect();
            return [r.left, r.top, r.width, r.height];
        }"""
    )
    if not box or box[2] < 10 or box[3] < 10:
        return 0
    x, y, w, h = (int(round(v)) for v in box)
    img = np.asarray(Image.open(io.BytesIO(page.screenshot())))[
        max(y, 0) : y + h, max(x, 0) : x + w
    ]
    img = img[..., :3].astype(int)
    return int(((img[..., 0] > 150) & (img[..., 1] < 110) & (img[..., 2] < 110)).sum())


def test_a_chart_keeps_its_history_when_the_window_changes(viewer):
    app, page = viewer
    hoop = app.exhibits["hoop"].model
    page.get_by_role("tab", name="Hoop").click()
    wait_until(lambda: np.ptp(hoop.chart_data()[0]) >= 8.0, 60, "ten seconds of chart")
    wait_until(lambda: _red_pixels(page) > 50, 30, "the error line", poll_s=0.5)
    first = hoop.chart_data()[0][0]
    page.get_by_role("combobox", name="Chart window").click()
    page.get_by_role("option", name="10 min", exact=True).click()
    wait_until(lambda: app.chart_window == 600.0, 15, "the 10-minute window")
    t = hoop.chart_data()[0]
    assert t[0] <= first  # nothing thrown away: the points of the 10 s window are still there
    # what the page's chart is given starts there too, and its line is drawn (short: ten
    # seconds of a ten-minute axis)
    chart = app.w["hoop.chart"]
    wait_until(lambda: chart.data[0][0] <= first, 15, "the chart to be given the long window")
    wait_until(lambda: _red_pixels(page) > 5, 30, "the error line in the long window", poll_s=0.5)
    page.get_by_role("combobox", name="Chart window").click()
    page.get_by_role("option", name="10 s", exact=True).click()
    wait_until(lambda: app.chart_window == 10.0, 15, "the 10-second window")
