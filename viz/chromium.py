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
