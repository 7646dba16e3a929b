"""Run the whole benchmark, write ``results.json`` and the charts, and summarise.

The result file records the machine, library versions, load average and date with every
figure; ratios between implementations come from this one run (PERF_NOTES section 11).
"""

from __future__ import annotations

import json
import math
import os
import platform
import sys
import time
from pathlib import Path

from ..integrators.base import get_method
from ..simulation import Simulation
from . import exhibits, experiments
from .problems import ADAPTIVE_OURS, ADAPTIVE_SCIPY, PROBLEMS, load_references, versions
from .sweeps import Settings, ratio_table, retime_ratios, sweep_adaptive, sweep_fixed


class Progress:
    """A one-line progress bar on stderr when it is a terminal; silent otherwise."""

    def __init__(self, total: int, enabled: bool | None = None) -> None:
        self.total = max(total, 1)
        self.done = 0
        self.label = ""
        self.t0 = time.perf_counter()
        self.enabled = sys.stderr.isatty() if enabled is None else enabled

    def set(self, label: str) -> None:
        self.label = label
        self._draw()

    def __call__(self, n: int = 1) -> None:
        self.done = min(self.total, self.done + n)
        self._draw()

    def _draw(self) -> None:
        if not self.enabled:
            return
        width = 30
        fill = int(width * self.done / self.total)
        secs = time.perf_counter() - self.t0
        sys.stderr.write(f"\r[{'#' * fill}{'.' * (width - fill)}] {self.done}/{self.total} "
                         f"{secs:5.0f} s  {self.label[:40]:<40}")  # fmt: skip
        sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            sys.stderr.write("\n")


def machine() -> dict:
    info = {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
    }
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return info


def _load() -> list[float] | None:
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except OSError:
        return None


def _fixed(pb, settings: Settings) -> tuple[str, ...]:
    return tuple(m for m in pb.fixed if m not in settings.skip_fixed)


def _compile_times(progress: Progress, settings: Settings) -> dict:
    """First call of every method on every problem (compilation or cache load), reported
    separately from the timings, which all come after it."""
    out = {}
    for key, pb in PROBLEMS.items():
        for m in _fixed(pb, settings) + ADAPTIVE_OURS + settings.scipy_methods:
            meth = get_method(m)
            kw = {"rtol": 1e-3, "atol": 1e-3} if meth.adaptive else {"dt": pb.t_end / 1000}
            sim = Simulation(pb.system, m, state=pb.y0, reference=None, **kw)
            t0 = time.perf_counter()
            sim.advance_to(pb.t_end / 100)
            out[f"{key}/{m}"] = time.perf_counter() - t0
        progress.set(f"compile {key}")
        progress()
    return out


def run_bench(
    *, quick: bool = False, out: str | Path = "docs/bench", extras: dict | None = None,
    show_progress: bool | None = None, charts: bool = True, exhibit_cases: dict | None = None,
) -> dict:  # fmt: skip
    """Run everything; write ``out/results.json`` and charts; return the result dict.

    ``exhibit_cases``: the viewer's exhibits as :func:`.exhibits.choose_defaults` takes them
    (the viewer owns its defaults; ``mechviz bench`` passes them); ``None`` skips that part."""
    out = Path(out)
    settings = Settings.for_mode(quick)
    refs = load_references()
    n_sweeps = sum(len(_fixed(pb, settings)) + len(ADAPTIVE_OURS) + len(settings.scipy_methods)
                   for pb in PROBLEMS.values())  # fmt: skip
    total = len(PROBLEMS) + n_sweeps + 1 + 10 + 7 + len(experiments.STEP_CASES) + 3
    progress = Progress(total, show_progress)
    started = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
    t_start = time.perf_counter()
    load_before = _load()

    compile_s = _compile_times(progress, settings)
    points = []
    for key, pb in PROBLEMS.items():
        for m in _fixed(pb, settings):
            progress.set(f"{key}: {m}")
            points += sweep_fixed(pb, m, settings)
            progress()
        for m in ADAPTIVE_OURS + settings.scipy_methods:
            progress.set(f"{key}: {m}")
            points += sweep_adaptive(pb, m, settings)
            progress()
    ours = {m for pb in PROBLEMS.values() for m in pb.fixed} | set(ADAPTIVE_OURS)
    ratios = ratio_table(points, ours, set(ADAPTIVE_SCIPY))
    progress.set("ratios head to head")
    retime_ratios(ratios, points, PROBLEMS, settings)
    progress()

    progress.set("long runs (10^4 periods)")
    long_run = experiments.long_run_energy(1e4, 400, progress)
    progress.set("stability")
    stab = experiments.stability_points(progress)
    progress.set("per-step cost (numba and C)")
    per_step = experiments.per_step_costs(quick, progress)
    progress.set("exhibit defaults")
    exhibit = exhibits.choose_defaults(exhibit_cases, quick) if exhibit_cases else {}
    progress(3)
    progress.close()

    result = {
        "about": (
            "mechviz benchmark (issue 6). Errors: relative 2-norm of the final state against the "
            "reference (charge: normalised by the transverse part (x, y, vx, vy) of the exact "
            "state). Times: median wall time of Simulation.advance_to(T) after one untimed call, "
            "gc disabled, short calls repeated to >= 2 ms per sample; compile times separate. "
            "Ratios: the contenders of each side re-timed head to head in interleaved rounds."
        ),
        "command": "mechviz bench" + (" --quick" if quick else ""),
        "mode": "quick" if quick else "full",
        "date": started,
        "duration_s": round(time.perf_counter() - t_start, 1),
        "machine": machine(),
        "versions": versions(),
        "load_average": {"before": load_before, "after": _load()},
        "settings": {
            "repeats": settings.repeats,
            "min_sample_s": settings.min_sample,
            "cap_per_call_s": settings.cap,
            "energy_samples": settings.energy_samples,
            "fixed_step_factor": math.sqrt(2) if settings.half_steps else 2,
            "tolerances": list(settings.tolerances),
            "head_to_head_rounds": settings.head_to_head_rounds,
            "scipy_methods": list(settings.scipy_methods),
            "skipped_fixed_methods": list(settings.skip_fixed),
        },
        "problems": {
            k: {
                "title": pb.title,
                "t_end": pb.t_end,
                "state0": list(pb.state0),
                "floor": pb.floor,
                "reference": refs["problems"][k]["kind"],
                "reference_cross_check": refs["problems"][k].get("radau_1e-12"),
            }
            for k, pb in PROBLEMS.items()
        },
        "compile_s": compile_s,
        "points": [p.to_json() for p in points],
        "ratios": ratios,
        "targets": _targets(ratios, per_step),
        "long_run": long_run,
        "stability": stab,
        "per_step": per_step,
        "exhibits": exhibit,
    }
    if extras:
        result.update(extras)
    out.mkdir(parents=True, exist_ok=True)
    if charts:
        from . import charts as _charts

        result["charts"] = _charts.all_charts(result, out)
    from ..files import write_files_atomically
    from .report import markdown

    results = json.dumps(result, indent=1, default=_json_default) + "\n"
    write_files_atomically(
        out, {"tables.md": markdown(result).encode(), "results.json": results.encode()}
    )
    return result


def _json_default(x):
    if hasattr(x, "item"):
        return x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    raise TypeError(f"not JSON serialisable: {type(x)}")


def _targets(ratios: dict, per_step: dict) -> dict:
    speed = {}
    for key, row in ratios.items():
        for target, entry in row.items():
            r = entry.get("ratio")
            speed[f"{key} {target}"] = None if r is None else r >= 10.0
    cost = {name: row.get("within_2x_of_c") for name, row in per_step["rows"].items()}
    return {
        "ours_10x_faster_than_scipy": speed,
        "all_10x": all(v for v in speed.values() if v is not None)
        and all(v is not None for v in speed.values()),
        "step_within_2x_of_c": cost,
    }


def summary(result: dict) -> dict:
    """The short form ``mechviz bench --json`` prints."""
    ratios = {
        key: {
            t: (None if e.get("ratio") is None else round(e["ratio"], 1))
            for t, e in row.items()
        }
        for key, row in result["ratios"].items()
    }  # fmt: skip
    fastest = {
        key: {
            t: {
                "ours": e.get("ours"),
                "scipy": e.get("scipy"),
                "lower_bound": e.get("ratio_is_lower_bound"),
            }
            for t, e in row.items()
        }
        for key, row in result["ratios"].items()
    }  # fmt: skip
    return {
        "mode": result["mode"],
        "date": result["date"],
        "duration_s": result["duration_s"],
        "load_average": result["load_average"],
        "ratios": ratios,
        "fastest": fastest,
        "targets": result["targets"],
        "per_step_ns": {
            k: {"numba": round(v["numba_ns"], 1), "c": v.get("c_ns")}
            for k, v in result["per_step"]["rows"].items()
        },
        "exhibit_defaults": {
            k: None
            if v["chosen"] is None
            else {"method": v["chosen"]["method"], "dt": v["chosen"]["dt"]}
            for k, v in result["exhibits"].items()
        },
        "viewer": result.get("viewer"),
        "charts": result.get("charts"),
    }
