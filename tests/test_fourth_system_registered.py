"""The fourth system (:mod:`spherical`, defined in the test suite only) registered at run time
(:func:`mechviz.dynamics.registry.register`) and run through the product's front doors: the
driver (:class:`~mechviz.dynamics.simulation.Simulation`), :func:`mechviz.dynamics.api.simulate`
and ``mechviz simulate``, with every method the product offers a system without a closed form.

The physics checked: energy and ``L_z`` kept to the tolerance of each adaptive method, the
methods agreeing with a tight DOP853 run made by the tableau runner directly (not through the
registry), the fixed-step methods converging at their orders, and Taylor's method in the driver
taking bitwise the steps of the bare compiled loop.
"""

from __future__ import annotations

import contextlib
import io
import json
from dataclasses import dataclass

import numpy as np
import pytest
import spherical
from spherical import FORMS, NAME, PendulumParams, SphericalPendulum

from mechviz.dynamics import api, registry
from mechviz.dynamics.integrators import kernels, rk, taylor
from mechviz.dynamics.integrators.base import METHODS
from mechviz.dynamics.params import SettingError
from mechviz.dynamics.simulation import Simulation

P = PendulumParams()
Y0 = spherical.start_state(*spherical.START)
T = 4.0  # about two swings
#: The methods the product offers a system with a compiled right-hand side, no closed form and no
#: symmetric step of its own (every other method needs one of these).
GENERAL = [m.name for m in METHODS.values() if m.needs == "rhs"]
ADAPTIVE = [n for n in GENERAL if METHODS[n].adaptive]
FIXED = {"euler": (1, (800, 1600)), "midpoint": (2, (100, 200)), "rk4": (4, (100, 200))}


@pytest.fixture(scope="module")
def registered():
    with spherical.registered() as reg:
        yield reg


def tableau_run(t_end: float, tol: float, pair: str = "dop853") -> np.ndarray:
    """``pair`` from :data:`Y0` to ``t_end`` by the tableau runner with the generated
    right-hand side, landing on ``t_end``: the registry plays no part."""
    pr = rk.load_pair(pair)
    Y = Y0[None].copy()
    stats, status = np.zeros((1, 3), np.int64), np.zeros(3, np.int64)
    args = (Y, P.kernel_params(), 0.0, t_end, tol, tol, np.zeros(1), np.zeros((1, 4)), stats)
    rk.run_rk(pr, FORMS.rhs, *args, status, rk.RKCarry(1, 4, pr), land=True)
    assert status[0] == kernels.OK
    return Y[0]


@pytest.fixture(scope="module")
def reference() -> np.ndarray:
    return tableau_run(T, 1e-13)


def relative_drift(values: np.ndarray) -> float:
    return float(np.max(np.abs(values - values[0])) / abs(values[0]))


def test_a_registration_is_checked_and_undone():
    with spherical.registered() as reg:
        assert registry.spec_named(NAME) is spherical.SPEC
        assert registry.system_named(NAME) is SphericalPendulum
        with pytest.raises(ValueError, match="registered already"):
            spherical.registered()
        assert reg.active
    assert NAME not in registry.SPECS and NAME not in registry.SYSTEMS
    with pytest.raises(SettingError, match="system must be one of"):
        api.simulate(NAME, t_end=1.0)

    @dataclass(frozen=True)
    class OnAShippedId(SphericalPendulum):
        name = "pendulum-on-the-hoops-id"
        sys_id = 1  # the hoop's place in the shipped tables

    with pytest.raises(TypeError, match="sys_id must be its own SystemForms"):
        registry.register(spherical.SPEC, (OnAShippedId,))
    assert NAME not in registry.SPECS  # nothing was put in before the refusal


def test_the_product_offers_it_every_general_method_and_refuses_the_rest(registered):
    assert api.methods(NAME) == GENERAL
    assert {"taylor", "dop853", "vern6", "vern9", "rk4", "midpoint"} <= set(GENERAL)
    for name in ("yoshida4", "verlet", "boris", "splitting", "exact"):
        with pytest.raises(SettingError, match="does not apply") as exc:
            api.simulate(NAME, method=name, t_end=1.0)
        assert exc.value.field == "method"


@pytest.mark.parametrize("method", ADAPTIVE)
def test_simulate_keeps_energy_and_lz_with_every_adaptive_method(method, registered, reference):
    run = api.simulate(NAME, method=method, t_end=T, rtol=1e-10, atol=1e-10, samples=9)
    assert run.system == NAME and run.columns == ("theta", "phi", "omega", "nu")
    assert np.max(np.abs(run.energy_error)) < 1e-7  # relative to the energy above hanging
    assert relative_drift(run.invariants["Lz"]) < 1e-7
    assert np.allclose(run.quantities["Lz"], run.invariants["Lz"], rtol=0, atol=0)
    assert np.max(np.abs(run.states[-1] - reference)) < 1e-6
    # the driver's own error measure, against its DOP853 reference through the same forms
    assert run.error_vs == "reference" and run.error[-1] < 1e-6
    assert run.reference_error[-1] < 1e-9


@pytest.mark.parametrize("method", sorted(FIXED))
def test_simulate_converges_at_each_fixed_step_methods_order(method, registered):
    """The error against the tight reference at ``t = 2`` s falls by ``2^order`` as ``dt``
    halves (as the bare drivers do, :mod:`test_fourth_system`)."""
    order, steps = FIXED[method]
    exact = tableau_run(2.0, 1e-13)
    errs = []
    for n in steps:
        run = api.simulate(NAME, method=method, t_end=2.0, dt=2.0 / n, samples=2, reference=None)
        assert run.rhs_evaluations > 0
        errs.append(np.max(np.abs(run.states[-1] - exact)))
    rate = np.log2(errs[0] / errs[1])
    assert abs(rate - order) < 0.15, (rate, errs)


def test_rk4_keeps_energy_to_its_order(registered):
    """Energy and ``L_z`` at ``dt = 1/120`` s (the description's default step): RK4's drift
    over two swings is ``O(dt^4)``, and halving the step cuts it about 16 times."""
    drifts = []
    for dt in (1 / 120, 1 / 240):
        run = api.simulate(NAME, t_end=T, dt=dt, reference=None)  # rk4, the default
        assert run.method == "rk4"
        drifts.append(
            max(relative_drift(run.invariants["energy"]), relative_drift(run.quantities["Lz"]))
        )
    assert drifts[0] < 1e-5
    assert 10 < drifts[0] / drifts[1] < 24, drifts


def test_taylor_in_the_driver_takes_the_bare_loops_steps_bit_for_bit(registered):
    """Sampled seven times through the driver (each sample inside a kept step) or run in one
    call of the bare loop with the generated expansion: the same state, bit for bit."""
    sim = Simulation(SphericalPendulum(), "taylor", rtol=1e-12, atol=1e-12, reference=None)
    end = sim.run(T, n_samples=7).states[-1, 0]
    expand, rows = FORMS.expand, FORMS.rows
    order, a = taylor.order_for(1e-12, 1e-12, FORMS)
    Y = Y0[None].copy()
    stats, status = np.zeros((1, 3), np.int64), np.zeros(3, np.int64)
    p = P.kernel_params()
    steps = taylor.run_taylor_with(
        expand, rows, Y, p, 0.0, T, 1e-12, 1e-12, order, a, stats, status
    )
    assert status[0] == kernels.OK and steps == sim.steps
    np.testing.assert_array_equal(end, Y[0])


def test_an_ensemble_keeps_each_members_lz(registered, reference):
    """Three starts of different precession through the driver with DOP853: each member keeps
    its own ``L_z``, and the first is the single run."""
    starts = np.array(
        [Y0, spherical.start_state(0.5, 0.0, 3.0), spherical.start_state(2.0, -1, 0.4)]
    )
    run = api.simulate(NAME, method="dop853", t_end=T, rtol=1e-11, atol=1e-11, state=starts)
    lz = run.quantities["Lz"]
    assert lz.shape == (len(run.t), 3)
    assert np.max(np.abs(lz - lz[0]) / np.abs(lz[0])) < 1e-8
    assert np.max(np.abs(run.states[-1, 0] - reference)) < 1e-7


def test_the_command_line_simulates_it(registered, reference):
    from mechviz.viz.cli import main

    out = io.StringIO()
    argv = ["simulate", NAME, "--method", "taylor", "--t-end", str(T), "--rtol", "1e-11"]
    with contextlib.redirect_stdout(out):
        assert main([*argv, "--json", "--no-progress"]) == 0
    result = json.loads(out.getvalue())
    assert result["system"] == NAME and result["method"] == "taylor"
    assert abs(result["energy_drift"]) < 1e-9
    final = np.array([result["final_state"][n] for n in SphericalPendulum.state_names])
    assert np.max(np.abs(final - reference)) < 1e-7
    assert result["error_vs_reference"] < 1e-8


def test_the_solver_solves_it_as_the_driver_does(registered):
    """:class:`~mechviz.dynamics.solver.Solver` on the registered system: the driver's Taylor
    run to the same time, bit for bit; other parameters (a longer rod swings slower) and
    starts are taken as arrays, and ``L_z`` is kept."""
    from mechviz.dynamics.solver import Solver

    solver = Solver(SphericalPendulum(), rtol=1e-12)
    sim = Simulation(SphericalPendulum(), "taylor", rtol=1e-12, atol=1e-12, reference=None)
    sim.advance_to(T)
    np.testing.assert_array_equal(solver.solve(T), sim.state[0])
    assert solver.steps == sim.steps
    longer = PendulumParams(length=2.6)
    end = solver.solve(T, state=Y0, params=longer.kernel_params()).copy()
    lz0, lz1 = (spherical.invariants(longer, s)[1] for s in (Y0, end))
    assert abs(lz1 - lz0) < 1e-10 * abs(lz0)
    assert not np.allclose(end, sim.state[0], atol=1e-3)
