"""A still of a recorded page for a notebook: the PNG :class:`mechviz.viz.player.Player` draws of the
recording at a moment (the same player ``mechviz still`` and the videos use).

A notebook keeps this picture beside the player: Jupyter drops an ``<iframe>`` from an
untrusted notebook's outputs, and GitHub and nbviewer show no live page, but every one of them
shows a PNG. Chromium is the system's (:mod:`mechviz.viz.chromium`), driven through playwright (the
``notebook`` and ``video`` extras); without either, :func:`page_still` raises
:class:`StillUnavailable` saying why.
"""

from __future__ import annotations

import concurrent.futures

from .chromium import find_chromium


class StillUnavailable(RuntimeError):
    """No still could be taken here; the message says why in a few words."""


def page_still(page: bytes, at: float, *, width: int = 800, height: int = 450) -> bytes:
    """A ``width`` x ``height`` PNG of the recorded ``page`` (viser's self-contained HTML) at
    ``at`` [s of playback], from the recording's own camera. Raises :class:`StillUnavailable`
    without Chromium or playwright, or if Chromium fails to draw it."""
    if find_chromium() is None:
        raise StillUnavailable("no Chromium found (apt-get install chromium)")
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        raise StillUnavailable(
            "playwright is not installed (pip install 'mechviz-lab[notebook]')"
        ) from None
    # playwright's sync API refuses to run in a thread with a running event loop (a Jupyter
    # kernel's): it gets a thread of its own.
    with concurrent.futures.ThreadPoolExecutor(1) as pool:
        return pool.submit(_photograph, page, at, width, height).result()


def _photograph(page: bytes, at: float, width: int, height: int) -> bytes:
    from .player import Player, PlayerError

    try:
        with Player(page, (width, height)) as player:
            return player.png(at)
    except PlayerError as exc:
        raise StillUnavailable(str(exc).splitlines()[0]) from None
