"""DOP853's dense output and the step it carries across the times asked for: the interpolant's
order, sampled runs taking an unsampled run's steps, a tolerance that shows frame by frame, kept
steps dropped by a jump or a restart, and the reference run's own accuracy."""

import numpy as np
import pytest
from scipy.integrate import DOP853, solve_ivp

from mechviz.dynamics import Cyclotron, Hoop, Simulation, hoop
from mechviz.dynamics.integrators import kernels, rk
from mechviz.dynamics.simulation import REFERENCE_ACCURACY, reference_run

HOOP_STATE = hoop.mode_state(Hoop().params, (0.5, 0.2))  # both modes: no exact solution
CHARGE_STATE = np.array([1.0, -0.5, 0.2, 0.3, 1.0, 0.1])
PAIR = rk.load_pair("dop853")


def _scipy_rhs(system):
    rhs, p = kernels.RHS[system.sys_id], system.kernel_params()

    def f(t, y):
        out = np.empty(y.size)
        rhs(np.ascontiguousarray(y), p, out)
        return out

    return f


def _one_step(system, y0, h):
    """One DOP853 step of length ``h`` from ``y0`` (its tableau) and its interpolation
    coefficients from the runner's dense output."""
    rhs, p = kernels.RHS[system.sys_id], system.kernel_params()
    d = y0.size
    K = np.zeros((PAIR.n_all, d))
    kout = np.empty(d)
    rhs(y0, p, kout)
    K[0] = kout
    for s in range(1, PAIR.n_stages + 1):
        y = y0 + h * (PAIR.A[s, :s] @ K[:s])
        rhs(y, p, kout)
        K[s] = kout
    Q = np.empty((PAIR.rows, d))
    _, _, _, P = PAIR.arrays()
    rk.dense_coefficients(
        system.sys_id, p, y0, y, K, h, Q, np.empty(d), kout, PAIR.A, P, PAIR.n_stages, True
    )
    return y, Q


def test_the_interpolant_at_mid_step_is_seventh_order():
    """A continuous extension of order 7 errs by O(h^8) inside a step: fit the slope of
    log(error at h/2) against log(h) on the charge, whose exact flow is known. The step's own
    error is O(h^9), so the interpolant's dominates. Measured: 7.99 (each halving divides the
    error by 251-256); below h = 0.1 round-off takes over."""
    system = Cyclotron()
    hs = [1.6 / 2**k for k in range(5)]
    errs = []
    for h in hs:
        _, Q = _one_step(system, CHARGE_STATE, h)
        mid = np.empty(CHARGE_STATE.size)
        rk.interpolate(Q, CHARGE_STATE, 0.5, mid, True)
        errs.append(float(system.error(mid, system.exact(CHARGE_STATE, h / 2))))
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert abs(slope - 8.0) < 0.3, (slope, errs)


def test_the_interpolant_meets_the_step_at_both_ends():
    y1, Q = _one_step(Cyclotron(), CHARGE_STATE, 0.7)
    ends = np.empty((2, CHARGE_STATE.size))
    rk.interpolate(Q, CHARGE_STATE, 0.0, ends[0], True)
    rk.interpolate(Q, CHARGE_STATE, 1.0, ends[1], True)
    np.testing.assert_allclose(ends, [CHARGE_STATE, y1], rtol=0, atol=1e-15)


def _frames(sim, n, fps=60):
    states = []
    for k in range(1, n + 1):
        sim.advance_to(k / fps)
        states.append(sim.state[0].copy())
    return np.array(states)


@pytest.mark.parametrize("tol", [1e-6, 1e-9])
def test_a_run_sampled_every_frame_is_the_dense_output_of_one_unsampled_run(tol):
    """600 frames over 10 s: the steps of one call to 10 s, and at every frame the dense output
    of scipy's DOP853 stepped through without stopping. Given the same first step (scipy's chosen
    for the span of the first frame, as ours is) the states agree to round-off; from scipy's first
    step for the whole span, within the tolerance (measured: 13 tol at 1e-6, 9 tol at 1e-9, the
    two runs' own global errors)."""
    system = Hoop()
    sampled = Simulation(system, "dop853", rtol=tol, atol=tol, state=HOOP_STATE, reference=None)
    states = _frames(sampled, 600)
    one = Simulation(system, "dop853", rtol=tol, atol=tol, state=HOOP_STATE, reference=None)
    one.advance_to(10.0)
    assert abs(sampled.steps - one.steps) <= 2  # the first step differs
    times = np.arange(1, 601) / 60

    solver = DOP853(_scipy_rhs(system), 0.0, HOOP_STATE, 1 / 60, rtol=tol, atol=tol)
    solver.t_bound = 20.0  # the first step chosen for the first frame; none cut after that
    same = np.empty_like(states)
    k = steps = 0
    while k < times.size:
        solver.step()
        steps += 1
        dense = solver.dense_output()
        while k < times.size and times[k] <= solver.t:
            same[k] = dense(times[k])
            k += 1
    assert sampled.steps == steps
    # round-off apart, which the motion amplifies over 10 s (measured: 4e-15 over the first 4 s,
    # 4e-11 at the end at 1e-6), far below the tolerance
    np.testing.assert_allclose(states, same, rtol=0, atol=1e-10)

    whole = (
        solve_ivp(
            _scipy_rhs(system),
            (0.0, 10.0),
            HOOP_STATE,
            method="DOP853",
            rtol=tol,
            atol=tol,
            dense_output=True,
        )
        .sol(times)
        .T
    )
    assert np.all(np.abs(states - whole) < 30 * tol * (1.0 + np.abs(whole)))


def test_the_tolerance_shows_when_advanced_frame_by_frame():
    """10 s of the hoop in 1/60 s frames, against the reference run. Steps cut at every frame
    made every tolerance look like round-off (5.5e-15 at 1e-3 and at 1e-9 alike, 600 steps).
    DOP853's global error over a few periods is a small multiple of rtol (measured: 5e-3 at
    1e-3, 2.4e-9 at 1e-9); the thresholds leave a factor of 4 or more on each side: at 1e-3 it
    must exceed rtol / 100 and at 1e-9 stay below 10 rtol. At 1e-3 steps are about 0.6 s long,
    36 frames: far fewer steps than frames (measured 18)."""
    errors, steps = {}, {}
    for rtol in (1e-3, 1e-9):
        sim = Simulation(Hoop(), "dop853", rtol=rtol, atol=rtol, state=HOOP_STATE)
        _frames(sim, 600)
        smp = sim.sample()
        assert smp.reference_kind == "reference"
        errors[rtol], steps[rtol] = float(smp.error[0]), sim.steps
        assert sim.last_step is not None and sim.last_step > 1 / 60
    assert errors[1e-3] > 1e-5
    assert errors[1e-9] < 1e-8
    assert errors[1e-3] > 1e4 * errors[1e-9]
    assert steps[1e-3] < 600 / 10


def test_chunk_ends_do_not_cut_steps():
    """A long advance in many chunks takes the steps of one call and lands on the same state;
    each chunk's end costs the dense output's three evaluations."""
    a = Simulation(Hoop(), "dop853", rtol=1e-9, state=HOOP_STATE, reference=None)
    b = Simulation(Hoop(), "dop853", rtol=1e-9, state=HOOP_STATE, reference=None)
    b._chunk_steps = 3
    chunks = []
    b.on_chunk = lambda s: chunks.append(s.t)
    a.advance_to(20.0)
    b.advance_to(20.0)
    assert len(chunks) > 3  # chunks grow while they take under CHUNK_SECONDS / 4
    assert b.steps == a.steps and b.rejected == a.rejected
    assert b.nfev == a.nfev + 3 * (len(chunks) - 1)
    np.testing.assert_array_equal(b.state, a.state)


@pytest.mark.parametrize("change", ["jump", "write"])
def test_a_kick_inside_a_kept_step_continues_from_the_new_state(change):
    """At t = 1 s the charge is inside a kept step (0.36 s long at 1e-10). A kick there, by
    ``jump`` or by writing the state, must start afresh from the kicked state at t: the error
    against the exact flow from the kicked state stays at the tolerance's level (continuing the
    kept step would carry on the old orbit, an error of order 1)."""
    system = Cyclotron()
    sim = Simulation(system, "dop853", rtol=1e-10, state=CHARGE_STATE)
    _frames(sim, 60)
    assert sim.last_step is not None and sim.last_step > 0.1
    kicked = sim.state[0].copy()
    kicked[3:5] *= -1.5
    if change == "jump":
        sim.jump(kicked)
        assert sim.last_step is None
    else:
        sim.state[0] = kicked
    for k in range(61, 181):
        sim.advance_to(k / 60)
    err = float(system.error(sim.state[0], system.exact(kicked, 2.0)))
    assert err < 1e-8
    if change == "jump":
        assert sim.sample().error[0] == pytest.approx(err)


def test_a_jump_and_a_written_state_start_the_same_fresh_step():
    runs = []
    for change in ("jump", "write"):
        sim = Simulation(Hoop(), "dop853", rtol=1e-8, state=HOOP_STATE, reference=None)
        _frames(sim, 30)
        kicked = sim.state[0] + [0.0, 0.0, 0.3, -0.2]
        if change == "jump":
            sim.jump(kicked)
        else:
            sim.state[0] = kicked
        sim.advance_to(2.0)
        runs.append((sim.state.copy(), sim.nfev, sim.steps))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    assert runs[0][1:] == runs[1][1:]


def test_restart_drops_the_kept_step():
    sim = Simulation(Hoop(), "dop853", rtol=1e-8, state=HOOP_STATE)
    _frames(sim, 30)
    assert sim.last_step is not None
    sim.restart()
    assert sim.last_step is None
    fresh = Simulation(Hoop(), "dop853", rtol=1e-8, state=HOOP_STATE)
    np.testing.assert_array_equal(_frames(sim, 30), _frames(fresh, 30))
    assert (sim.steps, sim.nfev) == (fresh.steps, fresh.nfev)


@pytest.mark.parametrize(
    ("system", "state"),
    [(Cyclotron(), CHARGE_STATE)]
    + [(Hoop(), hoop.mode_state(Hoop().params, (a, 0.0))) for a in (0.05, 0.3, 0.8)],
    ids=["charge", "mode1-0.05", "mode1-0.3", "mode1-0.8"],
)
def test_the_reference_run_is_within_its_stated_accuracy_over_100_s(system, state):
    """The reference run, advanced in 1/60 s frames as in the viewer, against the exact flow
    (the charge; the hoop's mode 1, where small amplitudes are hardest: atol dominates a small
    state). Measured worst: 2e-14 (charge), 2.3e-13, 1.9e-13, 1.4e-13 (mode 1)."""
    ref = reference_run(system, state)
    worst = 0.0
    for k in range(1, 6001):
        ref.advance_to(k / 60)
        if k % 6 == 0:
            exact = system.exact(state, k / 60).reshape(-1)
            worst = max(worst, float(system.error(ref.state[0], exact)))
    assert worst < REFERENCE_ACCURACY
    assert ref.steps < 6000  # fewer steps than frames: the frames do not cut them


@pytest.mark.parametrize("tol", [1e-9, 1e-12])
def test_a_final_time_is_the_end_point_of_a_step_cut_there(tol):
    """At a final time (``Simulation.run``'s end) the last step is cut to end there, as scipy's
    solve_ivp cuts it: the same steps and the same end state to round-off, and at least as
    accurate against the exact helix as the interpolant of an uncut step (measured: 5.4e-9
    against 6.4e-9 at 1e-9; 5.50e-12 against 5.50e-12 at 1e-12)."""
    from mechviz.dynamics.cyclotron import CyclotronParams

    system = Cyclotron(CyclotronParams(charge=-2.0, mass=1.5, field=0.7))
    T = 30.0
    run = Simulation(system, "dop853", rtol=tol, atol=tol, state=CHARGE_STATE, reference=None)
    end = run.run(T, n_samples=2).states[-1, 0]
    scipy_end = solve_ivp(
        _scipy_rhs(system), (0.0, T), CHARGE_STATE, method="DOP853", rtol=tol, atol=tol
    ).y[:, -1]
    np.testing.assert_allclose(end, scipy_end, rtol=1e-13, atol=1e-13)
    dense = Simulation(system, "dop853", rtol=tol, atol=tol, state=CHARGE_STATE, reference=None)
    dense.advance_to(T)
    exact = system.exact(CHARGE_STATE, T)
    assert float(system.error(end, exact)) <= float(system.error(dense.state[0], exact))
    # the run may go on from the cut step's end
    run.advance_to(T + 5.0)
    assert float(system.error(run.state[0], system.exact(CHARGE_STATE, T + 5.0))) < 1e3 * tol
