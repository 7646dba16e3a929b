"""The atlas's maps beyond the boundary and the start plane, computed serially (the distributed
run is tested in test_atlas.py): the chaos map's other sections of the hoop's starts, and the
accuracy map, whose every column converges at its method's order.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("distributed")
pytest.importorskip("xarray")

from mechviz.dynamics import get_method, hoop
from mechviz.dynamics.atlas.driver import compute_serial
from mechviz.dynamics.atlas.grid import AtlasSpec, Axis
from mechviz.viz.cli import main

OMEGA1, OMEGA2 = (float(w) for w in hoop.normal_modes(hoop.HoopParams())[0])


def chaos(y: Axis, x: Axis, duration: float = 60.0):
    spec = AtlasSpec("chaos", "hoop", ("rk4",), y, x, duration=duration, chunk=(y.n, x.n))
    return compute_serial(spec)["lyapunov"].values[0]


def test_sections_meet_the_plane_at_rest_where_they_share_starts():
    """The hoop's section (theta1, theta1') at theta1' = 0 and the bead's (theta2, theta2') at
    theta2' = 0 are starts of the plane at rest: the same runs, the same bits."""
    angles = Axis("theta1", -2.5, 2.5, 5)
    rest = chaos(Axis("theta2", -2.5, 2.5, 5), angles, 10.0)
    hoop_section = chaos(Axis("omega1", -2.0, 2.0, 3), angles, 10.0)
    assert hoop_section[1].tobytes() == rest[2].tobytes()  # theta2 = 0 is the middle row
    bead_section = chaos(Axis("omega2", -2.0, 2.0, 3), Axis("theta2", -2.5, 2.5, 5), 10.0)
    assert bead_section[1].tobytes() == rest[:, 2].copy().tobytes()  # theta1 = 0: the middle


def test_hoop_section_is_regular_near_rest_and_chaotic_past_the_pendulums_separatrix():
    """Starts (theta1, theta1') with the bead straight below: small swings are regular; a
    rate beyond 2 omega_1 (the top of the mode-1 pendulum's separatrix) sends the hoop over
    the top with the bead thrown about, a chaotic motion."""
    top = 2.0 * OMEGA1
    lyap = chaos(Axis("omega1", -1.5 * top, 1.5 * top, 9), Axis("theta1", -3.0, 3.0, 9))
    rates = np.linspace(-1.5 * top, 1.5 * top, 9)[:, None]
    angles = np.linspace(-3.0, 3.0, 9)[None, :]
    near = (abs(rates) <= 0.2 * top) & (abs(angles) <= 0.8)
    over = np.broadcast_to(abs(rates) > 1.2 * top, lyap.shape)
    assert near.sum() >= 3 and over.sum() >= 18
    assert lyap[near].max() < 0.1
    assert np.median(lyap[over]) > 0.4


@pytest.mark.slow
def test_cli_draws_a_section_with_its_axes_labelled(tmp_path):
    out = tmp_path / "bead"
    args = ["atlas", "chaos", "--section", "theta2", "--theta2=-3:3:4", "--omega2=-5:5:3"]
    assert main([*args, "--duration", "2", "--out", str(out), "--no-progress"]) == 0
    svg = (out / "chaos.svg").read_text()
    assert "bead rate theta2'" in svg and "theta1 = theta1' = 0" in svg


def slopes(ds, k: int, name: str) -> np.ndarray:
    """Per amplitude column: the slope of log(error) against log(step or tolerance)."""
    y = np.log(ds[name].values)
    return np.array([np.polyfit(y, np.log(col), 1)[0] for col in ds["error"].values[k].T])


@pytest.mark.parametrize(
    "methods, finest",
    [(("euler", "midpoint", "verlet"), 0.0005), (("rk4", "yoshida4"), 0.01)],
)
def test_accuracy_map_converges_at_each_methods_order_in_every_column(methods, finest):
    """The hoop (a tight DOP853 run is the reference), amplitudes from small to large swings,
    steps from ``finest / omega_2`` over a factor 16: every column's error falls as dt^p."""
    spec = AtlasSpec(
        "accuracy",
        "hoop",
        methods,
        Axis("dt", finest / OMEGA2, 16 * finest / OMEGA2, 5, "log"),
        Axis("amplitude", 0.05, 0.8, 4),
        duration=5.0,
        chunk=(5, 4),
    )
    ds = compute_serial(spec)
    for k, name in enumerate(methods):
        order = get_method(name).order
        assert np.abs(slopes(ds, k, "dt") - order).max() < 0.2, (name, slopes(ds, k, "dt"))


def test_accuracy_map_against_the_exact_cyclotron_orbit():
    """The charge's exact orbit is the reference: Boris converges at order 2, RK4 at 4, at
    every speed (the relative error of a linear system does not depend on the amplitude)."""
    spec = AtlasSpec(
        "accuracy",
        "cyclotron",
        ("boris", "rk4"),
        Axis("dt", 0.01, 0.16, 5, "log"),
        Axis("amplitude", 0.1, 2.0, 3),
        duration=5.0,
        chunk=(5, 3),
    )
    ds = compute_serial(spec)
    for k, order in enumerate((2, 4)):
        s = slopes(ds, k, "dt")
        assert np.abs(s - order).max() < 0.1, s
        assert np.ptp(np.log10(ds["error"].values[k]), axis=1).max() < 0.01


def test_adaptive_error_follows_the_tolerance():
    """DOP853's error after the run is proportional to rtol (slope 1 within a quarter) over
    five decades, at every amplitude."""
    spec = AtlasSpec(
        "accuracy",
        "hoop",
        ("dop853",),
        Axis("rtol", 1e-10, 1e-5, 6, "log"),
        Axis("amplitude", 0.1, 1.0, 4),
        duration=5.0,
        chunk=(6, 4),
    )
    ds = compute_serial(spec)
    assert np.abs(slopes(ds, 0, "rtol") - 1.0).max() < 0.25


@pytest.mark.parametrize(
    "args, flag",
    [
        (["stability", "--section", "theta1"], "--section"),
        (["chaos", "--section", "theta1", "--theta2=-1:1:3"], "--theta2"),
        (["chaos", "--omega1=-1:1:3"], "--omega1"),
        (["accuracy", "--theta1=-1:1:3"], "--theta1"),
    ],
)
def test_an_axis_the_map_does_not_have_is_refused_in_one_line(tmp_path, capsys, args, flag):
    assert main(["atlas", *args, "--out", str(tmp_path / "a"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"mechviz: error: {flag}"), err
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize(
    ("n", "rows", "workers", "expected"),
    [
        (64, 5.4, 2, 4),
        (64, 40, 2, 32),
        (32, 0.5, 2, 1),
        (48, 7, 2, 6),
        (48, 7, 4, 6),
        (48, 7, 16, 3),
    ],
)
def test_bench_chunks_are_equal_and_shared_evenly_by_the_workers(n, rows, workers, expected):
    """The atlas bench's chunks: equal, a whole number per worker, the largest not above the
    rows asked for (a worker left idle at the end would count as scheduling overhead)."""
    from mechviz.dynamics.atlas.bench import balanced_rows

    got = balanced_rows(n, rows, workers)
    assert got == expected
    assert n % got == 0 and (n // got) % workers == 0 and (got <= rows or got == 1)
