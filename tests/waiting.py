"""Waiting in tests: on a condition, never for a fixed time, with time limits that scale.

A time limit only says how long a test waits before it calls a condition that never came a
failure, so it scales with the machine: ``MECHVIZ_TIMEOUT_FACTOR`` multiplies every limit (set
it on a slow or shared machine), and a load average above the number of cores raises it
further: the load when the tests started or the load now, whichever is higher (another job
that starts halfway through a run slows every test after it).
"""

from __future__ import annotations

import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

T = TypeVar("T")

_SET = float(os.environ.get("MECHVIZ_TIMEOUT_FACTOR", "1") or 1)


def _load() -> float:
    """The load average per core, at least 1."""
    try:
        return max(1.0, os.getloadavg()[0] / (os.cpu_count() or 1))
    except OSError:
        return 1.0


FACTOR = _SET * _load()  # as the tests started


def scaled(seconds: float) -> float:
    """A time limit of ``seconds`` on a quiet machine, scaled for this one as it is now."""
    return seconds * max(FACTOR, _SET * _load())


def wait_until(condition: Callable[[], T], timeout_s: float, what: str, poll_s: float = 0.05) -> T:
    """Poll ``condition()`` until it returns something true and return that; ``TimeoutError``
    naming ``what`` after :func:`scaled` (``timeout_s``) seconds, the limit scaled afresh at
    every poll."""
    start = time.monotonic()
    while not (value := condition()):
        limit = scaled(timeout_s)
        if time.monotonic() - start > limit:
            raise TimeoutError(f"timed out after {limit:.0f} s waiting for {what}")
        time.sleep(poll_s)
    return value


def frames_later(app, n: int, timeout_s: float = 30.0) -> None:
    """Wait until the viewer ``app`` has drawn ``n`` more frames (its loop is running)."""
    start = app.frame
    wait_until(lambda: app.frame >= start + n, timeout_s, f"{n} frames of the viewer")


def _stat(pid: str) -> tuple[str, str, int] | None:
    """(name, state, parent pid) of a process, or None if it is gone."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = stat[stat.rindex(")") + 2 :].split()
    return stat[stat.index("(") + 1 : stat.rindex(")")], fields[0], int(fields[1])


def descendants(pid: int) -> dict[int, str]:
    """pid -> name of every live process descended from ``pid`` (Linux /proc); Chromium starts
    sessions of its own, so a session id would not find it."""
    parents: dict[int, list[int]] = {}
    names = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and (st := _stat(entry.name)) and st[1] != "Z":
            parents.setdefault(st[2], []).append(int(entry.name))
            names[int(entry.name)] = st[0]
    found, todo = {}, [pid]
    while todo:
        for child in parents.get(todo.pop(), []):
            found[child] = names[child]
            todo.append(child)
    return found


def alive(pids) -> list[int]:
    return [p for p in pids if (st := _stat(str(p))) is not None and st[1] != "Z"]
