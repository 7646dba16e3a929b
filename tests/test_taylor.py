"""Taylor's method: its series agree with the equations, converge at their order, and a sampled
run takes the same steps as an unsampled one."""

import math

import numpy as np
import pytest

from mechviz.dynamics import Cyclotron, Hoop, ReleasedDisk, Simulation
from mechviz.dynamics.disk import DiskParams
from mechviz.dynamics.integrators import taylor
from mechviz.dynamics.integrators.kernels import CYCLOTRON, FREE_BODY, HOOP, RHS

SYSTEMS = {
    CYCLOTRON: Cyclotron(),
    HOOP: Hoop(),
    FREE_BODY: ReleasedDisk(DiskParams(omega=1.0), (0.3, 0.0, 0.2)),
}
STATES = {
    CYCLOTRON: np.array([1.0, -0.5, 0.2, 0.3, 1.0, 0.1]),
    HOOP: np.array([0.9, -1.2, 0.7, -0.4]),
    FREE_BODY: None,
}


def _series(sys_id, y, order):
    system = SYSTEMS[sys_id]
    A = np.zeros((taylor.N_ROWS, taylor.MAX_ORDER + 1))
    A[: y.size, 0] = y
    taylor._expand(sys_id, A, system.kernel_params(), order)
    return A


def _state(sys_id):
    s = STATES[sys_id]
    return SYSTEMS[sys_id].default_state() if s is None else s


def _advance(sys_id, y, order, h):
    A = _series(sys_id, y, order)
    out = np.empty(y.size)
    taylor._horner(A, y.size, order, h, out)
    return out


@pytest.mark.parametrize("sys_id", list(SYSTEMS))
def test_first_coefficient_is_the_right_hand_side(sys_id):
    """y^[1] = f(y): the expansion is written for the same equations as the compiled RHS."""
    rhs = RHS[sys_id]
    y = _state(sys_id)
    f = np.empty(y.size)
    rhs(y, SYSTEMS[sys_id].kernel_params(), f)
    A = _series(sys_id, y, 6)
    np.testing.assert_allclose(A[: y.size, 1], f, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("sys_id", list(SYSTEMS))
@pytest.mark.parametrize("order", [3, 5])
def test_one_step_error_falls_as_h_to_the_order_plus_one(sys_id, order):
    """The series truncated at order p differs from the converged series by O(h^(p+1)): fit the
    slope of log(error) against log(h) (the order test, per step)."""
    y = _state(sys_id)
    hs = [0.2 / 2**k for k in range(5)]
    errs = []
    for h in hs:
        exact = _advance(sys_id, y, 28, h)
        errs.append(np.linalg.norm(_advance(sys_id, y, order, h) - exact) / np.linalg.norm(exact))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - (order + 1)) < 0.3, (slope, errs)


@pytest.mark.parametrize("sys_id", list(SYSTEMS))
def test_tight_tolerance_lands_on_the_dop853_reference(sys_id):
    system = SYSTEMS[sys_id]
    y0 = _state(sys_id)
    T = 5.0
    ref = Simulation(system, "dop853", rtol=1e-13, atol=1e-13, state=y0, reference=None)
    ref.advance_to(T)
    sim = Simulation(system, "taylor", rtol=1e-13, atol=1e-13, state=y0, reference=None)
    sim.advance_to(T)
    assert float(system.error(sim.state, ref.state)[0]) < 1e-11


@pytest.mark.parametrize("sys_id", list(SYSTEMS))
def test_sampling_does_not_add_steps(sys_id):
    """The last step is carried to the next call, with its start time's compensation: 200
    samples take the steps of one run and end on the same bits."""
    system = SYSTEMS[sys_id]
    y0 = _state(sys_id)
    one = Simulation(system, "taylor", rtol=1e-10, atol=1e-10, state=y0, reference=None)
    one.advance_to(10.0)
    many = Simulation(system, "taylor", rtol=1e-10, atol=1e-10, state=y0, reference=None)
    many.run(10.0, n_samples=200)
    assert many.steps == one.steps
    np.testing.assert_array_equal(many.state, one.state)


def test_a_state_changed_between_calls_starts_a_fresh_step():
    system = SYSTEMS[HOOP]
    sim = Simulation(system, "taylor", rtol=1e-10, atol=1e-10, state=_state(HOOP), reference=None)
    sim.advance_to(0.01)  # inside the first step
    sim.state[0] = [0.1, 0.2, 0.0, 0.0]
    sim.advance_to(1.0)
    fresh = Simulation(
        system, "taylor", rtol=1e-10, atol=1e-10, state=[0.1, 0.2, 0.0, 0.0], reference=None
    )
    fresh.advance_to(0.99)
    np.testing.assert_allclose(sim.state, fresh.state, rtol=1e-9, atol=1e-9)


def test_order_and_step_minimise_the_modelled_work():
    """With a step cost of p^2 alone the choice is Jorba and Zou's (a = 2, p = ln(1/tol)/2 + 1);
    a cost with constant and linear parts takes higher orders and longer steps, never beyond
    rho / e."""
    saved = taylor.STEP_COST[HOOP]
    try:
        taylor.STEP_COST[HOOP] = (0.0, 0.0, 1.0)
        taylor.forget()
        p, a = taylor.order_for(1e-12, 1e-12, HOOP)
        assert abs(p - (math.log(1e12) / 2 + 1)) <= 1.5 and abs(a - 2.0) < 0.25
    finally:
        taylor.STEP_COST[HOOP] = saved
        taylor.forget()
    for sys_id in SYSTEMS:
        for tol in (1e-3, 1e-9, 1e-14):
            p, a = taylor.order_for(tol, tol, sys_id)
            assert 3 <= p <= taylor.MAX_ORDER and 1.0 <= a <= 2.0
            assert (p - 1) * a >= -math.log(tol) - 1e-9  # (h/rho)^(p-1) within tol
    assert taylor.order_for(1e-12, 1e-12, CYCLOTRON)[0] > taylor.order_for(1e-12, 1e-12, HOOP)[0]


@pytest.mark.parametrize("method", ["taylor", "dop853", "rk4"])
def test_restart_repeats_the_run_of_a_fresh_simulation(method):
    system = SYSTEMS[HOOP]
    kw = {"dt": 0.01} if method == "rk4" else {"rtol": 1e-9, "atol": 1e-9}
    sim = Simulation(system, method, state=_state(HOOP), **kw)
    sim.advance_to(3.0)
    first = sim.state.copy(), sim.steps, sim.nfev
    sim.restart()
    assert sim.t == 0.0 and sim.steps == 0
    sim.advance_to(3.0)
    np.testing.assert_array_equal(sim.state, first[0])
    assert (sim.steps, sim.nfev) == first[1:]
    assert sim.sample().error[0] < 1e-6


def _ensemble_run(run, sys_id, Y0):
    system = SYSTEMS[sys_id]
    Y = Y0.copy()
    n, d = Y.shape
    carry = taylor.TaylorCarry(n, d)
    stats = np.zeros((n, 3), dtype=np.int64)
    status = np.zeros(3, dtype=np.int64)
    order, a = taylor.order_for(1e-9, 1e-9, sys_id)
    args = (Y, system.kernel_params(), 0.0, 3.0, 1e-9, 1e-9, order, a, stats, status)
    total = run(sys_id, *args, carry.arrays)
    return Y, stats, status, total


@pytest.mark.parametrize("sys_id", list(SYSTEMS))
def test_parallel_ensemble_is_bitwise_the_serial_one(sys_id):
    """The members spread over threads do the serial loop's arithmetic: the same bits, the same
    step counts."""
    rng = np.random.default_rng(3)
    y0 = _state(sys_id)
    Y0 = y0 + 1e-2 * rng.standard_normal((40, y0.size))
    serial = _ensemble_run(taylor.run_taylor_compiled, sys_id, Y0)
    parallel = _ensemble_run(taylor.run_taylor_parallel, sys_id, Y0)
    assert np.array_equal(serial[0], parallel[0])
    assert np.array_equal(serial[1], parallel[1])
    assert serial[3] == parallel[3] == serial[1][:, 1].sum()
    assert serial[2][0] == parallel[2][0] == 0


def test_parallel_ensemble_names_the_first_member_that_failed():
    Y0 = np.tile(_state(HOOP), (20, 1))
    Y0[[5, 12], 2] = 1e308  # overflows at the first step
    serial = _ensemble_run(taylor.run_taylor_compiled, HOOP, Y0)
    parallel = _ensemble_run(taylor.run_taylor_parallel, HOOP, Y0)
    assert serial[2][0] == parallel[2][0] != 0
    assert serial[2][2] == parallel[2][2] == 5
    assert np.array_equal(serial[0][:5], parallel[0][:5])


def test_a_large_ensemble_runs_in_parallel_with_the_serial_result(monkeypatch):
    """Through the driver: above PARALLEL_MIN members the parallel loop runs, same result."""
    y0 = _state(HOOP)
    states = y0 + 1e-3 * np.arange(24)[:, None]
    runs = []
    for threshold in (1 << 62, 2):
        monkeypatch.setattr(taylor, "PARALLEL_MIN", threshold)
        sim = Simulation(
            SYSTEMS[HOOP], "taylor", rtol=1e-9, atol=1e-9, state=states, reference=None
        )
        sim.run(2.0, n_samples=5)
        runs.append((sim.state.copy(), sim.steps))
    assert np.array_equal(runs[0][0], runs[1][0]) and runs[0][1] == runs[1][1]


def test_the_method_list_states_the_orders_the_rule_picks():
    """``--list-methods`` shows Taylor's orders as ``order_for`` picks them at each tolerance it
    names (not a fixed order), and LSODA's as variable; an evaluation of Taylor's method is one
    series expansion, one per step."""
    import re

    from mechviz.dynamics.integrators import METHODS

    text = METHODS["taylor"].order_text()
    for label in ("1e-3", "1e-9", "1e-12"):
        tol = float(label)
        picked = sorted({taylor.order_for(tol, tol, s)[0] for s in (CYCLOTRON, HOOP, FREE_BODY)})
        shown = re.search(rf"(\d+)(?:-(\d+))? at {label}\b", text)
        assert shown is not None, text
        assert (int(shown[1]), int(shown[2] or shown[1])) == (picked[0], picked[-1])
    lo = min(taylor.order_for(t, t, s)[0] for t in (0.9, 0.5, 0.1) for s in (CYCLOTRON, HOOP))
    assert f"{lo}-{taylor.MAX_ORDER} over all tolerances" in text
    assert taylor.order_for(1e-300, 1e-300, HOOP)[0] == taylor.MAX_ORDER
    for name in ("scipy-lsoda", "odeint"):
        assert "variable order" in METHODS[name].describe()
    sim = Simulation(Hoop(), "taylor", rtol=1e-9, reference=None)
    sim.advance_to(3.0)
    assert sim.nfev == sim.steps and "series expansions" in METHODS["taylor"].counts


@pytest.mark.parametrize("sys_id", [HOOP, FREE_BODY])
def test_the_loop_given_an_expansion_is_the_shipped_loop_bit_for_bit(sys_id):
    """A registered system's loop (:func:`taylor.run_taylor_given`, handed its expansion) and
    the shipped systems' (by id) are two copies of one step rule: given the shipped system's own
    generated expansion, they take the same steps to the same bits, over calls that end inside
    a kept step and a state changed between calls."""
    from mechviz.dynamics.codegen.product import product_module

    expand, rows = taylor._generated(sys_id), product_module(sys_id, "series").ROWS
    rng = np.random.default_rng(5)
    y0 = _state(sys_id)
    Y0 = y0 + 1e-2 * rng.standard_normal((3, y0.size))
    runs = []
    for run in (taylor.run_taylor_compiled, None):
        Y = Y0.copy()
        n, d = Y.shape
        carry = taylor.TaylorCarry(n, d)
        stats, status = np.zeros((n, 3), dtype=np.int64), np.zeros(3, dtype=np.int64)
        order, a = taylor.order_for(1e-10, 1e-10, sys_id)
        p = SYSTEMS[sys_id].kernel_params()
        for t0, t1 in ((0.0, 0.37), (0.37, 1.1), (1.1, 2.9)):
            if t0 == 1.1:
                Y[1, 0] += 1e-3  # a state changed between calls: a fresh step for that member
            args = (Y, p, t0, t1, 1e-10, 1e-10, order, a, stats, status, carry.arrays)
            if run is None:
                taylor.run_taylor_given(expand, rows, *args)
            else:
                run(sys_id, *args)
            assert status[0] == 0
        runs.append((Y, stats))
    assert np.array_equal(runs[0][0], runs[1][0])
    assert np.array_equal(runs[0][1], runs[1][1])
