"""What an atlas costs: per cell, per core, and what Dask adds (``mechviz atlas --bench OUT``).

Measures, on the chaos map of the hoop (the map that outgrows one machine):

- *cost per cell*: one chunk run as an ensemble (:func:`.kernels.compute_chunk`) against the same
  cells run one at a time, each its own :class:`mechviz.dynamics.Simulation` (ratio below 1: the
  ensemble is cheaper);
- *parallel efficiency*: the same atlas on a ``LocalCluster`` (TCP) of one worker process and of
  two, workers warmed first (compiled kernels, not timed); speed-up ``T1 / T2``;
- *scheduling overhead*: ``1 - (sum of task seconds) / (workers x wall seconds)``, the share of
  the workers' time not spent inside a task (scheduling, transfer, writing the store);
- *CPU share*: the CPU seconds the tasks' threads got over their wall seconds; 1 when each
  worker had a core to itself, lower when other processes took part of it. A speed-up short of
  two with a high share is overhead; with a share that falls from one worker to two, it is load.
  The speed-up at equal shares, ``T1 / T2 x share_1 / share_2``, is what the two workers would
  give with a core each: two times what scheduling leaves of their time;
- *cells per second per core* from the tasks' CPU seconds (what a core does when it is given),
  and the projected wall time of a 1024 x 1024 map over 60 s on 1, 8 and 64 cores: at the
  measured two-worker efficiency, and at the scheduling overhead alone (cores not shared).

The load average is recorded before and after: on a shared machine the wall-time figures are a
lower bound on what the code does alone.
"""

from __future__ import annotations

import datetime as _dt
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np

from ..systems import Hoop
from .grid import AtlasSpec, Axis
from .kernels import compute_chunk
from .store import versions


def _spec(n: int, duration: float, chunk: tuple[int, int]) -> AtlasSpec:
    return AtlasSpec(
        "chaos",
        Hoop.name,
        ("rk4",),
        Axis("theta2", -3.0, 3.0, n),
        Axis("theta1", -3.0, 3.0, n),
        duration=duration,
        chunk=chunk,
    )


def _warm(spec: AtlasSpec) -> bool:
    compute_chunk(_spec(2, 0.1, (2, 2)), (0, 0, 0))
    return True


def balanced_rows(n: int, rows: float, workers: int) -> int:
    """Rows per chunk for ``n`` rows: the most that divides ``n`` into equal chunks, a whole
    number of them per worker, and is at most ``rows`` (about a second of work; at least one
    row). Unequal chunks, or a count the workers do not share evenly, leave a worker idle at
    the end while the other finishes: time that would be counted as scheduling overhead."""
    fits = [d for d in range(1, n + 1) if n % d == 0 and (n // d) % workers == 0 and d <= rows]
    return max(fits, default=1)


def per_cell_cost(n: int, duration: float) -> dict:
    """Seconds per cell: ``n`` cells as one ensemble against the same cells one at a time."""
    spec = _spec(n, duration, (1, n))
    compute_chunk(spec, (0, 0, 0))  # compile
    t0, c0 = time.perf_counter(), time.thread_time()
    compute_chunk(spec, (0, 0, 0))
    ensemble, ensemble_cpu = (time.perf_counter() - t0) / n, (time.thread_time() - c0) / n
    single = _spec(n, duration, (1, 1))
    t0, c0 = time.perf_counter(), time.thread_time()
    for j in range(n):
        compute_chunk(single, (0, 0, j))
    serial, serial_cpu = (time.perf_counter() - t0) / n, (time.thread_time() - c0) / n
    return {
        "cells": n,
        "duration_s": duration,
        "ensemble_s_per_cell": ensemble,
        "serial_simulation_s_per_cell": serial,
        "ratio": ensemble / serial,
        "ensemble_cpu_s_per_cell": ensemble_cpu,
        "serial_simulation_cpu_s_per_cell": serial_cpu,
        "ratio_cpu": ensemble_cpu / serial_cpu,
    }


def distributed_run(spec: AtlasSpec, workers: int) -> dict:
    """The atlas on a fresh LocalCluster of ``workers`` processes (TCP, as the command starts
    it: its scratch folder its own, its workers gone at the end); warmed, then timed."""
    from .driver import dask_client, run_atlas

    with dask_client(workers=workers) as client, tempfile.TemporaryDirectory() as tmp:
        client.wait_for_workers(workers)
        client.run(_warm, spec)
        report = run_atlas(spec, Path(tmp) / "a.zarr", client=client)
    busy = report.task_seconds / (workers * report.wall_seconds)
    return {
        "workers": workers,
        "chunks": report.total,
        "wall_s": report.wall_seconds,
        "task_s": report.task_seconds,
        "task_cpu_s": report.task_cpu_seconds,
        "cpu_share": report.task_cpu_seconds / report.task_seconds,
        "scheduling_overhead": 1.0 - busy,
    }


def run_bench(out: Path, *, quick: bool = False, progress: bool = True) -> dict:
    """Run the measurements and write ``out/atlas-bench.json``; returns the result."""

    def say(text: str) -> None:
        if progress:
            print(f"mechviz atlas --bench: {text}", flush=True)

    load_before = os.getloadavg()
    started = time.perf_counter()
    duration = 60.0
    say("cost per cell: one ensemble against one Simulation per cell")
    cost = per_cell_cost(32 if quick else 128, duration)
    n = 32 if quick else 64
    target = 0.25 if quick else 1.0
    rows = balanced_rows(n, target / (cost["ensemble_s_per_cell"] * n), workers=2)
    spec = _spec(n, duration, (rows, n))
    say(
        f"parallel efficiency: {n}x{n} cells in {len(spec.chunks())} chunks of {rows}x{n}, "
        "on 1 and 2 workers"
    )
    one = distributed_run(spec, 1)
    two = distributed_run(spec, 2)
    speedup = one["wall_s"] / two["wall_s"]
    speedup_equal_share = speedup * one["cpu_share"] / two["cpu_share"]
    cells = n * n
    per_core = cells / one["task_cpu_s"]
    efficiency = speedup / 2.0
    overhead = max(one["scheduling_overhead"], two["scheduling_overhead"])
    projected = {
        str(c): 1024 * 1024 / (per_core * c * (1.0 if c == 1 else efficiency)) for c in (1, 8, 64)
    }
    unshared = {str(c): 1024 * 1024 / (per_core * c * (1.0 - overhead)) for c in (1, 8, 64)}
    load_after = os.getloadavg()
    result = {
        "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
        "mode": "quick" if quick else "full",
        "cpu_count": os.cpu_count(),
        "load_average_before": [round(x, 2) for x in load_before],
        "load_average_after": [round(x, 2) for x in load_after],
        "loaded_machine": max(load_before[0], load_after[0]) > 0.5 * (os.cpu_count() or 1),
        "versions": versions(),
        "map": {"kind": "chaos", "method": "rk4", "step_s": spec.step, "duration_s": duration},
        "per_cell": cost,
        "one_worker": one,
        "two_workers": two,
        "speedup_1_to_2": speedup,
        "speedup_1_to_2_at_equal_cpu_share": speedup_equal_share,
        "parallel_efficiency_2": efficiency,
        "scheduling_overhead": overhead,
        "cpu_share_1": one["cpu_share"],
        "cpu_share_2": two["cpu_share"],
        "cells_per_s_per_core": per_core,
        "projected_1024x1024_wall_s": projected,
        "projected_1024x1024_wall_s_unshared": unshared,
        "bench_seconds": time.perf_counter() - started,
        "targets": {
            "per_cell_within_1.2x_of_serial": cost["ratio"] <= 1.2,
            "speedup_1_to_2_at_least_1.7": speedup >= 1.7,
            "scheduling_overhead_under_5pct": overhead < 0.05,
        },
    }
    out.mkdir(parents=True, exist_ok=True)
    path = out / "atlas-bench.json"
    partial = path.with_suffix(".json.partial")
    partial.write_text(json.dumps(result, indent=1))
    partial.replace(path)
    result["path"] = str(path)
    return result


def format_summary(r: dict) -> str:
    c = r["per_cell"]
    lines = [
        f"atlas bench ({r['mode']}, {r['date']}, {r['cpu_count']} cores, load "
        f"{r['load_average_before']} -> {r['load_average_after']}"
        f"{', a loaded machine' if r['loaded_machine'] else ''})",
        f"  per cell: ensemble {1e3 * c['ensemble_s_per_cell']:.3g} ms, one Simulation per cell "
        f"{1e3 * c['serial_simulation_s_per_cell']:.3g} ms (ratio {c['ratio']:.2f})",
        f"  1 worker {r['one_worker']['wall_s']:.2f} s, 2 workers {r['two_workers']['wall_s']:.2f} s:"
        f" speed-up {r['speedup_1_to_2']:.2f}x (efficiency {100 * r['parallel_efficiency_2']:.0f} %)",
        f"  scheduling overhead {100 * r['scheduling_overhead']:.1f} %; CPU share of the "
        f"tasks {100 * r['cpu_share_1']:.0f} % on 1 worker, {100 * r['cpu_share_2']:.0f} % on 2"
        " (below 100 %: other processes took the cores); speed-up at equal shares "
        f"{r['speedup_1_to_2_at_equal_cpu_share']:.2f}x",
        f"  {r['cells_per_s_per_core']:.0f} cells/s/core; 1024x1024 over 60 s: "
        + ", ".join(f"{k} cores {_hms(v)}" for k, v in r["projected_1024x1024_wall_s"].items())
        + " (cores not shared: "
        + ", ".join(f"{k} {_hms(v)}" for k, v in r["projected_1024x1024_wall_s_unshared"].items())
        + ")",
        "  targets: "
        + ", ".join(f"{k} {'met' if v else 'MISSED'}" for k, v in r["targets"].items()),
        f"  written: {r['path']}",
    ]
    return "\n".join(lines)


def _hms(seconds: float) -> str:
    if not np.isfinite(seconds):
        return "n/a"
    m, s = divmod(int(round(seconds)), 60)
    h, m = divmod(m, 60)
    return f"{h}h{m:02d}m{s:02d}s" if h else f"{m}m{s:02d}s"
