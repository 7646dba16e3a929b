"""Model no more than a scene needs: the cheapest method and step for each viewer exhibit.

For each exhibit (its default parameters and initial state, given by the viewer, which owns them:
``mechviz.viz.scene.bench_cases``) and each candidate fixed-step method, the step is halved from one
display frame (1/60 s) down until the largest on-screen position error over 10 minutes of
simulated time, sampled every second against a tight reference, is below ``1e-3`` of the
exhibit's size. The cheapest of the passing (method, step) pairs, by measured compute time per
simulated second, is the default; its step must also lie below the method's stability limit
(:mod:`mechviz.dynamics.stability`).

The on-screen error and the exhibit's size are each exhibit's own: its model says them
(:meth:`mechviz.viz.model.hooks.SystemHooks.screen_case`; the charge: the distance between the
computed and the exact position over the orbit's diameter, for instance).
"""

from __future__ import annotations

import math
import time

import numpy as np

from mechviz.dynamics import stability
from mechviz.dynamics.integrators.base import IntegrationError
from mechviz.dynamics.simulation import Simulation

SPAN = 600.0  # 10 minutes of simulated time [s]
SAMPLE = 1.0  # error sampled every second [s]
FRAME = 1.0 / 60.0
TOLERANCE = 1e-3  # of the exhibit's size


def _reference_path(ex: dict, times: np.ndarray) -> np.ndarray:
    sysm = ex["system"]
    exact = sysm.exact(ex["state"], 0.0)
    if exact is not None:
        return np.stack([sysm.exact(ex["state"], t) for t in times])
    sim = Simulation(sysm, "dop853", rtol=1e-13, atol=1e-13, state=ex["state"], reference=None)
    out = []
    for t in times:
        sim.advance_to(float(t))
        out.append(sim.state[0].copy())
    return np.stack(out)


def _max_error(ex, method, dt, times, ref) -> tuple[float | None, float, int]:
    sim = Simulation(ex["system"], method, dt=dt, state=ex["state"], reference=None)
    worst = 0.0
    t0 = time.perf_counter()
    try:
        for t, r in zip(times, ref, strict=True):
            sim.advance_to(float(t))
            # Fixed steps stop at the last whole step before t: compare at that time exactly.
            worst = max(worst, ex["error"](sim.state[0], r) if sim.t == t else math.inf)
    except IntegrationError:
        return None, time.perf_counter() - t0, sim.steps
    # Cost: the sampled run above compiled everything; time clean runs over the whole span
    # (best of three), as a viewer advancing frame by frame pays the same steps.
    best = math.inf
    for _ in range(3):
        clean = Simulation(ex["system"], method, dt=dt, state=ex["state"], reference=None)
        t0 = time.perf_counter()
        clean.advance_to(SPAN)
        best = min(best, time.perf_counter() - t0)
    return worst, best, sim.steps


def choose_defaults(cases: dict, quick: bool = False, progress=None) -> dict:
    """Sweep each exhibit's candidate methods (``cases``: see :func:`bench_cases`); return the
    table and the chosen defaults."""
    out = {}
    times = np.arange(1, int(SPAN / SAMPLE) + 1) * SAMPLE
    divisors = (1, 2, 4, 8, 16, 32, 64, 128) if not quick else (1, 4, 16, 64)
    for name, ex in cases.items():
        ref = _reference_path(ex, times)
        budget = TOLERANCE * ex["size"]
        rows = []
        for method in ex["methods"]:
            limit = stability.stability_limit(method, ex["system"], ex["state"])
            for k in divisors:
                dt = FRAME / k
                # Sample times on whole steps: 60 k steps per second.
                err, secs, steps = _max_error(ex, method, dt, times, ref)
                rows.append(
                    {
                        "method": method,
                        "dt": dt,
                        "steps_per_frame": k,
                        "max_error": err,
                        "relative_error": None if err is None else err / ex["size"],
                        "seconds_per_simulated_second": secs / SPAN,
                        "steps": steps,
                        "stability_limit_dt": limit,
                        "passes": err is not None and err <= budget,
                    }
                )
                if progress:
                    progress()
                if err is not None and err <= budget:
                    break  # the largest passing step of this method: smaller ones cost more
        passing = [r for r in rows if r["passes"]]
        best = min(passing, key=lambda r: r["seconds_per_simulated_second"]) if passing else None
        out[name] = {
            "size": ex["size"],
            "budget": budget,
            "state": [float(v) for v in ex["state"]],
            "state_note": ex["state_note"],
            "rows": rows,
            "chosen": best,
        }
    return out


def bench_cases() -> dict[str, dict]:
    """The viewer's default exhibits as the bench's exhibit-defaults sweep takes them
    (:func:`choose_defaults`): each exhibit's model says its system, initial state, a note, its
    on-screen error, its size and its candidate methods
    (:meth:`mechviz.viz.model.hooks.SystemHooks.screen_case`)."""
    from mechviz.viz.model import MODELS

    return dict(case for cls in MODELS.values() if (case := cls.screen_case()) is not None)
