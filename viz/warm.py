"""Compiling ahead: the numba kernels a method needs, once per process, before a frame needs them.

A method's first run compiles its kernels (0.2-3 s). The viewer compiles the ones its exhibits
start with before it serves, the rest in the background, and a method picked in the GUI in the
callback's thread, so no frame of the simulation loop waits for the compiler.
"""

from __future__ import annotations

import contextlib
import signal
import threading
import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import numpy as np

from mechviz import dynamics
from mechviz.dynamics._spawn import spawned_workers_ignore_ctrl_c
from mechviz.dynamics.results import REFERENCE_METHOD

from .model import MODELS

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
        (s, m.name)
        for s in systems
        for m in dynamics.methods_for(dynamics.SYSTEMS[s])
        if m.backend != "scipy"
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


_HELD_SIGNALS = {getattr(signal, n) for n in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, n)}


@contextlib.contextmanager
def _quiet_start():
    """While workers start: Ctrl-C, SIGTERM and SIGHUP noted here rather than handled, so a
    signal that comes then does not leave workers half started, and none is lost: the first
    noted is raised again as this ends. The workers themselves ignore Ctrl-C until their set-up
    (:func:`mechviz.dynamics._spawn.spawned_workers_ignore_ctrl_c`): a spawned interpreter
    inherits neither this mask nor these handlers, and one interrupted while it imports prints
    ``Fatal Python error`` into the terminal.

    The mask alone does not hold them here: it is this thread's, and the kernel hands a signal
    sent to the process to any thread that does not block it (numpy's BLAS threads, started
    before), whose handler then raises in this thread all the same, in the middle of a worker's
    start (a worker whose parent stopped writing its start-up data fails reading it, with a
    traceback). So the handlers are also replaced by ones that only note the signal."""
    if not hasattr(signal, "pthread_sigmask"):  # Windows: no masks, nothing held
        yield
        return
    noted: list[int] = []
    previous = {}
    if threading.current_thread() is threading.main_thread():
        previous = {
            s: signal.signal(s, lambda signum, frame: noted.append(signum)) for s in _HELD_SIGNALS
        }
    held = signal.pthread_sigmask(signal.SIG_BLOCK, _HELD_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)
        for s, handler in previous.items():
            signal.signal(s, handler if handler is not None else signal.SIG_DFL)
        if noted:
            signal.raise_signal(noted[0])


def _end_with_parent(parent: int) -> None:
    """A worker's set-up: Ctrl-C (sent to the whole process group) ends it at once, and so does
    the end of ``parent`` (the process that started it), however that ends: SIGKILL included.
    numba's compiler would swallow the ``KeyboardInterrupt``, and its cache files are written
    whole (renamed into place), so nothing is left half-written."""
    import os

    signal.signal(signal.SIGINT, lambda signum, frame: os._exit(130))
    signal.signal(signal.SIGTERM, lambda signum, frame: os._exit(143))
    with contextlib.suppress(OSError, AttributeError):  # Linux: the kernel tells us
        import ctypes

        pr_set_pdeathsig = 1
        ctypes.CDLL(None, use_errno=True).prctl(pr_set_pdeathsig, signal.SIGTERM)

    def watch() -> None:  # elsewhere (and if the parent ended before prctl): poll for it
        while os.getppid() == parent:
            time.sleep(0.5)
        os._exit(143)

    threading.Thread(target=watch, name="mechviz-parent-watch", daemon=True).start()


def _warm_chunk(pairs: list[tuple[str, str]], parent: int) -> None:
    """A worker process: compile ``pairs``, Taylor's parallel ensemble loop included; it ends
    with ``parent`` (:func:`_end_with_parent`)."""
    _end_with_parent(parent)
    from mechviz.dynamics.integrators import taylor

    # this process only: the single-state warm-up takes the serial loop, the two-member one
    # the parallel loop (which ensembles of ``PARALLEL_MIN`` members or more use)
    taylor.PARALLEL_MIN = 2
    warm_all(pairs)


def fill_cache_in_parallel(
    workers: int | None = None, meanwhile: Callable[[], object] | None = None
) -> tuple[float, int]:
    """Fill numba's on-disk cache with every compiled method, split over ``workers`` processes
    (default: one per core); returns (wall seconds, processes used).

    From an empty cache one process compiles everything in about 49 s here, two in 28 s; a
    process that then needs a kernel loads it from disk. Once this has run for this source
    checkout and cache (a stamp file says so) no process is started: loading a warm cache in
    extra processes only costs time. A checkout whose files were touched since may still find
    stale entries; numba then compiles those where they are first called, as without this step.
    ``meanwhile`` runs in this process while the workers compile (compilation this process
    needs and cannot cache, such as a peer's).
    """
    import hashlib
    import multiprocessing
    import os
    import tempfile
    from pathlib import Path

    import numba

    where = str(Path(dynamics.__file__).resolve().parent)
    stamp = (
        Path(numba.config.CACHE_DIR) / f"filled-{hashlib.sha256(where.encode()).hexdigest()[:16]}"
    )
    t0 = time.perf_counter()
    if stamp.exists():
        if meanwhile is not None:
            meanwhile()
        return time.perf_counter() - t0, 0
    pairs = every_method(dynamics.SYSTEMS)
    n = max(1, min(workers or os.cpu_count() or 1, len(pairs)))
    # spawn, not fork: a forked child would share this process's numba and threading state
    context = multiprocessing.get_context("spawn")
    procs: list = []
    scratch = tempfile.TemporaryDirectory(prefix="mechviz-warm-")
    try:
        with _quiet_start(), spawned_workers_ignore_ctrl_c(scratch.name):
            for i in range(n):
                proc = context.Process(
                    target=_warm_chunk,
                    args=(pairs[i::n], os.getpid()),
                    name=f"mechviz-warm-{i}",
                    daemon=True,
                )
                procs.append(proc)
                proc.start()
        if meanwhile is not None:
            meanwhile()
        for p in procs:
            p.join()
        failed = [p.name for p in procs if p.exitcode != 0]
        if failed:
            raise RuntimeError(f"compiling ahead failed in {', '.join(failed)} (its error above)")
    except BaseException:  # Ctrl-C, SIGTERM, a failure: the workers end now, not when done
        for p in procs:
            if p.is_alive():
                p.terminate()
        raise
    finally:
        for p in procs:
            if p.pid is not None:
                p.join()
        scratch.cleanup()
    stamp.parent.mkdir(parents=True, exist_ok=True)
    stamp.touch()
    return time.perf_counter() - t0, n


def warm_up(
    which: str = "defaults",
    configs: Mapping[str, Any] | None = None,
    should_stop: Callable[[], bool] | None = None,
) -> float:
    """Compile the kernels the exhibits start with (``"defaults"``) or every method (``"all"``).

    ``should_stop`` is polled between methods (Ctrl-C during start-up)."""
    if which == "all":
        systems = {cls.Config.system_name for cls in MODELS.values()}
        return warm_all(every_method(sorted(systems)), should_stop)
    cfg = configs or {}
    # the tight reference runs of the systems without an exact solution everywhere (the
    # registry's adapters say which)
    needed = dynamics.registry.reference_runs(REFERENCE_METHOD)
    for key, cls in MODELS.items():
        c = cfg.get(key) or cls.Config()
        needed.append((c.system_name, c.method))
        if getattr(c, "compare_method", None):
            needed.append((c.system_name, c.compare_method))
    return warm_all(needed, should_stop)
