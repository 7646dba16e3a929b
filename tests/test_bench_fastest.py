"""The peers-in-their-fastest-form harness computes what it says (nothing here is timed).

Each peer in its fastest form answers the benchmark problem to the accuracy its tolerance
promises against the same reference as ours (heyoka with built-in constants as its
runtime-parameter twin does, to round-off); the random cases are reproducible from their seed;
the grid is in eighths of a decade and refined only around the picks; each rule picks what it
says (on constructed sweeps where the two differ) and every pick meets its target; a form built
per case pays its construction against ours fresh only; the report lists every losing case
under each rule.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from mechviz.bench import fast_peers as fp
from mechviz.bench import fastest, fastest_picks, fastest_report, untuned
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


SOLVERS = ["odeint", "odeint closure"]
if HAVE["heyoka"] is None:
    SOLVERS += ["heyoka", "heyoka fast_math", "heyoka builtin", "heyoka builtin fast_math"]
if HAVE["CyRK"] is None:
    SOLVERS += [f"cyrk {m}" for m in fp.CYRK_METHODS]


def _solve(name: str, pb: Problem, tol: float) -> np.ndarray:
    sid, p = pb.system.sys_id, pb.system.kernel_params()
    if name.startswith("heyoka builtin"):
        consts = heyoka_pars(sid, p)
        s = fp.HeyokaBuiltinSolver(sid, consts, len(pb.y0), tol, name.endswith("fast_math"))
        return s.solve(pb.y0, pb.t_end)[0]
    if name.startswith("heyoka"):
        pars = heyoka_pars(sid, p)
        s = fp.heyoka_solver(sid, len(pb.y0), len(pars), tol, name.endswith("fast_math"))
        return s.solve(pb.y0, pars, pb.t_end)[0]
    if name.startswith("cyrk"):
        return fp.CyrkSolver(sid, name.split()[1]).solve(pb.y0, p, pb.t_end, tol)[0]
    fun = fp.odeint_closure(sid, p) if name == "odeint closure" else None
    return fp.odeint_solve(sid, pb.y0, p, pb.t_end, tol, fun)[0]


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


@pytest.mark.parametrize("key", ["charge", "hoop", "disk"])
def test_heyoka_with_built_in_constants_is_its_runtime_parameter_twin(key):
    """Built per parameter set, the constants' numbers in its code, heyoka takes the steps its
    runtime-parameter form takes and lands on the same final state to round-off (a constant in
    the wrong place would be off by far more than the tolerance); its construction is timed."""
    if HAVE["heyoka"] is not None:
        pytest.skip(HAVE["heyoka"])
    pb = _short(key, 5.0)
    sid, p = pb.system.sys_id, pb.system.kernel_params()
    pars = heyoka_pars(sid, p)
    for fm in (False, True):
        twin = fp.HeyokaSolver(sid, len(pb.y0), len(pars), 1e-10, fm)
        built = fp.HeyokaBuiltinSolver(sid, pars, len(pb.y0), 1e-10, fm)
        y1, n1 = twin.solve(pb.y0, pars, pb.t_end)
        y2, n2 = built.solve(pb.y0, pb.t_end)
        assert n1 == n2
        assert np.max(np.abs(y1 - y2)) <= 1e-12 * max(1.0, float(np.max(np.abs(y1))))
        assert built.construction_s > 0.0
        again, _ = built.solve(pb.y0, pb.t_end)  # reset per solve: the same answer again
        assert np.array_equal(again, y2)


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
    for target, full in out["targets"].items():
        for rule in fastest_picks.RULES:
            row = fastest_picks.rule_row(full, rule)
            for e in row["fastest"].values():
                assert e["error"] <= float(target)
                y = cs[e["who"]].make(e["tol"])()
                assert pb.error(np.asarray(y), ref.state) <= float(target)
                if rule == "every-tighter" and not e["who"].startswith("heyoka builtin"):
                    sweep = out["sweeps"][e["who"]]
                    tighter = [q for q in sweep if q["tol"] <= e["tol"] and not q.get("failed")]
                    assert all(q["error"] <= float(target) for q in tighter)
            f = row["fastest"]
            for name, r in row["ratios"].items():
                peer, form = name.split("/")
                theirs = fastest_picks.peer_entry(f, peer, form)
                if theirs is not None and f"ours-{form}" in f:
                    assert r == pytest.approx(theirs["seconds"] / f[f"ours-{form}"]["seconds"])


def _row(ratios: dict) -> dict:
    fast = {
        "ours-kept": {"who": "taylor kept", "tol": 1e-9, "error": 1e-10, "seconds": 1e-4},
        "ours-fresh": {"who": "taylor fresh", "tol": 1e-9, "error": 1e-10, "seconds": 2e-4},
    }
    for name, r in ratios.items():
        peer, form = name.split("/")
        if r is not None:
            secs = r * fast[f"ours-{form}"]["seconds"]
            fast[peer] = {"who": peer, "tol": 1e-9, "error": 1e-10, "seconds": secs}
    return {"fastest": fast, "ratios": ratios}


def _fake(ratios_by_case: dict, every_tighter: dict | None = None) -> dict:
    """Results with the given ratios (the loosest rule's; ``every_tighter``'s too if given)."""
    cases = {}
    for key, rows in ratios_by_case.items():
        targets = {}
        for target, ratios in rows.items():
            targets[target] = _row(ratios)
            if every_tighter is not None:
                targets[target]["every_tighter"] = _row(every_tighter[key][target])
        cases[key] = {"targets": targets}
    result = {"seed": 1, "n_random": 2, "rounds": 1, "cases": cases}
    rules = fastest_picks.RULES if every_tighter is not None else ("loosest",)
    for rule in rules:
        result[fastest_picks.result_key("losses", rule)] = fastest.losses(result, rule)
        result[fastest_picks.result_key("distribution", rule)] = fastest.distribution(result, rule)
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


def test_the_grid_is_eighths_of_a_decade_and_its_first_sweep_the_half_decades():
    g = np.array(fastest_picks.GRID)
    assert len(g) == 105 and g[0] == 1e-2 and g[-1] == pytest.approx(1e-15, rel=1e-12)
    assert np.allclose(g[:-1] / g[1:], 10.0**0.125, rtol=1e-12)
    # the half-decades are the very doubles the half-decade grid had
    assert fastest_picks.COARSE == tuple(10.0 ** (-k / 2) for k in range(4, 31))


def _points(errors: dict[float, float]) -> list[dict]:
    return [{"tol": t, "error": e, "seconds": 1e-3} for t, e in errors.items()]


def test_the_two_rules_pick_differently_on_a_constructed_sweep():
    """A lucky point: at 1e-3 the error meets 1e-4 by chance, tighter tolerances miss it until
    1e-5. The loosest rule picks the lucky point; the every-tighter rule the loosest point from
    which every tighter one meets the target."""
    pts = _points({1e-2: 1e-1, 1e-3: 5e-5, 1e-4: 3e-4, 1e-5: 8e-5, 1e-6: 9e-6, 1e-7: 2e-7})
    assert fastest_picks.loosest(pts, 1e-4)["tol"] == 1e-3
    assert fastest_picks.every_tighter(pts, 1e-4)["tol"] == 1e-5
    # where no luck is involved they agree
    assert fastest_picks.loosest(pts, 1e-5)["tol"] == fastest_picks.every_tighter(pts, 1e-5)["tol"]
    # the order the points were swept in does not matter
    assert fastest_picks.every_tighter(pts[::-1], 1e-4)["tol"] == 1e-5
    # a non-finite answer at the sweep's end (infinite error) leaves the every-tighter rule no
    # pick; a tolerance the solver refused (no answer) is left out of it
    blown = [*pts, {"tol": 1e-8, "error": math.inf, "seconds": 1e-3}]
    assert fastest_picks.every_tighter(blown, 1e-4) is None
    assert fastest_picks.loosest(blown, 1e-4)["tol"] == 1e-3
    refused = [*pts, {"tol": 1e-8, "error": math.inf, "seconds": 1e-3, "failed": True}]
    assert fastest_picks.every_tighter(refused, 1e-4)["tol"] == 1e-5
    assert fastest_picks.loosest(refused, 1e-4)["tol"] == 1e-3
    assert (
        fastest_picks.loosest(pts, 1e-9) is None and fastest_picks.every_tighter(pts, 1e-9) is None
    )


def test_the_sweep_fills_in_the_eighths_only_where_a_pick_could_move():
    """A made-up contender whose error is 2 tol, but 1e-2 at 10^-6.25 (an eighth the
    half-decades do not look at). The half-decades are swept down to the tightest target, then
    only the eighths between each pick and the half-decade above it; the loosest rule then picks
    an eighth at each target, and the every-tighter rule at 1e-3 steps below the miss that the
    eighths found."""
    grid = fastest_picks.GRID  # grid[k] = 10^-(2 + k/8)
    solved: list[float] = []

    def make(tol):
        solved.append(tol)
        return lambda: np.array([1e-2 if tol == grid[34] else 2.0 * tol])

    c = fastest.Contender("made-up", "ours-kept", make)
    pb = type("Pb", (), {"error": staticmethod(lambda y, ref: float(y[0]))})()
    ref = untuned.Reference(np.zeros(1), "none", 0.0)
    fastest.sweep(c, pb, ref, (1e-3, 1e-6))
    tols = [p["tol"] for p in c.points]
    assert tols == sorted(tols, reverse=True) and len(set(tols)) == len(tols)
    # the half-decades down to 10^-6.5, the first meeting 1e-6; the eighths in two brackets
    assert [t for t in tols if t in fastest_picks.COARSE] == list(fastest_picks.COARSE[:10])
    assert {t for t in tols if t not in fastest_picks.COARSE} == {
        grid[k] for k in (9, 10, 11, 33, 34, 35)
    }
    assert set(solved) == set(tols)
    assert fastest.pick(c, 1e-3)["tol"] == grid[11]  # 10^-3.375: error 8.4e-4
    assert fastest.pick(c, 1e-6)["tol"] == grid[35]  # 10^-6.375: error 8.4e-7
    assert fastest.pick(c, 1e-3, "every-tighter")["tol"] == grid[35]  # below the miss
    assert fastest.pick(c, 1e-6, "every-tighter")["tol"] == grid[35]


def test_a_lucky_eighth_moves_only_the_loosest_rule():
    """Errors that miss at every half-decade above 1e-5 but meet the target at one eighth in
    between, then miss again: the loosest rule takes the eighth, the every-tighter rule does not."""
    grid = fastest_picks.GRID  # grid[k] = 10^-(2 + k/8)
    lucky = grid[22]  # 10^-4.75
    pts = _points({t: t / 2 for t in fastest_picks.COARSE[:8]})  # 1e-2 ... 10^-5.5
    assert fastest_picks.to_refine(pts, (1e-5,), grid) == [grid[21], grid[22], grid[23]]
    pts += _points({grid[21]: 1e-3, lucky: 1e-7, grid[23]: 1e-3})
    assert fastest_picks.loosest(pts, 1e-5)["tol"] == lucky
    assert fastest_picks.every_tighter(pts, 1e-5)["tol"] == grid[24]  # 10^-5


def test_a_form_built_per_case_pays_its_construction_against_ours_fresh_only():
    kept = fastest.Contender("taylor kept", "ours-kept", None)
    fresh = fastest.Contender("taylor fresh", "ours-fresh", None)
    shared = fastest.Contender("heyoka", "heyoka", None)
    built = fastest.Contender("heyoka builtin", "heyoka", None, per_case=True, twin="heyoka")
    built.construction[1e-6] = 0.05
    p = {"tol": 1e-6, "error": 1e-7}
    times = fastest.family_times(
        [(kept, p, 10e-6), (fresh, p, 12e-6), (shared, p, 11e-6), (built, p, 8e-6)]
    )
    assert times["heyoka"]["who"] == "heyoka builtin" and times["heyoka"]["seconds"] == 8e-6
    assert times["heyoka-fresh"]["who"] == "heyoka" and times["heyoka-fresh"]["seconds"] == 11e-6
    r = fastest_picks.ratios(times, {"ours-kept", "ours-fresh", "heyoka"})
    assert r["heyoka/kept"] == pytest.approx(0.8) and r["heyoka/fresh"] == pytest.approx(11 / 12)
    alone = fastest.family_times([(fresh, p, 12e-6), (built, p, 8e-6)])
    assert alone["heyoka-fresh"]["seconds"] == pytest.approx(0.05 + 8e-6)
    assert alone["heyoka-fresh"]["construction_s"] == 0.05


def test_both_rules_have_their_ratios_and_losses_in_the_results_and_the_report():
    result = _fake(
        {
            "hoop": {"1e-09": {"heyoka/kept": 1.2, "cyrk/kept": 1.3}},
            "random-00-disk": {"1e-06": {"heyoka/kept": 1.1, "cyrk/kept": 0.95}},
        },
        every_tighter={
            "hoop": {"1e-09": {"heyoka/kept": 0.9, "cyrk/kept": 1.3}},
            "random-00-disk": {"1e-06": {"heyoka/kept": 1.1, "cyrk/kept": 1.05}},
        },
    )
    assert [e["case"] for e in result["losses"]] == ["random-00-disk"]
    assert [e["case"] for e in result["losses_every_tighter"]] == ["hoop"]
    d = result["distribution_every_tighter"]["1e-06"]["cyrk/kept"]
    assert d["below_1"] == 0 and d["min"] == pytest.approx(1.05)
    md = fastest_report.markdown(result)
    assert "hoop 1e-09 kept: heyoka / ours = 0.90" in md
    assert "random-00-disk 1e-06 kept: cyrk / ours = 0.95" in md
    assert md.count("### Each contender's pick") == 2
    lines = fastest_report.verdict_lines(result)
    assert len(lines) == 2 and "slower in 1" in lines[0] and "slower in 1" in lines[1]
    assert "every tighter one meets the target too" in lines[1]
    # a result from before the second rule renders as it did: one verdict, no rule headings
    old = _fake({"hoop": {"1e-09": {"heyoka/kept": 1.2}}})
    assert len(fastest_report.verdict_lines(old)) == 1
    assert "### Each contender's pick" not in fastest_report.markdown(old)
