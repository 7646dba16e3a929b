"""Progress on a terminal for long commands: one tqdm bar on stderr, silent when stderr is not a
terminal (a log, a pipe, a test), so that nothing but results reaches a file, and silent
everywhere after :func:`silence` (``--no-progress``, which every command that shows progress
takes: :func:`add_option`)."""

from __future__ import annotations

import os
import sys

from tqdm import tqdm

_silenced = False


def silence() -> None:
    """No progress bar from here on, terminal or not (``--no-progress``)."""
    global _silenced
    _silenced = True


def shown(stream=None) -> bool:
    """Whether a bar would show on ``stream`` (stderr): a terminal, and not silenced."""
    stream = stream or sys.stderr
    return not _silenced and hasattr(stream, "isatty") and stream.isatty()


def add_option(p) -> None:
    """``--no-progress`` on the parser ``p`` of a command that shows progress."""
    p.add_argument(
        "--no-progress",
        action="store_true",
        help="no progress bar (one shows only on a terminal, on stderr)",
    )


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
        disable=not (enabled and shown(stream)),
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
