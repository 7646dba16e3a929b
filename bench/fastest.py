"""Ours against the peers in their fastest form, on the benchmark problems and on random cases.

For every case (the three benchmark problems and :func:`mechviz.bench.untuned.draw`'s random
cases) and every contender, the tolerance ``rtol = atol = tol`` is swept down a grid in eighths
of a decade (the half-decades first, then the eighths around each pick: :mod:`.fastest_picks`)
and each solve's error is measured against the case's reference (the same for every
contender). At each accuracy target a contender's pick follows each of two rules: its loosest
tolerance meeting the target, and its loosest tolerance from which every tighter swept one
meets it too. The picks of all contenders under both rules are then timed in interleaved rounds
in this one process (every round times every pick once, in rotating order; each pick's fastest
round is kept), and the ratios are peer / ours, per rule: below 1 the peer is faster.

Contenders, by family (a family's time is its fastest member's):

- ours, **kept**: a :class:`~mechviz.dynamics.simulation.Simulation` built once and ``restart()``-ed per
  solve (``taylor`` and ``dop853``), and a :class:`~mechviz.dynamics.solver.Solver` built once per
  system kind and tolerance and handed each case's start and parameters; ours, **fresh**: a new
  ``Simulation`` (or ``Solver``) per solve (the cost of a user who builds one for every
  problem);
- heyoka: ``taylor_adaptive`` with and without ``fast_math``, each with runtime parameters (one
  integrator per system and tolerance, its construction not timed) and with the case's
  constants built in (one per case and tolerance: against ours kept its solve is timed,
  against ours fresh its construction is added, as ours fresh pays its own); CyRK:
  ``nbsolve2_ivp`` from an ``njit`` caller, DOP853, Vern8 and Vern7; scipy: ``odeint`` calling
  the compiled right-hand side through an ``njit`` function and through a Python one
  (:mod:`.fast_peers`).

The built-in-constants form solves the same equations as its runtime-parameter twin with the
same steps, to round-off, and each of its builds costs a compilation, so it is not swept: it is
solved at its twin's picks, each moved to the next tighter tolerance its twin swept while its
own error misses.

Where our fastest and a peer's are within 2x of each other, every pick is timed in as many
rounds again and keeps its fastest of all. A target below what the case's reference resolves is
reported as unresolved. Every case where a peer is faster than ours (kept or fresh) is listed
with its ratio (:func:`losses`).
"""

from __future__ import annotations

import gc
import math
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from mechviz.dynamics.simulation import Simulation

from . import fast_peers as fp
from .fastest_picks import (  # (GRID, TARGETS, PEERS, losses, distribution: also re-exported)
    COARSE_EVERY,
    GRID,
    PEERS,
    PICKS,
    RULES,
    TARGETS,
    distribution,
    losses,
    ordered,
    ratios,
    result_key,
    to_refine,
)
from .peer_equations import heyoka_pars
from .problems import PROBLEMS, Problem, listed, reference_state
from .untuned import Reference, draw, reference

OURS = listed("fastest")
FAMILIES = ("ours-kept", "ours-fresh", "heyoka", "cyrk", "odeint")
CAP_S = 2.0  # a contender's sweep stops after a solve slower than this
BUDGET_S = 8.0  # ... or after this long
__all__ = ["GRID", "PEERS", "TARGETS", "distribution", "losses"]


@dataclass
class Contender:
    """One way to solve a case: ``make(tol)`` returns the solve (a call giving the final state).

    ``per_case``: built for each parameter set, its construction (``construction[tol]``, wall
    seconds) counted against ours fresh. ``twin``: the name of the contender whose picks this
    one follows instead of sweeping (its ``picks``, by rule and target)."""

    name: str
    family: str
    make: Callable[[float], Callable[[], np.ndarray]]
    points: list[dict] = field(default_factory=list)  # the sweep: tol, error, seconds
    per_case: bool = False
    twin: str | None = None
    construction: dict[float, float] = field(default_factory=dict)
    picks: dict[tuple[str, float], dict | None] = field(default_factory=dict)


def _ours_kept(pb: Problem, method: str):
    def make(tol: float):
        sim = Simulation(pb.system, method, rtol=tol, atol=tol, state=pb.y0, reference=None)
        t_end = pb.t_end

        def solve():
            sim.restart()
            sim.advance_to(t_end)
            return sim.state[0]

        return solve

    return make


def _ours_fresh(pb: Problem, method: str):
    def make(tol: float):
        system, y0, t_end = pb.system, pb.y0, pb.t_end

        def solve():
            sim = Simulation(system, method, rtol=tol, atol=tol, state=y0, reference=None)
            sim.advance_to(t_end)
            return sim.state[0]

        return solve

    return make


def _solver_kept(pb: Problem):
    """One :class:`~mechviz.dynamics.solver.Solver` per system kind and tolerance, handed the case's
    start and parameters at every solve (as heyoka's integrator is)."""
    from mechviz.dynamics.solver import Solver

    p = np.ascontiguousarray(pb.system.kernel_params(), dtype=np.float64)

    def make(tol: float):
        solver = _SOLVERS.get((pb.system.sys_id, tol))
        if solver is None:
            solver = _SOLVERS[(pb.system.sys_id, tol)] = Solver(pb.system, rtol=tol, atol=tol)
        y0, t_end = pb.y0, pb.t_end
        return lambda: solver.solve(t_end, y0, p)

    return make


def _solver_fresh(pb: Problem):
    from mechviz.dynamics.solver import Solver

    def make(tol: float):
        system, y0, t_end = pb.system, pb.y0, pb.t_end
        return lambda: Solver(system, rtol=tol, atol=tol).solve(t_end, y0)

    return make


_SOLVERS: dict = {}


def _heyoka(pb: Problem, fast_math: bool):
    sid, y0 = pb.system.sys_id, pb.y0
    pars = heyoka_pars(sid, pb.system.kernel_params())

    def make(tol: float):
        solver = fp.heyoka_solver(sid, len(y0), len(pars), tol, fast_math)
        return lambda: solver.solve(y0, pars, pb.t_end)[0]

    return make


def _heyoka_builtin(pb: Problem, fast_math: bool, construction: dict[float, float]):
    """heyoka with this case's constants built in: one integrator per tolerance, built on first
    use and kept for the case; its construction seconds go into ``construction``."""
    sid, y0 = pb.system.sys_id, pb.y0
    constants = heyoka_pars(sid, pb.system.kernel_params())
    built: dict[float, fp.HeyokaBuiltinSolver] = {}

    def make(tol: float):
        solver = built.get(tol)
        if solver is None:
            solver = built[tol] = fp.HeyokaBuiltinSolver(sid, constants, len(y0), tol, fast_math)
            construction[tol] = solver.construction_s
        return lambda: solver.solve(y0, pb.t_end)[0]

    return make


def _cyrk(pb: Problem, method: str):
    solver = fp.CyrkSolver(pb.system.sys_id, method)
    p = np.ascontiguousarray(pb.system.kernel_params(), dtype=np.float64)

    def make(tol: float):
        return lambda: solver.solve(pb.y0, p, pb.t_end, tol)[0]

    return make


def _odeint(pb: Problem, closure: bool):
    sid, p = pb.system.sys_id, pb.system.kernel_params()
    fun = fp.odeint_closure(sid, p) if closure else None

    def make(tol: float):
        return lambda: fp.odeint_solve(sid, pb.y0, p, pb.t_end, tol, fun)[0]

    return make


def contenders(pb: Problem, peers: dict[str, str | None]) -> list[Contender]:
    """Every contender on ``pb``; a peer whose package is missing is left out."""
    out = [Contender(f"{m} kept", "ours-kept", _ours_kept(pb, m)) for m in OURS]
    out += [Contender(f"{m} fresh", "ours-fresh", _ours_fresh(pb, m)) for m in OURS]
    out.append(Contender("taylor solver kept", "ours-kept", _solver_kept(pb)))
    out.append(Contender("taylor solver fresh", "ours-fresh", _solver_fresh(pb)))
    if peers.get("heyoka") is None:
        for fm in (False, True):
            name = f"heyoka{' fast_math' if fm else ''}"
            out.append(Contender(name, "heyoka", _heyoka(pb, fm)))
            built = Contender(f"heyoka builtin{' fast_math' if fm else ''}", "heyoka", None)
            built.make = _heyoka_builtin(pb, fm, built.construction)
            built.per_case, built.twin = True, name
            out.append(built)
    if peers.get("CyRK") is None:
        out += [Contender(f"cyrk {m}", "cyrk", _cyrk(pb, m)) for m in fp.CYRK_METHODS]
    out.append(Contender("odeint", "odeint", _odeint(pb, False)))
    out.append(Contender("odeint closure", "odeint", _odeint(pb, True)))
    return out


def _once(solve) -> tuple[np.ndarray | None, float]:
    t0 = time.perf_counter()
    try:
        y = np.array(solve(), dtype=float)
    except Exception:  # a solver failing at one tolerance is a point without an answer
        return None, time.perf_counter() - t0
    return y, time.perf_counter() - t0


def _point(c: Contender, pb: Problem, ref: Reference, tol: float, first: bool) -> dict | None:
    """``c`` solved at ``tol``: ``{"tol", "error", "seconds"}`` (``None``: it could not be built
    there). Solved twice (the first call may have compiled) unless the first is slower than
    :data:`CAP_S` and not the ``first`` of its sweep."""
    try:
        solve = c.make(tol)
    except Exception:
        return None
    y, secs = _once(solve)
    if y is not None and (first or secs < CAP_S):
        y, secs = _once(solve)
    if y is None:  # no answer (the solver refused the tolerance or failed): no error to judge
        return {"tol": tol, "error": math.inf, "seconds": secs, "failed": True}
    err = math.inf if not np.all(np.isfinite(y)) else pb.error(y, ref.state)
    return {"tol": tol, "error": err, "seconds": secs}


def sweep(
    c: Contender,
    pb: Problem,
    ref: Reference,
    targets: tuple[float, ...],
    grid: tuple[float, ...] = GRID,
    every: int = COARSE_EVERY,
) -> None:
    """``c``'s points: down every ``every``-th tolerance of ``grid`` until its error meets the
    tightest of ``targets``, a solve takes longer than :data:`CAP_S`, or the sweep has taken
    :data:`BUDGET_S`; then the rest of ``grid`` wherever a pick could still move
    (:func:`.fastest_picks.to_refine`), until no pick does. (No stop on an error that stops
    falling: on a sensitive trajectory the error stays near 1 for decades of tolerance, then
    falls.)"""
    start = time.perf_counter()
    tightest = min(targets)
    for tol in grid[::every]:
        p = _point(c, pb, ref, tol, first=not c.points)
        if p is None:
            continue
        c.points.append(p)
        if p["error"] <= tightest or p["seconds"] > CAP_S:
            break
        if time.perf_counter() - start > BUDGET_S:
            break
    while todo := to_refine(c.points, targets, grid):
        c.points += [p for tol in todo if (p := _point(c, pb, ref, tol, False)) is not None]
        c.points[:] = ordered(c.points)
        if not any(p["tol"] in todo for p in c.points):
            break  # none of them could be built: nothing new to pick from


def follow(c: Contender, twin: Contender, pb: Problem, ref: Reference, targets) -> None:
    """``c``'s picks from its ``twin``'s: per rule and target, the twin's pick, moved to the
    twin's next tighter swept tolerance while ``c``'s own error there misses the target (at
    most two moves); no pick where the twin has none or ``c`` still misses."""
    done: dict[float, dict | None] = {}
    swept = [p["tol"] for p in ordered(twin.points)]
    for target in targets:
        for rule, pick_of in PICKS.items():
            c.picks[(rule, target)] = None
            p = pick_of(twin.points, target)
            if p is None:
                continue
            i = swept.index(p["tol"])
            for tol in swept[i : i + 3]:
                if tol not in done:
                    done[tol] = _point(c, pb, ref, tol, first=not done)
                mine = done[tol]
                if mine is not None and mine["error"] <= target:
                    c.picks[(rule, target)] = mine
                    break
    c.points = ordered(p for p in done.values() if p is not None)


def pick(c: Contender, target: float, rule: str = "loosest") -> dict | None:
    """``c``'s pick at ``target`` under ``rule`` (:mod:`.fastest_picks`; ``None``: none met
    it)."""
    if c.twin is not None:
        return c.picks.get((rule, target))
    return PICKS[rule](c.points, target)


def interleaved(solves: list[Callable[[], object]], rounds: int, min_sample: float) -> list[float]:
    """Seconds per call of each solve: its fastest of ``rounds`` rounds, every round timing every
    solve once in rotating order (calls repeated to at least ``min_sample`` per sample)."""
    per = []
    for s in solves:
        t0 = time.perf_counter()
        s()
        dt = time.perf_counter() - t0
        per.append(max(1, math.ceil(min_sample / max(dt, 1e-7))))
    best = [math.inf] * len(solves)
    enabled = gc.isenabled()
    gc.disable()
    try:
        for r in range(rounds):
            for k in range(len(solves)):
                i = (k + r) % len(solves)
                s, n = solves[i], per[i]
                t0 = time.perf_counter()
                for _ in range(n):
                    s()
                best[i] = min(best[i], (time.perf_counter() - t0) / n)
    finally:
        if enabled:
            gc.enable()
    return best


def _close(chosen: list, secs: list[float], within: float = 2.0) -> bool:
    """Whether our fastest and a peer's fastest are within ``within`` of each other."""
    best: dict[str, float] = {}
    for (c, _), t in zip(chosen, secs, strict=True):
        best[c.family] = min(best.get(c.family, math.inf), t)
    ours = [best[f] for f in ("ours-kept", "ours-fresh") if f in best]
    theirs = [best[f] for f in PEERS if f in best]
    return any(1.0 / within < t / o < within for o in ours for t in theirs)


def _entry(c: Contender, p: dict, seconds: float, construction: bool) -> dict:
    e = {"who": c.name, "tol": p["tol"], "error": p["error"], "seconds": seconds}
    if construction:
        e["construction_s"] = c.construction[p["tol"]]
        e["seconds"] = seconds + e["construction_s"]
    return e


def family_times(timed: list[tuple[Contender, dict, float]]) -> dict[str, dict]:
    """Each family's fastest timed pick (``timed``: contender, pick, seconds per solve). A
    peer's is given twice: ``<peer>`` for the ratio over ours kept, ``<peer>-fresh`` for the
    ratio over ours fresh, where a form built per case adds its construction."""
    times: dict[str, dict] = {}

    def keep(key: str, e: dict) -> None:
        if key not in times or e["seconds"] < times[key]["seconds"]:
            times[key] = e

    for c, p, s in timed:
        keep(c.family, _entry(c, p, s, False))
        if c.family in PEERS:
            keep(f"{c.family}-fresh", _entry(c, p, s, c.per_case))
    return times


def measure_case(
    pb: Problem,
    ref: Reference,
    peers: dict[str, str | None],
    rounds: int = 5,
    min_sample: float = 2e-3,
    targets: tuple[float, ...] = TARGETS,
    grid: tuple[float, ...] = GRID,
    every: int = COARSE_EVERY,
) -> dict:
    """One case: every contender's sweep (down ``grid``, every ``every``-th tolerance first),
    then per target the picks of both rules timed head to head (a pick both rules make, once)."""
    cs = contenders(pb, peers)
    resolved = tuple(t for t in targets if t >= ref.resolves) or targets
    by_name = {c.name: c for c in cs}
    for c in cs:
        if c.twin is None:
            sweep(c, pb, ref, resolved, grid, every)
    for c in cs:
        if c.twin is not None:
            follow(c, by_name[c.twin], pb, ref, resolved)
    out: dict = {"title": pb.title, "t_end": pb.t_end, "state0": list(pb.state0)}
    out["reference"] = ref.kind
    out["sweeps"] = {c.name: c.points for c in cs}
    families = {c.family for c in cs}
    rows = {}
    for target in targets:
        key = f"{target:.0e}"
        if target < ref.resolves:
            rows[key] = {"unresolved": f"the reference resolves {ref.resolves:.1e}"}
            continue
        picks = {
            rule: [(c, p) for c in cs if (p := pick(c, target, rule)) is not None] for rule in RULES
        }
        chosen = list({(c.name, p["tol"]): (c, p) for v in picks.values() for c, p in v}.values())
        solves = [c.make(p["tol"]) for c, p in chosen]
        secs = interleaved(solves, rounds, min_sample) if chosen else []
        if _close(chosen, secs):  # a near tie: as many rounds again, for every contender alike
            again = interleaved(solves, rounds, min_sample)
            secs = [min(a, b) for a, b in zip(secs, again, strict=True)]
        timed = {(c.name, p["tol"]): s for (c, p), s in zip(chosen, secs, strict=True)}
        row: dict = {}
        for rule, field_ in RULES.items():
            times = family_times([(c, p, timed[(c.name, p["tol"])]) for c, p in picks[rule]])
            figures = {"fastest": times, "ratios": ratios(times, families)}
            if field_:
                row[field_] = figures
            else:
                row.update(figures)
        rows[key] = row
    out["targets"] = rows
    return out


def how() -> str:
    """How the comparison is made, for the report: this module's description (its paragraphs
    unwrapped, list items kept one a line)."""
    paragraphs = __doc__.split("\n\n")[1:5]
    return "\n\n".join(re.sub(r"\n(?!- )\s*", " ", p) for p in paragraphs)


def run(
    seed: int,
    n_random: int = 21,
    rounds: int = 5,
    min_sample: float = 2e-3,
    progress: Callable[[str], None] | None = None,
    fixed: bool = True,
) -> dict:
    """The whole comparison: the benchmark problems (``fixed``) and ``n_random`` cases from
    ``seed``. Returns the results (JSON-ready), with the distributions and losses under each
    rule (:mod:`.fastest_picks`)."""
    peers = fp.available()
    cases: dict[str, tuple[Problem, Reference]] = {}
    if fixed:
        for key, pb in PROBLEMS.items():
            cases[key] = (pb, Reference(reference_state(pb), "stored reference", 0.0))
    t0 = time.perf_counter()
    for key, pb in draw(seed, n_random).items():
        cases[key] = (pb, reference(pb))
    ref_s = time.perf_counter() - t0
    results = {}
    for key, (pb, ref) in cases.items():
        if progress:
            progress(key)
        results[key] = measure_case(pb, ref, peers, rounds, min_sample)
    out = {
        "about": (
            "Ours against each peer's fastest form: per case and accuracy, each contender's "
            "pick (rtol = atol, in eighths of a decade) under two rules: the loosest tolerance "
            "meeting the accuracy against the case's reference, and the loosest from which "
            "every tighter swept tolerance meets it too (figures under 'every_tighter'); the "
            "picks timed in interleaved rounds in one process (fastest round kept). Ratios: "
            "peer time / our time, below 1 the peer is faster; 'kept' our Simulation restarted "
            "per solve, 'fresh' a new Simulation per solve (against it, a peer form built per "
            "case, heyoka with built-in constants, adds its construction: '<peer>-fresh')."
        ),
        "how": how(),
        "seed": seed,
        "n_random": n_random,
        "rounds": rounds,
        "min_sample_s": min_sample,
        "grid": {"from": GRID[0], "to": GRID[-1], "per_decade": 8, "first_sweep_every": 4},
        "peers_missing": {k: v for k, v in peers.items() if v is not None},
        "reference_seconds": round(ref_s, 1),
        "cases": results,
    }
    for rule in RULES:
        out[result_key("distribution", rule)] = distribution(out, rule)
        out[result_key("losses", rule)] = losses(out, rule)
    return out
