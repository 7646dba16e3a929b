"""Wall-clock timing of one benchmark point.

One untimed call first (it compiles and warms up, and its result is the one reported), then
``repeats`` timed samples with the garbage collector off; a call shorter than ``min_sample``
is repeated inside each sample until the sample lasts that long, and the sample is divided by
the number of calls. The median over samples is reported. (Quick runs take a call of 20 ms or
more as its own single sample; see :func:`time_calls`.)
"""

from __future__ import annotations

import gc
import math
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Timing:
    median: float  # seconds per call
    best: float  # fastest sample, seconds per call (less sensitive to other load)
    samples: int
    calls_per_sample: int
    first_call: float  # seconds of the untimed first call (includes any compilation)


def time_calls(
    make: Callable[[], Callable[[], object]],
    *,
    repeats: int = 5,
    min_sample: float = 2e-3,
    first_call: float | None = None,
    one_sample_from: float = math.inf,
) -> Timing:
    """Time ``make()()``: ``make`` builds a fresh call (untimed), the call itself is timed.

    ``first_call`` is the duration of an untimed call the caller already made (measured here
    otherwise). A call that took at least ``one_sample_from`` seconds is that one sample: a
    quick run's sweeps only place the points (its ratios are timed again head to head), and
    repeating the slowest calls, scipy's at tight tolerances, was most of its time. Such a first
    call compiles nothing: the bench compiles every method before it sweeps.
    """
    if first_call is None:
        fn = make()
        t0 = time.perf_counter()
        fn()
        first_call = time.perf_counter() - t0
    if first_call >= one_sample_from:
        return Timing(first_call, first_call, 1, 1, first_call)
    # How many calls make one sample of at least min_sample.
    per = 1 if first_call >= min_sample else max(1, int(min_sample / max(first_call, 1e-7)) + 1)
    if first_call >= 1.5:
        repeats = min(repeats, 3)
    samples = []
    was_enabled = gc.isenabled()
    try:
        for _ in range(repeats):
            calls = [make() for _ in range(per)]
            gc.disable()
            t0 = time.perf_counter()
            for fn in calls:
                fn()
            dt = time.perf_counter() - t0
            gc.enable()
            # Short calls: if this sample still fell short (first call was slow), add calls.
            if dt < min_sample and per < 10**6:
                per = max(per + 1, int(per * min_sample / max(dt, 1e-9)) + 1)
            samples.append(dt / len(calls))
    finally:
        if was_enabled:
            gc.enable()
        else:
            gc.disable()
    return Timing(statistics.median(samples), min(samples), len(samples), per, first_call)
