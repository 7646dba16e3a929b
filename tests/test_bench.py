"""The benchmark's fixed parts: stored references, the ratio table, the command line.

Nothing here times anything; the benchmark itself (``mechviz bench``) is not run by the tests.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest

from mechviz.bench.problems import PROBLEMS, load_references, reference_state
from mechviz.bench.sweeps import (
    TARGETS,
    Point,
    Settings,
    ratio_table,
    retime_ratios,
    time_to_reach,
)
from mechviz.dynamics.simulation import Simulation


@pytest.mark.parametrize("key", ["hoop", "disk"])
def test_stored_reference_is_within_reach_of_a_fresh_dop853_run_at_1e_13(key):
    """DOP853 at 1e-13 lands about 1e-12 from the true solution: close, but not close enough to
    be the reference for a 1e-12 target."""
    pb = PROBLEMS[key]
    sim = Simulation(pb.system, "dop853", rtol=1e-13, atol=1e-13, state=pb.y0, reference=None)
    sim.advance_to(pb.t_end)
    assert pb.error(sim.state[0], reference_state(pb)) < 1e-11


@pytest.mark.parametrize("key", ["hoop", "disk"])
def test_stored_reference_agrees_with_a_second_method_100x_below_the_tightest_target(key):
    """The long-double reference and mpmath's 25-digit Taylor series agree far below 1e-12 / 100;
    scipy's Radau at 1e-12 agrees to its own accuracy."""
    entry = load_references()["problems"][key]
    assert entry["mpmath_25_digits"]["error"] < 1e-14
    assert entry["radau_1e-12"]["error"] < 1e-11


def test_every_sweep_reaches_below_the_tightest_target():
    assert all(pb.floor < min(TARGETS) for pb in PROBLEMS.values())
    assert min(Settings().tolerances) < 1e-13 and min(Settings.for_mode(True).tolerances) < 1e-13


def test_charge_reference_is_the_exact_helix():
    pb = PROBLEMS["charge"]
    ref = reference_state(pb)
    t = pb.t_end
    assert np.allclose(
        ref, [2 - np.cos(t), np.sin(t), 0.1 * t, np.sin(t), np.cos(t), 0.1], atol=1e-12
    )


def _pt(method, error, seconds, problem="hoop"):
    return Point(
        problem, method, False, 0.1, None, 10, 40, error, 0.0, seconds, seconds, 0.0, 5, 1, "ok"
    )


def test_time_to_reach_is_the_fastest_point_at_or_below_the_target():
    pts = [_pt("rk4", 1e-2, 1.0), _pt("rk4", 5e-4, 3.0), _pt("rk4", 1e-7, 2.0)]
    assert time_to_reach(pts, 1e-3).seconds == 2.0
    assert time_to_reach(pts, 1e-6).seconds == 2.0
    assert time_to_reach(pts, 1e-9) is None


def test_ratio_is_fastest_scipy_over_fastest_ours_and_flags_a_lower_bound():
    pts = [
        _pt("rk4", 1e-4, 0.001),
        _pt("dop853", 1e-4, 0.002),
        _pt("odeint", 1e-4, 0.05),
        _pt("scipy-dop853", 1e-4, 0.2),
        _pt("rk4", 1e-7, 0.01),
        _pt("odeint", 1e-5, 0.5),
    ]
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
    ours = Point(
        "hoop",
        "rk4",
        False,
        pb.t_end / 640,
        None,
        640,
        2560,
        1e-4,
        0.0,
        1e-3,
        1e-3,
        0.0,
        5,
        1,
        "ok",
    )
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
    from mechviz.viz.cli import build_parser

    args = build_parser().parse_args(["bench", "--quick", "--json", "--peers", "--out", "x"])
    assert args.quick and args.json and args.peers and args.out == "x"
    # The committed charts change only through `make bench-docs`, never by default.
    default = Path(build_parser().parse_args(["bench"]).out).resolve()
    assert not default.is_relative_to(Path(__file__).resolve().parents[1])


def test_targets_name_each_miss_with_its_figure():
    from mechviz.bench.run import _targets

    ratios = {"hoop": {"1e-09": {"ratio": 80.0}, "1e-12": {"ratio": 30.0}}}
    peers = {"heyoka": {"hoop": {"1e-09": {"ratio": 1.4}, "1e-12": {"ratio": 0.8}}}}
    t = _targets(ratios, None, peers)
    assert t["ours_50x_faster_than_scipy"] == {"hoop 1e-09": True, "hoop 1e-12": False}
    assert t["ours_at_least_as_fast_as_every_peer"]["heyoka hoop 1e-12"] is False
    assert t["missed"] == [
        "hoop 1e-12: scipy / ours = 30.0 < 50",
        "heyoka hoop 1e-12: heyoka / ours = 0.80 < 1",
    ]
    # the first answer: Simulation(..., "taylor") in a fresh process against odeint
    first = {
        "taylor": {"median_s": 0.6},
        "dop853": {"median_s": 0.35},
        "scipy-odeint": {"median_s": 0.4},
    }
    t = _targets(ratios, None, peers, first)
    assert t["first_answer_at_least_as_fast_as_odeint"] is False
    assert t["missed"][-1] == "first answer (taylor): ours / odeint = 0.6 s / 0.4 s = 1.50 > 1"
    first["taylor"]["median_s"] = 0.15
    assert _targets(ratios, None, peers, first)["first_answer_at_least_as_fast_as_odeint"]
    # a form generated from the equations that costs more than 5 % over the hand-written one
    form = {"ratio": 1.08, "ns_per_step_generated": 108.0, "ns_per_step_hand": 100.0}
    generated = {"hoop": {"taylor series": form, "rhs": {**form, "ratio": 1.01}, "rk4 step": form}}
    generated["hoop"]["rk4 step"] = {**form, "ratio": 0.97}
    t = _targets(ratios, None, peers, generated=generated)
    assert t["generated_forms_within_5pct_of_hand_written"] is False
    assert t["missed"][-1] == (
        "generated taylor series on hoop: 1.080x the hand-written per step (goal <= 1.05)"
    )
    generated["hoop"]["taylor series"] = {**form, "ratio": 1.04}
    t = _targets(ratios, None, peers, generated=generated)
    assert t["generated_forms_within_5pct_of_hand_written"] is True


ROOT = Path(__file__).resolve().parents[1]


def _committed_result() -> dict:
    import json

    return json.loads((ROOT / "docs" / "bench" / "results.json").read_text())


def test_the_speed_page_and_tables_quote_the_committed_run():
    """Every figure of a run on the site's speed page and in docs/bench/tables.md is rendered
    from docs/bench/results.json (`make bench-docs`): hand edits or a stale render fail here."""
    from mechviz.bench import docs, report

    result = _committed_result()
    readme = (ROOT / "docs" / "speed.md").read_text()
    assert docs.splice(readme, result) == readme
    assert (ROOT / "docs" / "bench" / "tables.md").read_text() == report.markdown(result)
    # the page says which run it quotes, and the targets it reports are that run's
    assert result["date"] in readme and result["command"] in readme


def test_rendering_fills_only_the_blocks_and_twice_changes_nothing():
    from mechviz.bench import docs

    result = _committed_result()
    blocks = "".join(
        f"<!-- bench:{n} -->\nold {n}\n<!-- /bench:{n} -->\ntext between\n" for n in docs.BLOCKS
    )
    text = "# Title\n\nprose before\n" + blocks + "prose after\n"
    once = docs.splice(text, result)
    assert docs.splice(once, result) == once
    assert once.startswith("# Title\n\nprose before\n") and once.endswith("prose after\n")
    assert once.count("text between\n") == len(docs.BLOCKS) and "old " not in once
    for name, render in docs.BLOCKS.items():
        assert f"<!-- bench:{name} -->\n{render(result).rstrip()}\n<!-- /bench:{name} -->" in once


@pytest.mark.parametrize(
    "damage",
    [
        lambda t: t.replace("<!-- /bench:peers -->", ""),  # a block not closed
        lambda t: t.replace("<!-- bench:steps -->\n<!-- /bench:steps -->", ""),  # one missing
        lambda t: t + "<!-- bench:steps -->\n<!-- /bench:steps -->\n",  # one twice
        lambda t: t + "<!-- bench:speed -->\n<!-- /bench:speed -->\n",  # one unknown
    ],
)
def test_a_readme_with_broken_blocks_is_refused_and_left_as_it_was(tmp_path, capsys, damage):
    import shutil

    from mechviz.bench import docs

    text = "".join(f"<!-- bench:{n} -->\n<!-- /bench:{n} -->\n" for n in docs.BLOCKS)
    readme = tmp_path / "README.md"
    readme.write_text(damage(text))
    out = tmp_path / "bench"
    out.mkdir()
    shutil.copy(ROOT / "docs" / "bench" / "results.json", out / "results.json")
    assert docs.main(["--check", str(readme)]) == 2
    assert docs.main([str(out), str(readme)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 2 and all(line.startswith("error: README.md: ") for line in err)
    assert readme.read_text() == damage(text)
    assert sorted(p.name for p in out.iterdir()) == ["results.json"]  # no tables.md written


def test_a_peer_that_cannot_be_imported_is_skipped_with_the_reason(monkeypatch):
    import builtins

    from mechviz.bench import peers

    real = builtins.__import__

    def fake(name, *args, **kwargs):
        if name == "heyoka":
            raise ImportError("No module named 'heyoka'")
        return real(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", fake)
    why = peers.available()["heyoka"]
    assert why is not None and "heyoka" in why and "ImportError" in why


@pytest.mark.parametrize("peer", ["heyoka", "cyrk-dop853", "cyrk-py-dop853"])
@pytest.mark.parametrize("key", ["charge", "hoop", "disk"])
def test_each_peer_solves_the_same_problem(peer, key):
    """A peer integrates the same equations from the same state: at 1e-10 it lands near the
    reference (skipped when the peer is not installed)."""
    from mechviz.bench import peers

    why = peers.available()[peers.package_of(peer)]
    if why is not None:
        pytest.skip(why)
    pb = PROBLEMS[key]
    run = peers.prepare(peer, pb, 1e-10)
    assert pb.error(run.run(), reference_state(pb)) < 1e-6
    assert run.nfev() > 0


def test_an_adaptive_sweep_stops_where_the_error_stops_falling():
    from mechviz.bench.sweeps import _stalled

    def pt(tol, err):
        return Point("hoop", "odeint", True, None, tol, 10, 40, err, 0.0, 1.0, 1.0, 0.0, 5, 1, "ok")

    jumpy = [pt(10.0 ** (-k / 4), e) for k, e in enumerate([1e-3, 2e-4, 3e-4, 3e-4, 2.5e-4, 1e-5])]
    assert not _stalled(jumpy)  # flat for a decade, then falling again: not a floor
    flat = [pt(10.0 ** (-k / 4), 1e-7 if k > 2 else 1e-3) for k in range(12)]
    assert _stalled(flat)  # two decades below the best without beating it


def test_the_bench_silences_only_scipys_warnings_about_swept_tolerances():
    import warnings

    from scipy.integrate import ODEintWarning, solve_ivp

    from mechviz.bench.run import _quiet_scipy

    def sweep_point():
        solve_ivp(lambda t, y: -y, (0.0, 1.0), [1.0], rtol=1e-16, atol=1e-16)
        warnings.warn("Excess accuracy requested", ODEintWarning, stacklevel=1)
        warnings.warn("something else", UserWarning, stacklevel=1)

    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        _quiet_scipy(sweep_point)()
    assert [str(w.message) for w in seen] == ["something else"]
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        sweep_point()  # without the filter all three are seen: the test can fail
    assert len(seen) == 3


def test_no_cached_kernel_lives_in_the_atlas_and_only_its_edits_keep_the_cache(tmp_path):
    """The compiled-code cache is keyed on every dynamics source but the atlas's
    (``mechviz.dynamics._jit.UNCACHED``): that holds only while no cached function is defined there. The
    benchmark lives outside the package (``mechviz.bench``) and defines none either."""
    import shutil

    from mechviz.dynamics import _jit

    for folder in (ROOT / "dynamics" / "atlas", ROOT / "bench"):
        assert any(folder.rglob("*.py")), folder
        for path in folder.rglob("*.py"):
            assert "cache=True" not in path.read_text(), path
    tree = tmp_path / "dynamics"
    shutil.copytree(ROOT / "dynamics", tree, ignore=shutil.ignore_patterns("__pycache__"))
    key = _jit._source_hash(tree)
    assert key == _jit._source_hash(ROOT / "dynamics")
    with open(tree / "atlas" / "maps.py", "a") as f:
        f.write("# an edit to the atlas\n")
    assert _jit._source_hash(tree) == key
    with open(tree / "integrators" / "taylor.py", "a") as f:
        f.write("# an edit to an integrator\n")
    assert _jit._source_hash(tree) != key


def test_a_quick_runs_long_call_is_its_own_single_sample_and_short_calls_are_repeated():
    from mechviz.bench.sweeps import Settings
    from mechviz.bench.timing import time_calls

    quick = Settings.for_mode(True)
    calls = []

    def timed(seconds):
        def make():
            return lambda: (calls.append(seconds), time.sleep(seconds))

        return make

    long_call = 1.5 * quick.one_sample_from
    t = time_calls(
        timed(long_call),
        repeats=quick.repeats,
        min_sample=quick.min_sample,
        one_sample_from=quick.one_sample_from,
    )
    assert calls == [long_call] and t.samples == 1 and t.calls_per_sample == 1
    assert t.median == t.first_call >= long_call
    calls.clear()
    # a first call known to be short (given, as the sweeps give it: a busy machine can stretch a
    # 2 ms sleep past one_sample_from) is repeated into full samples
    short = quick.min_sample
    t = time_calls(
        timed(short),
        repeats=quick.repeats,
        min_sample=quick.min_sample,
        first_call=short,
        one_sample_from=quick.one_sample_from,
    )
    assert t.samples == quick.repeats and len(calls) >= quick.repeats
    # a full run repeats every call
    assert Settings.for_mode(False).one_sample_from == float("inf")


@pytest.mark.slow
def test_the_compile_cache_is_filled_by_worker_processes_once_per_checkout(tmp_path, monkeypatch):
    import numba

    from mechviz.viz import warm

    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))  # where the stamp goes
    monkeypatch.setattr(
        warm, "every_method", lambda systems: [("hoop", "verlet"), ("hoop", "taylor")]
    )
    meanwhile = []
    _, processes = warm.fill_cache_in_parallel(2, meanwhile=lambda: meanwhile.append(1))
    assert processes == 2 and meanwhile == [1] and len(list(tmp_path.glob("filled-*"))) == 1
    # filled: no process is started again, and this process's own compilation still runs
    _, processes = warm.fill_cache_in_parallel(2, meanwhile=lambda: meanwhile.append(1))
    assert processes == 0 and meanwhile == [1, 1]


def test_a_miss_with_no_scipy_answer_is_summarised_and_the_tables_are_made():
    """An accuracy scipy never reached has a lower-bound ratio and no scipy entry; if that bound
    is below the target the run counts a miss, and the summary says so instead of failing."""
    import copy

    from mechviz.bench import report
    from mechviz.bench.report import SCIPY_FACTOR

    result = copy.deepcopy(_committed_result())
    key = next(iter(result["ratios"]))
    acc = next(iter(result["ratios"][key]))
    entry = result["ratios"][key][acc]
    entry.pop("scipy", None)
    entry.update(ratio=SCIPY_FACTOR / 2, ratio_is_lower_bound=True)
    result["targets"][f"ours_{SCIPY_FACTOR:g}x_faster_than_scipy"][f"{key} {acc}"] = False
    text = report.targets_summary(result)
    assert f"{key} at {acc} (>={SCIPY_FACTOR / 2:.0f}x" in text
    assert "no scipy option reaching it" in text
    assert "## Targets" in report.markdown(result)


def test_the_first_answer_and_construction_targets_are_flagged_with_their_figures():
    from mechviz.bench.first_answer import JUDGED, construction_missed, first_answer_missed

    fa = {JUDGED: {"median_s": 0.6}, "scipy-odeint": {"median_s": 0.4}}
    assert first_answer_missed(fa) == [
        "first answer (taylor): ours / odeint = 0.6 s / 0.4 s = 1.50 > 1"
    ]
    fa[JUDGED]["median_s"] = 0.3
    assert first_answer_missed(fa) == []
    costs = {"hoop": {"new_simulation": 2.8, "new_solver": 0.7, "restart": 1.0}}
    assert construction_missed(costs) == ["construction: hoop Simulation (taylor) 2.8 us > 1 us"]
