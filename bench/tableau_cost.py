"""The generic Runge-Kutta runner against the loop written for DOP853 alone: cost per step.

Every embedded pair now runs through one compiled runner given its tableau
(:mod:`mechviz.dynamics.integrators.rk`); DOP853 used to have a loop of its own
(:mod:`.dop853_before`). Both are run here side by side in one process on each benchmark
problem, interleaved call by call (alternating which goes first), on the same ensemble at the same
tolerance, so that load on a shared machine falls on both alike. Each call is timed in CPU time of
this thread (``time.thread_time``: time the process waits for a core does not count). Reported per
system: nanoseconds per accepted step of each (median over the rounds), the ratio generic / before
(the median over rounds of each round's ratio, the paired comparison: at most 1.05 is the goal),
the ratio of the medians and of the fastest calls beside it, the steps and evaluations (which must
be equal) and the largest difference between the final states (none expected: the arithmetic is
the same).
"""

from __future__ import annotations

import gc
import statistics
import time

import numpy as np

from mechviz.dynamics.integrators import rk

from . import dop853_before as before
from .problems import PROBLEMS

GOAL = 1.05  # the generic runner may cost at most 5 % more per step


def ensemble(problem, members: int) -> np.ndarray:
    """``members`` copies of the problem's start, spread by up to 1e-3 so that the steps differ
    a little between members (as an ensemble's do)."""
    rng = np.random.default_rng(0)
    y0 = problem.y0
    return y0 + 1e-3 * rng.uniform(-1.0, 1.0, (members, y0.size)) * np.maximum(np.abs(y0), 1.0)


def paired_rounds(a, b, rounds: int) -> tuple[list[float], list[float]]:
    """Seconds of each of ``rounds`` calls of ``a()`` and ``b()`` (each returns its CPU seconds
    first), interleaved, alternating which goes first, the garbage collector off meanwhile."""
    times: tuple[list[float], list[float]] = ([], [])
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        for k in range(rounds):
            order = ((0, a), (1, b)) if k % 2 == 0 else ((1, b), (0, a))
            for i, call in order:
                times[i].append(call()[0])
    finally:
        if was_enabled:
            gc.enable()
    return times


def _calls(problem, members: int, tol: float):
    """The two runs of one problem: ``(before, generic)``, each a call that returns
    ``(seconds, final states, stats)``."""
    system = problem.system
    sys_id, p = system.sys_id, system.kernel_params()
    Y0 = ensemble(problem, members)
    n, d = Y0.shape
    pair = rk.load_pair("dop853")

    def run(which):
        def call():
            Y = Y0.copy()
            H, F = np.zeros(n), np.zeros((n, d))
            stats, status = np.zeros((n, 3), dtype=np.int64), np.zeros(4, dtype=np.int64)
            if which == "before":
                carry = before.Dop853Carry(n, d)
                args = (sys_id, Y, p, 0.0, problem.t_end, tol, tol, H, F, stats, status, carry)
                t0 = time.thread_time()
                before.run_dop853(*args)
            else:
                carry = rk.RKCarry(n, d, pair)
                args = (pair, sys_id, Y, p, 0.0, problem.t_end, tol, tol, H, F, stats, status)
                t0 = time.thread_time()
                rk.run_rk(*args, carry)
            return time.thread_time() - t0, Y, stats

        return call

    return run("before"), run("generic")


def tableau_cost(*, quick: bool = False, members: int = 32, tol: float = 1e-10) -> dict:
    """Per-step cost of the generic runner against the DOP853-only loop on each problem (module
    docstring); ``quick``: fewer rounds."""
    rounds = 9 if quick else 31
    out: dict[str, dict] = {}
    for name, problem in PROBLEMS.items():
        old, new = _calls(problem, members, tol)
        _, y_old, s_old = old()  # compiles and warms up
        _, y_new, s_new = new()
        before, generic = paired_rounds(old, new, rounds)
        times = {"before": before, "generic": generic}
        steps = int(s_new[:, 1].sum())
        per_step = {k: 1e9 * statistics.median(v) / steps for k, v in times.items()}
        round_ratios = [g / b for g, b in zip(times["generic"], times["before"], strict=True)]
        scale = np.maximum(np.abs(y_old), 1.0)
        out[name] = {
            "ns_per_step_before": round(per_step["before"], 2),
            "ns_per_step_generic": round(per_step["generic"], 2),
            "ratio": round(statistics.median(round_ratios), 4),
            "ratio_of_medians": round(per_step["generic"] / per_step["before"], 4),
            "best_ratio": round(min(times["generic"]) / min(times["before"]), 4),
            "steps": steps,
            "same_counts": bool(np.array_equal(s_old, s_new)),
            "evaluations": int(s_new[:, 0].sum()),
            "max_state_difference": float(np.max(np.abs(y_new - y_old) / scale)),
            "members": members,
            "tol": tol,
            "rounds": rounds,
        }
    return out


def missed(result: dict) -> list[str]:
    """The systems on which the generic runner cost more than :data:`GOAL` times the old loop."""
    return [
        f"generic Runge-Kutta runner on {name}: {r['ratio']:.3f}x DOP853's own loop per step "
        f"(goal <= {GOAL})"
        for name, r in result.items()
        if r["ratio"] > GOAL
    ]
