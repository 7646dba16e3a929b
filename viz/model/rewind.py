"""The last minute of the show, kept so a paused exhibit can be taken back through it.

A lecturer who pauses and goes back thinks in what the hall saw, so the span kept is in seconds
of the *show*, not of simulated time: each advance counts the wall seconds it stands for (the
viewer passes simulated seconds over its speed; a model run alone counts simulated seconds, as at
1x). At 10x a minute of the show is ten simulated minutes, at 0.1x six simulated seconds: either
way the picture can go back to what was on the screen a minute ago.

The runs' states (:mod:`mechviz.dynamics.snapshot`: the whole of every simulation, the reference run
included) are kept in one preallocated buffer, at most one every ``SECONDS / rows`` of the show,
where ``rows`` is the display rate's worth for ``SECONDS`` (one a frame at 60 Hz) or fewer when a
row is large (a beam of many charges), so the memory never exceeds ``BUDGET`` bytes whatever the
run; the oldest rows go first.
"""

from __future__ import annotations

import numpy as np

from mechviz.dynamics import snapshot as snap

from .history import Ring
from .observed import Observed

SECONDS = 60.0  # s of the show kept
RATE = 60.0  # rows per second of the show at most (the viewer's frame rate)
BUDGET = 16 * 2**20  # bytes of one exhibit's buffer at most (Ring stores each row twice)


class Rewind:
    """Snapshots of ``sims`` (the model's simulations, in a fixed order) over the last
    ``seconds`` of the show. ``clock`` counts seconds of the show since the runs started."""

    def __init__(self, sims, seconds: float = SECONDS) -> None:
        self.widths = [snap.width(s) for s in sims]
        row = 1 + sum(self.widths)  # the show clock, then each run's row
        rows = int(min(seconds * RATE, BUDGET // (2 * 8 * row) - 1))  # Ring: rows + 1, twice
        self.seconds = float(seconds)
        self.rows = max(2, rows)
        self.spacing = self.seconds / self.rows  # s of the show between kept rows at least
        self._ring = Ring((row,), self.rows + 1)  # the span's both ends
        self._row = np.empty(row)
        self.clock = 0.0
        self._last = -np.inf  # show clock of the newest row

    def __len__(self) -> int:
        return len(self._ring)

    @property
    def nbytes(self) -> int:
        """Memory of the buffer [bytes]."""
        return self._ring.nbytes

    def add(self, sims, *, force: bool = False) -> None:
        """Keep the runs' state now if ``spacing`` has passed since the last kept (or ``force``)."""
        # (a whisker under the spacing: frames of 1/60 s, summed, fall short of it by round-off)
        if not force and self.clock - self._last < 0.999 * self.spacing:
            return
        if force and self.clock == self._last:
            self._ring.drop_newest(1)  # the same moment again: the newer state replaces it
        row = self._row
        row[0] = self.clock
        k = 1
        for sim, w in zip(sims, self.widths, strict=True):
            snap.snapshot(sim, row[k : k + w])
            k += w
        self._ring.add(row)
        self._last = self.clock

    def times(self) -> np.ndarray:
        """The show clock [s] of every kept row, oldest first, within the last ``seconds``."""
        clocks = self._ring.array()[:, 0]
        return clocks[clocks >= self.clock - self.seconds - 1e-9]

    def span(self) -> float:
        """How far back [s of the show] the oldest kept row is."""
        t = self.times()
        return float(self.clock - t[0]) if len(t) else 0.0

    def restore(self, sims, seconds_back: float) -> float:
        """Put the runs back to the kept row nearest ``seconds_back`` before ``clock``, never
        beyond the oldest; returns how far back [s of the show] that row is. ``clock`` stays."""
        rows = self._ring.array()
        clocks = rows[:, 0]
        first = int(np.searchsorted(clocks, self.clock - self.seconds - 1e-9))
        target = self.clock - max(0.0, float(seconds_back))
        i = first + int(np.argmin(np.abs(clocks[first:] - target)))
        k = 1
        for sim, w in zip(sims, self.widths, strict=True):
            snap.restore(sim, rows[i, k : k + w])
            k += w
        return float(self.clock - clocks[i])

    def cut(self, seconds_back: float) -> None:
        """Forget the rows newer than ``seconds_back`` before ``clock`` and move ``clock`` back
        there: the run goes on from that moment (what came after it never happened)."""
        clocks = self._ring.array()[:, 0]
        keep = int(np.searchsorted(clocks, self.clock - seconds_back + 1e-9, side="right"))
        self._ring.drop_newest(len(clocks) - keep)
        self.clock -= seconds_back
        self._last = self.clock


class Rewinding(Observed):
    """What an exhibit's model (:class:`mechviz.viz.model.base.ExhibitModel`) gets to go back in its run:
    ``scrub(seconds_back)`` shows the runs as they were that long ago in the show (the
    simulations themselves are put back, so everything drawn and read out from them, ``t`` first,
    is of that moment; the newer states stay kept until the run goes on), and the run goes on
    *from the moment shown*, as a video editor's "resume from here": the next advance, command
    or :meth:`resume_here` forgets what came after it (samples, chart points and a failure that
    had not happened yet). Scrubbing back to 0 s and playing goes on from where it paused."""

    scrubbed: float | None = None  # s of the show back from the newest kept state, while shown
    rewind: Rewind

    def _rewind_start(self) -> None:
        """A new run: keep its states from its start on."""
        self.scrubbed = None
        self.rewind = Rewind(self.simulations())
        self.rewind.add(self.simulations(), force=True)

    def _rewind_keep(self, shown: float) -> None:
        """After an advance that stood for ``shown`` seconds of the show."""
        self.rewind.clock += shown
        self.rewind.add(self.simulations())

    def rewind_span(self) -> float:
        """How far back [s of the show] the exhibit can be scrubbed now."""
        return self.rewind.span()

    def scrub(self, seconds_back: float) -> float:
        """Show the runs as they were ``seconds_back`` seconds of the show before the moment
        paused at (the nearest kept state, never beyond the oldest); returns how far back that
        is. Pause the exhibit's clock first: an advance goes on from the moment shown."""
        sims = self.simulations()
        if self.scrubbed is None:  # the moment paused at is kept, so scrubbing can come back
            self.rewind.add(sims, force=True)
        self.scrubbed = self.rewind.restore(sims, seconds_back)
        self._sample = self._compare_sample = None
        self.changed()
        self._rewound()
        return self.scrubbed

    def resume_here(self) -> None:
        """Go on from the moment shown: forget the states, samples and chart points after it."""
        back, self.scrubbed = self.scrubbed, None
        if back is None:
            return
        self.rewind.cut(back)
        t = self.t
        for samples in self._timed_samples():
            samples.forget_after(t)
        self.long_history.resume_at(t)
        self._chart_t = t
        err = self.failure_error
        if err is not None and err.t > t:  # the blow-up lies after the moment gone back to
            self.paused, self.failure, self.failure_error = False, None, None
        self.changed()
        self._rewound()

    def _timed_samples(self) -> list:
        """Everything kept in time order that can forget what came after a moment: the charts'
        points, the plot's trace and the estimators' samples (:class:`mechviz.viz.model.history.Motion`)."""
        from .history import Motion

        kept = [self.history, self.long_history, self.trace]
        kept += [value for value in vars(self).values() if isinstance(value, Motion)]
        return kept

    def _rewound(self) -> None:
        """Called after the runs were put back (scrubbed, or resumed from there): a model
        works out again what it derives from the state (its override, then this), and this
        announces it (a view breaks its trails)."""
        self.announce("rewound")

    def chart_version(self) -> tuple:
        """Changes whenever the charts would show something else."""
        return (self.long_history.version, self.scrubbed, self.t if self.scrubbed else None)
