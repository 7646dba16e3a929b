"""The samples an exhibit keeps: :class:`Ring` (the last rows in one preallocated buffer), the
chart points (:class:`History`), a run's motion for the estimators (:class:`Motion`), and the
long history behind the charts, the last ten minutes of chart points whatever window the chart
shows, so a change of window keeps what was drawn (:class:`LongHistory`)."""

from __future__ import annotations

import math
import threading

import numpy as np

LONG_SECONDS = 600.0  # s of simulated time every chart window can draw on (the longest window)
LONG_SPACING = 0.05  # s between the long history's points at most (20 a second at 1x)


class Ring:
    """The last ``maxlen`` rows of shape ``shape`` in one preallocated buffer written twice (at
    ``i`` and ``i + maxlen``), so the newest rows are always one contiguous slice: adding a row
    allocates nothing and :meth:`array` copies one block. ``version`` changes on every change."""

    def __init__(self, shape: tuple[int, ...], maxlen: int) -> None:
        self.shape = tuple(shape)  # of one row
        self.maxlen = max(2, int(maxlen))
        self._buf = np.full((2 * self.maxlen, *shape), math.nan)
        self._i = self._n = 0
        self.count = 0  # rows ever added since the last clear
        self.version = 0

    def __len__(self) -> int:
        return self._n

    def clear(self) -> None:
        self._i = self._n = self.count = 0
        self.version += 1

    def add(self, row) -> None:
        i, m = self._i, self.maxlen
        self._buf[i] = row
        self._buf[i + m] = row
        self._i = (i + 1) % m
        self._n = min(self._n + 1, m)
        self.count += 1
        self.version += 1

    def drop_newest(self, n: int) -> None:
        """Forget the newest ``n`` rows (a run taken back to an earlier time)."""
        n = min(max(0, int(n)), self._n)
        self._i = (self._i - n) % self.maxlen
        self._n -= n
        self.count -= n
        self.version += 1

    def newest(self):
        """The newest row (a view; the ring must not be empty)."""
        return self._buf[self._i - 1 + self.maxlen]

    def array(self) -> np.ndarray:
        """The rows held, oldest first, as a fresh array."""
        end = self._i + self.maxlen
        return self._buf[end - self._n : end].copy()

    @property
    def nbytes(self) -> int:
        """Memory of the buffer [bytes]."""
        return self._buf.nbytes

    def forget_after(self, t: float) -> None:
        """Forget the newest rows whose first entry (a time [s]) is later than ``t``."""
        end = self._i + self.maxlen
        rows = self._buf[end - self._n : end]
        times = rows if rows.ndim == 1 else rows[:, 0]
        self.drop_newest(int(np.count_nonzero(times > t + 1e-12)))


class History:
    """Chart points: ``t`` and named series, the last ``maxlen`` of them (:class:`Ring`)."""

    def __init__(self, names: tuple[str, ...], maxlen: int = 600) -> None:
        self.names = tuple(names)
        self._ring = Ring((1 + len(self.names),), maxlen)
        self.maxlen = self._ring.maxlen

    def __len__(self) -> int:
        return len(self._ring)

    @property
    def version(self) -> int:
        return self._ring.version

    def clear(self) -> None:
        self._ring.clear()

    def forget_after(self, t: float) -> None:
        """Forget the points later than ``t`` [s]."""
        self._ring.forget_after(t)

    def add(self, t: float, **values: float) -> None:
        self._ring.add([t, *(values.get(n, math.nan) for n in self.names)])

    @property
    def t(self) -> np.ndarray:
        return self.arrays()[0]

    def arrays(self) -> tuple[np.ndarray, ...]:
        """``(t, *series)`` oldest first, as fresh arrays."""
        return tuple(self._ring.array().T)


class Motion:
    """Samples of a run's motion since it started or last jumped: the times and one array per
    sample (a velocity, the angles, ...), the newest ``maxlen``. The estimators of
    :mod:`mechviz.dynamics.measure` read them, exactly as the recorder reads its frames."""

    def __init__(self, shape: tuple[int, ...], maxlen: int = 1800) -> None:
        self.shape = tuple(shape)
        self._t = Ring((), maxlen)
        self._x = Ring(self.shape, maxlen)
        # the loop thread adds while another (a page's request, a test) may read: the times
        # and the states are two rings, read and written together
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._t)

    def clear(self) -> None:
        with self._lock:
            self._t.clear()
            self._x.clear()

    def add(self, t: float, x) -> None:
        """Keep the state at ``t`` [s], once: a frame in which the run took no step (a step
        longer than a frame) adds nothing, so the estimators read the run's own samples, not
        the same one over and over (a charge that seemed not to move between two frames looked
        like an alias)."""
        with self._lock:
            if len(self._t) and t <= self._t.newest():
                return
            self._t.add(t)
            self._x.add(x)

    def arrays(self) -> tuple[np.ndarray, np.ndarray]:
        """``(t, x)`` as fresh arrays of one length, from any thread."""
        with self._lock:
            return self._t.array(), self._x.array()

    def forget_after(self, t: float) -> None:
        """Forget the samples later than ``t`` [s]."""
        with self._lock:
            n = len(self._t)
            self._t.forget_after(t)
            self._x.drop_newest(n - len(self._t))


class LongHistory(History):
    """Chart points ``(t, *series)`` at least ``LONG_SPACING`` apart in simulated time, the
    last ``LONG_SECONDS`` of them (:meth:`keep`); :meth:`window` picks a chart's points from
    them."""

    def __init__(self, names: tuple[str, ...]) -> None:
        super().__init__(names, maxlen=round(LONG_SECONDS / LONG_SPACING))
        self._t = -math.inf

    def clear(self) -> None:
        super().clear()
        self._t = -math.inf

    def keep(self, t: float, values: dict[str, float], force: bool = False) -> None:
        """Keep the point at ``t`` [s] if ``LONG_SPACING`` has passed since the last (or
        ``force``: paused, the newest state is the one to show)."""
        if force or t - self._t >= LONG_SPACING or not len(self):
            self.resume_at(t)
            self.add(t, **values)

    def resume_at(self, t: float) -> None:
        """Count the spacing from ``t`` [s] (the newest point kept, or a moment gone back to)."""
        self._t = t

    def window(self, seconds: float, points: int) -> tuple[np.ndarray, ...]:
        """``(t, *series)`` over the last ``seconds``: at most ``points`` of them, evenly
        strided back from the newest (which is always among them)."""
        arrays = self.arrays()
        t = arrays[0]
        first = int(np.searchsorted(t, t[-1] - seconds))
        stride = max(1, math.ceil((len(t) - first) / points))
        keep = np.arange(len(t) - 1, first - 1, -stride)[::-1]
        return tuple(a[keep] for a in arrays)
