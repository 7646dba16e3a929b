"""Generated compiled forms against the hand-written ones: cost per step, side by side.

Each system's equations are written once (:mod:`mechviz.dynamics.codegen.equations`) and its
compiled forms generated from them: the right-hand side, classical RK4's step and Taylor's
recurrences. Here each generated form is run beside the hand-written one, on each benchmark
problem, in one process, interleaved call by call (alternating which goes first) on the same
ensemble, so that load on a shared machine falls on both alike:

- ``rhs``: DOP853 through the tableau runner given the system's id (the product's right-hand
  side, generated: :data:`~mechviz.dynamics.integrators.kernels.RHS`) or the hand-written one it
  replaced (:mod:`.handwritten`; same steps, same arithmetic around it);
- ``rk4``: fixed steps of the product's RK4 step, generated
  (:data:`~mechviz.dynamics.integrators.kernels.RK4`), and of the hand-written one it replaced;
- ``taylor``: Taylor's method (:func:`~mechviz.dynamics.integrators.taylor.run_taylor_with`, one
  driver) with the hand-written expansion (:data:`.handwritten.EXPANDS`) or the generated one,
  at the order the product uses (the product uses the generated ones on the free body and the
  hoop).
  (The product's charge takes its steps in closed form, :mod:`~mechviz.dynamics.integrators.
  taylor_linear`; its expansion is compared all the same.)

Each call is timed in CPU time of this thread (``time.thread_time``: time the process waits for
a core does not count). Reported per system and form: nanoseconds per step of each (median over
the rounds), the ratio generated / hand-written (median over the rounds of each round's ratio,
the paired comparison: at most :data:`GOAL` is the goal), the ratio of the medians beside it, and
the largest difference between the final states (round-off, or the tolerance's for the adaptive
methods whose steps follow the round-off).
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

import numpy as np

from mechviz.dynamics.codegen.equations import EQUATIONS
from mechviz.dynamics.codegen.series import generated_expand
from mechviz.dynamics.integrators import kernels, rk, taylor

from . import handwritten
from .problems import PROBLEMS
from .tableau_cost import ensemble, paired_rounds

GOAL = 1.05  # a generated form may cost at most 5 % more per step than the hand-written one
#: The forms compared: the right-hand side (inside DOP853), the RK4 step, the Taylor series.
FORMS = ("rhs", "rk4 step", "taylor series")
Call = Callable[[], tuple[float, np.ndarray, int]]  # () -> (CPU seconds, final states, steps)


def _dop853(sys, Y0, p, t_end, tol) -> Call:
    pair = rk.load_pair("dop853")
    n, d = Y0.shape

    def call():
        Y = Y0.copy()
        stats, status = np.zeros((n, 3), np.int64), np.zeros(3, np.int64)
        carry = rk.RKCarry(n, d, pair)
        args = (Y, p, 0.0, t_end, tol, tol, np.zeros(n), np.zeros((n, d)), stats, status, carry)
        t0 = time.thread_time()
        rk.run_rk(pair, sys, *args)
        return time.thread_time() - t0, Y, int(stats[:, 1].sum())

    return call


def _rk4(step, Y0, p, h, n_steps) -> Call:
    def call():
        Y = Y0.copy()
        status = np.zeros(3, np.int64)
        t0 = time.thread_time()
        kernels.run_direct(step, Y, p, h, n_steps, status)
        return time.thread_time() - t0, Y, n_steps * len(Y)

    return call


def _taylor(expand, rows, sys_id, Y0, p, t_end, tol) -> Call:
    order, a = taylor.order_for(tol, tol, sys_id)
    n = len(Y0)

    def call():
        Y = Y0.copy()
        stats, status = np.zeros((n, 3), np.int64), np.zeros(3, np.int64)
        t0 = time.thread_time()
        steps = taylor.run_taylor_with(
            expand, rows, Y, p, 0.0, t_end, tol, tol, order, a, stats, status
        )
        return time.thread_time() - t0, Y, int(steps)

    return call


def _calls(problem, members: int, tol: float) -> dict[str, tuple[Call, Call]]:
    """Per form, ``(hand-written, generated)`` calls on this problem."""
    system = problem.system
    sys_id, p = system.sys_id, system.kernel_params()
    eq = EQUATIONS[sys_id]()
    Y0 = ensemble(problem, members)
    t_end = problem.t_end
    n_fixed = 2000  # RK4 steps of a call, over a tenth of the span
    return {
        "rhs": (
            _dop853(handwritten.RHS[sys_id], Y0, p, t_end, tol),
            _dop853(sys_id, Y0, p, t_end, tol),
        ),
        "rk4 step": (
            _rk4(handwritten.RK4[sys_id], Y0, p, 0.1 * t_end / n_fixed, n_fixed),
            _rk4(kernels.RK4[sys_id], Y0, p, 0.1 * t_end / n_fixed, n_fixed),
        ),
        "taylor series": (
            _taylor(handwritten.EXPANDS[sys_id], taylor.N_ROWS, sys_id, Y0, p, t_end, tol),
            _taylor(*generated_expand(eq), sys_id, Y0, p, t_end, tol),
        ),
    }


def _paired(old: Call, new: Call, rounds: int) -> dict:
    _, y_old, steps = old()  # compiles and warms up
    _, y_new, new_steps = new()
    hand, generated = paired_rounds(old, new, rounds)
    times = {"hand": hand, "generated": generated}
    per_step = {k: 1e9 * statistics.median(v) / steps for k, v in times.items()}
    ratios = [g / h for g, h in zip(times["generated"], times["hand"], strict=True)]
    scale = np.maximum(np.abs(y_old), 1.0)
    return {
        "ns_per_step_hand": round(per_step["hand"], 2),
        "ns_per_step_generated": round(per_step["generated"], 2),
        "ratio": round(statistics.median(ratios), 4),
        "ratio_of_medians": round(per_step["generated"] / per_step["hand"], 4),
        "steps": steps,
        "same_steps": steps == new_steps,
        "max_state_difference": float(np.max(np.abs(y_new - y_old) / scale)),
    }


def generated_cost(*, quick: bool = False, members: int = 32, tol: float = 1e-10) -> dict:
    """Per problem and form (:data:`FORMS`), the generated form's cost per step against the
    hand-written one's (module docstring); ``quick``: fewer rounds."""
    rounds = 9 if quick else 31
    out: dict[str, dict] = {}
    for name, problem in PROBLEMS.items():
        calls = _calls(problem, members, tol)
        out[name] = {form: _paired(*calls[form], rounds) for form in FORMS}
        out[name]["rounds"] = rounds
    return out


def missed(result: dict) -> list[str]:
    """The forms whose generated code cost more than :data:`GOAL` times the hand-written."""
    return [
        f"generated {form} on {name}: {r[form]['ratio']:.3f}x the hand-written per step "
        f"(goal <= {GOAL})"
        for name, r in result.items()
        for form in FORMS
        if r[form]["ratio"] > GOAL
    ]


def report(result: dict) -> list[str]:
    """The result in lines of text."""
    lines = [f"per step, generated / hand-written (goal <= {GOAL}), side by side:"]
    for name, r in result.items():
        for form in FORMS:
            f = r[form]
            lines.append(
                f"  {name:7s} {form:13s} {f['ns_per_step_generated']:8.1f} / "
                f"{f['ns_per_step_hand']:8.1f} ns, median of round ratios {f['ratio']:.3f} "
                f"(of medians {f['ratio_of_medians']:.3f}; {f['steps']} steps, same steps "
                f"{f['same_steps']}, largest state difference {f['max_state_difference']:.1e})"
            )
    lines += [f"missed: {line}" for line in missed(result)]
    return lines
