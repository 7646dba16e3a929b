"""Cyclotron motion: equations of motion, the seed's analytic results, exact flow, radial kick."""

import math

import numpy as np
import pytest
import sympy as sp

from mechviz.dynamics import Cyclotron, Simulation, cyclotron
from mechviz.dynamics.cyclotron import CyclotronParams
from mechviz.dynamics.integrators import kernels

PARAMS = [
    CyclotronParams(),
    CyclotronParams(-1.6e-19, 9.11e-31, 2e-3),
    CyclotronParams(2.0, 3.0, -0.7),
]


def test_equations_of_motion_equal_euler_lagrange_of_the_gauge_lagrangian():
    """L = m v^2/2 + q v.A, A = (B/2)(-y, x, 0): sympy's Euler-Lagrange accelerations equal rhs."""
    t = sp.symbols("t")
    q, m, B = sp.symbols("q m B", real=True)
    x, y, z = (sp.Function(n)(t) for n in "xyz")
    v = [sp.diff(c, t) for c in (x, y, z)]
    A = [-B * y / 2, B * x / 2, 0]
    L = m / 2 * sum(c**2 for c in v) + q * sum(vi * ai for vi, ai in zip(v, A, strict=True))
    eqs = [sp.diff(sp.diff(L, vi), t) - sp.diff(L, c) for c, vi in zip((x, y, z), v, strict=True)]
    acc = sp.solve(eqs, [sp.diff(c, t, 2) for c in (x, y, z)])
    rng = np.random.default_rng(1)
    for p in PARAMS[::2]:
        for _ in range(5):
            s = rng.normal(size=6)
            subs = {q: p.charge, m: p.mass, B: p.field}
            subs.update({sp.diff(c, t): s[3 + i] for i, c in enumerate((x, y, z))})
            subs.update({c: s[i] for i, c in enumerate((x, y, z))})
            expected = [float(acc[sp.diff(c, t, 2)].subs(subs)) for c in (x, y, z)]
            out = np.empty(6)
            kernels.RHS[kernels.CYCLOTRON](s, p.kernel_params(), out)
            np.testing.assert_allclose(out[:3], s[3:], rtol=0, atol=0)
            np.testing.assert_allclose(out[3:], expected, rtol=1e-12, atol=1e-12)


def test_seed_hamiltonian_effective_potential_curvature_is_q2B2_over_m():
    """Seed 1c: V_eff''(r0) = (qB)^2/m, so the radial frequency equals the orbital one."""
    r, p_phi, qb, m = sp.symbols("r p_phi qB m", positive=True)
    V = (p_phi - qb * r**2 / 2) ** 2 / (2 * m * r**2)
    r0 = sp.sqrt(2 * p_phi / qb)
    assert sp.simplify(sp.diff(V, r).subs(r, r0)) == 0
    assert sp.simplify(sp.diff(V, r, 2).subs(r, r0) - qb**2 / m) == 0
    # Expanded, V is the seed's V_eff with eB -> -qB.
    expanded = p_phi**2 / (2 * m * r**2) - qb * p_phi / (2 * m) + qb**2 * r**2 / (8 * m)
    assert sp.simplify(V - expanded) == 0


@pytest.mark.parametrize("p", PARAMS)
def test_seed_circular_orbit_frequency_and_radius(p):
    w = abs(p.charge * p.field) / p.mass
    assert cyclotron.gyrofrequency(p) == pytest.approx(w, rel=1e-15)
    speed = 3.7 * (1 if p.mass > 1e-20 else 1e5)
    E = 0.5 * p.mass * speed**2
    assert cyclotron.orbit_radius(p, E) == pytest.approx(
        math.sqrt(2 * p.mass * E) / abs(p.charge * p.field)
    )
    assert cyclotron.orbit_radius(p, E) == pytest.approx(speed / w, rel=1e-12)
    # The exact solution closes after one period, on a circle of that radius about the centre.
    s0 = cyclotron.circular_orbit_state(p, speed)
    ts = np.linspace(0, cyclotron.period(p), 50)
    traj = cyclotron.exact_solution(p, s0, ts)
    np.testing.assert_allclose(traj[-1, :3], s0[:3], atol=1e-9 * speed / w)
    np.testing.assert_allclose(traj[-1, 3:], s0[3:], atol=1e-9 * speed)
    c = cyclotron.guiding_centre(p, s0)
    np.testing.assert_allclose(
        np.hypot(traj[:, 0] - c[0], traj[:, 1] - c[1]), speed / w, rtol=1e-10
    )


@pytest.mark.parametrize("p", PARAMS)
def test_radial_frequency_equals_gyrofrequency_for_either_sign_of_p_phi(p):
    for p_phi in (2.5, -0.3):
        scale = p.mass * (abs(p.charge * p.field) / p.mass)  # keep V_eff well conditioned
        assert cyclotron.radial_oscillation_frequency(p, p_phi * scale) == pytest.approx(
            cyclotron.gyrofrequency(p), rel=1e-12
        )


def test_positive_charge_turns_clockwise_seen_from_plus_z():
    p = CyclotronParams(1.0, 1.0, 1.0)
    s = cyclotron.exact_solution(p, [1.0, 0, 0, 0, -1.0, 0], np.array([0.0, 0.1]))
    # From (1, 0) moving along -y about the origin: clockwise, angle decreasing.
    assert math.atan2(s[1, 1], s[1, 0]) < 0
    electron = CyclotronParams(-1.0, 1.0, 1.0)
    s = cyclotron.exact_solution(electron, [1.0, 0, 0, 0, 1.0, 0], np.array([0.0, 0.1]))
    assert math.atan2(s[1, 1], s[1, 0]) > 0


def test_exact_solution_satisfies_the_equations_of_motion():
    p = CyclotronParams(1.3, 0.7, -2.1)
    s0 = np.array([0.3, -1.0, 0.5, 0.8, 0.4, -0.2])
    h = 1e-5
    for t in (0.0, 0.7, 5.3):
        y = cyclotron.exact_solution(p, s0, t)
        dy = (cyclotron.exact_solution(p, s0, t + h) - cyclotron.exact_solution(p, s0, t - h)) / (
            2 * h
        )
        f = np.empty(6)
        kernels.RHS[kernels.CYCLOTRON](y, p.kernel_params(), f)
        np.testing.assert_allclose(dy, f, atol=1e-8)


def test_energy_and_canonical_angular_momentum_are_conserved_along_the_exact_flow():
    p = CyclotronParams(0.9, 1.1, 1.7)
    s0 = np.array([0.3, -1.0, 0.5, 0.8, 0.4, -0.2])
    traj = cyclotron.exact_solution(p, s0, np.linspace(0, 30, 301))
    E = cyclotron.energy(p, traj)
    P = cyclotron.canonical_angular_momentum(p, traj)
    assert np.ptp(E) < 1e-14 * E[0]
    assert np.ptp(P) < 1e-13 * max(1.0, abs(P[0]))


def test_velocity_along_B_gives_a_helix_with_constant_pitch():
    p = CyclotronParams()
    s0 = np.array([1.0, 0.0, 0.0, 0.0, -1.0, 0.25])
    traj = Simulation(Cyclotron(p), "exact", state=s0).run(4 * math.pi, 9).states[:, 0]
    np.testing.assert_allclose(traj[:, 2], np.linspace(0, 4 * math.pi, 9) * 0.25, atol=1e-12)
    # Same transverse point after each period, advanced by the pitch 2 pi vz / omega.
    s_exact = cyclotron.exact_solution(p, s0, 2 * math.pi)
    np.testing.assert_allclose(s_exact[:2], s0[:2], atol=1e-12)
    assert s_exact[2] == pytest.approx(2 * math.pi * 0.25)


@pytest.mark.parametrize("dv", [0.05, 0.4, -0.7])
def test_radial_kick_moves_the_circle_to_the_predicted_centre_and_radius(dv):
    """Seed 1c, exactly: after a radial kick the charge moves on a circle whose centre and radius
    are radial_kick's prediction, at the same frequency; integrated here with DOP853."""
    p = CyclotronParams(1.0, 2.0, 0.5)
    s = cyclotron.circular_orbit_state(p, 1.5)
    s = cyclotron.exact_solution(p, s, 1.234)  # somewhere along the orbit
    kicked, centre, radius = cyclotron.radial_kick(p, s, dv)
    assert radius == pytest.approx(math.hypot(1.5, dv) / cyclotron.gyrofrequency(p))
    sim = Simulation(Cyclotron(p), "dop853", rtol=1e-12, atol=1e-12, state=kicked)
    T = cyclotron.period(p)
    traj = sim.run(3 * T, 301).states[:, 0]
    dist = np.hypot(traj[:, 0] - centre[0], traj[:, 1] - centre[1])
    np.testing.assert_allclose(dist, radius, rtol=1e-9)
    # Same period: back at the kicked state after each turn.
    np.testing.assert_allclose(traj[-1, :2], kicked[:2], atol=1e-8)
    # The shift of the centre is |dv| / omega, at right angles to the kick.
    shift = centre[:2] - cyclotron.guiding_centre(p, s)[:2]
    assert np.linalg.norm(shift) == pytest.approx(abs(dv) / cyclotron.gyrofrequency(p))
    radial = s[:2] - cyclotron.guiding_centre(p, s)[:2]
    assert abs(np.dot(shift, radial)) < 1e-12


def test_small_kick_makes_the_distance_from_the_old_centre_oscillate_at_the_orbital_frequency():
    p = CyclotronParams()
    s = cyclotron.circular_orbit_state(p, 1.0)
    kicked, _, _ = cyclotron.radial_kick(p, s, 0.01)
    ts = np.linspace(0, 20 * cyclotron.period(p), 4001)
    traj = cyclotron.exact_solution(p, kicked, ts)
    rho = np.hypot(traj[:, 0], traj[:, 1]) - 1.0
    spectrum = np.abs(np.fft.rfft(rho - rho.mean()))
    freq = np.fft.rfftfreq(len(ts), ts[1] - ts[0]) * 2 * math.pi
    assert freq[np.argmax(spectrum)] == pytest.approx(cyclotron.gyrofrequency(p), rel=0.01)


@pytest.mark.parametrize(
    ("field", "value", "text"),
    [
        ("charge", 0.0, "nonzero"),
        ("field", 0.0, "nonzero"),
        ("mass", -1.0, "positive"),
        ("mass", float("nan"), "finite"),
        ("field", float("inf"), "finite"),
        ("charge", "abc", "number"),
    ],
)
def test_bad_parameters_are_rejected_naming_the_field(field, value, text):
    with pytest.raises(ValueError, match=rf"^{field} must be .*{text}|^{field} must be a {text}"):
        CyclotronParams(**{field: value})


def test_the_radial_motion_stays_on_its_energy_level_in_the_effective_potential():
    """E_perp = p_r^2/2m + V_eff(r) along the exact flow, for an orbit that encloses the axis
    and one that does not (p_phi of either sign)."""
    p = cyclotron.CyclotronParams(charge=1.3, mass=0.7, field=-0.9)
    for centre in ((0.2, 0.1), (2.5, -1.0)):
        s0 = cyclotron.circular_orbit_state(p, 1.1, centre, 0.3)
        states = cyclotron.exact_solution(p, s0, np.linspace(0.0, 20.0, 400))
        r, p_r = cyclotron.radial_coordinates(p, states)
        p_phi = float(cyclotron.canonical_angular_momentum(p, s0))
        e_perp = 0.5 * p.mass * (s0[3] ** 2 + s0[4] ** 2)
        level = p_r**2 / (2 * p.mass) + cyclotron.effective_potential(p, r, p_phi)
        np.testing.assert_allclose(level, e_perp, rtol=1e-12)
