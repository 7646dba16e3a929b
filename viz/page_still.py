"""A still of a recorded page: viser's own player, opened in headless Chromium, paused at a
moment and photographed (a PNG of the scene, without the playback bar).

A notebook keeps this picture beside the player: Jupyter drops an ``<iframe>`` from an
untrusted notebook's outputs, and GitHub and nbviewer show no live page, but every one of them
shows a PNG. Chromium is the system's (:mod:`viz.chromium`), driven through playwright (the
``notebook`` and ``video`` extras); without either, :func:`page_still` answers ``None`` and why.
"""

from __future__ import annotations

import concurrent.futures
import tempfile
import time
from pathlib import Path

from .chromium import find_chromium, first_page, launch

#: Height [px] of the player's bar along the page's bottom edge (pause, time, scrubber, speed),
#: left out of the picture.
BAR_HEIGHT = 44


class StillUnavailable(RuntimeError):
    """No still could be taken here; the message says why in a few words."""


def page_still(
    page: bytes, at: float, *, width: int = 800, height: int = 450, timeout: float = 120.0
) -> bytes:
    """A ``width`` x ``height`` PNG of the recorded ``page`` (viser's self-contained HTML)
    paused at ``at`` [s of playback]. Raises :class:`StillUnavailable` without Chromium or
    playwright, or if the scene is not drawn within ``timeout`` [s]."""
    if find_chromium() is None:
        raise StillUnavailable("no Chromium found (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        raise StillUnavailable(
            "playwright is not installed (pip install 'mechviz[notebook]')"
        ) from None
    # playwright's sync API refuses to run in a thread with a running event loop (a Jupyter
    # kernel's): it gets a thread of its own.
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(_photograph, page, at, width, height, timeout).result()


def _photograph(page: bytes, at: float, width: int, height: int, timeout: float) -> bytes:
    from playwright.sync_api import Error as PlaywrightError
    from playwright.sync_api import sync_playwright

    with tempfile.TemporaryDirectory(prefix="mechviz-still-") as tmp:
        path = Path(tmp) / "page.html"
        path.write_bytes(page)
        try:
            with sync_playwright() as pw:
                ctx = launch(
                    pw, str(Path(tmp) / "profile"), find_chromium(), width, height + BAR_HEIGHT
                )
                try:
                    return _seek_and_shoot(first_page(ctx), path, at, width, height, timeout)
                finally:
                    ctx.close()
        except PlaywrightError as exc:
            raise StillUnavailable(f"Chromium failed: {str(exc).splitlines()[0]}") from None


def _seek_and_shoot(page, path: Path, at: float, width: int, height: int, timeout: float) -> bytes:
    deadline = time.monotonic() + timeout
    ms = int(timeout * 1000)
    page.goto(path.as_uri())
    box = page.get_by_role("textbox")  # the player's time box
    box.wait_for(timeout=ms)
    alert = page.get_by_role("alert").filter(has_text="Software WebGL")
    if alert.count():
        alert.get_by_role("button").click(timeout=ms)
    # The pause button is the first button of the bar, left of the time box.
    box.locator("xpath=preceding::button[1]").click(timeout=ms)
    box.fill(f"{at:.6g}")
    box.press("Enter")
    clip = {"x": 0, "y": 0, "width": width, "height": height}
    last = b""
    while time.monotonic() < deadline:
        # drawn once two pictures in a row agree (the first frame with lit meshes takes seconds)
        shot = page.screenshot(clip=clip, type="png", animations="disabled")
        if shot == last and _has_scene(shot):
            return shot
        last = shot
    raise StillUnavailable(f"the scene was not drawn within {timeout:g} s")


def _has_scene(png: bytes) -> bool:
    """Whether the picture holds more than a blank page (some hundred colours at least)."""
    import io

    import numpy as np
    from PIL import Image

    img = np.asarray(Image.open(io.BytesIO(png)).convert("RGB"))
    return len(np.unique(img.reshape(-1, 3), axis=0)) > 200
