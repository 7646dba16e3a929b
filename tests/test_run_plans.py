"""A run or a solver built per problem (:mod:`mechviz.dynamics.run_plan`): what is kept from the
first of the same settings serves the next without leaking one run's state into another, a new
system is never served another's settings, every bad setting is still refused on construction,
naming its field, and a Taylor run imports only what it uses."""

from __future__ import annotations

import dataclasses
import json
import os
import subprocess
import sys

import numpy as np
import pytest

from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, SettingError, Simulation, get_method
from mechviz.dynamics.solver import Solver

SYSTEMS = {
    "cyclotron": Cyclotron(),
    "hoop": Hoop(),
    "free-body": ReleasedDisk(extra_spin=(0.01, 0.0, 0.01)),
}
METHODS = ("taylor", "dop853", "rk4")


def _run(system, method: str, state=None, t: float = 2.0) -> Simulation:
    kw = {"dt": 1e-3} if method == "rk4" else {"rtol": 1e-9, "atol": 1e-9}
    sim = Simulation(system, method, state=state, reference=None, **kw)
    sim.advance_to(t / 2)
    sim.advance_to(t)
    return sim


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", list(SYSTEMS))
def test_a_run_built_again_runs_as_the_first_and_shares_no_state(name, method):
    system = SYSTEMS[name]
    first = _run(system, method)
    again = _run(system, method)
    np.testing.assert_array_equal(again.state, first.state)
    assert (again.t, again.steps, again.nfev) == (first.t, first.steps, first.nfev)
    # nothing a run writes is another's
    for attr in ("state", "state0", "_stats", "_status"):
        assert getattr(again, attr) is not getattr(first, attr)
    fresh = Simulation(system, method, reference=None, **_settings(method))
    assert (fresh.t, fresh.clock, fresh.t0, fresh.steps, fresh.nfev, fresh.rejected) == (
        0.0,
        0.0,
        0.0,
        0,
        0,
        0,
    )
    assert fresh.last_step is None
    first.jump(first.state * 0.5)  # a change to one run is not seen by the other
    np.testing.assert_array_equal(fresh.state0, again.state0)
    np.testing.assert_array_equal(fresh.state, fresh.state0)


def _settings(method: str) -> dict:
    return {"dt": 1e-3} if method == "rk4" else {"rtol": 1e-9, "atol": 1e-9}


def test_a_restart_before_any_step_and_after_gives_the_same_run():
    sim = Simulation(Hoop(), "dop853", rtol=1e-9, atol=1e-9, reference=None)
    sim.restart()  # nothing made yet: nothing to reset
    sim.advance_to(3.0)
    end = sim.state.copy()
    sim.restart()
    assert (sim.t, sim.steps, sim.nfev) == (0.0, 0, 0)
    sim.advance_to(3.0)
    np.testing.assert_array_equal(sim.state, end)


def test_the_caller_keeps_their_state():
    start = np.array([0.5, -0.3, 0.0, 0.0])
    sim = Simulation(Hoop(), "taylor", rtol=1e-9, state=start, reference=None)
    sim.advance_to(1.0)
    np.testing.assert_array_equal(start, [0.5, -0.3, 0.0, 0.0])
    assert sim.state0.shape == (1, 4) and not np.shares_memory(sim.state0, start)


@pytest.mark.parametrize("name", list(SYSTEMS))
def test_new_parameters_are_never_served_the_settings_kept_for_others(name):
    system = SYSTEMS[name]
    field = dataclasses.fields(system.params)[0].name
    other = dataclasses.replace(
        system,
        params=dataclasses.replace(system.params, **{field: 2.0 * getattr(system.params, field)}),
    )
    state = system.default_state()
    for method in ("taylor", "dop853"):
        a = _run(system, method, state)
        b = _run(other, method, state)
        np.testing.assert_array_equal(b.p, other.kernel_params())
        assert not np.array_equal(a.p, b.p)
        assert not np.array_equal(a.state, b.state)
        c = _run(system, method, state)  # and the first system still gets its own
        np.testing.assert_array_equal(c.state, a.state)
    s1, s2 = Solver(system), Solver(other)
    np.testing.assert_array_equal(s2.params, other.kernel_params())
    assert not np.array_equal(s1.solve(1.0).copy(), s2.solve(1.0))


BAD = [
    ({"method": "leapfrog"}, ValueError, "method must be one of"),
    ({"method": "verlet", "system": Cyclotron()}, SettingError, "method"),
    ({"method": "rk4"}, SettingError, "dt"),
    ({"method": "rk4", "dt": -1e-3}, SettingError, "dt"),
    ({"method": "taylor", "rtol": -1e-9}, SettingError, "rtol"),
    ({"method": "taylor", "rtol": 1e-9, "atol": float("nan")}, SettingError, "atol"),
    ({"method": "dop853", "rtol": 2.0}, SettingError, "rtol"),
    ({"method": "taylor", "state": [0.1, 0.2]}, SettingError, "state"),
    ({"method": "taylor", "state": [0.1, np.inf, 0.0, 0.0]}, SettingError, "state"),
    ({"method": "taylor", "state": "abc"}, SettingError, "state"),
]


@pytest.mark.parametrize(("kwargs", "error", "field"), BAD)
def test_every_bad_setting_is_refused_on_construction_every_time(kwargs, error, field):
    kwargs = dict(kwargs)
    system = kwargs.pop("system", Hoop())
    method = kwargs.pop("method")
    good = {k: v for k, v in kwargs.items() if k == "state"}
    if method != "leapfrog" and "state" in good:  # the same settings seen first with a good start
        Simulation(system, method, rtol=1e-9, reference=None)
    for _ in range(2):  # the second time after the first was refused (nothing kept from it)
        with pytest.raises(error) as exc:
            Simulation(system, method, reference=None, **kwargs)
        if error is SettingError:
            assert exc.value.field == field
        else:
            assert field in str(exc.value)


def test_a_method_given_as_an_object_is_checked_like_its_name():
    verlet = get_method("verlet")
    Simulation(Hoop(), verlet, dt=1e-3, reference=None)
    for _ in range(2):
        with pytest.raises(SettingError) as exc:
            Simulation(Cyclotron(), verlet, dt=1e-3, reference=None)
        assert exc.value.field == "method"


def test_a_solver_built_again_solves_as_the_first_and_bad_tolerances_are_refused():
    state = [0.5, -0.3, 0.0, 0.0]
    a = Solver(Hoop(), rtol=1e-10).solve(5.0, state).copy()
    solver = Solver(Hoop(), rtol=1e-10)
    np.testing.assert_array_equal(solver.solve(5.0, state), a)
    assert solver.steps > 0 and Solver(Hoop(), rtol=1e-10).steps == 0
    for _ in range(2):
        with pytest.raises(SettingError) as exc:
            Solver(Hoop(), rtol=-1.0)
        assert exc.value.field == "rtol"


LIGHT = """
import json, sys
from mechviz.dynamics import Hoop, Simulation
sim = Simulation(Hoop(), "taylor", rtol=1e-9, atol=1e-9, state=[0.5, -0.3, 0.0, 0.0],
                 reference=None)
sim.advance_to(2.0)
names = ("numba", "sympy", "mechviz.dynamics.integrators.rk",
         "mechviz.dynamics.integrators.scipy_ivp", "mechviz.dynamics.codegen.equations")
print(json.dumps({n: n in sys.modules for n in names}))
"""


@pytest.mark.slow
def test_a_taylor_run_through_numba_imports_neither_sympy_nor_the_other_methods():
    # through numba: the heavier of the two roads (numba's first call imports scipy.linalg;
    # without numba, tests/test_aot.py, neither is imported)
    env = {**os.environ, "MECHVIZ_AOT": "0"}
    run = subprocess.run(
        [sys.executable, "-c", LIGHT], env=env, capture_output=True, text=True, check=True
    )
    loaded = json.loads(run.stdout)
    assert loaded.pop("numba") is True
    assert not any(loaded.values()), loaded
