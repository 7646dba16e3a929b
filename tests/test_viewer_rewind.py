"""The viewer's Rewind control, headless: typed or dragged, it pauses every exhibit and shows
each as it was that many seconds of the show back (scene, readout, chart); Play goes on from the
moment shown; a value outside -60..0 s is refused, naming the field."""

from __future__ import annotations

import re

import numpy as np
import pytest
from viewer_steps import FRAME

from mechviz.viz.app_commands import Play

# every test here starts the viewer's server (the app fixture: tests/conftest.py)
pytestmark = [pytest.mark.slow, pytest.mark.usefixtures("warm_viewer")]


def enter(app, text) -> None:
    app.w["rewind"].value = str(text)
    app.number_fields["rewind"].submit()
    app.step_frame()


def shown_t(text: str) -> float:
    return float(re.search(r"t = ([0-9.]+) s", text).group(1))


def test_rewinding_pauses_and_shows_every_exhibit_that_far_back_then_play_goes_on_from_there(app):
    for _ in range(6 * 60):  # six seconds of the show at 1x
        app.step_frame(FRAME)
    t_paused = {k: ex.model.t for k, ex in app.exhibits.items()}
    charge = app.exhibits["cyclotron"].bodies.batched_positions[0].copy()
    enter(app, "-2.5")
    assert not app.playing
    for key, ex in app.exhibits.items():
        assert ex.model.t == pytest.approx(t_paused[key] - 2.5, abs=FRAME), key
    app._update_gui(force=True)  # the readouts and charts refreshed (each on its own frame)
    for key, ex in app.exhibits.items():
        assert shown_t(app.w[f"{key}.readout"].content) == pytest.approx(ex.model.t, abs=0.01)
        # the chart ends there: its last point is the moment shown, not an earlier kept one
        assert app.w[f"{key}.chart"].data[0][-1] == pytest.approx(ex.model.t, abs=1e-9)
    status = app.w["status"].content
    assert "back" in status and "t = " not in status  # one time per exhibit: its readout's
    # the charge is drawn where it was then (the field turns it about 2.5 rad in 2.5 s)
    moved = app.exhibits["cyclotron"].bodies.batched_positions[0]
    assert np.linalg.norm(moved - charge) > 0.5
    assert app.w["rewind"].value == "-2.5"
    # Play: on from the moment shown, the clock included
    app.enqueue("app", Play())
    app.step_frame(FRAME)
    assert app.playing and app.w["rewind"].value == "0"
    for key, ex in app.exhibits.items():
        assert ex.model.scrubbed is None
        assert ex.model.t == pytest.approx(t_paused[key] - 2.5 + FRAME, abs=2 * FRAME), key
    assert app.sim_time == pytest.approx(t_paused["hoop"] - 2.5 + FRAME, abs=2 * FRAME)


def test_back_to_zero_and_play_goes_on_from_where_it_paused(app):
    for _ in range(120):
        app.step_frame(FRAME)
    t0 = app.exhibits["hoop"].model.t
    enter(app, "-1")
    enter(app, "0")
    app.enqueue("app", Play())
    app.step_frame(FRAME)
    assert app.exhibits["hoop"].model.t == pytest.approx(t0 + FRAME, abs=1e-9)


@pytest.mark.parametrize("text", ["5", "-61", "abc"])
def test_a_rewind_outside_the_last_minute_is_refused_naming_the_field(app, text):
    app.step_frame(FRAME)
    enter(app, text)
    assert app.messages and app.messages[-1][1].startswith("Rewind [s]")
    assert app.w["rewind"].value == "0"
    # nothing changed: still playing, no exhibit taken back
    assert app.playing and all(ex.model.scrubbed is None for ex in app.exhibits.values())
