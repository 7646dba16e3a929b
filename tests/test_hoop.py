"""Bead on a hanging hoop: Lagrangian equations, normal modes, the exact nonlinear mode 1."""

import math

import numpy as np
import pytest
import sympy as sp

from mechviz.dynamics import Hoop, Simulation, floquet, hoop
from mechviz.dynamics.hoop import HoopParams
from mechviz.dynamics.integrators import kernels

PARAMS = [HoopParams(), HoopParams(1.0, 1.0, 1.0, 9.81), HoopParams(3.0, 0.2, 0.5, 1.62)]


def _lagrangian_accelerations():
    """Euler-Lagrange accelerations from the Cartesian positions (no hand-made Lagrangian)."""
    t = sp.symbols("t")
    M, m, a, g = sp.symbols("M m a g", positive=True)
    th1, th2 = sp.Function("th1")(t), sp.Function("th2")(t)
    x1, y1 = a * sp.sin(th1), -a * sp.cos(th1)
    x2, y2 = x1 + a * sp.sin(th2), y1 - a * sp.cos(th2)
    T = (2 * M * a**2) / 2 * sp.diff(th1, t) ** 2 + m / 2 * (
        sp.diff(x2, t) ** 2 + sp.diff(y2, t) ** 2
    )
    V = M * g * y1 + m * g * y2
    L = T - V
    eqs = [sp.diff(sp.diff(L, sp.diff(q, t)), t) - sp.diff(L, q) for q in (th1, th2)]
    dd = [sp.diff(q, t, 2) for q in (th1, th2)]
    sol = sp.solve(eqs, dd)
    syms = sp.symbols("q1 q2 w1 w2")
    rep = {sp.diff(th1, t): syms[2], sp.diff(th2, t): syms[3]}
    rep2 = {th1: syms[0], th2: syms[1]}
    exprs = [sol[d].subs(rep).subs(rep2) for d in dd]
    return sp.lambdify((*syms, M, m, a, g), exprs, "math"), (L, th1, th2, t, M, m, a, g)


@pytest.mark.slow
def test_equations_of_motion_equal_euler_lagrange_from_the_positions():
    f, _ = _lagrangian_accelerations()
    rng = np.random.default_rng(7)
    for p in PARAMS:
        for _ in range(10):
            s = rng.uniform(-2.5, 2.5, size=4)
            out = np.empty(4)
            kernels.RHS[kernels.HOOP](s, p.kernel_params(), out)
            expected = f(*s, p.hoop_mass, p.bead_mass, p.radius, p.gravity)
            np.testing.assert_allclose(out[2:], expected, rtol=1e-11, atol=1e-11)
            np.testing.assert_allclose(out[:2], s[2:])


@pytest.mark.slow
def test_seed_lagrangian_with_the_missing_a_restored():
    """The seed's L, with (M + m) g a cos th1 (the seed drops the a), equals T - V."""
    _, (L, th1, th2, t, M, m, a, g) = _lagrangian_accelerations()
    w1, w2 = sp.diff(th1, t), sp.diff(th2, t)
    seed = (
        (M + m / 2) * a**2 * w1**2
        + m * a**2 / 2 * w2**2
        + m * a**2 * sp.cos(th1 - th2) * w1 * w2
        + (M + m) * g * a * sp.cos(th1)
        + m * g * a * sp.cos(th2)
    )
    assert sp.simplify(sp.expand_trig(L - seed)) == 0


def test_second_equation_has_minus_cos_th1_dd_not_the_seeds_plus():
    f, _ = _lagrangian_accelerations()
    p = PARAMS[0]
    s = (0.4, -0.2, 0.3, 0.5)
    a1, a2 = f(*s, p.hoop_mass, p.bead_mass, p.radius, p.gravity)
    d = s[0] - s[1]
    ga = p.gravity / p.radius
    ours = math.sin(d) * s[2] ** 2 - math.cos(d) * a1 - ga * math.sin(s[1])
    seeds = math.sin(d) * s[2] ** 2 + math.cos(d) * a1 - ga * math.sin(s[1])
    assert a2 == pytest.approx(ours, rel=1e-12)
    assert abs(a2 - seeds) > 0.1


def test_seed_normal_mode_frequencies_and_shapes():
    for p in PARAMS:
        freqs, shapes = hoop.normal_modes(p)
        M, m, a, g = p.hoop_mass, p.bead_mass, p.radius, p.gravity
        np.testing.assert_allclose(freqs, [math.sqrt(g / (2 * a)), math.sqrt((1 + m / M) * g / a)])
        # Shapes solve the generalised eigenproblem K v = w^2 M v of the linearised equations.
        Mm = hoop.mass_matrix(p, 0.0, 0.0)
        K = np.diag([(M + m) * g * a, m * g * a])
        for w, v in zip(freqs, shapes, strict=True):
            np.testing.assert_allclose(K @ v, w**2 * Mm @ v, atol=1e-12 * np.abs(K).max())
        # Seed's ratios: (1, 1) in phase; (m, -(M + m)) out of phase with the bead wider.
        assert shapes[1][0] / shapes[1][1] == pytest.approx(-m / (M + m))


@pytest.mark.parametrize("mode", [0, 1])
def test_small_amplitude_mode_stays_in_its_mode_at_the_predicted_frequency(mode):
    p = HoopParams()
    freqs, shapes = hoop.normal_modes(p)
    amps = [0.0, 0.0]
    amps[mode] = 1e-3
    s0 = hoop.mode_state(p, tuple(amps))
    T = 2 * math.pi / freqs[mode]
    traj = Simulation(Hoop(p), "rk4", dt=T / 2000, state=s0).run(20 * T, 20 * 400 + 1)
    th = traj.states[:, 0, :2]
    # Projection onto the other mode (shapes are M-orthogonal at rest) stays tiny.
    Mm = hoop.mass_matrix(p, 0, 0)
    other = shapes[1 - mode]
    leak = np.abs(th @ Mm @ other) / np.sqrt(other @ Mm @ other)
    own = np.abs(th @ Mm @ shapes[mode]) / np.sqrt(shapes[mode] @ Mm @ shapes[mode])
    assert leak.max() < 1e-6 * own.max()
    # Frequency from the upward zero crossings of theta1, linearly interpolated.
    x = th[:, 0]
    idx = np.where((x[:-1] < 0) & (x[1:] >= 0))[0]
    tc = traj.t[idx] - x[idx] * (traj.t[idx + 1] - traj.t[idx]) / (x[idx + 1] - x[idx])
    measured = 2 * math.pi / np.mean(np.diff(tc))
    assert measured == pytest.approx(freqs[mode], rel=1e-4)


def test_linear_solution_solves_the_linearised_equations():
    p = HoopParams(1.0, 0.7, 1.3, 9.81)
    s0 = np.array([0.01, -0.02, 0.03, 0.005])
    ts = np.array([0.0, 0.37, 2.1])
    h = 1e-4
    y = hoop.linear_solution(p, s0, ts)
    np.testing.assert_allclose(y[0], s0, atol=1e-15)
    ydd = (hoop.linear_solution(p, s0, ts + h) - 2 * y + hoop.linear_solution(p, s0, ts - h)) / h**2
    Mm = hoop.mass_matrix(p, 0, 0)
    K = np.diag(
        [(p.hoop_mass + p.bead_mass) * p.gravity * p.radius, p.bead_mass * p.gravity * p.radius]
    )
    np.testing.assert_allclose(ydd[:, :2] @ Mm.T, -(y[:, :2] @ K.T), atol=1e-6)


@pytest.mark.parametrize("amplitude", [0.1, 1.0, 2.5])
def test_mode1_is_an_exact_pendulum_at_any_amplitude(amplitude):
    """th1 = th2 is invariant; the elliptic-function solution matches a tight integration and
    its period is 4 K(sin^2(A/2)) / w0."""
    p = HoopParams()
    s0 = hoop.mode_state(p, (amplitude, 0.0))
    T = hoop.mode1_period(p, amplitude)
    ref = Simulation(Hoop(p), "dop853", rtol=1e-12, atol=1e-12, reference=None, state=s0).run(
        2 * T, 41
    )
    exact = hoop.mode1_exact_solution(p, s0, ref.t)
    np.testing.assert_allclose(ref.states[:, 0], exact, atol=1e-8)
    np.testing.assert_allclose(exact[-1], s0, atol=1e-9)
    w0 = math.sqrt(p.gravity / (2 * p.radius))
    assert T > 2 * math.pi / w0  # the period lengthens with amplitude


def test_mode1_exact_solution_from_a_moving_start():
    p = HoopParams()
    s0 = np.array([0.3, 0.3, -1.1, -1.1])
    ts = np.linspace(0, 5, 11)
    ref = Simulation(Hoop(p), "dop853", rtol=1e-12, atol=1e-12, reference=None, state=s0).run(5, 11)
    np.testing.assert_allclose(ref.states[:, 0], hoop.mode1_exact_solution(p, s0, ts), atol=1e-9)


def test_energy_is_conserved_by_the_true_motion():
    p = HoopParams()
    traj = Simulation(Hoop(p), "dop853", rtol=1e-12, atol=1e-12, state=[1.0, -1.5, 0.5, 2.0]).run(
        20, 201
    )
    assert np.max(np.abs(traj.energy_error)) < 1e-10


@pytest.mark.parametrize(
    ("field", "value"), [("hoop_mass", -1.0), ("radius", 0.0), ("gravity", float("nan"))]
)
def test_bad_parameters_are_rejected_naming_the_field(field, value):
    with pytest.raises(ValueError, match=rf"^{field} must be"):
        HoopParams(**{field: value})


def test_mode1_start_over_the_top_is_measured_against_the_reference():
    """No libration to solve in closed form: the driver falls back on the tight reference."""
    sim = Simulation(Hoop(), "rk4", dt=0.01, state=[3.0, 3.0, 2.0, 2.0])
    sim.advance_to(1.0)
    assert sim.reference_kind == "reference"
    assert sim.sample().error[0] < 1e-7


def test_energy_above_rest_is_the_energy_plus_the_hanging_floor():
    """The cancellation-free form equals ``E + (M + 2m) g a`` where that difference is benign
    (swings of order a radian, any mix of angles and rates)."""
    p = HoopParams(2.3, 0.7, 0.6, 3.7)
    rng = np.random.default_rng(3)
    states = rng.uniform(-2.0, 2.0, (50, 4))
    floor = (p.hoop_mass + 2 * p.bead_mass) * p.gravity * p.radius
    np.testing.assert_allclose(
        hoop.energy_above_rest(p, states), hoop.energy(p, states) + floor, rtol=1e-13
    )
    assert hoop.energy_above_rest(p, np.zeros(4)) == 0.0


@pytest.mark.parametrize("amplitude", [1e-2, 1e-4, 1e-6, 1e-8])
def test_energy_error_of_the_exact_mode1_motion_is_round_off_at_any_swing(amplitude):
    """The driver's relative energy error of exact mode-1 states (closed form, non-default
    parameters) stays at round-off of the energy that moves, whatever the swing: the energy is
    taken above the hanging rest without cancellation. Taken about the pivot and differenced,
    it had a floor of about 7e-16 / A^2 (7e-4 at 1e-6 rad)."""
    p = HoopParams(1.7, 0.35, 0.8, 4.2)
    s0 = hoop.mode_state(p, (amplitude, 0.0))
    sim = Simulation(Hoop(p), "rk4", dt=0.01, state=s0, reference=None)
    t = np.linspace(0.0, 20.0, 81)
    exact = hoop.mode1_exact_solution(p, s0, t)
    worst = 0.0
    for s in exact:
        sim.state[0] = s
        worst = max(worst, float(abs(sim.sample().energy_error[0])))
    assert worst < 1e-13


@pytest.mark.parametrize(
    ("bead_mass", "amplitude"), [(0.5, 0.5), (0.5, 2.0), (0.05, 2.0), (0.05, 2.7)]
)
def test_mode1_floquet_multiplier_predicts_how_a_departure_from_mode1_grows(bead_mass, amplitude):
    """The multiplier from one period's monodromy predicts a small departure's growth over
    several periods of the full equations: l^k where it is unstable, bounded where it is 1;
    the monodromy keeps volume (its determinant is 1)."""
    p = hoop.HoopParams(bead_mass=bead_mass)
    D = floquet.mode1_monodromy(p, amplitude)
    assert np.linalg.det(D) == pytest.approx(1.0, abs=1e-4)
    lam = floquet.mode1_floquet_multiplier(p, amplitude)
    T = hoop.mode1_period(p, amplitude)
    # a departure along the growing direction (or, if none, the transverse one), of 1e-9
    w, V = np.linalg.eig(D)
    grow = np.real(V[:, np.argmax(np.abs(w))]) if lam > 1.01 else np.array([1.0, -1.0, 0, 0])
    d0 = 1e-9 * grow / np.linalg.norm(grow)
    start = np.array([amplitude, amplitude, 0.0, 0.0])
    periods = 3
    sim = Simulation(
        Hoop(p),
        "dop853",
        rtol=1e-13,
        atol=1e-16,
        state=np.stack([start, start + d0]),
        reference=None,
    )
    sim.advance_to(periods * T, final=True)
    growth = np.linalg.norm(sim.state[1] - sim.state[0]) / 1e-9
    if lam > 1.01:
        assert growth == pytest.approx(lam**periods, rel=0.05)
    else:
        assert lam == pytest.approx(1.0, abs=1e-4)
        assert growth < 20.0


def test_the_verlet_step_never_takes_an_overflowed_iterate_for_a_fixed_point():
    """A drift whose iterate overflows is a diverged iteration (-1: "did not converge"), not a
    step to a non-finite state: ``inf <= tol (1 + inf)`` alone would pass the convergence test.
    (A bead at ~1e180 rad/s and a step of ~1e128 s: the first drift lands at ~1e308 rad and the
    next one overflows.)"""
    y = np.array(
        [0.331150757626947, -1.1150804016081923, 3.341131007789588e94, 2.93136057891846e180]
    )
    p = HoopParams().kernel_params()
    assert hoop.verlet_step(y, p, 5.947227314873471e127) == -1
    assert np.all(np.isfinite(y))  # a step that fails leaves the state as it was
