"""Running an atlas on Dask: one task per chunk, each written to the store as it finishes.

:func:`run_atlas` submits every chunk not yet done to a Dask cluster (by default a
``distributed.LocalCluster`` of one single-threaded worker process per core; or the scheduler at
an address, or a ``distributed.Client`` the caller holds) and writes each result into the Zarr
store from this process, in the order the chunks finish. A task is a pure function of the spec
and the chunk index (:func:`.kernels.compute_chunk`), so a task lost with its worker is simply run
again by the scheduler, and a resumed run computes exactly the chunks not yet marked done.

Ctrl-C, SIGTERM and SIGHUP are seen within :data:`POLL_SECONDS` whatever the length of a chunk:
every task still queued or running on the cluster is cancelled, a cluster this function started
has its workers killed (a worker inside a compiled slice would answer a polite close only when
the slice ends) and its temporary folder removed, and :class:`AtlasInterrupted` says what was
kept. Only one run works on a store's folder at a time (:func:`.store.locked`); a resumed run
keeps only the chunks it verifies (:func:`.store.open_for_resume`).

:func:`compute_serial` computes the same atlas in this process, chunk by chunk, without Dask: the
reference the distributed result is compared with bit for bit.
"""

from __future__ import annotations

import contextlib
import logging
import os
import random
import shutil
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import xarray as xr
from distributed.diagnostics.plugin import WorkerPlugin

from .._spawn import spawned_workers_ignore_ctrl_c
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
    signum: int = 0  # the signal that interrupted it

    @property
    def complete(self) -> bool:
        return len(self.computed) + len(self.skipped) == self.total


class ClusterError(RuntimeError):
    """The Dask cluster could not be reached or started (one line saying why)."""


class AtlasInterrupted(KeyboardInterrupt):
    """Ctrl-C during :func:`run_atlas`: the cluster's work was cancelled; ``report`` says what
    was kept."""

    def __init__(self, report: RunReport) -> None:
        super().__init__("interrupted")
        self.signum = report.signum or signal.SIGINT
        self.report = report


def new_session() -> int:
    return random.SystemRandom().randrange(1, 2**62)


#: Seconds a shutdown after a signal may take before the workers are killed and the process
#: exits at once (the run's chunks are on disk by then; only the cluster's goodbyes are cut).
HARD_EXIT_SECONDS = 3.0
#: How often [s] the loop that writes finished chunks looks for a signal.
POLL_SECONDS = 0.05


@contextlib.contextmanager
def dask_client(scheduler: str | None = None, workers: int | None = None):
    """A ``distributed.Client``: of the scheduler at ``scheduler`` (``tcp://host:8786``), or of a
    new ``LocalCluster`` of ``workers`` single-threaded processes (default: one per core), closed
    on exit. A cluster started here keeps its workers' files in a temporary folder of its own,
    removed with it, and its workers are killed on the way out rather than asked to finish (a
    task inside compiled code would hold them for its whole length)."""
    import dask
    from distributed import Client, LocalCluster

    if scheduler:
        try:
            client = Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise ClusterError(f"--scheduler {scheduler}: {exc}") from None
        try:
            yield client
        finally:
            client.close()
        return
    n = workers or os.cpu_count() or 1
    scratch = cluster = client = None
    try:  # (from before the folder is made: a Ctrl-C may now come at any instruction)
        scratch = tempfile.mkdtemp(prefix="mechviz-atlas-")
        _LIVE_SCRATCH.append(scratch)
        # the workers' interpreter ignores Ctrl-C for the cluster's whole life: a nanny starts a
        # lost worker again with it
        with spawned_workers_ignore_ctrl_c(scratch):
            before = _children()
            try:
                # the scheduler's scratch folder too (it reads the configuration, not an argument)
                with dask.config.set({"temporary-directory": scratch}):
                    cluster = LocalCluster(
                        n_workers=n,
                        threads_per_worker=1,
                        processes=True,
                        dashboard_address=None,
                        worker_dashboard_address=None,
                        silence_logs=logging.ERROR,
                        local_directory=scratch,
                        # set up as each worker starts (registering it on the client instead is
                        # a broadcast that a Ctrl-C could cut in the middle)
                        plugins={_IgnoreCtrlC()},
                    )
                _LIVE_CLUSTERS.append(cluster)
                client = Client(cluster)
            except BaseException:
                # a start cut short (Ctrl-C, or a worker that failed): its processes, those of
                # workers not yet registered included, go before their folder
                _kill_new_children(before)
                _shut_down(client, cluster)
                raise
            try:
                yield client
            finally:
                _shut_down(client, cluster)
    finally:
        if scratch is not None:
            shutil.rmtree(scratch, ignore_errors=True)
        with contextlib.suppress(ValueError):
            _LIVE_CLUSTERS.remove(cluster)
        with contextlib.suppress(ValueError):
            _LIVE_SCRATCH.remove(scratch)


def _children() -> set[int]:
    """The pids of this process's children, grandchildren and so on."""
    import psutil

    return {p.pid for p in psutil.Process().children(recursive=True)}


def _kill_new_children(before: set[int]) -> None:
    """SIGKILL every descendant of this process not in ``before`` but multiprocessing's resource
    tracker (one a process keeps for its life: killed, it is started again and prints a
    traceback for each name it was not told of). The cluster's start tasks whose worker died
    fail unread: the ``asyncio`` log's "Task exception was never retrieved" for them is dropped,
    as the interruption is said in its own line."""
    import psutil

    for pid in _children() - before:
        with contextlib.suppress(OSError, psutil.Error):
            if "resource_tracker" not in " ".join(psutil.Process(pid).cmdline()):
                os.kill(pid, signal.SIGKILL)
    logging.getLogger("asyncio").addFilter(_start_cut_short)


def _start_cut_short(record: logging.LogRecord) -> bool:
    """False for the ``asyncio`` log's record of a cluster start task that failed unread."""
    exc = record.exc_info[1] if record.exc_info else None
    return not (
        record.getMessage().startswith("Task exception was never retrieved")
        and "failed to start" in str(exc)
    )


def _worker_pids(cluster) -> list[int]:
    pids = []
    for nanny in list(getattr(cluster, "workers", {}).values()):
        process = getattr(nanny, "process", None)
        pid = getattr(process, "pid", None)
        if pid:
            pids.append(int(pid))
    return pids


def _kill_workers(cluster) -> None:
    """SIGKILL every worker process of ``cluster`` (its nannies told not to start them again):
    every chunk worth keeping is on disk, and a worker inside compiled code would answer a
    polite close only when its slice ends."""
    for nanny in list(getattr(cluster, "workers", {}).values()):
        with contextlib.suppress(Exception):
            nanny.auto_restart = False
    for pid in _worker_pids(cluster):
        with contextlib.suppress(OSError):
            os.kill(pid, signal.SIGKILL)


def _shut_down(client, cluster) -> None:
    if cluster is None:
        if client is not None:
            with contextlib.suppress(Exception):
                client.close(timeout=2)
        return
    # Killed, not asked to close: a worker left to close on its own could also meet the closed
    # scheduler with its heartbeat, and log that with a traceback on the user's terminal.
    _kill_workers(cluster)
    if client is not None:
        with contextlib.suppress(Exception):
            client.close(timeout=2)
    with contextlib.suppress(Exception):
        cluster.close(timeout=5)


class _IgnoreCtrlC(WorkerPlugin):
    """Worker plugin: the worker process ignores SIGINT (as it has from its first instruction,
    :func:`mechviz.dynamics._spawn.spawned_workers_ignore_ctrl_c`), and dies with the process
    that started it (Linux), so a run killed outright leaves no worker computing for nobody."""

    name = "mechviz-ignore-ctrl-c"

    def setup(self, worker) -> None:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
        _die_with_parent()


def _die_with_parent() -> None:
    if not sys.platform.startswith("linux"):
        return
    import ctypes

    parent = os.getppid()
    with contextlib.suppress(Exception):
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, signal.SIGKILL, 0, 0, 0)  # PR_SET_PDEATHSIG
    if os.getppid() != parent:  # the parent went before the wish was made
        os._exit(1)


@dataclass
class Prepared:
    """A store made ready for a run (:func:`prepare`): the chunks already done and verified, and
    the damaged ones that will be computed again."""

    done: np.ndarray
    damaged: dict = field(default_factory=dict)
    restarted: bool = False


def prepare(spec: AtlasSpec, path: str | Path, *, resume: bool, fresh: bool = False) -> Prepared:
    """Create the store at ``path`` (``fresh``: replacing one there), or with ``resume`` verify
    the one there (:func:`.store.open_for_resume`). Call it holding :func:`.store.locked` of
    ``path``'s folder."""
    path = Path(path)
    if resume:
        r = _store.open_for_resume(path, spec)
        return Prepared(r.done, r.damaged, r.restarted)
    if fresh:
        _store.remove(path)
    _store.create(path, spec)
    return Prepared(np.zeros(spec.chunk_grid, dtype=bool))


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
    prepared: Prepared | None = None,
) -> RunReport:
    """Compute ``spec`` into the Zarr store at ``path`` (a new one, or with ``resume`` the same
    run's, checked by its run key and every chunk kept verified); returns what this call
    computed. ``prepared``: the store was made ready by :func:`prepare` under the caller's lock;
    else this call takes the folder's lock itself. Raises :class:`.store.StoreError` before any
    work for a store it may not use, and :class:`AtlasInterrupted` on Ctrl-C, SIGTERM or SIGHUP."""
    path = Path(path)
    with contextlib.ExitStack() as outer:
        watchdog = _Watchdog()
        outer.callback(watchdog.cancel)  # after everything below has been closed
        with contextlib.ExitStack() as stack:
            if prepared is None:
                stack.enter_context(_store.locked(path.parent))
                prepared = prepare(spec, path, resume=resume)
            return _run(
                spec,
                path,
                prepared,
                client,
                scheduler,
                workers,
                progress,
                on_chunk,
                stack,
                watchdog,
            )


def _run(
    spec, path, prepared, client, scheduler, workers, progress, on_chunk, stack, watchdog
) -> RunReport:
    done = prepared.done
    report = RunReport(new_session(), total=len(spec.chunks()))
    report.skipped = [c for c in spec.chunks() if done[c]]
    todo = [c for c in spec.chunks() if not done[c]]
    t0 = time.perf_counter()
    if not todo:
        _store.finish(path)
        return report
    signals = stack.enter_context(_signals_between_chunks())
    try:
        if client is None:
            try:
                signals.at_once = True
                client = stack.enter_context(dask_client(scheduler, workers))
            except Exception:
                # a Ctrl-C in the instant between a worker's fork and its first instruction
                # kills that worker (it ignores SIGINT from its first instruction on), and the
                # cluster fails to start: that failure is the interruption
                if signals:
                    raise KeyboardInterrupt from None
                raise
            finally:
                signals.at_once = False
        if signals:
            raise KeyboardInterrupt
        report.workers = len(client.scheduler_info(n_workers=-1).get("workers", {}))
        bar = stack.enter_context(_progress(progress, len(todo), report.total - len(todo)))
        _run_tasks(client, spec, path, todo, report, bar, on_chunk, signals)
    except KeyboardInterrupt as exc:
        report.interrupted = True
        report.signum = signals[0] if signals else _signum_of(exc)
        watchdog.start(report.signum)
        raise AtlasInterrupted(report) from None
    _store.finish(path)  # every chunk is done: readers open it in one read
    report.wall_seconds = time.perf_counter() - t0
    return report


def _signum_of(exc: BaseException) -> int:
    return int(getattr(exc, "signum", signal.SIGINT))


def _run_tasks(client, spec, path, todo, report, bar, on_chunk, signals) -> None:
    from distributed import as_completed

    key = spec.run_key()
    futures = {}
    try:
        for c in todo:
            name = f"atlas-{key}-{c[0]}-{c[1]}-{c[2]}"
            fut = client.submit(compute_chunk, spec, c, key=name, pure=False)
            futures[fut] = c
        pending = as_completed(list(futures))
        while not pending.is_empty():
            # polled, not waited on: a signal is seen within POLL_SECONDS whatever the length of
            # the chunks, and results that finished meanwhile are not written
            if signals:
                raise KeyboardInterrupt
            if not pending.has_ready():
                time.sleep(POLL_SECONDS)
                continue
            for fut in pending.next_batch(block=False):
                if signals:
                    raise KeyboardInterrupt
                cells = fut.result()
                c = futures.pop(fut)
                _store.write_chunk(path, spec, c, cells, report.session)
                report.computed.append(c)
                report.task_seconds += float(cells["seconds"])
                report.task_cpu_seconds += float(cells.get("cpu_seconds", 0.0))
                bar.update(1)
                if on_chunk is not None:
                    on_chunk(c, report)
    except BaseException:
        with contextlib.suppress(Exception):
            client.cancel(list(futures), force=True)
        raise


class _Watchdog:
    """After a signal, the shutdown has :data:`HARD_EXIT_SECONDS`: past that, the workers of the
    clusters started here are killed, their folders removed and the process ends at once (the
    chunks are on disk; only the cluster's goodbyes are cut)."""

    def __init__(self) -> None:
        self.timer: threading.Timer | None = None

    def start(self, signum: int) -> None:
        if threading.current_thread() is not threading.main_thread():
            return

        def hard_exit() -> None:
            for cluster in list(_LIVE_CLUSTERS):
                _kill_workers(cluster)
            for folder in list(_LIVE_SCRATCH):
                shutil.rmtree(folder, ignore_errors=True)
            sys.stderr.write("mechviz: interrupted\n")
            sys.stderr.flush()
            os._exit(128 + signum)

        self.timer = threading.Timer(HARD_EXIT_SECONDS, hard_exit)
        self.timer.daemon = True
        self.timer.start()

    def cancel(self) -> None:
        if self.timer is not None:
            self.timer.cancel()


#: The clusters and temporary folders of the runs under way in this process.
_LIVE_CLUSTERS: list = []
_LIVE_SCRATCH: list[str] = []


class _Signals(list):
    """The signals a run received, first first. ``at_once``: a signal raises
    :class:`KeyboardInterrupt` where the main thread is (while a cluster starts there is no
    chunk to finish, and the start can take seconds)."""

    at_once = False


@contextlib.contextmanager
def _signals_between_chunks():
    """Ctrl-C, SIGTERM and SIGHUP are recorded, and the run stops at its next look (every
    :data:`POLL_SECONDS`): an exception raised inside a chunk's write (the Zarr store waits on
    its own event loop, which can hold the exception until the write is done) would otherwise
    let every finished result be written before the run stops. A second signal raises at once."""
    signals = _Signals()  # the signals received, first first
    if threading.current_thread() is not threading.main_thread():
        yield signals
        return

    def on_signal(signum, frame) -> None:
        signals.append(signum)
        if signals.at_once or len(signals) > 1:
            raise KeyboardInterrupt

    wanted = [
        signal.SIGINT,
        *(getattr(signal, n) for n in ("SIGTERM", "SIGHUP") if hasattr(signal, n)),
    ]
    previous = {s: signal.signal(s, on_signal) for s in wanted}
    try:
        yield signals
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


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
