"""Ours against the peers in their fastest form, on the benchmark problems and on random cases.

For every case (the three benchmark problems and :func:`mechviz.bench.untuned.draw`'s random
cases) and every contender, the tolerance ``rtol = atol = tol`` is swept down a grid of
half-decades (:data:`GRID`) and each solve's error is measured against the case's reference
(the same for every contender). At each accuracy target a contender's pick is its loosest
tolerance whose error meets the target. The picks of all contenders are then timed in
interleaved rounds in this one process (every round times every pick once, in rotating order;
each pick's fastest round is kept), and the ratios are peer / ours: below 1 the peer is faster.

Contenders, by family (a family's time is its fastest member's):

- ours, **kept**: a :class:`~mechviz.dynamics.simulation.Simulation` built once and ``restart()``-ed per
  solve (``taylor`` and ``dop853``), and a :class:`~mechviz.dynamics.solver.Solver` built once per
  system kind and tolerance and handed each case's start and parameters; ours, **fresh**: a new
  ``Simulation`` (or ``Solver``) per solve (the cost of a user who builds one for every
  problem);
- heyoka: ``taylor_adaptive`` with and without ``fast_math``; CyRK: ``nbsolve2_ivp`` from an
  ``njit`` caller, DOP853, Vern8 and Vern7; scipy: ``odeint`` (:mod:`.fast_peers`).

Where our fastest and a peer's are within 2x of each other, every pick is timed in as many
rounds again and keeps its fastest of all. A target below what the case's reference resolves is
reported as unresolved. Every case where a peer is faster than ours (kept or fresh) is listed
with its ratio (:func:`losses`).
"""

from __future__ import annotations

import gc
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from mechviz.dynamics.simulation import Simulation

from . import fast_peers as fp
from .peer_equations import heyoka_pars
from .problems import PROBLEMS, Problem, listed, reference_state
from .untuned import Reference, draw, reference

TARGETS = (1e-3, 1e-6, 1e-9, 1e-12)
GRID = tuple(10.0 ** (-k / 2) for k in range(4, 31))  # 1e-2 ... 1e-15 in half-decades
OURS = listed("fastest")
FAMILIES = ("ours-kept", "ours-fresh", "heyoka", "cyrk", "odeint")
PEERS = ("heyoka", "cyrk", "odeint")
CAP_S = 2.0  # a contender's sweep stops after a solve slower than this
BUDGET_S = 8.0  # ... or after this long


@dataclass
class Contender:
    """One way to solve a case: ``make(tol)`` returns the solve (a call giving the final state)."""

    name: str
    family: str
    make: Callable[[float], Callable[[], np.ndarray]]
    points: list[dict] = field(default_factory=list)  # the sweep: tol, error, seconds


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


def _cyrk(pb: Problem, method: str):
    solver = fp.CyrkSolver(pb.system.sys_id, method)
    p = np.ascontiguousarray(pb.system.kernel_params(), dtype=np.float64)

    def make(tol: float):
        return lambda: solver.solve(pb.y0, p, pb.t_end, tol)[0]

    return make


def _odeint(pb: Problem):
    p = pb.system.kernel_params()

    def make(tol: float):
        return lambda: fp.odeint_solve(pb.system.sys_id, pb.y0, p, pb.t_end, tol)[0]

    return make


def contenders(pb: Problem, peers: dict[str, str | None]) -> list[Contender]:
    """Every contender on ``pb``; a peer whose package is missing is left out."""
    out = [Contender(f"{m} kept", "ours-kept", _ours_kept(pb, m)) for m in OURS]
    out += [Contender(f"{m} fresh", "ours-fresh", _ours_fresh(pb, m)) for m in OURS]
    out.append(Contender("taylor solver kept", "ours-kept", _solver_kept(pb)))
    out.append(Contender("taylor solver fresh", "ours-fresh", _solver_fresh(pb)))
    if peers.get("heyoka") is None:
        out += [
            Contender(f"heyoka{' fast_math' if fm else ''}", "heyoka", _heyoka(pb, fm))
            for fm in (False, True)
        ]
    if peers.get("CyRK") is None:
        out += [Contender(f"cyrk {m}", "cyrk", _cyrk(pb, m)) for m in fp.CYRK_METHODS]
    out.append(Contender("odeint", "odeint", _odeint(pb)))
    return out


def _once(solve) -> tuple[np.ndarray | None, float]:
    t0 = time.perf_counter()
    try:
        y = np.array(solve(), dtype=float)
    except Exception:  # a solver failing at one tolerance is a point without an answer
        return None, time.perf_counter() - t0
    return y, time.perf_counter() - t0


def sweep(
    c: Contender, pb: Problem, ref: Reference, tightest: float, grid: tuple[float, ...] = GRID
) -> None:
    """``c``'s points down :data:`GRID` until its error meets ``tightest``, a solve takes longer
    than :data:`CAP_S`, or the sweep has taken :data:`BUDGET_S`. (No stop on an error that stops
    falling: on a sensitive trajectory the error stays near 1 for decades of tolerance, then
    falls.)"""
    start = time.perf_counter()
    for tol in grid:
        try:
            solve = c.make(tol)
        except Exception:
            continue
        y, secs = _once(solve)
        if y is not None and (not c.points or secs < CAP_S):
            y, secs = _once(solve)  # the first call may have compiled
        err = math.inf if y is None or not np.all(np.isfinite(y)) else pb.error(y, ref.state)
        c.points.append({"tol": tol, "error": err, "seconds": secs})
        if err <= tightest or secs > CAP_S or time.perf_counter() - start > BUDGET_S:
            break


def pick(c: Contender, target: float) -> dict | None:
    """The loosest swept tolerance whose error meets ``target`` (``None``: none did)."""
    return next((p for p in c.points if p["error"] <= target), None)


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


def measure_case(
    pb: Problem,
    ref: Reference,
    peers: dict[str, str | None],
    rounds: int = 5,
    min_sample: float = 2e-3,
    targets: tuple[float, ...] = TARGETS,
    grid: tuple[float, ...] = GRID,
) -> dict:
    """One case: every contender's sweep (down ``grid``), then per target the picks timed head
    to head."""
    cs = contenders(pb, peers)
    resolved = [t for t in targets if t >= ref.resolves]
    tightest = min(resolved) if resolved else min(targets)
    for c in cs:
        sweep(c, pb, ref, tightest, grid)
    out: dict = {"title": pb.title, "t_end": pb.t_end, "state0": list(pb.state0)}
    out["reference"] = ref.kind
    out["sweeps"] = {c.name: c.points for c in cs}
    rows = {}
    for target in targets:
        key = f"{target:.0e}"
        if target < ref.resolves:
            rows[key] = {"unresolved": f"the reference resolves {ref.resolves:.1e}"}
            continue
        chosen = [(c, p) for c in cs if (p := pick(c, target)) is not None]
        solves = [c.make(p["tol"]) for c, p in chosen]
        secs = interleaved(solves, rounds, min_sample) if chosen else []
        if _close(chosen, secs):  # a near tie: as many rounds again, for every contender alike
            again = interleaved(solves, rounds, min_sample)
            secs = [min(a, b) for a, b in zip(secs, again, strict=True)]
        times: dict[str, dict] = {}
        for (c, p), s in zip(chosen, secs, strict=True):
            e = times.get(c.family)
            if e is None or s < e["seconds"]:
                times[c.family] = {
                    "who": c.name,
                    "tol": p["tol"],
                    "error": p["error"],
                    "seconds": s,
                }
        ratios = {}
        for peer in PEERS:
            if peer not in {c.family for c in cs}:
                continue
            for form in ("kept", "fresh"):
                ours = times.get(f"ours-{form}")
                theirs = times.get(peer)
                if theirs is None:
                    r = None  # the peer did not reach the target: no ratio (ours wins)
                elif ours is None:
                    r = 0.0  # we did not reach it, the peer did
                else:
                    r = theirs["seconds"] / ours["seconds"]
                ratios[f"{peer}/{form}"] = r
        rows[key] = {"fastest": times, "ratios": ratios}
    out["targets"] = rows
    return out


def run(
    seed: int,
    n_random: int = 21,
    rounds: int = 5,
    min_sample: float = 2e-3,
    progress: Callable[[str], None] | None = None,
    fixed: bool = True,
) -> dict:
    """The whole comparison: the benchmark problems (``fixed``) and ``n_random`` cases from
    ``seed``. Returns the results (JSON-ready), with :func:`summarise`'s distributions."""
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
            "loosest tolerance (rtol = atol, half-decades) meeting the accuracy against the "
            "case's reference, timed in interleaved rounds in one process (fastest round kept). "
            "Ratios: peer time / our time, below 1 the peer is faster; 'kept' our Simulation "
            "restarted per solve, 'fresh' a new Simulation per solve."
        ),
        "seed": seed,
        "n_random": n_random,
        "rounds": rounds,
        "min_sample_s": min_sample,
        "peers_missing": {k: v for k, v in peers.items() if v is not None},
        "reference_seconds": round(ref_s, 1),
        "cases": results,
    }
    out["distribution"] = distribution(out)
    out["losses"] = losses(out)
    return out


def losses(result: dict) -> list[dict]:
    """Every case, accuracy, peer and form where the peer is faster than ours (ratio < 1)."""
    out = []
    for key, case in result["cases"].items():
        for target, row in case["targets"].items():
            for name, r in (row.get("ratios") or {}).items():
                if r is not None and r < 1.0:
                    peer, form = name.split("/")
                    f = row["fastest"]
                    ours = f.get(f"ours-{form}")
                    out.append(
                        {
                            "case": key,
                            "target": target,
                            "peer": peer,
                            "form": form,
                            "ratio": r,
                            "peer_who": f[peer]["who"],
                            "peer_seconds": f[peer]["seconds"],
                            "ours_who": None if ours is None else ours["who"],
                            "ours_seconds": None if ours is None else ours["seconds"],
                        }
                    )
    return out


def distribution(result: dict) -> dict:
    """Per accuracy, peer and form, over the random cases: how many ratios, how many below 1,
    and the minimum, quartiles and maximum of the ratios (a peer that did not reach the target
    counts as a win and is counted apart)."""
    out: dict = {}
    for target in (f"{t:.0e}" for t in TARGETS):
        out[target] = {}
        for peer in PEERS:
            for form in ("kept", "fresh"):
                rs, not_reached = [], 0
                for key, case in result["cases"].items():
                    if not key.startswith("random-"):
                        continue
                    row = case["targets"].get(target) or {}
                    ratios = row.get("ratios") or {}
                    if f"{peer}/{form}" not in ratios:
                        continue
                    r = ratios[f"{peer}/{form}"]
                    if r is None:
                        not_reached += 1
                    else:
                        rs.append(r)
                if not rs and not not_reached:
                    continue
                q = statistics.quantiles(rs, n=4, method="inclusive") if len(rs) >= 2 else rs * 3
                out[target][f"{peer}/{form}"] = {
                    "n": len(rs),
                    "below_1": sum(r < 1.0 for r in rs),
                    "peer_not_reached": not_reached,
                    "min": min(rs) if rs else None,
                    "q1": q[0] if rs else None,
                    "median": q[1] if rs else None,
                    "q3": q[2] if rs else None,
                    "max": max(rs) if rs else None,
                }
    return out
