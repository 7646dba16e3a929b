"""Stability where methods fail: each test measures a method through the driver and asserts the
closed-form prediction (:mod:`mechviz.dynamics.stability`). No timing is asserted anywhere.

omega is the gyrofrequency (charge) or the higher normal-mode frequency (hoop); x = omega dt.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechviz.dynamics import stability
from mechviz.dynamics.disk import DiskParams
from mechviz.dynamics.hoop import mode_state, normal_modes
from mechviz.dynamics.integrators import IntegrationError
from mechviz.dynamics.simulation import Simulation
from mechviz.dynamics.systems import Cyclotron, Hoop, ReleasedDisk

# Charge with q = m = B = 1 (omega = 1), moving in the plane normal to B.
GYRATION = np.array([1.0, 0.0, 0.0, 0.0, 1.0, 0.0])


def charge_run(method: str, x: float, steps: int) -> Simulation:
    sim = Simulation(Cyclotron(), method, dt=x, state=GYRATION, reference=None)
    sim.advance_to(steps * x)
    assert sim.steps == steps
    return sim


def speed(sim: Simulation) -> float:
    return math.hypot(sim.state[0, 3], sim.state[0, 4])


def rk4_factor(x: float) -> float:
    """|R(i x)| for the classical RK4."""
    return math.sqrt(1.0 - x**6 / 72.0 + x**8 / 576.0)


# --------------------------------------------------------------------------- explicit Euler
@pytest.mark.parametrize("x", [0.01, 0.1, 0.5, 1.0, 2.0])
def test_euler_speed_grows_by_sqrt_one_plus_omega_dt_squared_every_step(x):
    sim = Simulation(Cyclotron(), "euler", dt=x, state=GYRATION, reference=None)
    before = speed(sim)
    for _ in range(20):
        sim.advance(x)
        after = speed(sim)
        assert after / before == pytest.approx(math.sqrt(1.0 + x * x), rel=1e-14)
        before = after


def test_euler_energy_after_many_steps_is_the_product_of_the_per_step_factors():
    n, x = 100_000, 0.01
    sim = charge_run("euler", x, n)
    assert speed(sim) ** 2 == pytest.approx((1.0 + x * x) ** n, rel=1e-10)


def test_euler_is_unstable_at_every_step_size():
    assert stability.stability_limit("euler", Cyclotron()) == 0.0


# --------------------------------------------------------------------------- RK4
@pytest.mark.parametrize("x", [0.5, 1.0, 2.0, 2.8, 2.82])
def test_rk4_gyration_decays_below_two_sqrt_two_exactly_as_its_amplification_factor(x):
    n = 200
    sim = charge_run("rk4", x, n)
    assert speed(sim) < 1.0
    assert math.log(speed(sim)) == pytest.approx(n * math.log(rk4_factor(x)), rel=1e-9, abs=1e-13)


@pytest.mark.parametrize("x", [2.84, 2.9, 3.0, 3.5])
def test_rk4_gyration_grows_above_two_sqrt_two_exactly_as_its_amplification_factor(x):
    n = 200
    sim = charge_run("rk4", x, n)
    assert speed(sim) > 1.0
    assert math.log(speed(sim)) == pytest.approx(n * math.log(rk4_factor(x)), rel=1e-9)


def test_rk4_limit_is_two_sqrt_two_over_omega():
    limit = stability.stability_limit("rk4", Cyclotron())
    assert limit == pytest.approx(2.0 * math.sqrt(2.0))
    assert speed(charge_run("rk4", 0.999 * limit, 2000)) < 1.0
    assert speed(charge_run("rk4", 1.001 * limit, 2000)) > 1.0


def test_rk4_energy_decays_at_the_rate_its_amplification_factor_predicts():
    # E_n / E_0 = |R(i x)|^(2n): over 1e4 gyro-periods at x = 0.3 the energy falls to ~0.12.
    x = 0.3
    n = int(round(1e4 * 2.0 * math.pi / x))
    sim = charge_run("rk4", x, n)
    ratio = float(Cyclotron().energy(sim.state)[0] / Cyclotron().energy(GYRATION))
    assert ratio == pytest.approx(rk4_factor(x) ** (2 * n), rel=1e-8)
    assert 0.05 < ratio < 0.2


# --------------------------------------------------------------------------- Stormer-Verlet
HOOP = Hoop()
OMEGA_MAX = float(normal_modes(HOOP.params)[0][-1])
A0 = 1e-6  # rad: small enough that the linearised equations hold to ~1e-12


def mode2_amplitudes(method: str, x: float, steps: int) -> np.ndarray:
    """Amplitude sqrt(c^2 + (c'/omega)^2) of mode 2 after each step, started at rest at A0."""
    dt = x / OMEGA_MAX
    sim = Simulation(HOOP, method, dt=dt, state=mode_state(HOOP.params, (0.0, A0)), reference=None)
    basis = normal_modes(HOOP.params)[1].T
    out = []
    for k in range(1, steps + 1):
        sim.advance_to(k * dt * (1 + 1e-12))
        c = np.linalg.solve(basis, sim.state[0, :2])
        cd = np.linalg.solve(basis, sim.state[0, 2:])
        out.append(math.hypot(c[1], cd[1] / OMEGA_MAX))
        if out[-1] > 1e-2:
            break
    return np.array(out)


@pytest.mark.parametrize("x", [0.5, 1.5, 1.9, 1.99])
def test_verlet_on_the_linearised_hoop_is_stable_below_omega_max_dt_2(x):
    # Kick-drift-kick conserves p^2 + omega^2 (1 - x^2/4) q^2 exactly on a linear oscillator,
    # so the amplitude stays between sqrt(1 - x^2/4) A0 and A0 for ever.
    amp = mode2_amplitudes("verlet", x, 3000) / A0
    assert len(amp) == 3000
    assert amp.max() <= 1.0 + 1e-6
    assert amp.min() >= math.sqrt(1.0 - x * x / 4.0) * (1.0 - 1e-6)


@pytest.mark.parametrize("x", [2.05, 2.5, 3.0])
def test_verlet_on_the_linearised_hoop_grows_above_omega_max_dt_2_at_the_predicted_rate(x):
    amp = mode2_amplitudes("verlet", x, 3000)
    assert amp[-1] > 1e3 * A0  # blew up within the run
    # Growth per step over the second half of the run, against the larger eigenvalue.
    k = len(amp)
    measured = (amp[-1] / amp[k // 2]) ** (1.0 / (k - 1 - k // 2))
    assert measured == pytest.approx(stability.amplification("verlet", x), rel=0.02)


def test_verlet_limit_on_the_hoop_is_two_over_omega_max():
    assert stability.stability_limit("verlet", HOOP) == pytest.approx(2.0 / OMEGA_MAX)


# --------------------------------------------------------------------------- Boris and exact
@pytest.mark.parametrize("method", ["boris", "exact"])
@pytest.mark.parametrize("x", [0.1, 1.0, 3.0, 10.0, 100.0])
def test_boris_and_exact_rotation_keep_the_speed_to_round_off_at_any_omega_dt(method, x):
    n = 10_000
    sim = charge_run(method, x, n)
    # Round-off only: at most a few ulp per step (RK4 at x = 1 would be off by 1 - 0.994^n).
    assert abs(speed(sim) - 1.0) < 20 * n * np.finfo(float).eps


@pytest.mark.parametrize("x", [0.1, 0.5, 1.0, 2.0, 5.0])
def test_boris_phase_lags_exactly_as_two_arctan_half_omega_dt(x):
    n = 100
    sim = charge_run("boris", x, n)
    angle = -n * 2.0 * math.atan(0.5 * x)  # clockwise for q B > 0
    expected = np.array([math.sin(-angle), math.cos(angle)])  # v0 = (0, 1) turned by angle
    assert np.allclose(sim.state[0, 3:5], expected, rtol=0, atol=1e-12)
    # ... which is not the exact rotation by n x (the phase error is visible).
    if x >= 0.5:
        exact = np.array([math.sin(n * x), math.cos(n * x)])
        assert np.linalg.norm(sim.state[0, 3:5] - exact) > 1e-3


def test_exact_step_turns_the_velocity_by_exactly_omega_dt():
    n, x = 100, 1.0
    sim = charge_run("exact", x, n)
    assert np.allclose(sim.state[0, 3:5], [math.sin(n * x), math.cos(n * x)], atol=1e-12)


@pytest.mark.parametrize("method", ["boris", "exact", "splitting"])
def test_norm_preserving_methods_have_no_stability_limit(method):
    system = Cyclotron() if method != "splitting" else ReleasedDisk(extra_spin=(0.01, 0, 0.01))
    assert stability.stability_limit(method, system) is None


# --------------------------------------------------------------------------- long runs
def energy_history(system, method, dt, t_end, samples=200, state=None):
    sim = Simulation(system, method, dt=dt, state=state, reference=None)
    state0 = sim.state0
    E0 = float(system.energy(state0)[0])
    out = []
    for k in range(1, samples + 1):
        sim.advance_to(t_end * k / samples)
        out.append((float(system.energy(sim.state)[0]) - E0) / abs(E0))
    return np.array(out)


def no_trend(err: np.ndarray) -> bool:
    """The mean of the first and of the last 10 % of samples agree within a tenth of the spread."""
    tenth = len(err) // 10
    return abs(err[-tenth:].mean() - err[:tenth].mean()) < 0.1 * np.abs(err).max()


def linear_drift(err: np.ndarray) -> bool:
    """The error at T/4 and T/2 is a quarter and a half of that at T (within 10 %)."""
    n = len(err)
    end = err[-1]
    return (
        abs(err[n // 4 - 1] / end - 0.25) < 0.025
        and abs(err[n // 2 - 1] / end - 0.5) < 0.05
        and abs(end) > 10 * abs(err[n // 20])
    )


HOOP_PERIOD = 2.0 * math.pi / float(normal_modes(HOOP.params)[0][0])
LONG = {
    # system, step, 10^4 periods of the slowest motion
    "hoop": (Hoop(), 0.02, 1e4 * HOOP_PERIOD),
    "free-body": (
        ReleasedDisk(DiskParams(omega=1.0), extra_spin=(0.01, 0.0, 0.01)),
        0.2,
        1e4 * 2.0 * math.pi,
    ),
    "cyclotron": (Cyclotron(), 0.1, 1e4 * 2.0 * math.pi),
}
# In the plane normal to B. With a drift along B, z grows to ~6e3 and the midpoint solve's
# stopping test, relative to the size of the whole state, no longer resolves v to round-off:
# the energy then drifts by ~2e-7 over the run (a solver tolerance effect, not the method's).
STATES = {"cyclotron": GYRATION}


@pytest.mark.parametrize(
    "name, method",
    [
        ("hoop", "verlet"),
        ("hoop", "yoshida4"),
        ("free-body", "splitting"),
        ("free-body", "yoshida4"),
    ],
)
def test_symplectic_methods_keep_the_energy_error_bounded_over_ten_thousand_periods(name, method):
    system, dt, t_end = LONG[name]
    err = energy_history(system, method, dt, t_end, state=STATES.get(name))
    assert no_trend(err), (err[:20].mean(), err[-20:].mean(), np.abs(err).max())
    assert np.abs(err).max() < 1e-2


def test_implicit_midpoint_keeps_the_gyration_energy_to_its_solver_tolerance():
    # The midpoint rule conserves |v|^2 exactly (a quadratic invariant); what remains is the
    # fixed-point solve stopping at 1e-14 relative change, always from the same side: a drift
    # of ~1e-15 per step (6e-10 over these 6.3e5 steps), 1e7 times below RK4's at this step.
    system, dt, t_end = LONG["cyclotron"]
    mid = np.abs(energy_history(system, "midpoint", dt, t_end, state=GYRATION)).max()
    rk4 = np.abs(energy_history(system, "rk4", dt, t_end, state=GYRATION)).max()
    assert mid < 2e-9
    assert rk4 > 1e6 * mid


@pytest.mark.parametrize("name", ["hoop", "free-body", "cyclotron"])
def test_rk4_energy_error_grows_linearly_over_ten_thousand_periods(name):
    system, dt, t_end = LONG[name]
    err = energy_history(system, "rk4", dt, t_end, state=STATES.get(name))
    assert linear_drift(err), (err[49], err[99], err[-1])
    assert not no_trend(err)


def test_an_unstable_step_is_reported_not_returned_as_garbage():
    # Explicit Euler at x = 2 overflows within ~1000 steps; the driver names the method.
    sim = Simulation(Cyclotron(), "euler", dt=2.0, state=GYRATION, reference=None)
    with pytest.raises(IntegrationError, match="euler"):
        sim.advance_to(2.0 * 5000)
