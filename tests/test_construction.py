"""A Solver or a Simulation for a new problem takes what depends only on its system, method and
tolerances from the first one built, already checked: the same objects, the same answers as a
build from nothing, and a bad setting still refused, naming its field."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechviz.dynamics import (
    Hoop,
    ReleasedDisk,
    Simulation,
    params,
    run_plan,
    solver,
    steps,
    systems,
)
from mechviz.dynamics.disk import DiskParams
from mechviz.dynamics.params import SettingError
from mechviz.dynamics.solver import Solver

SYSTEMS = [Hoop(), ReleasedDisk(DiskParams(omega=1.0), (0.3, 0.0, 0.2))]


def _forget_everything_kept() -> None:
    solver._PLANS.clear()
    run_plan._PLANS.clear()
    steps._STEPS.clear()
    systems._KERNEL_PARAMS.clear()


@pytest.mark.parametrize("system", SYSTEMS, ids=lambda s: s.name)
def test_a_second_solver_of_a_system_takes_the_first_ones_settings_and_answers_alike(system):
    _forget_everything_kept()
    state = system.default_state() * 1.01
    first = Solver(system, rtol=1e-6, atol=1e-6)
    fresh = first.solve(3.0, state).copy()
    second = Solver(system, rtol=1e-6, atol=1e-6)
    assert second.params is first.params  # the kernel parameters, worked out once
    assert (second.order, second.a) == (first.order, first.a)
    assert second._out is not first._out  # each solver's answer is its own
    np.testing.assert_array_equal(second.solve(3.0, state), fresh)
    assert second.steps == first.steps


@pytest.mark.parametrize("method", ["taylor", "dop853", "rk4"])
@pytest.mark.parametrize("system", SYSTEMS, ids=lambda s: s.name)
def test_a_second_simulation_shares_the_checked_step_and_lands_on_the_same_bits(system, method):
    settings = {"dt": 0.01} if method == "rk4" else {"rtol": 1e-6, "atol": 1e-6}
    state = system.default_state() * 1.01
    _forget_everything_kept()
    first = Simulation(system, method, state=state, reference=None, **settings)
    first.advance_to(2.0)
    second = Simulation(system, method, state=state, reference=None, **settings)
    assert second.step is first.step and second.p is first.p
    second.advance_to(2.0)
    np.testing.assert_array_equal(second.state, first.state)
    assert (second.steps, second.nfev) == (first.steps, first.nfev)
    second.restart(state)  # a new problem on a kept run: the same answer again
    second.advance_to(2.0)
    np.testing.assert_array_equal(second.state, first.state)


@pytest.mark.parametrize(
    ("field", "value"), [("rtol", -1e-6), ("rtol", math.nan), ("atol", math.inf), ("atol", 0.0)]
)
def test_a_bad_tolerance_is_refused_by_name_after_good_ones_were_kept(field, value):
    system = Hoop()
    Solver(system, rtol=1e-6, atol=1e-6)
    Simulation(system, "taylor", rtol=1e-6, atol=1e-6, reference=None)
    bad = {"rtol": 1e-6, "atol": 1e-6, field: value}
    with pytest.raises(SettingError) as err:
        Solver(system, **bad)
    assert err.value.field == field
    with pytest.raises(SettingError) as err:
        Simulation(system, "taylor", reference=None, **bad)
    assert err.value.field == field


def test_a_kept_run_refuses_a_start_that_is_not_finite():
    sim = Simulation(Hoop(), "taylor", rtol=1e-6, reference=None)
    with pytest.raises(ValueError, match="finite"):
        sim.restart([0.1, np.inf, 0.0, 0.0])
    with pytest.raises(SettingError) as err:
        Simulation(Hoop(), "taylor", rtol=1e-6, state=[0.1, np.nan, 0.0, 0.0], reference=None)
    assert err.value.field == "state"


@pytest.mark.parametrize("value", [1e-6, -2.5, 0.0, -0.0, 1e300, params.TINY])
def test_a_plain_float_passes_the_number_checks_as_it_is(value):
    got = params.finite("x", value)
    assert got == value and math.copysign(1.0, got) == math.copysign(1.0, value)


@pytest.mark.parametrize("value", [math.inf, -math.inf, math.nan, params.TINY / 2, -5e-324])
def test_a_float_that_is_not_a_usable_number_is_refused_naming_its_field(value):
    with pytest.raises(SettingError) as err:
        params.finite("x", value)
    assert err.value.field == "x"
