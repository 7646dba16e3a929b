"""Waiting in tests: on a condition, never for a fixed time, with time limits that scale.

A time limit only says how long a test waits before it calls a condition that never came a
failure, so it scales with the machine: ``MECHVIZ_TIMEOUT_FACTOR`` multiplies every limit (set
it on a slow or shared machine), and a load average above the number of cores raises it
further, as measured when the tests start.
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from typing import TypeVar

T = TypeVar("T")


def _factor() -> float:
    factor = float(os.environ.get("MECHVIZ_TIMEOUT_FACTOR", "1") or 1)
    try:
        load = os.getloadavg()[0] / (os.cpu_count() or 1)
    except OSError:
        load = 1.0
    return factor * max(1.0, load)


FACTOR = _factor()


def scaled(seconds: float) -> float:
    """A time limit of ``seconds`` on a quiet machine, scaled for this one."""
    return seconds * FACTOR


def wait_until(condition: Callable[[], T], timeout_s: float, what: str, poll_s: float = 0.05) -> T:
    """Poll ``condition()`` until it returns something true and return that; ``TimeoutError``
    naming ``what`` after :func:`scaled` (``timeout_s``) seconds."""
    deadline = time.monotonic() + scaled(timeout_s)
    while not (value := condition()):
        if time.monotonic() > deadline:
            raise TimeoutError(f"timed out after {scaled(timeout_s):.0f} s waiting for {what}")
        time.sleep(poll_s)
    return value


def frames_later(app, n: int, timeout_s: float = 30.0) -> None:
    """Wait until the viewer ``app`` has drawn ``n`` more frames (its loop is running)."""
    start = app.frame
    wait_until(lambda: app.frame >= start + n, timeout_s, f"{n} frames of the viewer")
