"""Model no more than a scene needs: the cheapest method and step for each viewer exhibit.

For each exhibit (its default parameters and initial state, given by the viewer, which owns them:
``mechviz.viz.scene.bench_cases``) and each candidate fixed-step method, the step is halved from one
display frame (1/60 s) down until the largest on-screen position error over 10 minutes of
simulated time, sampled every second against a tight reference, is below ``1e-3`` of the
exhibit's size. The cheapest of the passing (method, step) pairs, by measured compute time per
simulated second, is the default; its step must also lie below the method's stability limit
(:mod:`mechviz.dynamics.stability`).

On-screen error, per exhibit:

- charge: distance between the computed and the exact position [m]; size: orbit diameter
  ``2 v / omega``.
- hoop: the larger of the errors of the hoop's centre and of the bead [m]; size: ``2 a``.
- released disk: rotation error times the farthest body point's distance from the centre of
  mass (the centre of mass itself moves exactly); size: ``2 R``.
"""

from __future__ import annotations

import math
import time

import numpy as np

from mechviz import dynamics
from mechviz.dynamics import cyclotron, disk, hoop, stability
from mechviz.dynamics.integrators.base import IntegrationError
from mechviz.dynamics.simulation import Simulation
from mechviz.dynamics.systems import CYCLOTRON, HOOP

SPAN = 600.0  # 10 minutes of simulated time [s]
SAMPLE = 1.0  # error sampled every second [s]
FRAME = 1.0 / 60.0
TOLERANCE = 1e-3  # of the exhibit's size


def _exhibits(cases: dict) -> dict:
    """``cases``: exhibit name -> ``{"system", "state", "state_note"}`` (the viewer's defaults);
    adds each exhibit's on-screen error, size and candidate methods."""
    out = {}
    if CYCLOTRON.name in cases:
        c = cases[CYCLOTRON.name]
        s0 = np.asarray(c["state"], float)

        def charge_err(y, ref):
            return float(np.linalg.norm(y[:3] - ref[:3]))

        out[CYCLOTRON.name] = {
            **c,
            "size": 2.0 * cyclotron.larmor_radius(c["system"].params, s0),
            "error": charge_err,
            "methods": ("exact", "boris", "rk4", "yoshida4"),
        }
    if HOOP.name in cases:
        c = cases[HOOP.name]
        hp = c["system"].params

        def hoop_err(y, ref):
            c1, b1 = hoop.positions(hp, y)
            c2, b2 = hoop.positions(hp, ref)
            return float(max(np.linalg.norm(c1 - c2), np.linalg.norm(b1 - b2)))

        out[HOOP.name] = {
            **c,
            "size": 2.0 * hp.radius,
            "error": hoop_err,
            "methods": ("verlet", "rk4", "yoshida4"),
        }
    if "disk-released" in cases:
        c = cases["disk-released"]
        dp = c["system"].params
        rim = np.array([[0.0, 0.0, 0.0], [0.0, 2.0, 0.0], [1.0, 1.0, 0.0], [-1.0, 1.0, 0.0]])
        reach = float(np.max(np.linalg.norm(rim * dp.radius - disk.centre_of_mass(dp), axis=1)))
        _, frame = disk._principal_frame_cm(dp)

        def disk_err(y, ref):
            r1 = disk.quaternion_to_matrix(y[3:7]) @ frame.T
            r2 = disk.quaternion_to_matrix(ref[3:7]) @ frame.T
            return float(np.linalg.norm(r1 - r2, 2) * reach)

        out["disk-released"] = {
            **c,
            "size": 2.0 * dp.radius,
            "error": disk_err,
            "methods": ("splitting", "rk4", "yoshida4"),
        }
    return out


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
    """Sweep each exhibit's candidate methods (``cases``: see :func:`_exhibits`); return the
    table and the chosen defaults."""
    out = {}
    times = np.arange(1, int(SPAN / SAMPLE) + 1) * SAMPLE
    divisors = (1, 2, 4, 8, 16, 32, 64, 128) if not quick else (1, 4, 16, 64)
    for name, ex in _exhibits(cases).items():
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
    (:func:`choose_defaults`): system, initial state and a note."""
    from mechviz.viz.model import CyclotronConfig, DiskConfig, HoopConfig

    cyc, hoop, disk = CyclotronConfig(), HoopConfig(), DiskConfig()
    released = dynamics.ReleasedDisk(disk.physics(), tuple(disk.extra_spin))
    return {
        CYCLOTRON.name: {
            "system": dynamics.Cyclotron(cyc.physics()),
            "state": cyc.initial_state(),
            "state_note": f"speed {cyc.speed:g} m/s, vz {cyc.vz:g} m/s (the viewer's default)",
        },
        HOOP.name: {
            "system": dynamics.Hoop(hoop.physics()),
            "state": hoop.initial_state(),
            "state_note": f"mode {hoop.mode!r}, amplitude {hoop.amplitude:g} rad (the viewer's default)",
        },
        "disk-released": {
            "system": released,
            "state": released.default_state(),
            "state_note": f"omega {disk.physics().omega:g} rad/s, extra spin {disk.extra_spin} "
            "rad/s (the viewer's default)",
        },
    }
