"""The driver's limits (:class:`mechviz.dynamics.Simulation`): work estimated before a run, compiled work
in short chunks so that Ctrl-C is seen, an energy error relative to the energy that moves, and a
reference clearly tighter than the run it judges."""

from __future__ import annotations

import math
import os
import signal
import threading

import numpy as np
import pytest

from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, Simulation, hoop
from mechviz.dynamics.simulation import MIN_COMPARED_TOL, REFERENCE_ACCURACY, REFERENCE_TOL


def test_estimated_steps_of_a_fixed_step_run_are_exact_and_count_the_ensemble():
    states = np.array([[1.0, 0, 0, 0, 1.0, 0], [2.0, 0, 0, 0, 2.0, 0]])
    sim = Simulation(Cyclotron(), "rk4", dt=0.01, state=states)
    assert sim.estimated_steps(10.0) == 2 * 1000
    sim.advance_to(4.0)
    assert sim.estimated_steps(10.0) == 2 * 600
    assert sim.estimated_steps(1e308) == math.inf
    assert Simulation(Cyclotron(), "exact").estimated_steps(1e9) == 0.0


@pytest.mark.parametrize("rtol", [1e-6, 1e-9, 1e-12])
@pytest.mark.parametrize("system", [Cyclotron(), Hoop(), ReleasedDisk()], ids=lambda s: s.name)
def test_estimated_steps_of_dop853_err_on_the_safe_side_by_at_most_5(system, rtol):
    state = hoop.mode_state(system.params, (0.5, 0.2)) if system.name == "hoop" else None
    sim = Simulation(system, "dop853", rtol=rtol, state=state, reference=None)
    guess = sim.estimated_steps(50.0)
    sim.advance_to(50.0)
    assert sim.steps < guess < sim.steps * 5


def test_the_reference_run_adds_its_steps_to_the_estimate():
    s0 = hoop.mode_state(Hoop().params, (0.0, 0.3))  # mode 2: no exact solution
    alone = Simulation(Hoop(), "rk4", dt=0.01, state=s0, reference=None).estimated_steps(10.0)
    judged = Simulation(Hoop(), "rk4", dt=0.01, state=s0).estimated_steps(10.0)
    assert alone == 1000 and judged > alone


def test_ctrl_c_interrupts_a_long_compiled_run_within_a_second():
    sim = Simulation(Hoop(), "rk4", dt=0.001, state=hoop.mode_state(Hoop().params, (0.3, 0.0)))
    sim.advance_to(0.01)  # compile or load the kernel first
    timer = threading.Timer(1.0, os.kill, (os.getpid(), signal.SIGINT))
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        sim.advance_to(1e6)  # 1e9 steps: minutes in one compiled call
    # The run stopped at the end of a whole chunk: a consistent state, time and step count.
    assert 0 < sim.steps < 1e9 and sim.t == pytest.approx(sim.steps * 0.001)
    assert np.all(np.isfinite(sim.state))


def test_chunks_give_the_same_fixed_step_run_as_one_call():
    s0 = hoop.mode_state(Hoop().params, (0.4, 0.2))
    a = Simulation(Hoop(), "rk4", dt=0.01, state=s0, reference=None)
    b = Simulation(Hoop(), "rk4", dt=0.01, state=s0, reference=None)
    b._chunk_steps = 7
    a.advance_to(20.0)
    b.advance_to(20.0)
    np.testing.assert_array_equal(a.state, b.state)
    assert a.steps == b.steps == 2000


def test_the_hoop_energy_error_is_relative_to_the_energy_above_hanging_at_rest():
    p = Hoop().params
    s0 = hoop.mode_state(p, (0.0, 0.01))
    sim = Simulation(Hoop(), "rk4", dt=0.05, state=s0, reference=None)
    sim.advance_to(10.0)
    E0 = float(hoop.energy(p, s0))
    E = float(hoop.energy(p, sim.state[0]))
    floor = -(p.hoop_mass + 2 * p.bead_mass) * p.gravity * p.radius
    assert sim.sample().energy_error[0] == pytest.approx((E - E0) / (E0 - floor))
    assert abs(sim.sample().energy_error[0]) > 1e3 * abs((E - E0) / E0)


def test_the_reference_is_a_hundred_times_tighter_than_any_run_it_judges():
    s0 = hoop.mode_state(Hoop().params, (0.0, 0.3))
    assert REFERENCE_TOL * 100 <= MIN_COMPARED_TOL
    sim = Simulation(Hoop(), "dop853", rtol=MIN_COMPARED_TOL, state=s0)
    sim.advance_to(10.0)
    smp = sim.sample()
    # the reference's own error, measured beside it: small on this regular motion, not zero
    assert (
        smp.reference_kind == "reference" and 0.0 < smp.reference_accuracy[0] < REFERENCE_ACCURACY
    )
    assert smp.error[0] > 0.0  # not the reference compared with itself
    tight = Simulation(Hoop(), "dop853", rtol=MIN_COMPARED_TOL / 10, state=s0)
    assert tight.reference_kind is None and "reference" in tight.reference_note
    exact = Simulation(Cyclotron(), "dop853", rtol=1e-13)
    assert exact.sample().reference_kind == "exact" and np.all(
        exact.sample().reference_accuracy == 0.0
    )
