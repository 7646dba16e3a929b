"""The server-side cost of the viewer's frames, with no loop thread and no browser, for
``mechviz bench``."""

from __future__ import annotations

import time

import numpy as np

from mechviz.viz.app import MechvizApp, warm_up
from mechviz.viz.model import MODELS


def measure_frame_cost(
    n_frames: int = 300, *, warmup_frames: int = 30, compare: bool = False
) -> dict:
    """Server-side milliseconds per frame with all three exhibits and their trails, no browser.

    The app runs headless on a free port without its loop thread; each frame is what the live
    loop does (commands, one ``dynamics`` call per simulation, drawing inside ``server.atomic()``,
    staggered GUI readouts), timed with ``time.perf_counter``. The exhibits start from
    their configs' defaults (trails on the charge and the bead); ``compare=True`` adds a
    comparison run (and its trail) to the charge and the hoop. Returns median, p95, mean and max
    [ms] and the number of trail segments drawn at the end.
    """
    configs = {}
    if compare:  # the comparison each exhibit's model names for this measurement
        configs = {
            key: cls.Config(compare_method=cls.frame_cost_compare)
            for key, cls in MODELS.items()
            if cls.frame_cost_compare is not None
        }
    warm_up("defaults", configs)
    app = MechvizApp(port=0, configs=configs, start_loop=False)
    try:
        for _ in range(warmup_frames):
            app.step_frame()
        times = []
        for _ in range(n_frames):
            t0 = time.perf_counter()
            app.step_frame()
            times.append(1e3 * (time.perf_counter() - t0))
        trails = sum(
            getattr(ex, name).n_segments
            for ex in app.exhibits.values()
            for name in ("trail", "compare_trail", "cmp_trail")
            if hasattr(ex, name)
        )
    finally:
        app.stop()
    a = np.asarray(times)
    return {
        "n_frames": int(n_frames),
        "median_ms": float(np.median(a)),
        "p95_ms": float(np.percentile(a, 95)),
        "mean_ms": float(a.mean()),
        "max_ms": float(a.max()),
        "trail_segments": int(trails),
        "compare": bool(compare),
    }
