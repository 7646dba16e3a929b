"""Compiling ahead: the numba kernels a method needs, once per process, before a frame needs them.

A method's first run compiles its kernels (0.2-3 s). The viewer compiles the ones its exhibits
start with before it serves, the rest in the background, and a method picked in the GUI in the
callback's thread, so no frame of the simulation loop waits for the compiler.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable, Iterable

import numpy as np

import dynamics

_lock = threading.Lock()
_done: set[tuple[str, str]] = set()


def warm_method(system_name: str, method: str) -> float:
    """Compile (once per process) what ``method`` needs on ``system_name``; returns seconds spent."""
    key = (system_name, method)
    if key in _done:
        return 0.0
    t0 = time.perf_counter()
    with _lock:
        if key in _done:
            return 0.0
        system = dynamics.SYSTEMS[system_name]()
        m = dynamics.get_method(method)
        if m.backend != "scipy":
            s0 = system.default_state()
            for state in (s0, np.tile(s0, (2, 1))):  # single and batched calls
                sim = dynamics.Simulation(
                    system, m, state=state, reference=None, **m.step_options(1e-3, 1e-6)
                )
                sim.advance(2e-3)
        _done.add(key)
    return time.perf_counter() - t0


def every_method(systems: Iterable[str]) -> list[tuple[str, str]]:
    """``(system, method)`` for every compiled method of ``systems``."""
    return [
        (s, m.name) for s in systems for m in dynamics.methods_for(s) if m.backend != "scipy"
    ]


def warm_all(
    needed: Iterable[tuple[str, str]], should_stop: Callable[[], bool] | None = None
) -> float:
    """Compile each ``(system, method)``; ``should_stop`` is polled between them (Ctrl-C)."""
    t0 = time.perf_counter()
    for system_name, method in needed:
        if should_stop is not None and should_stop():
            break
        warm_method(system_name, method)
    return time.perf_counter() - t0
