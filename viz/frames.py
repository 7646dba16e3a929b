"""The live loop's record of its frames: when each started and what it cost.

:class:`FrameLog` is written by the viewer's loop thread once per frame and read by anyone (the
endurance benchmark reads it while browsers watch).
"""

from __future__ import annotations

import math

import numpy as np


class FrameLog:
    """Start time (``time.perf_counter``, s), server-side cost (wall ms) and the loop thread's CPU
    time in it (ms) of the last ``capacity`` frames, in preallocated arrays: written by the loop
    thread once per frame, read by anyone. A cost well above its CPU time is time the thread
    waited (for the interpreter lock, or for a core).

    ``count`` is the number of frames ever logged; :meth:`since` returns the frames from a given
    index on (those still held), so a reader polling more often than ``capacity`` frames (136 s
    at 60 Hz by default) sees every frame exactly once.
    """

    def __init__(self, capacity: int = 8192) -> None:
        self.capacity = int(capacity)
        self.start = np.zeros(self.capacity)
        self.cost_ms = np.zeros(self.capacity)
        self.cpu_ms = np.zeros(self.capacity)
        self.count = 0

    def add(self, start: float, cost_ms: float, cpu_ms: float = math.nan) -> None:
        i = self.count % self.capacity
        self.start[i] = start
        self.cost_ms[i] = cost_ms
        self.cpu_ms[i] = cpu_ms
        self.count += 1

    def since(self, first: int) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """``(index of the first frame returned, starts, costs, cpu times)`` for frames
        ``first ..``; the index is larger than ``first`` when older frames were overwritten."""
        n = self.count
        lo = max(int(first), n - self.capacity + 1, 0)  # slot n may be being rewritten
        idx = np.arange(lo, n) % self.capacity
        return lo, self.start[idx], self.cost_ms[idx], self.cpu_ms[idx]


def refresh_frames(phases: dict[str, int], cycle: int, taken: tuple[int, ...]) -> dict[str, int]:
    """Each exhibit's refresh frame in a GUI cycle of ``cycle`` frames: the first after the
    previous exhibit's (in order) where it was just measured (``frame % 3`` its phase) and the
    status line is not pushed (``taken``), so the refreshes spread over the cycle; any free frame
    of its phase once the cycle is used up."""
    out: dict[str, int] = {}
    last = -1
    for key, phase in phases.items():
        free = [k for k in range(cycle) if k % 3 == phase and k not in taken]
        if not free:
            raise ValueError(f"no frame of phase {phase} in a GUI cycle of {cycle} for {key}")
        out[key] = next((k for k in free if k > last), free[0])
        last = out[key]
    return out
