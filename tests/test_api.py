"""dynamics.api, the notebook surface: a run's arrays and DataFrame say what the physics says."""

from __future__ import annotations

import math

import numpy as np
import pytest

import dynamics
from dynamics import api, measure


def test_cyclotron_run_goes_round_at_the_gyrofrequency_of_the_analysis():
    info = api.analyze("cyclotron", charge=2.0, mass=1.0, field=0.5, speed=1.5)
    run = api.simulate(
        "cyclotron",
        method="boris",
        dt=0.001,
        t_end=2 * info["period"],
        samples=400,
        charge=2.0,
        mass=1.0,
        field=0.5,
        speed=1.5,
    )
    assert run.states.shape == (400, 6) and run.columns[:2] == ("x", "y")
    w = measure.gyrofrequency(run.t, run.states[:, 3:5], xy=run.states[:, :2]).value
    assert w == pytest.approx(info["gyrofrequency"], rel=1e-5)
    _centre, radius = measure.fit_circle(run.states[:, :2]).value
    assert radius == pytest.approx(info["radius"], rel=1e-6)
    assert np.max(np.abs(run.energy_error)) < 1e-12  # Boris keeps |v|
    assert run.reference == "exact" and run.error is not None


def test_hoop_mode1_frequency_matches_the_normal_mode_analysis():
    freqs = api.analyze("hoop", bead_mass=0.5)["mode_frequencies"]
    run = api.simulate("hoop", method="dop853", rtol=1e-10, t_end=20.0, modes=(0.01, 0.0))
    q = run.column("theta1")
    assert measure.crossing_frequency(run.t, q).value == pytest.approx(freqs[0], rel=1e-3)
    assert np.allclose(run.column("theta1"), run.column("theta2"), atol=1e-9)  # in phase, equal


def test_driven_disk_analysis_gives_the_seeds_bearing_force():
    info = api.analyze("disk", disk_mass=1.0, radius=1.0, omega=2.0)
    assert info["axle_force_amplitude"] == pytest.approx(5 / 8 * 1.0 * 1.0 * 2.0**2)
    run = api.simulate("disk", motion="driven", method="exact", t_end=math.pi, samples=3, omega=2.0)
    assert run.column("angle")[-1] == pytest.approx(2 * math.pi)
    assert api.methods("disk", "driven") == ["exact"]


def test_released_disk_keeps_its_angular_momentum():
    run = api.simulate(
        "disk", motion="released", method="rk4", dt=0.01, t_end=5.0, extra_spin=(1e-3, 0, 0)
    )
    L = run.invariants["angular_momentum"]
    assert L.shape == (501, 3)
    assert np.max(np.abs(L - L[0])) < 1e-6 * np.linalg.norm(L[0])


def test_dataframe_has_one_row_per_sample_and_member():
    pytest.importorskip("pandas")
    one = api.simulate("hoop", method="rk4", dt=0.01, t_end=1.0, samples=11, modes=(0.1, 0.0))
    df = one.to_dataframe()
    assert list(df.columns) == ["t", *one.columns, "energy", "energy_error", "error"]
    assert len(df) == 11 and df["t"].iloc[-1] == pytest.approx(1.0)
    beam = api.simulate(
        "cyclotron",
        method="exact",
        t_end=1.0,
        samples=5,
        state=[[1, 0, 0, 0, 1, 0], [2, 0, 0, 0, 2, 0], [3, 0, 0, 0, 3, 0]],
    )
    assert beam.states.shape == (5, 3, 6)
    df = beam.to_dataframe()
    assert len(df) == 15 and sorted(set(df["member"])) == [0, 1, 2]


@pytest.mark.parametrize(
    ("call", "word"),
    [
        (lambda: api.simulate("pendulum", t_end=1.0), "system"),
        (lambda: api.simulate("hoop", t_end=1.0, dt=0.0), "dt"),
        (lambda: api.simulate("hoop", t_end=1.0, method="boris", dt=0.1), "boris"),
        (lambda: api.simulate("hoop", t_end=1.0, dt=0.1, speed=2.0), "speed"),
        (lambda: api.analyze("hoop", mass=1.0), "mass"),
        (lambda: api.analyze("cyclotron", field=-0.0), "field"),
        (lambda: api.parameters("disk", radius=-1.0), "radius"),
    ],
)
def test_bad_arguments_raise_value_error_naming_them(call, word):
    with pytest.raises(ValueError, match=word):
        call()


def test_summary_is_plain_json():
    import json

    run = api.simulate("hoop", method="verlet", dt=0.05, t_end=2.0, samples=5, modes=(0.2, 0.1))
    s = json.loads(json.dumps(run.summary()))
    assert s["method"] == "verlet" and s["steps"] == 40 and "error_vs_reference" in s


def test_fixed_step_samples_fall_at_exactly_the_times_asked():
    """dt = 0.03 does not divide the 0.1 s between samples: the step is shortened to 0.025 s,
    so every sample is at its time, and the central difference of the sampled angle is the rate
    to within its own error, (omega h)^2 / 6 of the amplitude of the rate."""
    run = api.simulate("hoop", method="rk4", dt=0.03, t_end=1.0, samples=11, modes=(0.05, 0.0))
    np.testing.assert_allclose(run.t, np.linspace(0.0, 1.0, 11), rtol=0, atol=1e-12)
    assert run.step == "dt=0.025 s" and run.steps == 40
    rate = np.gradient(run.column("theta1"), run.t)[1:-1]
    omega1 = api.analyze("hoop")["mode_frequencies"][0]
    bound = 1.5 * (omega1 * 0.1) ** 2 / 6 * (omega1 * 0.05)
    assert np.max(np.abs(rate - run.column("omega1")[1:-1])) < bound


def test_a_start_setting_that_cannot_apply_is_refused_naming_it():
    """The disk is driven unless released: an extra spin at release would be silently ignored."""
    with pytest.raises(dynamics.SettingError) as err:
        api.simulate("disk", t_end=1.0, extra_spin=(1e-3, 0.0, 0.0))
    assert err.value.field == "extra_spin" and "released" in str(err.value)
