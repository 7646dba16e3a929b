"""Construction cost and the first answer in a fresh process: ours against scipy's odeint."""

from __future__ import annotations

import sys
import time

from mechviz.dynamics.simulation import Simulation

from .problems import PROBLEMS, listed

#: Our methods timed from a fresh process: those whose entry lists them (``"first-answer"``).
FIRST = listed("first-answer")


def construction_costs() -> dict:
    """Microseconds to build a Simulation and to restart one (median of 200, in this process)."""
    import statistics

    out = {}
    for key, pb in PROBLEMS.items():
        build, again = [], []
        sim = Simulation(pb.system, "taylor", rtol=1e-9, atol=1e-9, state=pb.y0, reference=None)
        for _ in range(200):
            t0 = time.perf_counter()
            Simulation(pb.system, "taylor", rtol=1e-9, atol=1e-9, state=pb.y0, reference=None)
            t1 = time.perf_counter()
            sim.restart()
            t2 = time.perf_counter()
            build.append(t1 - t0)
            again.append(t2 - t1)
        out[key] = {
            "new_simulation": round(1e6 * statistics.median(build), 2),
            "restart": round(1e6 * statistics.median(again), 2),
        }
    return out


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
    (Taylor and DOP853 through a Simulation; Taylor compiled ahead of time, :mod:`mechviz.dynamics.aot`,
    built first if it is not) against scipy's odeint with a plain Python right-hand side; the
    whole process is timed (interpreter start, imports, compilation or cache load, the solve),
    the scripts interleaved round by round. The first of our runs may fill the compiled-code
    cache; the median of ``repeats`` is reported."""
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
    walls: dict[str, list[float]] = {name: [] for name in scripts}
    for _ in range(repeats):  # interleaved: each round runs every script once
        for name, code in scripts.items():
            t1 = time.perf_counter()
            subprocess.run([sys.executable, "-c", code], check=True, capture_output=True)
            walls[name].append(time.perf_counter() - t1)
    out: dict = {
        name: {"median_s": round(statistics.median(w), 3), "runs_s": [round(x, 3) for x in w]}
        for name, w in walls.items()
    }
    out["methods"] = list(FIRST)
    out["aot_build_s"] = None if aot_built else round(time.perf_counter() - t0, 1)
    ours = min(out[k]["median_s"] for k in (*FIRST, "taylor-aot"))
    out["ours_first_at_least_as_fast_as_scipy"] = ours <= out["scipy-odeint"]["median_s"]
    return out
