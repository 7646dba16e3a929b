"""The long history behind the charts: the last ten minutes of chart points, whatever window
the chart shows, so a change of window keeps what was drawn (:class:`LongHistory`)."""

from __future__ import annotations

import math

import numpy as np

LONG_SECONDS = 600.0  # s of simulated time every chart window can draw on (the longest window)
LONG_SPACING = 0.05  # s between the long history's points at most (20 a second at 1x)


class LongHistory:
    """Chart points ``(t, *series)`` at least ``LONG_SPACING`` apart in simulated time, the
    last ``LONG_SECONDS`` of them; :meth:`window` picks a chart's points from them."""

    def __init__(self, history_cls, names: tuple[str, ...]) -> None:
        self._points = history_cls(names, maxlen=round(LONG_SECONDS / LONG_SPACING))
        self._t = -math.inf

    def __len__(self) -> int:
        return len(self._points)

    @property
    def version(self) -> int:
        return self._points.version

    def clear(self) -> None:
        self._points.clear()
        self._t = -math.inf

    def add(self, t: float, values: dict[str, float], force: bool = False) -> None:
        """Keep the point at ``t`` [s] if ``LONG_SPACING`` has passed since the last (or
        ``force``: paused, the newest state is the one to show)."""
        if force or t - self._t >= LONG_SPACING or not len(self._points):
            self._t = t
            self._points.add(t, **values)

    def window(self, seconds: float, points: int) -> tuple[np.ndarray, ...]:
        """``(t, *series)`` over the last ``seconds``: at most ``points`` of them, evenly
        strided back from the newest (which is always among them)."""
        arrays = self._points.arrays()
        t = arrays[0]
        first = int(np.searchsorted(t, t[-1] - seconds))
        stride = max(1, math.ceil((len(t) - first) / points))
        keep = np.arange(len(t) - 1, first - 1, -stride)[::-1]
        return tuple(a[keep] for a in arrays)
