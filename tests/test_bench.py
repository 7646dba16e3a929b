"""The benchmark's fixed parts: stored references, the ratio table, the command line.

Nothing here times anything; the benchmark itself (``mechviz bench``) is not run by the tests.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from dynamics.bench.problems import PROBLEMS, load_references, reference_state
from dynamics.bench.sweeps import Point, Settings, ratio_table, retime_ratios, time_to_reach
from dynamics.simulation import Simulation


@pytest.mark.parametrize("key", ["hoop", "disk"])
def test_stored_reference_is_reproduced_by_a_fresh_dop853_run_at_1e_13(key):
    pb = PROBLEMS[key]
    sim = Simulation(pb.system, "dop853", rtol=1e-13, atol=1e-13, state=pb.y0, reference=None)
    sim.advance_to(pb.t_end)
    assert pb.error(sim.state[0], reference_state(pb)) < 1e-13


@pytest.mark.parametrize("key", ["hoop", "disk"])
def test_stored_reference_agrees_with_scipy_radau_at_1e_12(key):
    entry = load_references()["problems"][key]
    assert entry["radau_1e-12"]["error"] < 1e-11


def test_charge_reference_is_the_exact_helix():
    pb = PROBLEMS["charge"]
    ref = reference_state(pb)
    t = pb.t_end
    assert np.allclose(ref, [2 - np.cos(t), np.sin(t), 0.1 * t, np.sin(t), np.cos(t), 0.1],
                       atol=1e-12)  # fmt: skip


def _pt(method, error, seconds, problem="hoop"):
    return Point(problem, method, False, 0.1, None, 10, 40, error, 0.0, seconds, seconds, 0.0,
                 5, 1, "ok")  # fmt: skip


def test_time_to_reach_is_the_fastest_point_at_or_below_the_target():
    pts = [_pt("rk4", 1e-2, 1.0), _pt("rk4", 5e-4, 3.0), _pt("rk4", 1e-7, 2.0)]
    assert time_to_reach(pts, 1e-3).seconds == 2.0
    assert time_to_reach(pts, 1e-6).seconds == 2.0
    assert time_to_reach(pts, 1e-9) is None


def test_ratio_is_fastest_scipy_over_fastest_ours_and_flags_a_lower_bound():
    pts = [
        _pt("rk4", 1e-4, 0.001), _pt("dop853", 1e-4, 0.002),
        _pt("odeint", 1e-4, 0.05), _pt("scipy-dop853", 1e-4, 0.2),
        _pt("rk4", 1e-7, 0.01), _pt("odeint", 1e-5, 0.5),
    ]  # fmt: skip
    table = ratio_table(pts, {"rk4", "dop853"}, {"odeint", "scipy-dop853"})["hoop"]
    assert table["1e-03"]["ratio"] == pytest.approx(50.0)
    assert table["1e-03"]["scipy"]["method"] == "odeint"
    assert not table["1e-03"]["ratio_is_lower_bound"]
    # No scipy point reached 1e-6: the ratio uses the slowest scipy call made, as a bound.
    assert table["1e-06"]["ratio_is_lower_bound"]
    assert table["1e-06"]["ratio"] == pytest.approx(0.5 / 0.01)


def test_head_to_head_retiming_runs_the_chosen_points_and_keeps_the_sweep_figures():
    # Real runs of the hoop (short: rk4 at 640 steps, odeint at 1e-4); the assertions are about
    # bookkeeping, not about which is faster.
    pb = PROBLEMS["hoop"]
    ours = Point("hoop", "rk4", False, pb.t_end / 640, None, 640, 2560, 1e-4, 0.0, 1e-3, 1e-3,
                 0.0, 5, 1, "ok")  # fmt: skip
    theirs = Point("hoop", "odeint", True, None, 1e-4, 0, 0, 1e-4, 0.0, 2e-2, 2e-2, 0.0, 5, 1, "ok")
    table = ratio_table([ours, theirs], {"rk4"}, {"odeint"})
    assert table["hoop"]["1e-03"]["ratio"] == pytest.approx(20.0)
    retime_ratios(table, [ours, theirs], PROBLEMS, Settings(head_to_head_rounds=2, min_sample=0))
    e = table["hoop"]["1e-03"]
    assert e["sweep_ratio"] == pytest.approx(20.0)
    assert e["sweep"]["ours"] == {"method": "rk4", "seconds": 1e-3}
    timed = e["head_to_head"]["seconds"]
    assert set(timed) == {"ours:rk4", "scipy:odeint"} and all(t > 0 for t in timed.values())
    assert e["ratio"] == pytest.approx(timed["scipy:odeint"] / timed["ours:rk4"])
    assert e["ours"]["seconds"] == timed["ours:rk4"]


def test_bench_command_is_registered_with_its_flags():
    from viz.cli import build_parser

    args = build_parser().parse_args(["bench", "--quick", "--json", "--out", "somewhere"])
    assert args.quick and args.json and args.out == "somewhere"
    # The committed charts change only through `make bench-docs`, never by default.
    default = Path(build_parser().parse_args(["bench"]).out).resolve()
    assert not default.is_relative_to(Path(__file__).resolve().parents[1])
