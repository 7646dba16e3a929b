"""dynamics.api, the notebook surface: a run's arrays and DataFrame say what the physics says."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechviz import dynamics
from mechviz.dynamics import api


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
    w = api.gyrofrequency(run.t, run.states[:, 3:5], xy=run.states[:, :2]).value
    assert w == pytest.approx(info["gyrofrequency"], rel=1e-5)
    _centre, radius = api.fit_circle(run.states[:, :2]).value
    assert radius == pytest.approx(info["radius"], rel=1e-6)
    assert np.max(np.abs(run.energy_error)) < 1e-12  # Boris keeps |v|
    assert run.error_vs == "exact" and run.error is not None


def test_hoop_mode1_frequency_matches_the_normal_mode_analysis():
    freqs = api.analyze("hoop", bead_mass=0.5)["mode_frequencies"]
    run = api.simulate("hoop", method="dop853", rtol=1e-10, t_end=20.0, modes=(0.01, 0.0))
    q = run.column("theta1")
    assert api.crossing_frequency(run.t, q).value == pytest.approx(freqs[0], rel=1e-3)
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
    assert list(df.columns) == [
        "t",
        *one.columns,
        "energy",
        "energy_error",
        "error",
        *one.quantities,
    ]
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


@pytest.mark.parametrize(("dt", "t_end"), [(0.1, 60.0), (0.03, 1.0), (1 / 60, 20.0)])
def test_without_samples_asked_a_fixed_step_is_kept_and_samples_fall_on_steps(dt, t_end):
    """Left to itself the API keeps the step asked for, shortened only to land on t_end (the
    fewest steps that do, rounded up to a whole number per sample), and samples a whole number
    of steps apart: the run is the method at that step."""
    run = api.simulate("hoop", method="rk4", dt=dt, t_end=t_end, modes=(0.05, 0.0))
    h = t_end / run.steps
    per_sample = np.diff(run.t) / h
    k = round(per_sample[0])
    np.testing.assert_allclose(per_sample, k, rtol=0, atol=1e-6)
    fewest = math.ceil(t_end / dt - 1e-9)
    assert fewest <= run.steps < fewest + k and h <= dt * (1 + 1e-12)
    assert 2 <= len(run.t) <= api.SAMPLES and run.t[-1] == t_end


def test_a_start_setting_that_cannot_apply_is_refused_naming_it():
    """The disk is driven unless released: an extra spin at release would be silently ignored."""
    with pytest.raises(dynamics.SettingError) as err:
        api.simulate("disk", t_end=1.0, extra_spin=(1e-3, 0.0, 0.0))
    assert err.value.field == "extra_spin" and "released" in str(err.value)


def test_the_cyclotrons_radial_quantities_are_columns_and_move_on_the_effective_potential():
    """r, p_r, p_phi, V_eff as the CSV has them: p_phi is conserved (the field is uniform about
    the axis), and the transverse energy splits as p_r^2 / 2m + V_eff(r)."""
    run = api.simulate("cyclotron", method="exact", t_end=5.0, samples=101, centre=(0.7, 0.2))
    assert list(run.quantities) == ["r", "p_r", "p_phi", "V_eff"]
    assert "[m]" in run.quantity_labels["r"] and "[J]" in run.quantity_labels["V_eff"]
    p_phi, r = run.column("p_phi"), run.column("r")
    np.testing.assert_allclose(p_phi, p_phi[0], rtol=1e-12)
    np.testing.assert_allclose(r, np.hypot(run.column("x"), run.column("y")), rtol=1e-14)
    m = run.parameters["mass"]
    e_perp = 0.5 * m * (run.column("vx") ** 2 + run.column("vy") ** 2)
    np.testing.assert_allclose(run.column("p_r") ** 2 / (2 * m) + run.column("V_eff"), e_perp)


def test_the_hoops_modal_coordinates_split_the_two_modes():
    """Started on mode 2 alone, q1 stays 0 in linear motion and q2 swings at mode 2's frequency."""
    run = api.simulate("hoop", method="dop853", rtol=1e-11, t_end=10.0, modes=(0.0, 1e-3))
    assert np.max(np.abs(run.column("q1"))) < 1e-6 * np.max(np.abs(run.column("q2")))
    w2 = api.crossing_frequency(run.t, run.column("q2")).value
    assert w2 == pytest.approx(api.analyze("hoop")["mode_frequencies"][1], rel=1e-3)


def test_the_disks_angular_momentum_is_a_column_conserved_once_released_and_turning_driven():
    free = api.simulate("disk", motion="released", method="rk4", dt=0.01, t_end=3.0)
    L = np.stack([free.column(f"L{a}") for a in "xyz"], axis=-1)
    np.testing.assert_allclose(L, free.invariants["angular_momentum"])
    assert np.max(np.abs(L - L[0])) < 1e-8 * np.linalg.norm(L[0])
    driven = api.simulate("disk", t_end=math.pi, samples=5, omega=2.0)  # one turn
    L = np.stack([driven.column(f"L{a}") for a in "xyz"], axis=-1)
    norm = np.linalg.norm(api.analyze("disk", omega=2.0)["angular_momentum"])
    np.testing.assert_allclose(np.linalg.norm(L, axis=1), norm, rtol=1e-12)
    np.testing.assert_allclose(L[-1], L[0], atol=1e-12 * norm)  # back after a whole turn
    assert driven.summary()["bearing_force_b"]  # the CLI's figures of the driven disk, too


def test_an_ensembles_quantities_are_per_member():
    beam = api.simulate(
        "cyclotron",
        method="exact",
        t_end=1.0,
        samples=5,
        state=[[1, 0, 0, 0, 1, 0], [2, 0, 0, 0, 2, 0]],
    )
    assert beam.column("r").shape == (5, 2)
    np.testing.assert_allclose(beam.column("r")[0], [1.0, 2.0])


@pytest.mark.parametrize(
    ("system", "settings", "flags"),
    [
        ("hoop", {"method": "verlet", "dt": 0.05}, ["--method", "verlet", "--dt", "0.05"]),
        ("cyclotron", {"method": "rk4", "dt": 0.1}, ["--method", "rk4", "--dt", "0.1"]),
        ("disk", {"omega": 2.0}, ["--omega", "2"]),
    ],
)
def test_summary_says_what_mechviz_simulate_json_says(system, settings, flags):
    """The same names, signs and values as the command line (energy_drift signed, the error
    under error_vs_exact or error_vs_reference, the reference in words, the work counted)."""
    import json

    from test_cli import mechviz

    # samples 0.5 s apart: a whole number of either step, so neither is shortened
    run = api.simulate(system, t_end=2.0, samples=5, **settings)
    cli = mechviz("simulate", system, "--t-end", "2", "--samples", "5", "--json", *flags)
    assert cli.returncode == 0, cli.stderr
    want = json.loads(cli.stdout)
    got = json.loads(json.dumps(run.summary()))
    assert list(got) == list(want)
    for key, value in want.items():
        if isinstance(value, float):
            assert got[key] == pytest.approx(value, rel=1e-9, abs=1e-15), key
        elif isinstance(value, dict | list):
            assert got[key] == pytest.approx(value, rel=1e-9, abs=1e-15), key
        else:
            assert got[key] == value, key


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: api.simulate("hoop", t_end=-1), "t_end"),
        (lambda: api.simulate("hoop", t_end=float("nan")), "t_end"),
        (lambda: api.simulate("hoop", t_end=1.0, samples=1), "samples"),
        (lambda: api.simulate("hoop", t_end=1.0, reference="tight"), "reference"),
        (lambda: api.simulate("hoop", t_end=1.0, modes=(5.0, 0.0)), "modes"),
        (lambda: api.simulate("hoop", t_end=1.0, state=[1.0, 2.0]), "state"),
        (lambda: api.stability_limit("hoop", "boris"), "method"),
        (lambda: api.stability_limit("disk", "rk4", extra_spin=(0, 0, 1)), "extra_spin"),
        (lambda: api.simulate("hoop", t_end=1.0, samples=3).column("speed"), "name"),
    ],
)
def test_an_error_is_one_line_naming_its_argument(call, field):
    with pytest.raises(dynamics.SettingError) as err:
        call()
    assert err.value.field == field and field in str(err.value) and "\n" not in str(err.value)


def test_stability_limit_of_the_api_is_the_methods_region_over_the_fastest_frequency():
    """Explicit Euler is stable at no step on an oscillation; the symplectic Verlet up to
    omega dt = 2 on the hoop's faster mode; RK4 up to 2 sqrt(2) on the gyration."""
    w = api.analyze("hoop")["mode_frequencies"][1]
    assert api.stability_limit("hoop", "verlet") == pytest.approx(2.0 / w, rel=1e-6)
    assert api.stability_limit("hoop", "euler") == 0.0
    assert api.stability_limit("cyclotron", "rk4") == pytest.approx(2 * math.sqrt(2), rel=1e-3)
    assert api.stability_limit("cyclotron", "exact") is None
    assert api.stability_limit("disk", "rk4", motion="released") > 0


def test_the_released_disks_wobble_grows_at_the_analysis_rate():
    run = api.simulate(
        "disk",
        motion="released",
        method="rk4",
        dt=0.01,
        t_end=30.0,
        samples=1501,
        extra_spin=(1e-3, 0, 0),
    )
    growth = api.wobble_growth_rate(run.t, run.states[:, :3])
    assert growth.value == pytest.approx(api.analyze("disk")["wobble_growth_rate"], rel=1e-3)


def test_a_released_disk_starts_from_a_given_state():
    """``motion="released"`` picks the free body and ``state`` its start: the run begins there,
    keeps the free body's invariants from there, and is not the default release."""
    default = api.simulate("disk", motion="released", t_end=2.0, samples=3, method="dop853")
    w = np.array([0.7, -1.9, 2.6])
    q = np.array([0.9, 0.1, -0.3, 0.2])
    given = np.concatenate([w, q / np.linalg.norm(q)])
    run = api.simulate(
        "disk", motion="released", state=given, t_end=2.0, samples=3, method="dop853"
    )
    np.testing.assert_array_equal(run.states[0], given)
    assert run.summary()["motion"] == "released"
    assert not np.allclose(run.states[-1], default.states[-1])
    assert np.max(np.abs(run.energy_error)) < 1e-8
    L = np.stack([run.column(n) for n in ("Lx", "Ly", "Lz")], axis=-1)  # space frame
    assert np.max(np.abs(L - L[0])) < 1e-8 * np.linalg.norm(L[0])
    with pytest.raises(dynamics.params.SettingError) as err:
        api.simulate("disk", motion="released", extra_spin=(0, 0, 1), state=given, t_end=1.0)
    assert err.value.field == "extra_spin"
