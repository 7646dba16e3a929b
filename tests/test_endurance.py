"""The viewer's endurance benchmark (``mechviz bench --endurance``): its bookkeeping, and a short
smoke run with one headless Chromium client.

Nothing here checks a speed: the targets (60 fps for 10 minutes, flat memory) are measured by the
benchmark itself, never by a test.
"""

from __future__ import annotations

import json

import browser
import numpy as np
import pytest

from mechviz.bench.endurance import frame_windows, rss_trend
from mechviz.viz.frames import FrameLog


def test_frame_log_returns_every_frame_once_and_skips_what_was_overwritten():
    log = FrameLog(capacity=8)
    for k in range(5):
        log.add(float(k), 1.0 + k, 0.5)
    first, start, cost, cpu = log.since(0)
    assert first == 0 and list(start) == [0, 1, 2, 3, 4] and list(cost) == [1, 2, 3, 4, 5]
    assert list(cpu) == [0.5] * 5
    for k in range(5, 20):
        log.add(float(k), 1.0, 0.5)
    first, start, _, _ = log.since(5)  # frames 5..11 were overwritten meanwhile
    assert first == 20 - 8 + 1 and list(start) == list(range(first, 20))
    assert log.since(20)[1].size == 0


def test_windows_count_frames_periods_and_frames_over_budget():
    fps = 60.0
    start = np.arange(0.0, 20.0, 1 / fps)  # 20 s of regular frames ...
    start = np.delete(start, np.arange(700, 760))  # ... with one second missing at t = 11.7 s
    cost = np.full(len(start), 2.0)
    cost[10] = 20.0  # one frame over the 16.7 ms budget, in the first window
    w = frame_windows(start, cost, 0.0, 20.0, 10.0, fps)
    assert [x["frames"] for x in w] == [600, 540]
    assert w[0]["fps"] == pytest.approx(60.0) and w[1]["fps"] == pytest.approx(54.0)
    assert w[0]["over_budget"] == 1 and w[1]["over_budget"] == 0
    assert w[0]["late"] == 0 and w[1]["late"] == 1
    assert w[1]["period_max_ms"] == pytest.approx(61 / fps * 1e3)


def test_rss_trend_is_the_slope_over_the_second_half_in_mb_per_minute():
    t = np.arange(0.0, 600.0, 2.0)
    rss = np.where(t < 300, 200 + 0.1 * t, 230 + 0.5 * t / 60)  # warm-up growth, then 0.5 MB/min
    assert rss_trend(t, rss) == pytest.approx(0.5)
    assert rss_trend(t[:2], rss[:2]) is None


@pytest.mark.browser
def test_short_endurance_run_reports_windows_memory_and_a_connected_client(tmp_path):
    browser.require_browser()
    from mechviz.bench.endurance import format_summary, run_endurance

    out = tmp_path / "endurance.json"
    r = run_endurance(
        2, 1, out=out, window_s=1.0, rss_every_s=0.5, settle_s=0.0, check_s=0.5, warm=False
    )
    assert set(r) >= {"config", "frames", "windows", "memory", "clients", "targets", "machine"}
    assert r["frames"]["measured"] > 0 and r["frames"]["log_dropped"] == 0
    assert len(r["windows"]) == 2 and all(w["frames"] > 0 for w in r["windows"])
    assert len(r["memory"]["rss_mb"]) >= 2 and r["memory"]["start_mb"] > 0
    assert r["clients"]["requested"] == 1 and r["clients"]["viser_clients_at_end"] == 1
    (page,) = r["clients"]["pages"]
    assert page["connected"] and page["advancing"]
    assert {"fps_met", "memory_met", "clients_met", "met"} <= set(r["targets"])
    saved = json.loads(out.read_text())
    assert saved["frames"] == r["frames"] and saved["windows"] == r["windows"]
    assert "PASS" in format_summary(r) or "FAIL" in format_summary(r)
