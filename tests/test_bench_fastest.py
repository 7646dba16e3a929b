"""The peers-in-their-fastest-form harness computes what it says (nothing here is timed).

Each peer in its fastest form answers the benchmark problem to the accuracy its tolerance
promises against the same reference as ours; the random cases are reproducible from their seed;
a pick meets its target; the report lists every losing case.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechviz.bench import fast_peers as fp
from mechviz.bench import fastest, fastest_report, untuned
from mechviz.bench.peer_equations import heyoka_pars
from mechviz.bench.problems import PROBLEMS, Problem, reference_state
from mechviz.dynamics.simulation import Simulation

HAVE = fp.available()


def _short(key: str, t_end: float) -> Problem:
    pb = PROBLEMS[key]
    return Problem(pb.key, pb.title, pb.system, pb.state0, t_end, (), 0, pb.floor, pb.period, False)


def _dop853_reference(pb: Problem) -> np.ndarray:
    sim = Simulation(pb.system, "dop853", rtol=1e-14, atol=1e-14, state=pb.y0, reference=None)
    sim.advance_to(pb.t_end)
    return sim.state[0].copy()


SOLVERS = ["odeint"]
if HAVE["heyoka"] is None:
    SOLVERS += ["heyoka", "heyoka fast_math"]
if HAVE["CyRK"] is None:
    SOLVERS += [f"cyrk {m}" for m in fp.CYRK_METHODS]


def _solve(name: str, pb: Problem, tol: float) -> np.ndarray:
    sid, p = pb.system.sys_id, pb.system.kernel_params()
    if name.startswith("heyoka"):
        pars = heyoka_pars(sid, p)
        s = fp.heyoka_solver(sid, len(pb.y0), len(pars), tol, name.endswith("fast_math"))
        return s.solve(pb.y0, pars, pb.t_end)[0]
    if name.startswith("cyrk"):
        return fp.CyrkSolver(sid, name.split()[1]).solve(pb.y0, p, pb.t_end, tol)[0]
    return fp.odeint_solve(sid, pb.y0, p, pb.t_end, tol)[0]


@pytest.mark.parametrize("name", SOLVERS)
@pytest.mark.parametrize("key", ["charge", "hoop", "disk"])
def test_each_peer_in_its_fastest_form_solves_our_equations(name, key):
    """Same equations, same parameters: over a short span each peer at 1e-10 lands within 1e-6 of
    our DOP853 at 1e-14 (a peer solving a different equation would be off by O(1) there), and a
    looser tolerance lands farther: the error follows the tolerance."""
    pb = _short(key, 3.0)
    ref = _dop853_reference(pb)
    tight = pb.error(_solve(name, pb, 1e-10), ref)
    loose = pb.error(_solve(name, pb, 1e-4), ref)
    assert tight < 1e-6
    assert loose > tight


@pytest.mark.parametrize("kind", ["hoop", "disk"])
def test_heyoka_with_parameters_reproduces_the_stored_reference(kind):
    """heyoka with runtime parameters (one compiled integrator per system) solves the stored
    benchmark problem to 1e-9 at tol 1e-12: the parameter mapping is right."""
    if HAVE["heyoka"] is not None:
        pytest.skip(HAVE["heyoka"])
    pb = PROBLEMS[kind]
    assert pb.error(_solve("heyoka", pb, 1e-12), reference_state(pb)) < 1e-9


def test_random_cases_are_reproducible_from_the_seed_and_differ_between_seeds():
    a, b, c = untuned.draw(5, 6), untuned.draw(5, 6), untuned.draw(6, 6)
    assert list(a) == list(b)
    for key in a:
        assert a[key].state0 == b[key].state0
        assert a[key].t_end == b[key].t_end
        assert np.array_equal(a[key].system.kernel_params(), b[key].system.kernel_params())
    assert any(a[k].state0 != c[k].state0 for k in a)
    kinds = [k.rsplit("-", 1)[1] for k in a]
    assert kinds.count("charge") == kinds.count("hoop") == kinds.count("disk") == 2


def test_a_random_charge_is_measured_against_its_exact_helix():
    pb = next(p for k, p in untuned.draw(3, 3).items() if k.endswith("charge"))
    ref = untuned.reference(pb)
    assert ref.kind == "exact" and ref.resolves == 0.0
    ours = Simulation(pb.system, "taylor", rtol=1e-12, atol=1e-12, state=pb.y0, reference=None)
    ours.advance_to(pb.t_end)
    assert pb.error(ours.state[0], ref.state) < 1e-8


def test_every_pick_meets_its_target_and_the_ratios_are_peer_over_ours():
    """On a short charge (exact reference) each contender's pick, solved again, lands within
    its target; the ratios are the fastest peer's time over our fastest (kept or fresh)."""
    pb = _short("charge", 20.0)
    pb = Problem(pb.key, pb.title, pb.system, pb.state0, pb.t_end, (), 0, 1e-13, 1.0, True)
    ref = untuned.Reference(np.asarray(pb.system.exact(pb.y0, pb.t_end)), "exact", 0.0)
    grid = tuple(10.0**-k for k in range(3, 12, 2))
    out = fastest.measure_case(
        pb, ref, HAVE, rounds=1, min_sample=0.0, targets=(1e-4, 1e-8), grid=grid
    )
    cs = {c.name: c for c in fastest.contenders(pb, HAVE)}
    for target, row in out["targets"].items():
        for e in row["fastest"].values():
            assert e["error"] <= float(target)
            y = cs[e["who"]].make(e["tol"])()
            assert pb.error(np.asarray(y), ref.state) <= float(target)
        f = row["fastest"]
        for name, r in row["ratios"].items():
            peer, form = name.split("/")
            if peer in f and f"ours-{form}" in f:
                assert r == pytest.approx(f[peer]["seconds"] / f[f"ours-{form}"]["seconds"])


def _fake(ratios_by_case: dict) -> dict:
    cases = {}
    for key, rows in ratios_by_case.items():
        targets = {}
        for target, ratios in rows.items():
            fast = {
                "ours-kept": {"who": "taylor kept", "tol": 1e-9, "error": 1e-10, "seconds": 1e-4},
                "ours-fresh": {"who": "taylor fresh", "tol": 1e-9, "error": 1e-10, "seconds": 2e-4},
            }
            for name, r in ratios.items():
                peer, form = name.split("/")
                if r is not None:
                    secs = r * fast[f"ours-{form}"]["seconds"]
                    fast[peer] = {"who": peer, "tol": 1e-9, "error": 1e-10, "seconds": secs}
            targets[target] = {"fastest": fast, "ratios": ratios}
        cases[key] = {"targets": targets}
    result = {"seed": 1, "n_random": 2, "rounds": 1, "cases": cases}
    result["losses"] = fastest.losses(result)
    result["distribution"] = fastest.distribution(result)
    return result


def test_the_report_lists_every_losing_case_with_its_figure():
    result = _fake(
        {
            "hoop": {"1e-09": {"heyoka/kept": 0.8, "heyoka/fresh": 0.4, "cyrk/kept": 1.3}},
            "random-00-disk": {"1e-06": {"heyoka/kept": 1.1, "cyrk/kept": 0.95}},
            "random-01-hoop": {"1e-06": {"heyoka/kept": None, "cyrk/kept": 2.0}},
        }
    )
    lines = fastest_report.loss_lines(result)
    assert len(lines) == 3
    assert any("hoop 1e-09 kept: heyoka / ours = 0.80" in line for line in lines)
    assert any("hoop 1e-09 fresh: heyoka / ours = 0.40" in line for line in lines)
    assert any("random-00-disk 1e-06 kept: cyrk / ours = 0.95" in line for line in lines)
    md = fastest_report.markdown(result)
    assert all(line in md for line in lines)
    d = result["distribution"]["1e-06"]
    assert d["cyrk/kept"]["below_1"] == 1 and d["cyrk/kept"]["n"] == 2
    assert d["heyoka/kept"]["peer_not_reached"] == 1
    assert d["cyrk/kept"]["min"] == pytest.approx(0.95)


def test_a_loss_fails_the_bench_and_is_named_in_its_misses():
    from mechviz.bench.run import _targets

    result = _fake({"disk": {"1e-03": {"heyoka/kept": 0.5, "heyoka/fresh": 1.5}}})
    t = _targets({}, None, {}, None, result)
    assert len(t["missed"]) == 1 and "disk 1e-03 kept: heyoka / ours = 0.50" in t["missed"][0]
    assert t["all_peers"] is False
    won = _targets({}, None, {}, None, _fake({"disk": {"1e-03": {"heyoka/kept": 1.5}}}))
    assert won["missed"] == [] and won["all_peers"] is True


def test_interleaved_timing_times_every_solve_in_every_round():
    calls = [0, 0]

    def a():
        calls[0] += 1

    def b():
        calls[1] += 1

    secs = fastest.interleaved([a, b], rounds=3, min_sample=0.0)
    assert calls == [4, 4]  # one call each to size the samples, then one per round
    assert all(math.isfinite(s) and s >= 0 for s in secs)
