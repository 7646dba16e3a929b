"""Running an atlas on Dask: one task per chunk, each written to the store as it finishes.

:func:`run_atlas` submits every chunk not yet done to a Dask cluster (by default a
``distributed.LocalCluster`` of one single-threaded worker process per core; or the scheduler at
an address, or a ``distributed.Client`` the caller holds) and writes each result into the Zarr
store from this process, in the order the chunks finish. A task is a pure function of the spec
and the chunk index (:func:`.kernels.compute_chunk`), so a task lost with its worker is simply run
again by the scheduler, and a resumed run computes exactly the chunks not yet marked done.

Ctrl-C (``KeyboardInterrupt``) cancels every task still queued or running on the cluster, shuts
down a cluster this function started, and raises :class:`AtlasInterrupted` with what was kept.

:func:`compute_serial` computes the same atlas in this process, chunk by chunk, without Dask: the
reference the distributed result is compared with bit for bit.
"""

from __future__ import annotations

import contextlib
import logging
import os
import random
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr
from distributed.diagnostics.plugin import WorkerPlugin

from . import store as _store
from .grid import AtlasSpec
from .kernels import VARIABLES, compute_chunk

Chunk = tuple[int, int, int]


@dataclass
class RunReport:
    """What one call of :func:`run_atlas` did."""

    session: int  # the id written to chunk_session for every chunk this run computed
    computed: list[Chunk] = field(default_factory=list)  # in the order they were written
    skipped: list[Chunk] = field(default_factory=list)  # already done when it started
    total: int = 0
    workers: int = 0
    wall_seconds: float = 0.0
    task_seconds: float = 0.0  # the tasks' own time, summed
    task_cpu_seconds: float = 0.0  # the CPU time the tasks' threads got, summed
    interrupted: bool = False

    @property
    def complete(self) -> bool:
        return len(self.computed) + len(self.skipped) == self.total


class AtlasInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`run_atlas`: the cluster's work was cancelled; ``report`` says what
    was kept."""

    def __init__(self, report: RunReport) -> None:
        super().__init__("interrupted")
        self.report = report


def new_session() -> int:
    return random.SystemRandom().randrange(1, 2**62)


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None):
    """A ``distributed.Client``: of the scheduler at ``scheduler`` (``tcp://host:8786``), or of a
    new ``LocalCluster`` of ``workers`` single-threaded processes (default: one per core), closed
    on exit."""
    from distributed import Client, LocalCluster

    if scheduler:
        client = Client(scheduler, timeout="20s")
        try:
            yield client
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    with _workers_ignore_ctrl_c():
        cluster = LocalCluster(
            n_workers=n,
            threads_per_worker=1,
            processes=True,
            dashboard_address=None,
            silence_logs=logging.ERROR,
        )
    client = Client(cluster)
    client.register_plugin(_IgnoreCtrlC())  # and those a nanny starts again later
    try:
        yield client
    finally:
        # The cluster is ours to shut down: a worker whose heartbeat meets the scheduler already
        # closed logs that as an error with a traceback, on the user's terminal after a Ctrl-C
        # or a finished run. The workers' logs are quietened first (a worker already gone is
        # no matter); errors of the run itself reached the client before this.
        with contextlib.suppress(Exception):
            client.run(_quiet_logs)
        client.close()
        cluster.close()


def _quiet_logs() -> None:
    """In a worker process: only critical messages from Dask from now on."""
    logging.getLogger("distributed").setLevel(logging.CRITICAL)


@contextlib.contextmanager
def _workers_ignore_ctrl_c():
    """Worker processes started inside inherit an ignored SIGINT: a terminal's Ctrl-C reaches the
    whole process group, and it is this process's to handle (cancel, keep, shut the cluster
    down), not each worker's (a traceback apiece)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


class _IgnoreCtrlC(WorkerPlugin):
    """Worker plugin: the worker process ignores SIGINT (see :func:`_workers_ignore_ctrl_c`)."""

    name = "mechviz-ignore-ctrl-c"

    def setup(self, worker) -> None:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)


def run_atlas(
    spec: AtlasSpec,
    path: str | Path,
    *,
    client=None,
    scheduler: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    progress: bool = False,
    on_chunk: Callable[[Chunk, RunReport], None] | None = None,
) -> RunReport:
    """Compute ``spec`` into the Zarr store at ``path`` (a new one, or with ``resume`` the same
    run's, checked by its run key); returns what this call computed. Raises
    :class:`.store.StoreError` before any work for a store it may not use, and
    :class:`AtlasInterrupted` on Ctrl-C."""
    if resume:
        done = _store.open_for_resume(path, spec)
    else:
        _store.create(path, spec)
        done = np.zeros(spec.chunk_grid, dtype=bool)
    report = RunReport(new_session(), total=len(spec.chunks()))
    report.skipped = [c for c in spec.chunks() if done[c]]
    todo = [c for c in spec.chunks() if not done[c]]
    t0 = time.perf_counter()
    if not todo:
        _store.finish(path)
        return report
    with contextlib.ExitStack() as stack:
        if client is None:
            client = stack.enter_context(dask_client(scheduler, workers))
        report.workers = len(client.scheduler_info(n_workers=-1).get("workers", {}))
        bar = stack.enter_context(_progress(progress, len(todo), report.total - len(todo)))
        _run_tasks(client, spec, path, todo, report, bar, on_chunk)
    _store.finish(path)  # every chunk is done: readers open it in one read
    report.wall_seconds = time.perf_counter() - t0
    return report


def _run_tasks(client, spec, path, todo, report, bar, on_chunk) -> None:
    from distributed import as_completed

    key = spec.run_key()
    futures = {}
    try:
        with _ctrl_c_between_chunks() as stop:
            for c in todo:
                name = f"atlas-{key}-{c[0]}-{c[1]}-{c[2]}"
                fut = client.submit(compute_chunk, spec, c, key=name, pure=False)
                futures[fut] = c
            for fut, cells in as_completed(list(futures), with_results=True):
                if stop.is_set():  # results that finished meanwhile are not written
                    raise KeyboardInterrupt
                c = futures.pop(fut)
                _store.write_chunk(path, spec, c, cells, report.session)
                report.computed.append(c)
                report.task_seconds += float(cells["seconds"])
                report.task_cpu_seconds += float(cells.get("cpu_seconds", 0.0))
                bar.update(1)
                if on_chunk is not None:
                    on_chunk(c, report)
                if stop.is_set():
                    raise KeyboardInterrupt
    except KeyboardInterrupt:
        report.interrupted = True
        with contextlib.suppress(Exception):
            client.cancel(list(futures), force=True)
        raise AtlasInterrupted(report) from None


@contextlib.contextmanager
def _ctrl_c_between_chunks():
    """Ctrl-C sets the event this yields, and the loop stops at the next chunk: a
    ``KeyboardInterrupt`` raised inside a chunk's write (the Zarr store waits on its own event
    loop, which can hold the exception until the write is done) would otherwise let every
    finished result be written before the run stops. A second Ctrl-C raises at once."""
    stop = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def on_sigint(signum, frame) -> None:
        if stop.is_set():
            raise KeyboardInterrupt
        stop.set()

    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        yield stop
    finally:
        signal.signal(signal.SIGINT, previous)


@contextlib.contextmanager
def _progress(enabled: bool, total: int, initial: int):
    """A tqdm bar on stderr counting chunks (silent when not ``enabled`` and where stderr is
    not a terminal: a bar's redraws in a log or a pipe are noise)."""
    from tqdm import tqdm

    bar = tqdm(
        total=total + initial,
        initial=initial,
        unit="chunk",
        desc="mechviz atlas",
        disable=not (enabled and sys.stderr.isatty()),
        file=sys.stderr,
    )
    try:
        yield bar
    finally:
        bar.close()


def compute_serial(spec: AtlasSpec) -> xr.Dataset:
    """The whole atlas computed in this process without Dask (bookkeeping left empty)."""
    ds = _store.template(spec)
    for c in spec.chunks():
        k, rows, cols = spec.cells(c)
        cells = compute_chunk(spec, c)
        for name in VARIABLES[spec.kind]:
            ds[name].values[k, rows, cols] = cells[name]
    return ds
