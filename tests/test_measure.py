"""The estimators of sampled motion (dynamics.measure) against closed forms, and a jump of a
running simulation (Simulation.jump) that keeps its clock."""

from __future__ import annotations

import math

import numpy as np
import pytest

import dynamics
from dynamics import cyclotron as cy
from dynamics import disk as dk
from dynamics import hoop as hp
from dynamics import measure


# --------------------------------------------------------------------------- estimators
@pytest.mark.parametrize("field", [1.0, -2.5])
def test_gyrofrequency_of_the_exact_orbit_is_qb_over_m(field):
    p = cy.CyclotronParams(charge=1.5, mass=2.0, field=field)
    s0 = cy.circular_orbit_state(p, 0.7, (0.3, -0.2), 0.1)
    t = np.linspace(0.0, 10.0, 301)
    states = cy.exact_solution(p, s0, t)
    assert measure.gyrofrequency(t, states[:, 3:5]) == pytest.approx(cy.gyrofrequency(p), rel=1e-12)


def test_gyrofrequency_needs_half_a_radian_of_turn():
    p = cy.CyclotronParams()
    t = np.linspace(0.0, 0.3, 10)  # the velocity turns by 0.3 rad
    states = cy.exact_solution(p, cy.circular_orbit_state(p, 1.0), t)
    assert measure.gyrofrequency(t, states[:, 3:5]) is None


def test_every_member_of_a_beam_turns_at_the_same_rate():
    p = cy.CyclotronParams()
    s0 = np.stack([cy.circular_orbit_state(p, v) for v in (0.2, 1.0, 3.0)])
    t = np.linspace(0.0, 7.0, 200)
    states = cy.exact_solution(p, s0, t)  # (K, N, 6)
    rates = measure.gyrofrequency(t, states[..., 3:5])
    np.testing.assert_allclose(rates, 1.0, rtol=1e-12)


def test_circle_fit_recovers_centre_and_radius():
    ang = np.linspace(0.0, 1.5, 40)  # a fifth of a circle is enough for exact points
    xy = np.stack([2.0 + 0.5 * np.cos(ang), -1.0 + 0.5 * np.sin(ang)], axis=1)
    centre, radius = measure.fit_circle(xy)
    np.testing.assert_allclose(centre, [2.0, -1.0], atol=1e-12)
    assert radius == pytest.approx(0.5, rel=1e-12)
    assert measure.fit_circle(xy[:2]) is None
    assert measure.fit_circle(np.stack([ang, 2 * ang], axis=1)) is None  # on a line


def test_crossing_frequency_of_a_sampled_cosine():
    w = 2.3
    t = np.arange(0.0, 20.0, 1 / 30)
    # linear interpolation between samples places each crossing to O((w dt)^2)
    assert measure.crossing_frequency(t, np.cos(w * t + 0.4)) == pytest.approx(w, rel=1e-4)
    assert measure.crossing_frequency(t[:10], np.cos(w * t[:10])) is None  # below two crossings


@pytest.mark.parametrize("k", [0, 1])
def test_mode_frequencies_of_linear_theory_are_the_normal_mode_frequencies(k):
    p = hp.HoopParams()
    freqs, shapes = hp.normal_modes(p)
    amps = (0.05, 0.0) if k == 0 else (0.0, 0.05)
    t = np.arange(0.0, 30.0, 1 / 60)
    angles = hp.linear_solution(p, hp.mode_state(p, amps), t)[:, :2]
    measured = measure.mode_frequencies(t, angles, shapes)
    assert measured[k] == pytest.approx(freqs[k], rel=1e-4)
    assert measured[1 - k] is None  # the other mode is not excited
    np.testing.assert_allclose(measure.modal_coordinates(angles[0], shapes), amps, atol=1e-15)


def test_bearing_force_from_dl_dt_of_uniform_rotation_is_m_r_omega_squared_over_2():
    p = dk.DiskParams(omega=3.0)
    t = np.arange(0.0, 5.0, 1 / 60)
    angle = p.omega * t
    amp = measure.bearing_force_amplitude(p, t, angle, p.omega)
    # central differences of a rotation: relative error (omega dt)^2 / 6
    assert amp == pytest.approx(dk.axle_force_amplitude(p), rel=(3.0 / 60) ** 2 / 6 * 1.5)
    F = measure.bearing_force(p, t, angle, p.omega)
    np.testing.assert_allclose(F[30], dk.bearing_force_b(p, t[30]), rtol=2e-3, atol=1e-9)


def test_wobble_about_the_intermediate_axis_grows_at_the_linear_rate():
    p = dk.DiskParams(omega=2.0)
    system = dynamics.ReleasedDisk(p, extra_spin=(0.0, 0.0, 1e-4))
    sim = dynamics.Simulation(system, "dop853", rtol=1e-11, reference=None)
    t = np.linspace(0.0, 6.0, 601)
    w = []
    for tk in t:
        sim.advance_to(float(tk))
        w.append(sim.state[0, :3].copy())
    w = np.array(w)
    theory = measure.wobble_growth_rate_theory(system.kernel_params(), w[0])
    assert measure.wobble_growth_rate(t, w) == pytest.approx(theory, rel=1e-2)
    assert measure.wobble_growth_rate(t[:3], w[:3]) is None


# --------------------------------------------------------------------------- jumps
def test_a_kick_keeps_time_and_counts_and_the_run_follows_the_kicked_orbit():
    p = cy.CyclotronParams()
    sim = dynamics.Simulation(dynamics.Cyclotron(p), "boris", dt=0.01, state=cy.circular_orbit_state(p, 1.0))
    sim.advance_to(5.0)
    t, steps, nfev = sim.t, sim.steps, sim.nfev
    kicked, centre, radius = cy.radial_kick(p, sim.state[0], 0.5)
    sim.jump(kicked)
    assert (sim.t, sim.steps, sim.nfev) == (t, steps, nfev)
    s = sim.sample()
    assert s.energy_error[0] == 0.0 and s.error[0] == 0.0  # measured from the kicked state
    sim.advance_to(5.0 + 2 * math.pi)
    s = sim.sample()
    assert sim.steps > steps
    assert abs(s.energy_error[0]) < 1e-13  # Boris keeps |v| after the kick too
    assert s.error[0] < 1e-3  # against the exact orbit from the kicked state
    assert np.hypot(*(s.state[0, :2] - centre[:2])) == pytest.approx(radius, rel=1e-3)


def test_an_exact_run_after_a_jump_is_the_exact_flow_from_the_new_state():
    p = cy.CyclotronParams(field=2.0)
    sim = dynamics.Simulation(dynamics.Cyclotron(p), "exact", state=cy.circular_orbit_state(p, 1.0))
    sim.advance_to(1.3)
    new = cy.radial_kick(p, sim.state[0], -0.4)[0]
    sim.jump(new)
    sim.advance_to(2.0)
    np.testing.assert_allclose(sim.state[0], cy.exact_solution(p, new, 0.7), atol=1e-14)


def test_a_jump_without_an_exact_solution_restarts_the_reference_at_the_jump():
    p = hp.HoopParams()
    sim = dynamics.Simulation(dynamics.Hoop(p), "rk4", dt=0.01, state=hp.mode_state(p, (0.2, 0.1)))
    sim.advance_to(1.0)
    sim.jump(np.array([0.3, -0.2, 0.0, 0.0]))
    assert sim.sample().error[0] == 0.0
    sim.advance_to(3.0)
    assert sim.reference_kind == "reference" and 0.0 < sim.sample().error[0] < 1e-5


def test_a_jump_to_a_state_of_another_shape_is_refused_and_changes_nothing():
    sim = dynamics.Simulation(dynamics.Cyclotron(), "boris", dt=0.01)
    before = sim.state.copy()
    with pytest.raises(ValueError, match="state must have shape"):
        sim.jump(np.zeros((2, 6)))
    with pytest.raises(ValueError, match="state must be finite"):
        sim.jump(np.full(6, np.nan))
    np.testing.assert_array_equal(sim.state, before)
