"""A one-line progress bar for long commands on a terminal (``mechviz record``, videos)."""

from __future__ import annotations

import sys
import time


class ProgressBar:
    """A one-line progress bar on a terminal (stderr); silent otherwise."""

    def __init__(self, label: str, stream=None, width: int = 30):
        self.stream = stream or sys.stderr
        self.enabled = self.stream.isatty()
        self.label, self.width = label, width
        self.last = -1.0

    def __call__(self, done: int, total: int) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if done < total and now - self.last < 0.05:
            return
        self.last = now
        filled = int(self.width * done / total)
        bar = "#" * filled + "." * (self.width - filled)
        self.stream.write(
            f"\r{self.label:<22} [{bar}] {100 * done // total:3d}%  {done}/{total} frames"
        )
        if done >= total:
            self.stream.write("\n")
        self.stream.flush()
