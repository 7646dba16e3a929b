"""Typed numbers in the panel: read when the person presses Enter, exactly as typed.

Three facts of viser's browser client (1.1) decide how a number box works:

- Every message the panel sends (a box's text, a button's click, a form's submit) goes through
  one sender that keeps only the newest message while a 50 ms window is open, and the window is
  closed by a timer that a busy page runs late. A box's text reaches the server on each keystroke,
  but a keystroke followed quickly by Enter (a form's submit) or by a click elsewhere is
  *replaced* by that message: the server held ``2.`` when the person had typed ``2.5`` and
  pressed Enter, and applied 2.
- A text box shows whatever value the server last sent, at once, even while the person types in
  it: a value sent back as they start typing becomes the start of their text (``0.2`` + ``.5``).
- The server sees neither focus nor leaving the box.

So each number box is a multi-line text box in which Enter is a character: the Enter arrives
*inside* the box's own text (``2.5\\n``), in the same message as the last digit, and a newer
message of the same box carries the whole text again, so nothing the person typed can be
missing when the Enter is read. The number entered is the line Enter was pressed on. The server
never writes into a box the person has typed in (not to show the value in force, not to put a
refused value back) until they have moved on to another control; only then is the box set to
the value in force. Text left without Enter is *not* applied when the person moves on (the last
keystrokes may be the ones the click replaced): a notification says it was not entered and the
box shows the value in force again.

A :class:`NumberField` with ``track`` has a bare slider track under its box; one without has
a stepper (− / +, to the neighbouring value of a 1-2-5 series) instead, as a PhET number
control has arrows beside the number.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any


def number_text(x: float) -> str:
    """How a number field shows a value: six significant digits, no trailing zeros."""
    return f"{float(x):.6g}"


def entered_line(before: str, after: str) -> tuple[bool, str | None]:
    """Whether the text ``after`` (following ``before`` in the same box) holds an Enter the
    person pressed, and the line entered: ``(False, None)`` while typing; ``(True, line)``
    for the line Enter was pressed on; ``(True, None)`` when the box changed in more than one
    place at once and the line meant cannot be told (several edits in one message).

    >>> entered_line("2.5", "2.5\\n")
    (True, '2.5')
    >>> entered_line("2.5", "2.\\n5")   # Enter in the middle enters the whole line
    (True, '2.5')
    >>> entered_line("2.5\\n", "2.5\\n0.4\\n")   # the next number, typed on the new line
    (True, '0.4')
    >>> entered_line("", "1e-2")
    (False, None)
    """
    if after.count("\n") <= before.count("\n"):
        return False, None
    # one Enter typed at position i: ``after`` is ``before`` with "\n" put in at i
    if len(after) == len(before) + 1:
        i = next((k for k in range(len(before)) if before[k] != after[k]), len(before))
        if after[:i] + after[i + 1 :] == before and after[i] == "\n":
            start = before.rfind("\n", 0, i) + 1
            end = before.find("\n", i)
            return True, before[start : None if end < 0 else end]
    # several keystrokes in one message (the newest text replaces the ones between): the line
    # before the last newline, if the text ends there (typed, then Enter at its end)
    if after.endswith("\n"):
        return True, after[:-1].rsplit("\n", 1)[-1]
    return True, None


def stepped(x: float, direction: int, lo: float | None, hi: float | None) -> float:
    """The next value of the 1-2-5 series (…, 0.01, 0.02, 0.05, 0.1, …) above (``direction``
    +1) or below (-1) ``x``, negative values mirrored, held to ``lo..hi``. Where the range holds
    0 (``lo <= 0``), a step below a thousandth of the range's scale goes to 0, and from 0 to
    that thousandth."""
    scale = max(abs(v) for v in (x, lo or 0.0, hi or 0.0)) or 1.0
    has_zero = lo is not None and lo <= 0.0
    floor = 10.0 ** (math.floor(math.log10(scale)) - 3) if has_zero else 0.0
    if x == 0.0 or abs(x) < floor:
        y = direction * (floor or 10.0 ** (math.floor(math.log10(scale)) - 3))
    else:
        sign = 1.0 if x > 0 else -1.0
        decade = 10.0 ** math.floor(math.log10(abs(x)))
        grid = sorted(m * decade * 10.0**k for k in (-1, 0, 1) for m in (1.0, 2.0, 5.0))
        eps = 1e-9 * abs(x)
        if direction * sign > 0:  # away from 0
            y = sign * next(g for g in grid if g > abs(x) + eps)
        else:
            below = [g for g in grid if g < abs(x) - eps][-1]
            y = sign * below if below >= floor else 0.0
    if lo is not None:
        y = max(y, lo)
    if hi is not None:
        y = min(y, hi)
    return float(f"{y:.12g}")


class ThreadFlag:
    """A boolean attribute each thread sees on its own (a descriptor; False until set)."""

    def __set_name__(self, owner, name: str) -> None:
        self.key = f"_{name}_by_thread"

    def __get__(self, obj, objtype=None):
        if obj is None:
            return self
        return getattr(obj.__dict__.setdefault(self.key, threading.local()), "on", False)

    def __set__(self, obj, value: bool) -> None:
        obj.__dict__.setdefault(self.key, threading.local()).on = bool(value)


class Typing:
    """The number fields the person has typed in; touching any other control is leaving them."""

    def __init__(self, run: Callable[[Callable[[], None]], None] | None = None) -> None:
        self._lock = threading.Lock()
        self._used: dict[int, NumberField] = {}
        # how a field's leaving is carried out: the app runs it in its loop thread, between
        # frames, where every widget is shown
        self._run = run or (lambda fn: fn())

    def typed(self, field: NumberField) -> None:
        self.left(but=field)
        with self._lock:
            self._used[id(field)] = field

    def done(self, field: NumberField) -> None:
        with self._lock:
            self._used.pop(id(field), None)

    def left(self, but: Any = None) -> None:
        """The person moved on to another control: every field typed in except ``but`` shows
        the value in force again (text left without Enter is not applied, and they are told)."""
        with self._lock:
            fields = [f for f in self._used.values() if f is not but]
            for f in fields:
                self._used.pop(id(f), None)
        for f in fields:
            self._run(f.leave)


class NumberField:
    """A number box (and, with ``track = (lo, hi, step)``, a slider track under it, else a
    stepper).

    ``read(text)`` gets the line entered and applies it or refuses it; ``current()`` gives the
    value in force. ``on`` is the app's ``on_update`` that skips its own syncs; ``quiet()`` is
    a context in which the app's own widget changes are not taken for the person's.
    ``track_apply(x)`` takes a value set on the track or the stepper (inside ``lo..hi``).
    ``notify(title, body)`` tells the person what happened to text they left."""

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
        lo: float | None = None,
        hi: float | None = None,
        stepper: bool = True,
        quiet: Callable[[], Any] | None = None,
        defer: Callable[[Callable[[], None]], None] | None = None,
        notify: Callable[[str, str], None] | None = None,
    ) -> None:
        import contextlib

        self.label = label
        self._read, self._current, self._typing = read, current, typing
        self._quiet = quiet or contextlib.nullcontext
        self._defer = defer or (lambda fn: fn())
        self._notify = notify
        self._lock = threading.Lock()
        self._text = number_text(value)  # the box's text as last seen (sent or received)
        self._pending = False  # the person typed text not yet entered
        self._used = False  # the person typed in the box and has not moved on
        self._asked: float | None = None  # the value a stepper click asked for, until shown
        hint = (hint + ". " if hint else "") + "Type a number and press Enter"
        self.box = gui.add_text(label, initial_value=self._text, multiline=True, hint=hint)
        self.track = self.stepper = None
        self.lo, self.hi = lo, hi
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
                typing.left()
                x = float(v[0]) if len(v) else math.nan
                if math.isfinite(x) and lo <= x <= hi and track_apply is not None:
                    track_apply(x)

            on(self.track, dragged)
        elif stepper:
            self.stepper = gui.add_button_group(
                "",
                options=("−", "+"),
                hint=f"{label}: the next value down or up (1, 2, 5, 10, ...)",
            )

            def step(event) -> None:
                if event.client_id is None:
                    return  # the reset below
                typing.left()
                direction = 1 if self.stepper.value == "+" else -1
                # viser calls a button group's callbacks only when its value changes: without
                # this, a second click on the same arrow would do nothing
                self.stepper.value = ""
                self._defer(lambda: self._step(direction))

            self.stepper.on_click(step)

        @self.box.on_update
        async def _typed(event) -> None:
            # async: run on viser's event loop in the order the messages came, each seeing
            # its own message's text (pool threads would see them in any order)
            if event.client_id is None:
                return  # set from Python: the app showing a value, or a test (then submit())
            self._received(self.box.value)

    def _step(self, direction: int) -> None:
        """In the loop thread: the next value from the one in force, or from the one the last
        click asked for if that is still on its way (two quick clicks are two steps), checked
        as a typed number is."""
        base = self._current() if self._asked is None else self._asked
        self._asked = stepped(base, direction, self.lo, self.hi)
        self._read(number_text(self._asked))

    # ------------------------------------------------------------------ the person's text
    def _received(self, text: str) -> None:
        with self._lock:
            before, self._text = self._text, text
            entered, line = entered_line(before, text)
            self._used = True
            self._pending = not entered and text.strip() != number_text(self._current())
        self._typing.typed(self)
        if not entered:
            return
        if line is None:
            self._defer(
                lambda: self._tell(
                    "Enter pressed, but the box changed in several places at once: type the "
                    "number again and press Enter"
                )
            )
        elif line.strip():
            self._defer(lambda: self._read(line))

    def _tell(self, body: str) -> None:
        if self._notify is not None:
            self._notify(f"Not applied ({self.label})", body)

    def submit(self) -> None:
        """Read the box's whole text now, as Enter would (the headless API: a test or a tool
        sets ``box.value`` and submits)."""
        with self._lock:
            text = self._text = self.box.value
            self._pending = False
        self._typing.done(self)
        if str(text).strip() == number_text(self._current()):
            return
        self._read(text)

    def leave(self) -> None:
        """The person moved on: text typed and not entered is not applied (say so), and the
        box shows the value in force."""
        with self._lock:
            pending, self._pending, self._used = self._pending, False, False
        if pending:
            self._tell(
                "the number typed was not entered, so it was not applied: type it and press Enter"
            )
        with self._quiet():
            self.show(self._current())

    @property
    def in_use(self) -> bool:
        """The person has typed in the box and not moved on: the server does not write in it."""
        return self._used

    def show(self, x: float | str) -> None:
        """Show the value in force in the box (and on the track), unless the person is using
        the box; call with the app's syncing flag set, so the change is not taken for theirs."""
        self._asked = None  # what a step asked for is in force now (or was refused)
        if self.track is not None and not isinstance(x, str):
            self.track.value = (min(max(float(x), self.lo), self.hi),)
        with self._lock:
            if self._used:
                return
            text = x if isinstance(x, str) else number_text(x)
            if self.box.value == text:
                return
            # under the lock: a text the person sends meanwhile is seen after it, not before
            self._text = text
            self.box.value = text

    @property
    def visible(self) -> bool:
        return self.box.visible

    @visible.setter
    def visible(self, v: bool) -> None:
        self.box.visible = v
        for h in (self.track, self.stepper):
            if h is not None:
                h.visible = v
