"""Where Chromium is and how to start it headless here (browser tests and the endurance bench).

Debian's ``chromium`` package (``apt-get install chromium``), driven by Python's playwright with
``executable_path``; ``playwright install`` downloads a browser of its own and fails on these
machines, so it is never used. Without the background-networking flags Chromium keeps trying to
reach Google's hosts, which this machine's closed network refuses.
"""

from __future__ import annotations

import os
import shutil

CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
CANDIDATES = ("/usr/bin/chromium", "/usr/bin/chromium-browser", "/usr/lib/chromium/chromium")


def find_chromium() -> str | None:
    """Path of a Chromium executable (env ``MECHVIZ_CHROMIUM`` first, then :data:`CANDIDATES`,
    then ``chromium`` on PATH), or ``None``."""
    explicit = os.environ.get("MECHVIZ_CHROMIUM")
    for path in ((explicit,) if explicit else ()) + CANDIDATES:
        if path and os.path.isfile(path) and os.access(path, os.X_OK):
            return path
    return shutil.which("chromium")


def launch(pw, profile: str, executable: str, width: int, height: int, scale: float = 1.0):
    """A headless Chromium context (``executable``, its profile in the empty folder ``profile``,
    a ``width`` x ``height`` viewport in CSS pixels, ``scale`` device pixels per CSS pixel) from
    playwright's ``pw``, with :data:`CHROMIUM_ARGS`.

    Chromium's own temporary files go inside the profile too (``TMPDIR``): a browser killed
    with its parent leaves them behind, and removing the profile then removes everything."""
    tmp = os.path.join(str(profile), ".tmp")
    os.makedirs(tmp, exist_ok=True)
    return pw.chromium.launch_persistent_context(
        str(profile),
        executable_path=executable,
        headless=True,
        args=CHROMIUM_ARGS,
        viewport={"width": int(width), "height": int(height)},
        device_scale_factor=float(scale),
        env={**os.environ, "TMPDIR": tmp},
    )


def first_page(context):
    """The page a new context opened with, or a new one."""
    return context.pages[0] if context.pages else context.new_page()
