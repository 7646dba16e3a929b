"""What the exhibit's controls do to a run that is going (headless models): the kick's strength is
a setting of the next kick and the beam comes and goes, both without restarting the run; the
figures are measured from the run's own samples and stay once measured until the motion
changes; after going back, the chart ends at the moment shown."""

from __future__ import annotations

import numpy as np
import pytest

from mechviz.dynamics import measure
from mechviz.viz.model import CyclotronConfig, CyclotronModel
from mechviz.viz.model.commands import Kick, Set

FRAME = 1 / 60


def _frames(model, seconds: float) -> None:
    for _ in range(round(seconds / FRAME)):
        model.advance(FRAME, shown=FRAME)


def test_changing_the_kick_strength_changes_only_the_next_kick_and_keeps_the_run():
    model = CyclotronModel(CyclotronConfig(method="boris", dt=0.01))
    _frames(model, 2.0)
    model.apply(Kick(dv=0.3))
    _frames(model, 1.0)
    t, state, sim = model.t, model.state.copy(), model.sim
    model.apply(Set(fields={"kick": 0.8}))
    assert model.config.kick == 0.8
    assert model.sim is sim and model.t == t  # the same run, at the same time
    np.testing.assert_array_equal(model.state, state)  # the kick given stays given
    model.apply(Kick())  # the next kick is the new strength
    v_before = np.hypot(*state[3:5])
    assert np.hypot(*model.state[3:5]) == pytest.approx(np.hypot(v_before, 0.8), rel=1e-3)


def test_the_beam_comes_and_goes_without_restarting_the_run_or_dropping_a_kick():
    model = CyclotronModel(CyclotronConfig(method="boris", dt=0.01, beam_size=8))
    _frames(model, 1.5)
    model.apply(Kick(dv=0.5))
    _frames(model, 0.5)
    t, state, sim = model.t, model.state.copy(), model.sim
    model.apply(Set(fields={"beam": True}))
    assert model.sim is sim and model.t == t
    np.testing.assert_array_equal(model.state, state)  # the kicked charge goes on
    assert model.beam is not None and model.beam.t == t
    # the beam's charges leave from where the charge is, in its direction, at the beam's speeds
    b = model.beam.state
    np.testing.assert_allclose(b[:, :3], np.tile(state[:3], (8, 1)))
    speeds = np.hypot(b[:, 3], b[:, 4])
    np.testing.assert_allclose(speeds, np.linspace(*model.config.beam_speeds, 8))
    direction = b[:, 3:5] / speeds[:, None]
    np.testing.assert_allclose(direction, np.tile(state[3:5] / np.hypot(*state[3:5]), (8, 1)))
    _frames(model, 0.5)
    assert model.beam.t == pytest.approx(model.t)  # on the main run's clock
    t2, state2 = model.t, model.state.copy()
    model.apply(Set(fields={"beam_size": 4}))  # another beam, the run goes on
    assert model.sim is sim and model.t == t2 and len(model.beam.state) == 4
    model.apply(Set(fields={"beam": False}))
    assert model.beam is None and model.sim is sim and model.t == t2
    np.testing.assert_array_equal(model.state, state2)
    _frames(model, 0.5)
    assert model.t == pytest.approx(t2 + 0.5, abs=0.011)


def test_a_step_longer_than_a_frame_is_measured_from_the_runs_own_steps_not_called_aliased():
    # rk4 at dt = 0.1: six frames of 1/60 s to a step; each frame used to add the same sample
    # again, and a charge that "did not move" between two samples read as an alias
    model = CyclotronModel(CyclotronConfig(method="rk4", dt=0.1))
    _frames(model, 12.0)
    t, _ = model.motion.arrays()
    assert np.all(np.diff(t) > 0) and np.diff(t) == pytest.approx(0.1)
    m = model.measured()
    assert m["gyrofrequency"], m["gyrofrequency"].reason
    assert m["gyrofrequency"].value == pytest.approx(1.0, rel=1e-4)
    assert m["radius"], m["radius"].reason
    assert m["radius"].value == pytest.approx(model.theory_radius, rel=1e-3)


def test_a_figure_once_measured_stays_until_the_motion_changes():
    model = CyclotronModel(CyclotronConfig(method="boris", dt=0.01))
    estimates = iter([measure.Estimate(1.0), measure.unresolved("slid on"), None])
    model._measure = lambda: {"gyrofrequency": next(estimates)}
    assert model.measured()["gyrofrequency"].value == 1.0
    assert model.measured()["gyrofrequency"].value == 1.0  # no longer resolved: kept
    model.apply(Kick(dv=0.2))  # the motion changed: measured afresh
    model._measure = lambda: {"gyrofrequency": measure.unresolved("a new circle")}
    assert not model.measured()["gyrofrequency"]


@pytest.mark.parametrize("window", [None, 600.0], ids=["last points", "10 min window"])
def test_after_going_back_the_chart_ends_at_the_moment_shown(window):
    model = CyclotronModel(CyclotronConfig(method="rk4", dt=0.05, compare_method="euler"))
    if window is not None:
        model.set_chart_window(window)
    for _ in range(6 * 60):  # measured every third frame, as the viewer does
        for k in range(3):
            model.advance(FRAME, measure=k == 0, shown=FRAME)
    t_paused = model.t
    model.scrub(2.5)
    assert model.t == pytest.approx(t_paused - 2.5, abs=0.06)
    data = model.chart_data()
    assert data[0][-1] == pytest.approx(model.t, abs=1e-9)  # the last point is now's
    assert np.all(np.diff(data[0]) > 0)
    assert all(np.isfinite(a[-1]) for a in data[:3])
    model.scrub(0.0)  # back to where it paused: the chart ends there again
    assert model.chart_data()[0][-1] == pytest.approx(t_paused, abs=1e-9)
