"""The seed's pictures as a person sees them in the live viewer (headless Chromium): the well
V_eff(r), the hoop's phase portrait and configuration space, the disk's polhode, and
Poinsot's construction. Each test checks the picture shows the motion and the exact curve
beside it, and saves it; ``make screenshots`` saves them as the README's stills
(``docs/img/pictures/``), ``make test`` in a temporary folder."""

from __future__ import annotations

import io

import browser
import numpy as np
import pytest
from waiting import frames_later, wait_until

from mechviz.viz.app_commands import Present
from mechviz.viz.model.commands import Kick, Reset, Set

pytestmark = pytest.mark.browser


@pytest.fixture(scope="module")
def viewer():
    browser.require_browser()
    from mechviz.viz.app import MechvizApp, warm_up
    from mechviz.viz.model import CyclotronConfig, DiskConfig, HoopConfig

    configs = {
        # off the axis and kicked: r swings in its well
        "cyclotron": CyclotronConfig(centre=(0.5, 0.0), vz=0.0, method="boris", dt=0.01),
        "hoop": HoopConfig(mode="mode 1", amplitude=1.5, method="taylor", rtol=1e-10),
        "disk": DiskConfig(mode="released", extra_spin=(0.0, 0.0, 0.05)),
    }
    warm_up("defaults", configs)
    app = MechvizApp(port=0, environment_map=False, configs=configs)
    try:
        with browser.open_page(app.url, width=1280, height=800, timeout_s=60) as page:
            browser.dismiss_webgl_alert(page)
            yield app, page
    finally:
        app.stop()


def _plot(page, tab: str) -> np.ndarray:
    """The visible tab's plot image as the page shows it (RGB)."""
    from PIL import Image

    page.get_by_role("tab", name=tab).click()
    page.get_by_role("tab", name=tab, selected=True).wait_for()

    def plot_image():
        images = [i for i in page.locator("img").all() if i.is_visible()]
        images = [i for i in images if (i.bounding_box() or {}).get("height", 0) > 150]
        return images[0] if images else None

    img = wait_until(plot_image, 30, f"a plot image in the {tab} tab", poll_s=0.2)
    img.evaluate(  # two animation frames: the scroll is painted
        "e => new Promise(done => { e.scrollIntoView({block: 'center'}); "
        "requestAnimationFrame(() => requestAnimationFrame(done)); })"
    )
    png = page.screenshot(clip=img.bounding_box())
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))


def _drawn(img: np.ndarray) -> np.ndarray:
    """Where ``img`` differs from its background (its median colour)."""
    background = np.median(img.reshape(-1, 3), axis=0)
    return np.abs(img.astype(int) - background).max(axis=-1) > 40


def _pixels(img: np.ndarray, hex_colour: str, tol: int = 40) -> int:
    rgb = np.array([int(hex_colour[i : i + 2], 16) for i in (1, 3, 5)])
    return int((np.abs(img.astype(int) - rgb).max(axis=-1) < tol).sum())


def _save(img: np.ndarray, name: str, tmp_path) -> None:
    from PIL import Image

    Image.fromarray(img).save(browser.picture_path(f"pictures/{name}.png", tmp_path))


def _choose(app, key: str, x: str, y: str) -> None:
    ex = app.exhibits[key]
    variables = ex.model.plot_variables(ex.model.config)
    app.w[f"{key}.plot_x"].value = variables[x].label  # as the dropdowns do
    app.w[f"{key}.plot_y"].value = variables[y].label


#: Hides (``true``) or shows the panel around the Leave button (a still of the scene alone).
PANEL_HIDDEN = """hidden => {
    // the floating panel: the first ancestor of the Leave button placed on its own
    let e = [...document.querySelectorAll('button')].find(b => b.textContent.includes('Leave'));
    while (e && getComputedStyle(e).position !== 'absolute') e = e.parentElement;
    if (e) e.style.visibility = hidden ? 'hidden' : '';
    return Boolean(e);
}"""

KICK = Kick(dv=0.4)
MIX = Set(fields={"mode": "mix", "amplitude": 1.0})
MODE_1 = Set(fields={"mode": "mode 1", "amplitude": 1.5})


@pytest.mark.parametrize(
    ("tab", "key", "pair", "name", "start"),
    [
        ("Cyclotron", "cyclotron", ("r", "V_eff"), "well", (Reset(), KICK)),
        ("Cyclotron", "cyclotron", ("x", "y"), "orbit-from-above", (Reset(), KICK)),
        # mode 1 is unstable at large amplitude: the picture is taken within a few periods
        ("Hoop", "hoop", ("theta1", "omega1"), "phase-portrait", (MODE_1, Reset())),
        ("Hoop", "hoop", ("theta1", "theta2"), "configuration-space", (MIX, Reset())),
        ("Disk", "disk", ("w2", "w3"), "polhode", (Reset(),)),
    ],
)
def test_the_plot_shows_the_motion_and_its_exact_curve(
    viewer, tmp_path, tab, key, pair, name, start
):
    from mechviz.viz.model.plot import CURVE_COLOURS, PATH_COLOUR

    app, page = viewer
    for command in start:
        app.enqueue(key, command)
    frames_later(app, 2)  # the commands are applied at the start of a frame
    _choose(app, key, *pair)
    # 200 points are 600 frames (a point each measured frame, every third): 10 s at 60 fps
    wait_until(lambda: len(app.exhibits[key].model.trace) >= 200, 60, "the path to grow")
    img = _plot(page, tab)
    assert app.panels[key].plot_choice == pair
    _save(img, name, tmp_path)
    # a dashed curve drawn over the path where the motion runs on it hides much of the path
    assert _pixels(img, PATH_COLOUR) > 25, "the motion's path"
    assert _pixels(img, CURVE_COLOURS[0]) > 100, "the exact curve"


def test_poinsot_s_construction_presented_alone(viewer, tmp_path):
    """Presentation mode on the released disk: the inertia ellipsoid on its invariable plane,
    the polhode and herpolhode, the principal axes about the centre of mass."""
    app, page = viewer
    app.enqueue("app", Present("Disk"))
    try:
        wait_until(lambda: app.presenting is not None, 20, "presentation mode")

        # the still shows the construction, not presentation mode's key figures beside it
        def construction_only(a) -> None:
            a.stage_label.visible = False
            a.charts["disk"].visible = False

        app.enqueue("call", construction_only)
        frames_later(app, 60)  # the camera's move to the disk is a second of frames
        # nor the page's panel (its Leave button, once the page has it) over the still's corner
        wait_until(lambda: page.evaluate(PANEL_HIDDEN, True), 30, "the panel's Leave button")
        img = browser.wait_for_pixels(page, lambda im: _drawn(im).mean() > 0.02, 60)
        # the README's still: the disk's box as the browser's camera sees it (the body, its
        # construction and the construction's names under it), not the floor
        from mechviz.viz.scene import framing

        client = next(iter(app.server.get_clients().values()))
        cam = client.camera
        h, w = img.shape[:2]
        _, x0, x1, y0, y1 = framing.share(
            *app.exhibits["disk"].bounds, cam.position, cam.look_at, w, h, cam.fov
        )
        x0, y0 = max(0, int(x0) - 20), max(0, int(y0) - 20)
        _save(img[y0 : int(y1) + 20, x0 : int(x1) + 20], "poinsot", tmp_path)
        assert "Poinsot" in app.exhibits["disk"].poinsot.names[0].text
    finally:
        page.evaluate(PANEL_HIDDEN, False)
        app.enqueue("app", Present("Off"))
