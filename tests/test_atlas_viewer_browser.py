"""The hoop's chaos and stability maps in the live viewer, in headless Chromium.

A click on the chaos map standing in the scene starts the hoop at rest at the clicked angles
(read back through the model); the stability picture in the hoop's tab draws the current step
where its axes put the step ``dt`` the exhibit runs with. Skipped with the reason when no
Chromium is found (a failure under MECHVIZ_REQUIRE_BROWSER=1).
"""

from __future__ import annotations

import io
import math

import browser
import numpy as np
import pytest
from waiting import wait_until

pytestmark = [pytest.mark.browser, pytest.mark.slow]


@pytest.fixture(scope="module")
def viewer():
    with browser.open_viewer() as (app, page):
        page.get_by_role("tab", name=app.exhibits["hoop"].model.name).click()
        yield app, page


def project(camera, point, width: float, height: float) -> tuple[float, float]:
    """Canvas pixel of the world ``point`` seen by a viser camera (OpenCV frame: +z forward,
    +y down; ``fov`` vertical)."""
    from viser import transforms

    rot = transforms.SO3(np.asarray(camera.wxyz, float)).as_matrix()
    p = rot.T @ (np.asarray(point, float) - np.asarray(camera.position, float))
    f = 0.5 * height / math.tan(0.5 * camera.fov)
    return 0.5 * width + f * p[0] / p[2], 0.5 * height + f * p[1] / p[2]


def test_a_click_on_the_chaos_map_starts_the_hoop_at_rest_at_the_clicked_angles(viewer):
    app, page = viewer
    ex = app.exhibits["hoop"]
    view = ex.maps_view
    chaos = wait_until(lambda: view.maps.chaos, 120, "the chaos map")
    page.get_by_text("Chaos map", exact=True).click()
    page.get_by_role("button", name="Look at the map").click()
    client = next(iter(app.server.get_clients().values()))
    centre = view.world_of(0.5, 0.5)
    wait_until(
        lambda: (
            np.allclose(client.camera.look_at, centre, atol=1e-3)
            and np.allclose(client.camera.position, centre + (0.0, -2.2, 0.0), atol=1e-3)
        ),
        20,
        "the camera in front of the map",
    )
    box = browser.canvas(page).bounding_box()
    for target in ((1.2, -0.8), (-2.1, 2.4)):
        x, y = project(
            client.camera, view.world_of(*chaos.place_of(*target)), box["width"], box["height"]
        )
        page.mouse.click(box["x"] + x, box["y"] + y)
        wait_until(
            lambda t=target: (
                ex.model.config.mode == "custom"
                and np.allclose(ex.model.config.angles, t, atol=0.05)
            ),
            20,
            f"the hoop to start at {target}",
        )
        start = ex.model.sim.state0[0]  # where the running simulation started: there, at rest
        assert np.allclose(start[:2], target, atol=0.05) and np.all(start[2:] == 0.0)


def _magenta_rows(png: bytes) -> np.ndarray:
    import imageio.v3 as iio

    img = np.asarray(iio.imread(io.BytesIO(png)))[..., :3].astype(int)
    mask = (img[..., 0] > 200) & (img[..., 1] < 90) & (img[..., 2] > 200)
    return np.nonzero(mask)[0] / img.shape[0]


def test_the_stability_map_marks_the_current_step(viewer):
    app, page = viewer
    ex = app.exhibits["hoop"]
    view = ex.maps_view
    page.get_by_text("Stability map", exact=True).click()
    for dt in ("0.05", "0.2"):
        # the text box of the row labelled "Step dt" (viser links the label to its row)
        box = browser.number_box(page, "Step dt")
        box.fill(dt)
        box.press("Enter")  # a typed number applies on Enter, never half-typed
        wait_until(lambda d=float(dt): ex.model.config.dt == d, 20, f"dt = {dt}")
        drawn = wait_until(
            lambda d=float(dt): (
                view.step_drawn if view.step_drawn and view.step_drawn[1] == d else None
            ),
            120,
            f"the stability map marking dt = {dt}",
        )
        _, _, (u, v) = drawn

        def marker_row(v=v):
            for img in page.locator("img").all():
                if not img.is_visible():
                    continue
                rows = _magenta_rows(img.screenshot())
                if rows.size > 20 and abs(np.median(rows) - v) < 0.03:
                    return float(np.median(rows))
            return None

        row = wait_until(marker_row, 30, f"the page's stability picture marking dt = {dt}")
        # read back through the picture's own axes: the marked step is the exhibit's
        marked = view.stability_picture.data_at(u, row)[1]
        assert marked == pytest.approx(float(dt), rel=0.08)
