"""The viewer's Rewind control: pause, then scrub back through the last minute of the show.

A number field over a slider track from -60 s to 0 s, in seconds of the show (what the hall
saw, whatever the speed; :mod:`mechviz.viz.model.rewind`). Moving it pauses every exhibit and shows each
as it was that long before the moment paused at: the scene, the readouts (``t = ...``) and the
charts, which end at the moment shown. Play then goes on *from the moment shown*, as a video
player plays on from where its playhead stands: what came after it is dropped (a kick given
later was not given, a blow-up later has not happened). Back at 0 s, Play goes on from where it
paused, and nothing is lost.
"""

from __future__ import annotations

from .app_commands import Scrub
from .model.rewind import SECONDS
from .scene.fields import NumberField
from .scene.panel import parse_number

LABEL = "Rewind [s]"


class RewindControl:
    """The field, and what the app's ``scrub`` operation and Play do with it."""

    def __init__(self, app) -> None:
        self.app = app
        self.back = 0.0  # s of the show the exhibits are scrubbed back (0: at the moment paused)
        self._live_t: dict[str, float] = {}  # simulated time of each exhibit when scrubbing began
        self.field: NumberField | None = None

    def build(self, gui) -> None:
        app = self.app
        self.field = NumberField(
            gui,
            LABEL,
            0.0,
            read=lambda text: app.enqueue("app", Scrub(text)),
            current=lambda: -self.back,
            **app.field_hooks(),
            hint=(
                f"Pause and go back through the last {SECONDS:g} s of the show (seconds of what was "
                "on screen). Play goes on from the moment shown; what came after it is dropped. "
                "0 goes back to where it paused."
            ),
            track=(-SECONDS, 0.0, 0.1),
            track_apply=lambda x: app.enqueue("app", Scrub(x)),
        )
        app.w["rewind"], app.w["rewind_track"] = self.field.box, self.field.track
        app.number_fields["rewind"] = self.field

    def scrub(self, value) -> None:
        """Pause and show every exhibit ``-value`` seconds of the show back (``value`` as typed
        in the field, -60..0; an exhibit with less kept goes back as far as it can)."""
        app = self.app
        try:
            v = parse_number(LABEL, value, -SECONDS, 0.0)
        finally:
            self.show()
        app.playing = False
        app._rtf_window.clear()
        for key, ex in app.exhibits.items():
            if ex.model.scrubbed is None:
                self._live_t[key] = ex.model.t
            ex.model.scrub(-v)
        self.back = max((ex.model.scrubbed or 0.0) for ex in app.exhibits.values())
        self.show()

    def sim_back(self) -> float:
        """How far back [simulated s] the exhibits still scrubbed are from where they paused
        (one changed meanwhile went on from its moment shown, or started afresh)."""
        return max(
            (
                self._live_t.get(k, ex.model.t) - ex.model.t
                for k, ex in self.app.exhibits.items()
                if ex.model.scrubbed is not None
            ),
            default=0.0,
        )

    def resume(self) -> None:
        """Every exhibit goes on from the moment shown (called before Play and Step)."""
        app = self.app
        if any(ex.model.scrubbed is not None for ex in app.exhibits.values()):
            app.sim_time = max(0.0, app.sim_time - self.sim_back())
            for ex in app.exhibits.values():
                ex.model.resume_here()
        self.forget()

    def forget(self) -> None:
        """Back at the moment the exhibits are in (after Play, Step or Reset)."""
        self._live_t.clear()
        self.back = 0.0
        self.show()

    def show(self) -> None:
        if self.field is None:
            return
        app = self.app
        syncing, app._syncing = app._syncing, True
        try:
            self.field.show(round(-self.back, 2) + 0.0)
        finally:
            app._syncing = syncing

    def status(self) -> str:
        """The status line's words while scrubbed back ("" otherwise)."""
        if not any(ex.model.scrubbed is not None for ex in self.app.exhibits.values()):
            return ""
        return f" · {self.back:.1f} s back: Play goes on from here"
