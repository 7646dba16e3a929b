"""Steps of the headless viewer's tests: frames of 1/60 s, and typing into a number field."""

from __future__ import annotations

FRAME = 1.0 / 60.0  # s: one frame of the viewer's loop at 60 Hz


def frames(app, n: int) -> None:
    """Draw ``n`` frames of the viewer ``app`` (the tests' fixture, without its loop thread)."""
    for _ in range(n):
        app.step_frame()


def enter(app, key: str, text) -> None:
    """Type ``text`` into the number field ``key`` and press Enter, as a person does."""
    app.w[key].value = str(text)
    app.number_fields[key].submit()
