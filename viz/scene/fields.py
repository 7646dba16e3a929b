"""Typed numbers in the panel: a text box read on Enter or when the person moves on.

viser sends a text box's content to the server on every keystroke, so ``2`` arrives on the way
to ``2.5e-2``: reading the box after a pause in the typing applies half-typed numbers (a step of
2 s blows the hoop up in front of the class). Each :class:`NumberField` therefore sits in a form
of its own (viser's ``add_form`` without a header): Enter in the box submits the form, and only
then is the text read, by the one rule for typed numbers (:func:`mechviz.dynamics.params.parse_number`).
Text typed and left without Enter is read when the person touches any other control of the
panel (:class:`Typing` keeps what is pending), which is as close to "leaving the box" as the
server can see.

A slider's own number box in viser is the browser's number input, which rewrites scientific
notation while it is typed (``2.5e-2`` became -2.5); a :class:`NumberField` with ``track`` is a
labelled text box over a bare slider track (viser's one-handle multi-slider, which has no number
box), the two showing the same value in force.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any


def number_text(x: float) -> str:
    """How a number field shows a value: six significant digits, no trailing zeros."""
    return f"{float(x):.6g}"


class Typing:
    """The fields holding typed text not yet read; touching one control reads the others'."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pending: dict[int, NumberField] = {}

    def typed(self, field: NumberField) -> None:
        self.commit(but=field)
        with self._lock:
            self._pending[id(field)] = field

    def done(self, field: NumberField) -> None:
        with self._lock:
            self._pending.pop(id(field), None)

    def commit(self, but: Any = None) -> None:
        """Read every pending field except ``but`` (the person moved on to another control)."""
        with self._lock:
            fields = [f for f in self._pending.values() if f is not but]
        for f in fields:
            f.submit()


class NumberField:
    """A number box (and, with ``track = (lo, hi, step)``, a slider track under it).

    ``read(text)`` gets the text when it is submitted and applies it or refuses it (and then
    puts the box back); ``current()`` gives the value in force, so the browser echoing a value
    the app just showed changes nothing. ``on`` is the app's ``on_update`` that skips its own
    syncs. ``track_apply(x)`` takes a value dragged on the track (a number on the track's grid,
    inside its range)."""

    def __init__(
        self,
        gui,
        label: str,
        value: float,
        *,
        read: Callable[[str], None],
        current: Callable[[], float],
        on: Callable[[Any, Callable[[Any], None]], None],
        typing: Typing,
        hint: str | None = None,
        track: tuple[float, float, float] | None = None,
        track_apply: Callable[[float], None] | None = None,
    ) -> None:
        self.label = label
        self._read, self._current, self._typing = read, current, typing
        with gui.add_form(None) as form:
            self.box = gui.add_text(label, initial_value=number_text(value), hint=hint)
        self.form = form
        self.track = None
        if track is not None:
            lo, hi, step = track
            self.lo, self.hi = lo, hi
            self.track = gui.add_multi_slider(
                "",
                min=lo,
                max=hi,
                step=step,
                initial_value=(min(max(value, lo), hi),),
                hint=hint,
            )

            def dragged(v) -> None:
                typing.commit(but=self)
                x = float(v[0]) if len(v) else math.nan
                if math.isfinite(x) and lo <= x <= hi and track_apply is not None:
                    track_apply(x)

            on(self.track, dragged)

        def typed(v) -> None:
            if str(v).strip() == number_text(current()):
                typing.done(self)  # the browser echoing what the app showed
                return
            typing.typed(self)

        on(self.box, typed)
        form.on_submit(lambda _event: self.submit())

    def submit(self) -> None:
        """Read the box now (Enter, or the person moved on)."""
        self._typing.done(self)
        text = self.box.value
        if str(text).strip() == number_text(self._current()):
            return
        self._read(text)

    def show(self, x: float | str) -> None:
        """Show the value in force in the box (and on the track); call with the app's syncing
        flag set, so the change is not taken for typing."""
        text = x if isinstance(x, str) else number_text(x)
        self.box.value = text
        if self.track is not None and not isinstance(x, str):
            self.track.value = (min(max(float(x), self.lo), self.hi),)

    @property
    def visible(self) -> bool:
        return self.box.visible

    @visible.setter
    def visible(self, v: bool) -> None:
        self.box.visible = v
        if self.track is not None:
            self.track.visible = v
