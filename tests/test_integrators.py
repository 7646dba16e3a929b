"""Integrators: convergence orders, invariants, the DOP853 port against scipy, failure handling."""

import math
import os
import subprocess
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mechviz.dynamics import (
    METHODS,
    Cyclotron,
    DrivenDisk,
    Hoop,
    IntegrationError,
    ReleasedDisk,
    Simulation,
    cyclotron,
    disk,
    methods_for,
)
from mechviz.dynamics._jit import njit
from mechviz.dynamics.disk import DiskParams
from mechviz.dynamics.hoop import HoopParams
from mechviz.dynamics.integrators import kernels

# name -> (system, initial state, duration T, step sizes). The step sizes keep every method in
# its asymptotic regime and above the round-off floor: a slope fitted where round-off dominates,
# or where the step is too large for the leading error term, would not be the method's order.
PROBLEMS = {
    "cyclotron": (Cyclotron(), np.array([1.0, 0.0, 0.0, 0.0, 1.0, 0.1]), 2 * math.pi),
    "hoop": (Hoop(HoopParams()), np.array([0.5, -0.3, 0.0, 0.0]), 2.0),
    "free-body": (ReleasedDisk(DiskParams(omega=1.0), (0.3, 0.0, 0.2)), None, 4.0),
}


def _reference(system, s0, T):
    exact = system.exact(s0, T)
    if exact is not None:
        return exact
    sim = Simulation(system, "dop853", rtol=1e-13, atol=1e-13, state=s0, reference=None)
    sim.advance_to(T)
    return sim.state[0]


def _final_error(system, method, s0, T, n):
    sim = Simulation(system, method, dt=T / n, state=s0, reference=None)
    sim.advance_to(T)
    return float(system.error(sim.state[0], _reference(system, s0, T)))


FIXED = [
    (m.name, system)
    for system in PROBLEMS
    for m in methods_for(PROBLEMS[system][0])
    if not m.adaptive and m.backend == "numba" and m.name != "exact"
]


@pytest.mark.parametrize(("method", "system"), FIXED)
def test_convergence_order_matches_the_stated_order(method, system):
    """Fit the slope of log(error) against log(dt) (diffrax's order test); it must be within 0.25
    of the method's order. Points outside the asymptotic range or at round-off are dropped."""
    sysm, s0, T = PROBLEMS[system]
    s0 = sysm.default_state() if s0 is None else s0
    order = METHODS[method].order
    ns = [2**k for k in range(4, 15)]
    dts, errs = [], []
    for n in ns:
        try:
            e = _final_error(sysm, method, s0, T, n)
        except IntegrationError:
            continue  # a step too large for the implicit solve: not asymptotic anyway
        if 1e-11 < e < 1e-2:
            dts.append(T / n)
            errs.append(e)
    assert len(errs) >= 3, f"too few asymptotic points: {errs}"
    slope = np.polyfit(np.log(dts), np.log(errs), 1)[0]
    assert abs(slope - order) < 0.25, f"{method} on {system}: slope {slope:.3f}, order {order}"


def test_exact_flow_is_exact_at_any_step():
    sysm, s0, _ = PROBLEMS["cyclotron"]
    for dt in (0.01, 1.0, 3.0):
        sim = Simulation(sysm, "exact", dt=dt, state=s0)
        sim.advance_to(300 * dt)
        assert sim.sample().error[0] < 1e-12


def test_driven_disk_exact_motion_turns_at_omega():
    p = DiskParams(omega=2.0)
    traj = Simulation(DrivenDisk(p), "exact").run(3.0, 4)
    np.testing.assert_allclose(traj.states[:, 0, 0], 2.0 * traj.t)
    assert np.all(traj.energy_error == 0)


def test_boris_keeps_the_speed_to_round_off_at_any_step():
    sysm, s0, _ = PROBLEMS["cyclotron"]
    for dt in (0.01, 0.5, 2.0, 10.0):
        traj = Simulation(sysm, "boris", dt=dt, state=s0).run(2000 * dt, 11)
        assert np.max(np.abs(traj.energy_error)) < 1e-12


def test_rotation_splitting_keeps_angular_momentum_to_round_off():
    sysm = ReleasedDisk(DiskParams(omega=1.0), (0.01, 0.0, 0.01))
    traj = Simulation(sysm, "splitting", dt=0.2).run(2000.0, 21)
    L = disk.free_angular_momentum_space(sysm.kernel_params(), traj.states[:, 0])
    norms = np.linalg.norm(L, axis=1)
    assert np.max(np.abs(norms / norms[0] - 1)) < 1e-12
    assert np.max(np.linalg.norm(L - L[0], axis=1)) < 1e-11 * norms[0]


def _energy_trend(system, method, dt, T, s0=None):
    traj = Simulation(system, method, dt=dt, state=s0).run(T, 401)
    e = traj.energy_error[:, 0]
    k = len(e) // 10
    return e, abs(np.mean(e[-k:]) - np.mean(e[1 : k + 1]))


@pytest.mark.parametrize(
    ("system", "symplectic", "dt"),
    [
        (Hoop(), "verlet", 0.05),
        (Hoop(), "yoshida4", 0.05),
        (ReleasedDisk(DiskParams(omega=1.0), (0.01, 0, 0.01)), "splitting", 0.2),
    ],
)
def test_symplectic_energy_error_stays_bounded_while_rk4_drifts(system, symplectic, dt):
    """Over a long run at one step size RK4's energy error grows linearly; a symplectic or
    symmetric method's oscillates without trend (means of first and last tenth agree)."""
    T = 5000.0
    e_rk4, trend_rk4 = _energy_trend(system, "rk4", dt, T)
    e_sym, trend_sym = _energy_trend(system, symplectic, dt, T)
    assert trend_sym < 0.1 * np.max(np.abs(e_sym)) + 1e-12
    assert trend_rk4 > 20 * trend_sym
    # RK4's drift is linear: the error at T is about twice that at T/2.
    assert e_rk4[-1] / e_rk4[200] == pytest.approx(2.0, rel=0.1)


def _scipy_dop853_past(sysm, s0, T, tol):
    """scipy's DOP853 solver stepped from 0 until it passes ``T``, its initial step chosen for
    the span ``T`` (as ``solve_ivp`` to ``T`` does) but its steps not cut there."""
    from scipy.integrate import DOP853

    rhs, p = kernels.RHS[sysm.sys_id], sysm.kernel_params()

    def f(t, y):
        out = np.empty(y.size)
        rhs(np.ascontiguousarray(y), p, out)
        return out

    solver = DOP853(f, 0.0, s0, T, rtol=tol, atol=tol)
    solver.t_bound = 4 * T  # after the initial step: no clipping at T
    steps = 0
    while solver.t < T:
        solver.step()
        steps += 1
    return solver, steps


@pytest.mark.parametrize("system", ["cyclotron", "hoop", "free-body"])
def test_compiled_dop853_takes_scipys_steps(system):
    """Our DOP853 is a port of scipy's, with the dense output scipy also has: advanced to T it
    takes scipy's steps (the last one past T, not cut there) with scipy's evaluations plus the
    dense output's three, and hands back scipy's dense output at T to round-off. scipy's
    ``solve_ivp`` to T cuts the last step at T instead: that state differs from ours by the
    interpolant's error, within the tolerance."""
    sysm, s0, T = PROBLEMS[system]
    s0 = sysm.default_state() if s0 is None else s0
    for tol in (1e-6, 1e-10):
        ours = Simulation(sysm, "dop853", rtol=tol, atol=tol, state=s0, reference=None)
        ours.advance_to(T)
        solver, steps = _scipy_dop853_past(sysm, s0, T, tol)
        at_T = solver.dense_output()(T)
        assert ours.steps == steps
        assert ours.nfev == solver.nfev  # including the dense output's three stages
        np.testing.assert_allclose(ours.state[0], at_T, rtol=1e-12, atol=1e-12)
        theirs = Simulation(sysm, "scipy-dop853", rtol=tol, atol=tol, state=s0, reference=None)
        theirs.advance_to(T)
        # the same steps but the last, which may be rejected at full length where cut it was not
        assert abs(ours.steps - theirs.steps) <= 1
        scale = tol * (1.0 + np.abs(theirs.state))
        assert np.all(np.abs(ours.state - theirs.state) < 10 * scale)


@pytest.mark.parametrize(
    "method", ["scipy-rk45", "scipy-dop853", "scipy-radau", "scipy-lsoda", "odeint"]
)
def test_scipy_methods_go_through_the_same_driver_and_converge(method):
    sysm, s0, T = PROBLEMS["cyclotron"]
    sim = Simulation(sysm, method, rtol=1e-10, atol=1e-10, state=s0)
    sim.advance_to(T)
    assert sim.nfev > 0 and sim.steps > 0
    assert sim.sample().error[0] < 1e-6


def test_batched_states_advance_independently():
    sysm = Cyclotron()
    states = np.array([cyclotron.circular_orbit_state(sysm.params, v) for v in (0.5, 1.0, 2.0)])
    sim = Simulation(sysm, "rk4", dt=0.01, state=states)
    sim.advance_to(5.0)
    for i, s0 in enumerate(states):
        single = Simulation(sysm, "rk4", dt=0.01, state=s0)
        single.advance_to(5.0)
        np.testing.assert_array_equal(sim.state[i], single.state[0])
    # Every orbit has the same period, whatever its speed.
    sim.advance_to(cyclotron.period(sysm.params))
    assert np.max(sim.sample().error) < 1e-7


def test_blow_up_raises_a_clear_error_and_keeps_the_last_good_state():
    sysm, s0, _ = PROBLEMS["cyclotron"]
    sim = Simulation(sysm, "euler", dt=0.5, state=s0)
    sim.advance_to(10.0)
    with pytest.raises(
        IntegrationError, match=r"euler with dt=0.5 s: state became non-finite .* at t = "
    ):
        sim.advance_to(1e6)
    assert np.all(np.isfinite(sim.state))
    assert sim.t == pytest.approx(10.0)


def test_implicit_step_that_cannot_converge_raises():
    with pytest.raises(IntegrationError, match="implicit solve did not converge"):
        Simulation(Hoop(), "midpoint", dt=2.0, state=[2.0, -2.0, 5.0, -5.0]).advance_to(20.0)


def test_the_implicit_midpoint_never_takes_an_overflowed_iterate_for_a_fixed_point():
    """Iterates that overflow are a diverged iteration (-1: "did not converge"), not a step to a
    non-finite state: ``inf <= tol (1 + inf)`` alone would pass the convergence test."""

    @njit
    def blow_up(y, p, out):
        for j in range(y.size):
            out[j] = 1e300 * y[j] * y[j]

    y = np.array([1.0, 2.0])
    assert kernels.midpoint_step(blow_up, y, np.zeros(1), 1.0, np.empty((3, 2))) == -1


def test_fixed_steps_are_exactly_dt_and_time_is_counted_in_steps():
    sim = Simulation(Hoop(), "rk4", dt=0.03)
    sim.advance_to(1.0)
    assert sim.steps == 33 and sim.t == pytest.approx(0.99)
    sim.advance(0.02)  # clock 1.02: the 0.01 s left over from 1.0 makes one more step fit
    assert sim.steps == 34 and sim.nfev == 4 * 34


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"method": "rk4", "dt": 0.0}, "dt must be positive"),
        ({"method": "rk4", "dt": -1.0}, "dt must be positive"),
        ({"method": "rk4", "dt": float("nan")}, "dt must be finite"),
        ({"method": "rk4"}, "dt is required"),
        ({"method": "dop853", "rtol": 2.0}, "rtol must be below 1"),
        ({"method": "boris", "dt": 0.1}, "does not apply to hoop"),
        ({"method": "nope", "dt": 0.1}, "method must be one of"),
        (
            {"method": "rk4", "dt": 0.1, "state": [0.0, float("nan"), 0.0, 0.0]},
            "state must be finite",
        ),
        ({"method": "rk4", "dt": 0.1, "state": [0.0, 0.0]}, "state must have shape"),
    ],
)
def test_bad_simulation_settings_are_rejected_naming_the_field(kwargs, message):
    method = kwargs.pop("method")
    with pytest.raises(ValueError, match=message):
        Simulation(Hoop(), method, **kwargs)


def test_reference_solution_agrees_with_scipy_radau():
    """The tight DOP853 reference the driver measures errors against is itself right: it agrees
    with scipy's Radau at 1e-12 (an independent, implicit method)."""
    sysm, s0, T = PROBLEMS["hoop"]
    ref = _reference(sysm, s0, T)
    f = lambda t, y: (lambda out: (sysm_rhs(y, out), out)[1])(np.empty(4))  # noqa: E731

    def sysm_rhs(y, out):
        kernels.RHS[sysm.sys_id](np.ascontiguousarray(y), sysm.kernel_params(), out)

    radau = solve_ivp(f, (0, T), s0, method="Radau", rtol=1e-12, atol=1e-12).y[:, -1]
    assert np.linalg.norm(radau - ref) / np.linalg.norm(ref) < 1e-10


@pytest.mark.slow
def test_uncompiled_source_gives_bit_identical_results():
    """NUMBA_DISABLE_JIT=1 runs the same kernels as plain Python (for print and pdb): same bits."""
    script = (
        "import numpy as np, dynamics as d\n"
        "out = []\n"
        "for s, m in [(d.Cyclotron(), 'rk4'), (d.Cyclotron(), 'boris'), (d.Hoop(), 'verlet'),\n"
        "             (d.ReleasedDisk(extra_spin=(0.01, 0, 0.01)), 'splitting'), (d.Hoop(), 'midpoint')]:\n"
        "    sim = d.Simulation(s, m, dt=0.01, reference=None)\n"
        "    sim.advance_to(0.5)\n"
        "    out.append(sim.state[0].tobytes().hex())\n"
        "print(' '.join(out))\n"
    )
    runs = [
        subprocess.run(
            [sys.executable, "-c", script],
            capture_output=True,
            text=True,
            timeout=300,
            env={**os.environ, "NUMBA_DISABLE_JIT": flag},
        )
        for flag in ("0", "1")
    ]
    assert all(r.returncode == 0 for r in runs), [r.stderr for r in runs]
    assert runs[0].stdout == runs[1].stdout


_EVERY_METHOD = """
import mechviz.dynamics
from mechviz.dynamics.disk import DiskParams
systems = [
    mechviz.dynamics.Cyclotron(),
    mechviz.dynamics.Hoop(),
    mechviz.dynamics.ReleasedDisk(DiskParams(omega=1.0)),
]
for system in systems:
    for m in mechviz.dynamics.methods_for(system):
        if m.backend == "scipy":
            continue
        kw = {"rtol": 1e-6} if m.adaptive else ({} if m.backend == "exact" else {"dt": 1e-3})
        mechviz.dynamics.Simulation(system, m.name, reference=None, **kw).advance(2e-3)
print("ok")
"""


@pytest.mark.slow
def test_the_disk_cache_stops_growing_once_every_method_has_run(tmp_path):
    """numba keys a cache entry of a kernel that takes a compiled function on that function's
    dispatcher type, which is new in every process: with ``cache=True`` on such kernels each
    process appended entries that no later process could hit, and a stale one could make saving
    the index fail ("underlying object has vanished"). Those kernels are compiled per process
    instead, so a second and third process on the same cache add nothing and still run."""
    cache = tmp_path / "cache"
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache)}
    sizes = []
    for _ in range(3):
        run = subprocess.run(
            [sys.executable, "-c", _EVERY_METHOD],
            env=env,
            capture_output=True,
            text=True,
            timeout=600,
        )
        assert run.returncode == 0 and run.stdout.strip() == "ok", run.stderr[-2000:]
        sizes.append(sorted(str(f.relative_to(cache)) for f in cache.rglob("*.nbc")))
    assert sizes[0] and sizes[1] == sizes[0] and sizes[2] == sizes[0]


def test_every_fixed_step_method_carries_its_stability_facts_and_adaptive_ones_none():
    """A method's amplification factor, limit and reason are on its description: every
    fixed-step method of ours has them (the stability module and the viewer read nothing
    else), each limit is where its own amplification factor crosses 1, and an adaptive method,
    whose step control sets the step, is refused by name."""
    from mechviz.dynamics import stability
    from mechviz.dynamics.integrators import METHODS

    for m in METHODS.values():
        if m.adaptive:
            with pytest.raises(ValueError, match=m.name):
                stability.limit_omega_dt(m.name)
            continue
        assert m.amplification is not None and m.limit_reason, m.name
        x = m.limit_omega_dt
        if x is None:  # stable at every step: never above 1
            assert all(m.amplification(v) <= 1.0 + 1e-12 for v in (0.1, 1.0, 3.0, 10.0)), m.name
        elif x == 0.0:  # stable at none
            assert m.amplification(0.1) > 1.0, m.name
        elif m.name != "midpoint":  # (its limit is its fixed-point solve's, not its map's)
            assert m.amplification(0.999 * x) <= 1.0 + 1e-9 < m.amplification(1.01 * x), m.name


def test_a_method_no_product_module_knows_is_refused_not_run_as_another():
    """An adaptive method with neither a Runge-Kutta pair nor Taylor's kernel: the driver
    raises instead of running DOP853 in its place; the stability module and the benchmark's
    charts refuse a name they do not know."""
    import dataclasses

    from mechviz.bench.charts import color
    from mechviz.dynamics import stability
    from mechviz.dynamics.integrators import METHODS

    stranger = dataclasses.replace(METHODS["dop853"], name="stranger", pair=None)
    sim = Simulation(Cyclotron(), stranger, rtol=1e-6, reference=None)
    with pytest.raises(ValueError, match="stranger"):
        sim.advance_to(1.0)
    with pytest.raises(ValueError, match="stranger"):
        stability.amplification(stranger, 0.5)
    with pytest.raises(KeyError, match="stranger"):
        color("stranger")
    assert color("vern8") == METHODS["vern8"].chart_color


def test_the_benchmark_lists_are_read_from_the_methods():
    """Our adaptive methods in the sweeps, scipy's side of the ratios and ours against the
    peers in their fastest forms are the methods whose descriptions say so, Verner's among
    them."""
    from mechviz.bench import fastest, problems
    from mechviz.dynamics.integrators import METHODS

    assert set(problems.ADAPTIVE_OURS) == {m.name for m in METHODS.values() if "sweep" in m.bench}
    assert {"dop853", "vern6", "vern7", "vern8", "vern9", "taylor"} <= set(problems.ADAPTIVE_OURS)
    assert all(METHODS[m].backend == "scipy" for m in problems.ADAPTIVE_SCIPY)
    assert "vern8" in fastest.OURS


def test_a_fixed_step_method_finds_each_systems_own_compiled_step_or_refuses():
    """The compiled steps are looked up in tables by system id: the exact flow is the charge's
    only, and asked of another system it is refused, never another system's flow."""
    from mechviz.dynamics.integrators import METHODS, kernels
    from mechviz.dynamics.integrators.base import step_functions

    exact = next(m for m in METHODS.values() if m.kernel == "exact")
    assert step_functions(exact, kernels.CYCLOTRON) == (kernels.cyclotron.exact_step, None)
    for sys_id in (kernels.HOOP, kernels.FREE_BODY):
        with pytest.raises(ValueError, match="no compiled exact flow"):
            step_functions(exact, sys_id)
    rk4 = next(m for m in METHODS.values() if m.kernel == "rk4")
    assert [step_functions(rk4, i)[0] for i in range(3)] == list(kernels.RK4)
