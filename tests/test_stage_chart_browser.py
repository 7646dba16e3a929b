"""Each exhibit's chart on its stage, and Poinsot's construction large beside the released
disk, in headless Chromium at 1280x800 and 1920x1080.

For each stage: the exhibit's chart (:class:`mechviz.viz.scene.stage_chart.StageChart`) shows
there and nowhere else; its panel, projected through the camera the browser reports, lies in
the part of the page the panel leaves and apart from the exhibit's box; every label of it is at
least 3 % of the page's height; its last point is at the exhibit's time, also once Rewind has
taken the exhibit back. On the disk's stage, once released, Poinsot's picture (ellipsoid and
plane as drawn) is at least a third of the page's height, beside the disk's own box. A
screenshot of each stage is saved (``MECHVIZ_STAGE_SHOTS``: a directory to keep them in).
"""

from __future__ import annotations

import os
from pathlib import Path

import browser
import numpy as np
import pytest
from test_stage_browser import _arrived, _framed, _panel_left
from waiting import wait_until

from mechviz.viz.app_commands import Pause, Play, Scrub, Stage
from mechviz.viz.model.commands import Set

pytestmark = pytest.mark.browser

SIZES = [(1280, 800), (1920, 1080)]


@pytest.fixture(scope="module", params=SIZES, ids=lambda s: f"{s[0]}x{s[1]}")
def viewer(request):
    with browser.open_viewer(*request.param) as (app, page):
        yield app, page, request.param


def _stage(app, page, view: str):
    """Put ``view`` on stage with its button; the browser's camera once it is there."""
    before = _framed(app)
    button = page.get_by_role("button", name=view, exact=True)
    if button.is_visible():
        button.click()
    else:
        app.enqueue("app", Stage(view))
    from mechviz.viz.views import VIEWS

    wait_until(lambda: app.stage == VIEWS[view], 15, f"the {view} stage")
    return _arrived(app, before)


def _box(points, camera, width, height):
    from mechviz.viz.scene import framing

    position, target, fov = camera
    xy = framing.project(points, position, target, width, height, fov)
    return (*xy.min(axis=0), *xy.max(axis=0))


def _shot(page, name: str, tmp_path) -> None:
    where = Path(os.environ.get("MECHVIZ_STAGE_SHOTS") or tmp_path)
    where.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(where / name))


def _last_time(chart) -> float:
    """The time [s] the chart's drawn line ends at, read off the points sent to the browser."""
    return chart.time_of(float(np.asarray(chart.data.points)[-1, 1, 0]))


@pytest.mark.parametrize("view", ["Cyclotron", "Disk", "Hoop"])
def test_each_stage_shows_its_chart_beside_the_exhibit_readable_and_up_to_date(
    viewer, view, tmp_path
):
    from mechviz.viz.scene import framing
    from mechviz.viz.views import LABEL_INK_PX, VIEWS

    app, page, (width, height) = viewer
    key = VIEWS[view]
    position, target, fov = _stage(app, page, view)
    camera = (position, target, fov)
    for other, chart in app.charts.items():  # shown on its own stage only
        assert chart.visible == (other == key), other
        assert chart.root.startswith(app.exhibits[other].root)  # hidden with its exhibit
    chart, ex = app.charts[key], app.exhibits[key]
    # the chart's panel: inside the part of the page the panel leaves, apart from the exhibit
    free = min(_panel_left(page, width), width)
    cx0, cy0, cx1, cy1 = _box(chart.world_corners(), camera, width, height)
    _, x0, x1, y0, y1 = framing.share(*ex.bounds, position, target, width, height, fov)
    print(
        f"{view} at {width}x{height}: chart x {cx0:.0f}-{cx1:.0f} y {cy0:.0f}-{cy1:.0f}, "
        f"exhibit x {x0:.0f}-{x1:.0f} y {y0:.0f}-{y1:.0f}, free {free:.0f} px"
    )
    assert -1 <= cx0 and cx1 <= free + 1 and -1 <= cy0 and cy1 <= height + 1
    assert cx1 <= x0 + 1 or x1 <= cx0 + 1 or cy1 <= y0 + 1 or y1 <= cy0 + 1, "over the exhibit"
    # every word and number of the chart: at least 3 % of the page's height
    labels = [h for name, h in ex.nodes.items() if name.startswith(chart.root + "/")]
    shown = [h for h in labels if type(h).__name__ == "LabelHandle" and h.visible and h.text]
    assert len(shown) >= 4, [h.text for h in shown]  # the y title, t [s], two times, values
    sizes = [h.font_screen_scale * LABEL_INK_PX for h in shown]
    assert min(sizes) >= 0.03 * min(height, 1080), sizes
    assert "[" in chart.y_title.text and chart.x_title.text == "t [s]"  # axes with units
    # the line ends at the exhibit's time: paused, then taken back by Rewind
    app.enqueue("app", Pause())
    wait_until(lambda: not app.playing, 15, "the pause")
    wait_until(
        lambda: abs(_last_time(chart) - ex.model.t) < 1e-3, 15, "the chart at the time shown"
    )
    t_paused = ex.model.t
    app.enqueue("app", Scrub(-0.5))
    wait_until(lambda: ex.model.t < t_paused - 0.1, 15, "the exhibit taken back")
    wait_until(
        lambda: abs(_last_time(chart) - ex.model.t) < 1e-3,
        15,
        "the chart at the moment gone back to",
    )
    print(f"  paused at {t_paused:.2f} s, rewound to {ex.model.t:.2f} s: the chart ends there")
    app.enqueue("app", Play())
    wait_until(lambda: app.playing, 15, "play")
    wait_until(lambda: _last_time(chart) > ex.model.t - 0.2, 15, "the chart going on")
    _shot(page, f"stage-{key}-{width}x{height}.png", tmp_path)


def test_poinsot_is_a_third_of_the_page_high_beside_the_released_disk(viewer, tmp_path):
    from mechviz.viz import geometry as geo
    from mechviz.viz.scene import framing

    app, page, (width, height) = viewer
    _stage(app, page, "Disk")
    ex = app.exhibits["disk"]
    before = _framed(app)
    app.enqueue("disk", Set(fields={"mode": "released"}))
    try:
        wait_until(lambda: ex.model.config.mode == "released", 15, "the release")
        position, target, fov = _arrived(app, before)  # framed again with Poinsot beside
        camera = (position, target, fov)
        wait_until(lambda: ex.poinsot.frame.visible, 15, "Poinsot's picture")
        pts = ex.origin + ex.poinsot.picture_points()
        px0, py0, px1, py1 = _box(pts, camera, width, height)
        # the disk as drawn: its rim where the body stands, and the ω and L arrows
        turn = geo.matrix_from_quat(ex.body.wxyz)
        rim = np.asarray(ex.rim_node.points, float).reshape(-1, 3) @ turn.T + ex.body.position
        arrows = np.asarray(ex.vectors.points, float).reshape(-1, 3)
        x0, _, x1, _ = _box(ex.origin + np.concatenate([rim, arrows]), camera, width, height)
        print(
            f"Poinsot at {width}x{height}: {(py1 - py0) / height:.0%} of the height, "
            f"x {px0:.0f}-{px1:.0f}; the disk x {x0:.0f}-{x1:.0f}"
        )
        assert py1 - py0 >= height / 3, f"{(py1 - py0) / height:.0%} of the height"
        assert x1 <= px0, "Poinsot's picture over the disk"
        free = min(_panel_left(page, width), width)
        assert -1 <= px0 and px1 <= free + 1 and -1 <= py0 and py1 <= height + 1
        share, bx0, bx1, *_ = framing.share(*ex.bounds, position, target, width, height, fov)
        assert share >= 0.75 or bx1 - bx0 >= 0.9 * free, f"{share:.0%} of the height"
        wait_until(lambda: ex.poinsot.polhode.n_segments > 20, 30, "the polhode drawn")
        _shot(page, f"stage-disk-released-{width}x{height}.png", tmp_path)
    finally:
        app.enqueue("disk", Set(fields={"mode": "driven"}))
        wait_until(lambda: ex.model.config.mode == "driven", 15, "driven again")
