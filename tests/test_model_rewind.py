"""Going back in a run (:mod:`mechviz.viz.model.rewind`): a paused exhibit scrubbed back shows the state
its run had at that time, the run goes on from there as it went on then, and only the last
minute of the show is kept, in bounded memory."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechviz.dynamics import cyclotron as cy
from mechviz.viz.model import CyclotronConfig, CyclotronModel, DiskConfig, DiskModel, HoopModel
from mechviz.viz.model.commands import Kick, Set
from mechviz.viz.model.rewind import BUDGET, SECONDS

FRAME = 1 / 60


def _run(model, seconds: float, speed: float = 1.0) -> dict[float, dict]:
    """Advance ``model`` in frames of the show at ``speed``; returns what each frame showed,
    by simulated time: the state, the energy error and the error against the reference."""
    seen = {}
    for _ in range(round(seconds / FRAME)):
        model.advance(speed * FRAME, shown=FRAME)
        smp = model.sample
        seen[model.t] = {
            "state": model.state.copy(),
            "energy_error": float(smp.energy_error[0]),
            "error": None if smp.error is None else float(smp.error[0]),
        }
    return seen


def test_the_cyclotron_scrubbed_back_is_on_its_exact_circle_at_the_time_shown():
    m = CyclotronModel()  # the exact flow: the state at any time is the closed form's
    seen = _run(m, 30.0)
    t_paused = m.t
    back = m.scrub(12.5)
    assert back == pytest.approx(12.5, abs=FRAME)
    assert m.t == pytest.approx(t_paused - back, abs=1e-9)
    np.testing.assert_array_equal(m.state, seen[m.t]["state"])
    exact = m.sim.system.exact(m.sim.state0, m.t - m.sim.t0)[0]
    np.testing.assert_allclose(m.state, exact, rtol=0, atol=1e-12)
    # back to 0 s: where it paused
    m.scrub(0.0)
    assert m.t == t_paused and m.scrubbed == 0.0


def test_boris_resumed_from_the_moment_shown_retraces_its_own_run_and_forgets_a_later_kick():
    m = CyclotronModel(CyclotronConfig(method="boris", dt=0.01))
    m.set_chart_window(60.0)  # as the viewer's charts: drawn from the long history
    _run(m, 10.0)
    before_kick = m.theory_radius
    m.apply(Kick(dv=0.5))
    _run(m, 10.0)
    t_end, end = m.t, m.state.copy()
    assert m.theory_radius > before_kick * 1.05  # the kick widened the circle
    m.scrub(15.0)  # 5 s before the kick
    assert m.t == pytest.approx(t_end - 15.0, abs=0.02)
    assert m.theory_radius == pytest.approx(before_kick, rel=1e-12)  # the circle before it
    m.resume_here()
    t_cut = m.t
    assert m.scrubbed is None
    # the samples after the moment gone back to are forgotten: the charts end there
    assert m.chart_data()[0].max() == pytest.approx(t_cut, abs=0.05)
    assert np.all(m.motion.arrays()[0] <= t_cut + 1e-12)  # the estimators' samples too
    # the same steps again, without the kick: back on the first circle at the time paused at
    _run(m, t_end - t_cut)
    assert m.t == pytest.approx(t_end, abs=0.02)
    assert m.theory_radius == pytest.approx(before_kick, rel=1e-9)
    p = m.params
    assert cy.larmor_radius(p, m.state) == pytest.approx(before_kick, rel=1e-6)
    assert m.measured()["gyrofrequency"].value == pytest.approx(cy.gyrofrequency(p), rel=1e-3)
    assert not np.allclose(m.state, end)  # the kicked run ended elsewhere


def test_the_tumbling_disk_scrubbed_back_has_that_moments_energy_and_reference_error():
    """The released disk has no closed form in the viewer's terms: its energy error and its
    error against the tight reference run are what the run had then, and going on from there
    retraces it (RK4's fixed steps, the reference run restored with it)."""
    m = DiskModel(DiskConfig(mode="released", method="rk4"))
    seen = _run(m, 20.0)
    t_paused, paused = m.t, m.state.copy()
    m.scrub(8.0)
    then = seen[m.t]
    np.testing.assert_array_equal(m.state, then["state"])
    assert float(m.sample.energy_error[0]) == then["energy_error"]
    assert float(m.sample.error[0]) == pytest.approx(then["error"], rel=1e-6, abs=1e-15)
    m.advance_to(t_paused)  # an advance goes on from the moment shown
    np.testing.assert_array_equal(m.state, paused)
    assert float(m.sample.error[0]) == pytest.approx(seen[m.t]["error"], rel=1e-3, abs=1e-14)


def test_the_hoop_scrubbed_back_across_a_new_start_shows_the_old_start_and_its_ghost():
    m = HoopModel()
    seen = _run(m, 6.0)
    m.apply(Set(fields={"mode": "mode 2"}))  # the runs jump to another start, time goes on
    _run(m, 6.0)
    m.scrub(9.0)  # 3 s into the first start
    np.testing.assert_array_equal(m.state, seen[m.t]["state"])
    ghost_then = m.ghost_state()
    # the ghost is linear theory from the first start, not from the second
    m2 = HoopModel()
    m2.advance_to(m.t)
    np.testing.assert_allclose(ghost_then, m2.ghost_state(), rtol=0, atol=1e-12)


def test_a_blow_up_after_the_moment_gone_back_to_has_not_happened():
    m = HoopModel()
    m.apply(Set(fields={"method": "euler", "dt": 0.05}))
    _run(m, 60.0)
    assert m.paused and m.failure  # explicit Euler's energy grew past the limit
    t_fail = m.failure_error.t
    m.scrub(m.rewind_span())  # as far back as is kept
    assert m.t < t_fail
    m.resume_here()
    assert not m.paused and m.failure is None


@pytest.mark.parametrize("speed", [1.0, 10.0])
def test_only_the_last_minute_of_the_show_is_kept_in_bounded_memory(speed):
    m = HoopModel()
    _run(m, 100.0, speed=speed)
    assert m.rewind_span() == pytest.approx(SECONDS, abs=2 * FRAME)
    assert len(m.rewind) <= m.rewind.rows + 1
    t_now = m.t
    back = m.scrub(1000.0)  # asked beyond: as far as is kept
    assert back == pytest.approx(SECONDS, abs=2 * FRAME)
    # a minute of the show is a minute of simulated time at 1x, ten at 10x
    assert t_now - m.t == pytest.approx(speed * SECONDS, rel=1e-3)


def test_a_large_beam_keeps_its_minute_in_fewer_states_within_the_budget():
    m = CyclotronModel(CyclotronConfig(beam=True, beam_size=1000))
    assert m.rewind.nbytes <= BUDGET
    assert m.rewind.rows < SECONDS * 60  # coarser than a frame: the budget rules
    _run(m, 70.0)
    assert m.rewind.nbytes <= BUDGET
    assert m.rewind_span() == pytest.approx(SECONDS, abs=m.rewind.spacing + FRAME)
    t_paused = m.t
    back = m.scrub(30.0)
    assert abs(back - 30.0) <= m.rewind.spacing
    assert m.beam.t == pytest.approx(t_paused - back, abs=1e-9)
    assert math.isfinite(float(m.beam.state.sum()))
