"""Progress on a terminal for long commands: one tqdm bar on stderr, silent when stderr is not a
terminal (a log, a pipe, a test), so that nothing but results reaches a file."""

from __future__ import annotations

import os
import sys

from tqdm import tqdm


def progress_bar(
    label: str, total: float, *, unit: str = "", enabled: bool = True, stream=None, **kwargs
) -> tqdm:
    """A tqdm bar on ``stream`` (stderr) counting ``total`` ``unit``; disabled unless ``enabled``
    and the stream is a terminal. It clears its line when closed (``leave=False``): what stays on
    the terminal is the command's own report."""
    stream = stream or sys.stderr
    try:
        size = os.get_terminal_size(stream.fileno())
    except (AttributeError, OSError, ValueError):
        size = os.terminal_size((0, 0))
    return tqdm(
        total=total,
        desc=label,
        unit=unit,
        file=stream,
        disable=not (enabled and stream.isatty()),
        # a terminal that reports no size (0 x 0) still gets the line: tqdm would draw nothing
        ncols=size.columns or 80,
        nrows=size.lines or 24,
        mininterval=0.1,
        leave=False,
        **kwargs,
    )


class ProgressBar:
    """``bar(done, total)`` for the frame loops of ``record`` and ``video``: a
    :func:`progress_bar` of frames, made at the first call (when the total is known) and closed
    at the last."""

    def __init__(self, label: str, stream=None) -> None:
        self.label, self.stream = label, stream
        self._bar: tqdm | None = None

    def __call__(self, done: int, total: int) -> None:
        if self._bar is None:
            self._bar = progress_bar(self.label, total, unit="frame", stream=self.stream)
        self._bar.update(done - self._bar.n)
        if done >= total:
            self._bar.close()
