"""Shared helper for tests (and the recorder) that drive headless Chromium through playwright.

Debian's ``chromium`` package is used through ``executable_path``; ``playwright install`` is never
run (it downloads a browser build and fails offline). The flags keep Chromium off the network
(background services, component updates, sync) and away from the GPU the machines do not have.

Stable API (the recording helper imports it too)::

    find_chromium() -> str | None                # path of a Chromium executable, or None
    require_browser() -> str                     # that path; pytest.skip(...) when missing,
                                                 # pytest.fail(...) if MECHVIZ_REQUIRE_BROWSER=1
    CHROMIUM_ARGS                                # the command-line flags
    open_page(url, *, width=1280, height=800, timeout_s=30.0) -> context manager yielding page
    canvas(page)                                 # locator of viser's WebGL canvas
    number_box(page, label, exact=False)         # locator of a panel row's number box
    dismiss_webgl_alert(page)                    # closes "Software WebGL rendering detected"
    wait_for_pixels(page, predicate, timeout_s)  # polls canvas screenshots until predicate(img)
    screenshot_array(page) -> np.ndarray         # (H, W, 3) uint8 of the canvas

``open_page`` starts playwright, launches a persistent context in a fresh temporary profile,
loads ``url`` and waits until viser shows "Connected"; on exit it closes everything. Every time
limit is scaled for the machine (:mod:`waiting`, ``MECHVIZ_TIMEOUT_FACTOR``).
"""

from __future__ import annotations

import contextlib
import io
import os
import shutil
import tempfile
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
from waiting import scaled

from mechviz.viz.chromium import CHROMIUM_ARGS, find_chromium, first_page, launch  # noqa: F401  (API above)

REQUIRE_ENV = "MECHVIZ_REQUIRE_BROWSER"


def picture_path(relative: str, tmp_path: Path) -> Path:
    """Where a test saves a picture: ``docs/img/RELATIVE`` when ``MECHVIZ_WRITE_DOCS=1`` (``make
    screenshots``), else under ``tmp_path``, so that ``make test`` leaves the checkout as it was."""
    if os.environ.get("MECHVIZ_WRITE_DOCS") == "1":
        base = Path(__file__).resolve().parents[1] / "docs" / "img"
    else:
        base = Path(tmp_path)
    path = base / relative
    path.parent.mkdir(parents=True, exist_ok=True)
    return path


def _playwright_available() -> bool:
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return False
    return True


def require_browser() -> str:
    """Return Chromium's path, or skip the calling test with the reason (fail instead when
    ``MECHVIZ_REQUIRE_BROWSER=1``, as ``.ci/run`` sets after installing Chromium)."""
    import pytest

    path = find_chromium()
    reason = None
    if path is None:
        reason = "no Chromium found (apt-get install chromium; looked in /usr/bin/chromium)"
    elif not _playwright_available():
        reason = "the Python package playwright is not installed (pip install -e '.[test]')"
    if reason is not None:
        if os.environ.get(REQUIRE_ENV) == "1":
            pytest.fail(f"{REQUIRE_ENV}=1 but {reason}", pytrace=False)
        pytest.skip(reason)
    return path


@contextlib.contextmanager
def open_page(
    url: str,
    *,
    width: int = 1280,
    height: int = 800,
    timeout_s: float = 30.0,
    executable: str | None = None,
    wait_connected: bool = True,
) -> Iterator[object]:
    """Open ``url`` in headless Chromium; yield the playwright ``Page``; close all on exit."""
    from playwright.sync_api import sync_playwright

    exe = executable or find_chromium()
    if exe is None:
        raise RuntimeError("no Chromium executable found")
    profile = tempfile.mkdtemp(prefix="mechviz-chromium-")
    try:
        with sync_playwright() as pw:
            context = launch(pw, profile, exe, width, height)
            context.set_default_timeout(scaled(30) * 1000)  # every wait, screenshots included
            try:
                page = first_page(context)
                page.goto(url)
                if wait_connected:
                    page.get_by_text("Connected", exact=True).wait_for(
                        timeout=scaled(timeout_s) * 1000
                    )
                yield page
            finally:
                context.close()
    finally:
        shutil.rmtree(profile, ignore_errors=True)


@contextlib.contextmanager
def open_viewer(width: int = 1280, height: int = 800):
    """The viewer on a free port with its page open in Chromium, as ``(app, page)``; stopped
    on exit. No environment map: these are geometry checks, and SwiftShader draws lit meshes
    slowly with it."""
    require_browser()
    from mechviz.viz.app import MechvizApp, warm_up

    warm_up("defaults")
    app = MechvizApp(port=0, environment_map=False)
    try:
        with open_page(app.url, width=width, height=height, timeout_s=60) as page:
            dismiss_webgl_alert(page)
            yield app, page
    finally:
        app.stop()


def number_box(page, label: str, *, exact: bool = False):
    """The number box (a two-line text box: the Enter travels in its text,
    :mod:`mechviz.viz.scene.fields`) of the visible panel row labelled ``label`` (its start, or
    all of it with ``exact``); viser links the label to its row."""
    import re

    text = re.compile(f"^{re.escape(label)}$") if exact else label
    row = page.locator("label:visible", has_text=text).first
    return row.locator("xpath=ancestor::div[.//textarea][1]//textarea").first


def canvas(page):
    """viser's WebGL canvas (the first bare ``canvas`` in the DOM is a 0x0 helper)."""
    return page.locator('canvas[data-engine^="three.js"]')


def dismiss_webgl_alert(page, timeout_s: float = 5.0) -> bool:
    """Close the "Software WebGL rendering detected" alert if it shows; True if closed."""
    alert = page.get_by_role("alert").filter(has_text="Software WebGL")
    try:
        alert.first.wait_for(timeout=scaled(timeout_s) * 1000)
        alert.first.get_by_role("button").first.click()
        return True
    except Exception:
        return False


def screenshot_array(page) -> np.ndarray:
    """The canvas as an (H, W, 3) uint8 array."""
    import imageio.v3 as iio

    png = canvas(page).screenshot()
    img = iio.imread(io.BytesIO(png))
    return np.asarray(img)[..., :3]


def wait_for_pixels(
    page, predicate: Callable[[np.ndarray], bool], timeout_s: float = 30.0
) -> np.ndarray:
    """Poll canvas screenshots until ``predicate(image)`` holds; return that image.

    Raises ``TimeoutError`` (with the last image's distinct-colour count) otherwise.
    """
    deadline = time.monotonic() + scaled(timeout_s)
    img = screenshot_array(page)
    while not predicate(img):
        if time.monotonic() > deadline:
            n = len(np.unique(img.reshape(-1, 3), axis=0))
            raise TimeoutError(f"canvas never satisfied the check ({n} distinct colours)")
        time.sleep(0.3)
        img = screenshot_array(page)
    return img


def count_colour(img: np.ndarray, rgb: tuple[int, int, int], tol: int = 40) -> int:
    """Pixels within ``tol`` (per channel) of ``rgb``."""
    d = np.abs(img.astype(np.int16) - np.array(rgb, np.int16)).max(axis=-1)
    return int((d <= tol).sum())
