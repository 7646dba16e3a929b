"""Construction cost and the first answer in a fresh process: ours against scipy's odeint.

``python -m mechviz.bench.first_answer`` measures both and exits with status 1 when a target is
missed (each miss printed with its figure): the first answer through ``Simulation(...,
"taylor")`` in a fresh process no slower than odeint's, and a Solver and a Simulation built per
problem in under :data:`CONSTRUCTION_GOAL_US` microseconds.
"""

from __future__ import annotations

import os
import sys
import time

from mechviz.dynamics.integrators import METHODS
from mechviz.dynamics.simulation import Simulation
from mechviz.dynamics.solver import Solver

from .problems import PROBLEMS, listed

#: Our methods timed from a fresh process: those whose entry lists them (``"first-answer"``).
FIRST = listed("first-answer")
#: The method whose first answer is judged against odeint's: Taylor's (its steps are series),
#: which a fresh process runs through the module compiled ahead of time once it is built.
JUDGED = next(m for m in FIRST if METHODS[m].series)
#: A Solver or a Simulation ready for a new problem in this many microseconds [us].
CONSTRUCTION_GOAL_US = 1.0


def construction_costs(repeats: int = 200) -> dict:
    """Microseconds to build a Simulation (Taylor's method and DOP853, no reference), to restart
    one, and to build a Solver, on each problem (medians of ``repeats``, in this process, the
    four interleaved)."""
    import statistics

    out = {}
    for key, pb in PROBLEMS.items():
        system, y0 = pb.system, pb.y0
        sim = Simulation(system, "taylor", rtol=1e-9, atol=1e-9, state=y0, reference=None)
        Simulation(system, "dop853", rtol=1e-9, atol=1e-9, state=y0, reference=None)
        Solver(system, rtol=1e-9, atol=1e-9)
        times: dict[str, list[float]] = {k: [] for k in ("series", "pair", "restart", "solver")}
        clock = time.perf_counter
        for _ in range(repeats):
            t0 = clock()
            Simulation(system, "taylor", rtol=1e-9, atol=1e-9, state=y0, reference=None)
            t1 = clock()
            sim.restart()
            t2 = clock()
            Simulation(system, "dop853", rtol=1e-9, atol=1e-9, state=y0, reference=None)
            t3 = clock()
            Solver(system, rtol=1e-9, atol=1e-9)
            t4 = clock()
            for name, dt in zip(times, (t1 - t0, t3 - t2, t2 - t1, t4 - t3), strict=True):
                times[name].append(dt)
        med = {name: round(1e6 * statistics.median(v), 2) for name, v in times.items()}
        out[key] = {
            "new_simulation": med["series"],
            "new_simulation_dop853": med["pair"],
            "restart": med["restart"],
            "new_solver": med["solver"],
        }
    return out


def construction_missed(costs: dict) -> list[str]:
    """Each construction above :data:`CONSTRUCTION_GOAL_US`, with its figure."""
    names = {"new_simulation": "Simulation (taylor)", "new_solver": "Solver"}
    return [
        f"construction: {key} {label} {row[name]} us > {CONSTRUCTION_GOAL_US:g} us"
        for key, row in costs.items()
        for name, label in names.items()
        if name in row and row[name] > CONSTRUCTION_GOAL_US
    ]


FIRST_ANSWER_OURS = """
import time; t0 = time.perf_counter()
from mechviz.dynamics import Hoop, Simulation
sim = Simulation(Hoop(), {method!r}, rtol=1e-9, atol=1e-9, state=[0.5, -0.3, 0.0, 0.0],
                 reference=None)
sim.advance_to(20.0)
print(time.perf_counter() - t0, float(sim.state[0, 0]))
"""
FIRST_ANSWER_AOT = """
import time; t0 = time.perf_counter()
from mechviz.dynamics.aot import solve
y = solve("hoop", [0.5, -0.3, 0.0, 0.0], 20.0, params=[1.0, 0.5, 1.0, 9.81], rtol=1e-9)
print(time.perf_counter() - t0, float(y[0]))
"""
FIRST_ANSWER_SCIPY = """
import time; t0 = time.perf_counter()
import math
from scipy.integrate import odeint
def f(y, t):
    th1, th2, w1, w2 = y
    s, c = math.sin(th1 - th2), math.cos(th1 - th2)
    r1 = -0.5 * s * w2 * w2 - 1.5 * 9.81 * math.sin(th1)
    r2 = s * w1 * w1 - 9.81 * math.sin(th2)
    det = 2.5 - 0.5 * c * c
    return [w1, w2, (r1 - 0.5 * c * r2) / det, (2.5 * r2 - c * r1) / det]
y = odeint(f, [0.5, -0.3, 0.0, 0.0], [0.0, 20.0], rtol=1e-9, atol=1e-9)
print(time.perf_counter() - t0, float(y[-1, 0]))
"""


def first_answer(repeats: int = 3) -> dict:
    """Seconds from a fresh interpreter's start to the hoop's state at t = 20 s at 1e-9, ours
    (Taylor and DOP853 through a Simulation, as a user's process runs them: Taylor through the
    module compiled ahead of time, :mod:`mechviz.dynamics.aot`, built first if it is not; the
    same through :func:`mechviz.dynamics.aot.solve`) against scipy's odeint with a plain Python
    right-hand side; the whole process is timed (interpreter start, imports, compilation or
    cache load, the solve), the scripts interleaved round by round. The first of our runs may
    fill the compiled-code cache; the median of ``repeats`` is reported."""
    import statistics
    import subprocess

    from mechviz.dynamics import aot

    aot_built = aot.path() is not None
    t0 = time.perf_counter()
    if not aot_built:
        aot.build()  # untimed, as numba's cache filled by the first run is
    scripts = {
        **{m: FIRST_ANSWER_OURS.format(method=m) for m in FIRST},
        "taylor-aot": FIRST_ANSWER_AOT,
        "scipy-odeint": FIRST_ANSWER_SCIPY,
    }
    env = {k: v for k, v in os.environ.items() if k != "MECHVIZ_AOT"}  # a user's default
    walls: dict[str, list[float]] = {name: [] for name in scripts}
    for _ in range(repeats):  # interleaved: each round runs every script once
        for name, code in scripts.items():
            t1 = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, env=env)
            walls[name].append(time.perf_counter() - t1)
    out: dict = {
        name: {"median_s": round(statistics.median(w), 3), "runs_s": [round(x, 3) for x in w]}
        for name, w in walls.items()
    }
    out["methods"] = list(FIRST)
    out["aot_build_s"] = None if aot_built else round(time.perf_counter() - t0, 1)
    ours = min(out[k]["median_s"] for k in (*FIRST, "taylor-aot"))
    out["ours_first_at_least_as_fast_as_scipy"] = ours <= out["scipy-odeint"]["median_s"]
    out["taylor_first_at_least_as_fast_as_scipy"] = not first_answer_missed(out)
    return out


def first_answer_missed(fa: dict) -> list[str]:
    """The first answer through ``Simulation(..., "taylor")`` slower than odeint's, with its
    figures (empty if met)."""
    if JUDGED not in fa:
        return []
    ours, theirs = fa[JUDGED]["median_s"], fa["scipy-odeint"]["median_s"]
    if ours <= theirs:
        return []
    return [
        f"first answer (taylor): ours / odeint = {ours} s / {theirs} s = {ours / theirs:.2f} > 1"
    ]


def main(argv: list[str] | None = None) -> int:
    """Measure both (``--repeats N`` fresh processes per script, default 5), print them as
    JSON and each missed target; exit status 1 if one is missed."""
    import argparse
    import json

    parser = argparse.ArgumentParser(prog="python -m mechviz.bench.first_answer")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    costs = construction_costs()
    fa = first_answer(args.repeats)
    print(json.dumps({"construction_us": costs, "first_answer": fa}, indent=1))
    missed = construction_missed(costs) + first_answer_missed(fa)
    for line in missed:
        print(f"missed: {line}")
    return 1 if missed else 0


if __name__ == "__main__":
    sys.exit(main())
