"""What an endurance run measured, summarised: frame-rate windows, the memory trend, the
pass/fail verdict against the targets, and the one-screen text of it
(:func:`mechviz.bench.endurance.run_endurance` writes these)."""

from __future__ import annotations

import datetime
import os
import platform

import numpy as np

TARGET_FPS = 59.0  # every window must reach this rate (the loop aims at 60)
TARGET_RSS_SLOPE = 1.0  # MB/min, |linear trend| over the second half of the run


def frame_windows(
    start: np.ndarray, cost_ms: np.ndarray, t0: float, t1: float, window_s: float, fps: float
) -> list[dict]:
    """Per window of ~``window_s`` s in ``[t0, t1)`` (equal widths): frames, rate, frame period
    (start to start: mean, p99, max), server cost (median, p99), frames over the ``1/fps``
    budget (cost) and late frames (period over 1.5 budgets)."""
    budget_ms = 1e3 / fps
    n = max(1, round((t1 - t0) / window_s))
    width = (t1 - t0) / n
    period_ms = np.diff(start) * 1e3  # period_ms[i - 1]: from frame i - 1 to frame i
    out = []
    for k in range(n):
        a, b = t0 + k * width, t0 + (k + 1) * width
        idx = np.nonzero((start >= a) & (start < b))[0]
        per = period_ms[idx[idx > 0] - 1]
        cost = cost_ms[idx]
        out.append(
            {
                "t_s": round(a - t0, 3),
                "seconds": round(width, 3),
                "frames": int(len(idx)),
                "fps": round(len(idx) / width, 3),
                "period_mean_ms": _r(per.mean()) if len(per) else None,
                "period_p99_ms": _r(np.percentile(per, 99)) if len(per) else None,
                "period_max_ms": _r(per.max()) if len(per) else None,
                "cost_median_ms": _r(np.median(cost)) if len(cost) else None,
                "cost_p99_ms": _r(np.percentile(cost, 99)) if len(cost) else None,
                "over_budget": int((cost > budget_ms).sum()),
                "late": int((per > 1.5 * budget_ms).sum()),
            }
        )
    return out


def rss_trend(t_s: np.ndarray, rss_mb: np.ndarray) -> float | None:
    """Least-squares slope [MB/min] of RSS over the second half of the samples' time span."""
    t_s, rss_mb = np.asarray(t_s, float), np.asarray(rss_mb, float)
    if len(t_s) < 3:
        return None
    half = t_s >= t_s[0] + 0.5 * (t_s[-1] - t_s[0])
    if half.sum() < 2 or np.ptp(t_s[half]) <= 0:
        return None
    return float(np.polyfit(t_s[half] / 60.0, rss_mb[half], 1)[0])


def _r(x: float, digits: int = 3) -> float:
    return round(float(x), digits)


def _summarize(
    data: dict,
    *,
    t0: float,
    t1: float,
    frames,
    seconds,
    clients,
    clients_seen,
    page_checks,
    window_s,
    rss_every_s,
    settle_s,
    viewport,
    environment_map,
    client_limits,
    load,
    wall_s,
    started,
) -> dict:
    import viser

    fps = float(data["fps"])
    start, cost = np.asarray(data["start"]), np.asarray(data["cost_ms"])
    cpu_ms = np.asarray(data["cpu_ms"])
    inside = (start >= t0) & (start < t1)
    windows = frame_windows(start, cost, t0, t1, window_s, fps)
    per = np.diff(start[inside]) * 1e3
    s = np.asarray(data["samples"], float).reshape(-1, 6)
    s = s[(s[:, 0] >= t0 - rss_every_s) & (s[:, 0] <= t1 + rss_every_s)]
    rss_t = s[:, 0] - t0
    slope = rss_trend(rss_t, s[:, 1])
    cpu = None
    if len(s) >= 2 and s[-1, 0] > s[0, 0]:
        cpu = 100.0 * (s[-1, 2] - s[0, 2]) / (s[-1, 0] - s[0, 0])
    min_fps = min(w["fps"] for w in windows)
    fps_ok = min_fps >= TARGET_FPS
    rss_ok = slope is not None and abs(slope) < TARGET_RSS_SLOPE
    clients_ok = (
        data["final_clients"] >= clients
        and all(c["connected"] and c["advancing"] for c in page_checks)
        and len(page_checks) == clients
    )
    return {
        "about": "mechviz endurance benchmark: the live viewer's server loop with "
        "headless Chromium clients connected; see bench/endurance.py",
        "command": f"mechviz bench --endurance {seconds:g} --clients {clients}",
        "date": datetime.datetime.fromtimestamp(started, datetime.UTC).strftime(
            "%Y-%m-%dT%H:%M:%SZ"
        ),
        "machine": {
            "platform": platform.platform(),
            "cpus": os.cpu_count(),
            "python": platform.python_version(),
            "viser": viser.__version__,
        },
        "load_average": {
            "before": [round(x, 2) for x in load[0]],
            "after": [round(x, 2) for x in load[1]],
        },
        "config": {
            "seconds": seconds,
            "clients": clients,
            "window_s": window_s,
            "rss_every_s": rss_every_s,
            "settle_s": settle_s,
            "viewport": list(viewport),
            "environment_map": environment_map,
            "client_cpus": client_limits["cpus"],
            "server_cpus": client_limits.get("server_cpus"),
            "client_nice": client_limits["nice"],
            "target_fps": fps,
        },
        "wall_s": round(wall_s, 1),
        "frames": {
            "measured": int(inside.sum()),
            "loop_frames": int(frames[1] - frames[0]),  # the loop's own count over the span
            "expected": int(round(fps * (t1 - t0))),
            "span_s": round(t1 - t0, 3),
            "fps": round(float(inside.sum()) / (t1 - t0), 3),
            "period_mean_ms": _r(per.mean()) if len(per) else None,
            "period_p99_ms": _r(np.percentile(per, 99)) if len(per) else None,
            "period_max_ms": _r(per.max()) if len(per) else None,
            "cost_median_ms": _r(np.median(cost[inside])) if inside.any() else None,
            "cost_p99_ms": _r(np.percentile(cost[inside], 99)) if inside.any() else None,
            "cost_max_ms": _r(cost[inside].max()) if inside.any() else None,
            "over_budget": int((cost[inside] > 1e3 / fps).sum()),
            # of those, frames whose loop-thread CPU time alone exceeded the budget (the rest
            # waited: for the interpreter lock or for a core)
            "over_budget_cpu": int((cpu_ms[inside] > 1e3 / fps).sum()),
            "cpu_median_ms": _r(np.median(cpu_ms[inside])) if inside.any() else None,
            "cpu_p99_ms": _r(np.percentile(cpu_ms[inside], 99)) if inside.any() else None,
            "late": int((per > 1.5e3 / fps).sum()),
            "log_dropped": int(data["dropped"]),
        },
        "windows": windows,
        "memory": {
            "rss_mb": [[_r(t, 1), _r(m, 2)] for t, m in zip(rss_t, s[:, 1], strict=True)],
            "start_mb": _r(s[0, 1], 2) if len(s) else None,
            "end_mb": _r(s[-1, 1], 2) if len(s) else None,
            "max_mb": _r(s[:, 1].max(), 2) if len(s) else None,
            "slope_mb_per_min_second_half": None if slope is None else _r(slope, 4),
        },
        "server_cpu_percent": None if cpu is None else _r(cpu, 1),
        "server_gc": {  # Python's garbage collector in the server process, whole run
            f"gen{g}": {"collections": n, "total_ms": _r(tot, 1), "max_ms": _r(mx, 2)}
            for g, (n, tot, mx) in data["gc"].items()
        },
        "clients": {
            "requested": clients,
            "viser_clients_at_start": int(clients_seen[0]),
            "viser_clients_at_end": int(clients_seen[1]),
            "viser_clients_before_stop": int(data["final_clients"]),
            "pages": page_checks,
        },
        "targets": {
            "min_window_fps": TARGET_FPS,
            "rss_slope_mb_per_min": TARGET_RSS_SLOPE,
            "fps_met": bool(fps_ok),
            "memory_met": bool(rss_ok),
            "clients_met": bool(clients_ok),
            "met": bool(fps_ok and rss_ok and clients_ok),
            "min_window_fps_measured": min_fps,
        },
    }


def format_summary(r: dict) -> str:
    """A one-screen text summary of :func:`run_endurance`'s result."""
    f, m, c, t = r["frames"], r["memory"], r["clients"], r["targets"]

    def ok(flag: bool) -> str:
        return "PASS" if flag else "FAIL"

    w = r["windows"]
    fps = [x["fps"] for x in w]
    written = r.get("written_to")
    lines = [
        f"mechviz endurance ({r['date']}, {r['config']['seconds']:g} s, {c['requested']} client(s), "
        f"load {r['load_average']['before'][0]} -> {r['load_average']['after'][0]})",
        f"  frames   {f['measured']} of {f['expected']} expected over {f['span_s']:.1f} s "
        f"= {f['fps']:.2f} fps; period mean {f['period_mean_ms']} ms, p99 "
        f"{f['period_p99_ms']} ms, max {f['period_max_ms']} ms",
        f"  cost     median {f['cost_median_ms']} ms, p99 {f['cost_p99_ms']} ms, max "
        f"{f['cost_max_ms']} ms; over the {1e3 / r['config']['target_fps']:.1f} ms budget: "
        f"{f['over_budget']} ({f['over_budget_cpu']} of them by CPU time); late periods "
        f"(> 1.5 budgets): {f['late']}",
        f"  loop CPU median {f['cpu_median_ms']} ms, p99 {f['cpu_p99_ms']} ms per frame",
        f"  windows  {len(w)} x {w[0]['seconds']:.1f} s: fps min {min(fps):.2f}, "
        f"max {max(fps):.2f}; worst p99 period "
        f"{max((x['period_p99_ms'] or 0) for x in w):.2f} ms",
        f"  memory   RSS {m['start_mb']} -> {m['end_mb']} MB (max {m['max_mb']}); trend over "
        f"the second half {m['slope_mb_per_min_second_half']} MB/min",
        f"  server   CPU {r['server_cpu_percent']} % of one core",
        f"  clients  viser counted {c['viser_clients_at_start']} at start, "
        f"{c['viser_clients_at_end']} at end; pages: "
        + ", ".join(
            f"{'connected' if p['connected'] else 'DISCONNECTED'} "
            f"t {p['sim_time'][0]} -> {p['sim_time'][1]} s"
            for p in c["pages"]
        ),
        f"  {ok(t['fps_met'])}  every window >= {t['min_window_fps']:g} fps "
        f"(min {t['min_window_fps_measured']:.2f})",
        f"  {ok(t['memory_met'])}  |RSS trend| < {t['rss_slope_mb_per_min']:g} MB/min "
        f"({m['slope_mb_per_min_second_half']})",
        f"  {ok(t['clients_met'])}  every client connected, simulated time advancing",
        f"  overall: {ok(t['met'])}" + (f"; written to {written}" if written else ""),
    ]
    return "\n".join(lines)
