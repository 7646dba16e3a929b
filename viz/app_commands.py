"""The commands the viewer's app takes for itself (:meth:`mechviz.viz.app.MechvizApp.enqueue` with
target ``"app"``), each a frozen typed value, as the exhibits' own are
(:mod:`mechviz.viz.model.commands`)::

    app.enqueue("app", Pause())              # Play(), Pause(), Toggle(), Step(), ResetAll()
    app.enqueue("app", Speed(2.0))           # simulated seconds per second; text as typed too
    app.enqueue("app", Scrub(-10))           # paused, 10 s of the show back (0: the newest)
    app.enqueue("app", Stage("Hoop"))        # an exhibit's name on stage, or "Home"
    app.enqueue("app", Present("Off"))       # presentation mode: an exhibit's name, or "Off"

``client`` (a viser client handle, or ``None`` for every page) says whose page a camera move
is for. A value is checked where it is applied, in the app's loop thread, so that a refusal
names the field in the viewer (a notification) as a typed box's would; the kind of each
command is checked at once, in the caller's thread: anything that is not one of these is
refused there (:func:`refused`).
"""

from __future__ import annotations

from typing import Any

import msgspec


class AppCommand(msgspec.Struct, frozen=True, tag_field="op", forbid_unknown_fields=True):
    """What every app command shares: its ``op`` (the tag)."""

    @classmethod
    def op(cls) -> str:
        return cls.__struct_config__.tag


class Play(AppCommand, frozen=True, tag="play"):
    """Simulated time runs (from the moment shown, if the show was scrubbed back)."""


class Pause(AppCommand, frozen=True, tag="pause"):
    """Simulated time stops; the page keeps drawing."""


class Toggle(AppCommand, frozen=True, tag="toggle"):
    """Play if paused, pause if playing (the panel's Play/Pause button)."""


class Step(AppCommand, frozen=True, tag="step"):
    """Paused, one frame of simulated time on (its speed times the frame's 1/60 s)."""


class ResetAll(AppCommand, frozen=True, tag="reset"):
    """Every exhibit afresh from its start, the clock at 0, the rewind history forgotten."""


class Speed(AppCommand, frozen=True, tag="speed"):
    """Simulated seconds per second of the page, a number or the text a person typed
    (refused, naming Speed, outside the slider's range)."""

    value: float | str


class Scrub(AppCommand, frozen=True, tag="scrub"):
    """Paused, the show ``value`` seconds back from its newest moment (a number <= 0, or the
    text typed in the Rewind box)."""

    value: float | str | None


class ChartWindow(AppCommand, frozen=True, tag="chart_window"):
    """The time the charts span [s]: one of the panel's choices."""

    value: float | str


class Theme(AppCommand, frozen=True, tag="theme"):
    """The page's theme by name (light, dark, ...)."""

    value: str


class Stage(AppCommand, frozen=True, tag="stage"):
    """``value``, an exhibit's name, alone on stage, or "Home" for the three together."""

    value: str
    client: Any = None


class Present(AppCommand, frozen=True, tag="present"):
    """Presentation mode: ``value`` (an exhibit's name) on stage with the panel minimized, or
    "Off" back home with the panel open."""

    value: str
    client: Any = None


class Camera(AppCommand, frozen=True, tag="camera"):
    """A camera preset (an exhibit's name, "Home", "Top"), framed for ``client``'s page."""

    view: str
    client: Any = None


class Reframe(AppCommand, frozen=True, tag="reframe"):
    """The view in force framed again for ``client``'s page (it changed shape, or joined)."""

    client: Any = None


APP_COMMANDS: tuple[type[AppCommand], ...] = (
    Play,
    Pause,
    Toggle,
    Step,
    ResetAll,
    Speed,
    Scrub,
    ChartWindow,
    Theme,
    Stage,
    Present,
    Camera,
    Reframe,
)


def refused(command: object) -> ValueError:
    """The error for ``command`` given to the app, which is none of its commands."""
    ops = ", ".join(c.__name__ for c in APP_COMMANDS)
    return ValueError(
        f"an app command must be one of {ops} (mechviz.viz.app_commands); got {command!r}"
    )
