"""Endurance benchmark of the live viewer: frame rate and memory over minutes, browsers connected.

The target: the viewer holds 60 frames per second for 10 minutes with three browser clients
connected, with memory flat (trails capped). :func:`run_endurance` measures exactly that:

1. The real viewer (:class:`mechviz.viz.app.MechvizApp` with its 60 Hz loop thread, every exhibit at its
   defaults) runs in a **child process** bound to 127.0.0.1 on a free port. The child is the
   *server process* measured here; the browsers are driven from this (parent) process, so
   playwright never shares a Python process, an interpreter lock or a heap with the loop (in one
   process, playwright's event loop and the viewer's loop thread slow each other down).
2. ``clients`` headless Chromium instances (Debian's ``/usr/bin/chromium`` through playwright, each
   with its own empty profile; ``playwright install`` is never run) open the page and wait until
   viser shows "Connected". After ``settle_s`` seconds the measurement starts and lasts ``seconds``.
3. Inside the server process a sampler thread reads the loop's frame log
   (:class:`mechviz.viz.frames.FrameLog`: start time and server-side cost of every frame) and, every
   ``rss_every_s`` seconds, the resident set size (``/proc/self/statm``), the process CPU time and
   the number of connected viser clients.
4. At the end every page must still show "Connected" and its status line's simulated time must
   advance (read twice from the page text, ``t = ... s simulated``).

Reported (and written atomically to ``out``, by default ``docs/bench/endurance.json``): per window of
``window_s`` seconds the frames, the achieved rate, mean / p99 / max frame period (start to start),
median / p99 server cost, frames whose cost exceeded the 1/60 s budget and periods later than 1.5x
the budget; the RSS samples and their linear trend (MB/min) over the second half of the run;
the client checks; and pass/fail against the targets (every window >= 59 fps, |RSS trend| < 1
MB/min, every client connected and advancing).

Software rendering note: headless Chromium draws WebGL with SwiftShader on the CPU, on the same
machine as the server; three of them take every core of a small machine, which clients on their
own machines never do. By default the browsers therefore run on the last CPU only (at niceness
19) and the server process on the others (``client_cpus``; both sets are recorded), the pages are
small (800x600) and the viewer runs without its environment map (``environment_map=True`` for
the real look). None of this changes what the server computes or sends per frame.
"""

from __future__ import annotations

import contextlib
import gc
import math
import os
import re
import shlex
import shutil
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from mechviz.dynamics.files import write_json_atomically
from mechviz.viz.chromium import CANDIDATES, find_chromium, first_page, launch

from .endurance_report import (  # noqa: F401  (re-exported: the report of a run)
    TARGET_FPS,
    TARGET_RSS_SLOPE,
    _summarize,
    format_summary,
    frame_windows,
    rss_trend,
)

DEFAULT_OUT = Path("docs/bench/endurance.json")
_SIM_TIME = re.compile(r"\bt = ([0-9]+(?:\.[0-9]+)?) s\b")  # the visible readout's "t = 12.34 s"


class EnduranceUnavailable(RuntimeError):
    """The benchmark cannot run here (no Chromium, no playwright); the message says what to do."""


# --------------------------------------------------------------------------- browser
def check_browser() -> str:
    """Chromium's path; :class:`EnduranceUnavailable` with instructions if it cannot run."""
    exe = find_chromium()
    if exe is None:
        raise EnduranceUnavailable(
            "the endurance benchmark needs Chromium, and none was found (looked for "
            f"$MECHVIZ_CHROMIUM, {', '.join(CANDIDATES)} and chromium on PATH). Install "
            "Debian's package (apt-get install chromium) or set MECHVIZ_CHROMIUM to its path; "
            "do not run `playwright install`."
        )
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        raise EnduranceUnavailable(
            "the endurance benchmark drives Chromium through the Python package playwright, "
            "which is not installed (pip install 'mechviz-lab[test]')."
        ) from None
    return exe


# --------------------------------------------------------------------------- server process
def _rss_mb() -> float:
    with open("/proc/self/statm") as f:
        resident_pages = int(f.read().split()[1])
    return resident_pages * os.sysconf("SC_PAGE_SIZE") / 2**20


def _serve(
    conn,
    port: int,
    environment_map: bool,
    rss_every_s: float,
    cpus: tuple[int, ...] | None,
    warm: bool = True,
    expected_s: float = 600.0,
) -> None:
    """Child process: the viewer with its loop, a sampler thread, commands from ``conn``.

    ``cpus``: the CPUs the process may use (set first, so every thread inherits it).
    ``expected_s``: how long it will run, to size the frame store up front (so the store does
    not grow the memory being measured)
    Sends ``("ready", port)`` (or ``("error", text)``); on ``"mark"`` replies with the frame
    index, the time and the number of clients; on ``"stop"`` replies with everything sampled,
    then stops the viewer on the next message (``"exit"``) or when the parent goes away."""
    if cpus:
        with contextlib.suppress(AttributeError, OSError):
            os.sched_setaffinity(0, cpus)
    try:
        from mechviz.viz.app import MechvizApp, warm_up

        if warm:
            warm_up("defaults")  # as `mechviz view` does; else the first frames compile
        app = MechvizApp(host="127.0.0.1", port=port, environment_map=environment_map)
    except Exception as exc:  # pragma: no cover - reported to the parent
        conn.send(("error", f"{type(exc).__name__}: {exc}"))
        return
    log = app.frame_log
    gc_stats = {g: [0, 0.0, 0.0] for g in range(3)}  # generation: [count, total ms, max ms]
    gc_t0 = [0.0]

    def on_gc(phase: str, info: dict) -> None:
        if phase == "start":
            gc_t0[0] = time.perf_counter()
            return
        ms = 1e3 * (time.perf_counter() - gc_t0[0])
        st = gc_stats[info["generation"]]
        st[0] += 1
        st[1] += ms
        st[2] = max(st[2], ms)

    gc.callbacks.append(on_gc)
    # every frame's (start, cost, cpu), written in place: filled now, so its pages are resident
    # before the first memory sample
    store = [np.full((3, int(app.fps * (expected_s + 120.0))), np.nan)]
    samples: list[tuple[float, float, float, int, float, int]] = []
    state = {"next": 0, "dropped": 0, "stored": 0}
    lock = threading.Lock()
    stop = threading.Event()

    def drain() -> None:
        with lock:
            first, start, cost, cpu = log.since(state["next"])
            state["dropped"] += first - state["next"]
            state["next"] = first + len(start)
            n, k = state["stored"], len(start)
            if k:
                if n + k > store[0].shape[1]:  # ran longer than expected: grow (rare)
                    store[0] = np.concatenate([store[0], np.full((3, n + k), np.nan)], axis=1)
                store[0][:, n : n + k] = start, cost, cpu
                state["stored"] = n + k

    def sample() -> None:
        cpu = sum(os.times()[:2])
        clients = len(app.server.get_clients())
        samples.append((time.perf_counter(), _rss_mb(), cpu, clients, app.sim_time, log.count))

    def sampler() -> None:
        next_rss = time.perf_counter()
        while not stop.wait(0.5):
            drain()
            if time.perf_counter() >= next_rss:
                sample()
                next_rss += rss_every_s

    deadline = time.monotonic() + 300.0
    while log.count < 3 and time.monotonic() < deadline:  # the loop runs (kernels compiled)
        time.sleep(0.05)
    thread = threading.Thread(target=sampler, name="endurance-sampler", daemon=True)
    sample()
    thread.start()
    conn.send(("ready", app.port))
    try:
        while True:
            cmd = conn.recv()
            if cmd == "mark":
                drain()
                conn.send(("mark", log.count, time.perf_counter(), len(app.server.get_clients())))
            elif cmd == "clients":
                conn.send(("clients", len(app.server.get_clients()), app.sim_time))
            elif cmd == "stop":
                break
    finally:
        stop.set()
        thread.join(timeout=5.0)
        drain()
        sample()
        final_clients = len(app.server.get_clients())
        with contextlib.suppress(OSError, EOFError):
            conn.send(
                (
                    "data",
                    {
                        "start": store[0][0, : state["stored"]],
                        "cost_ms": store[0][1, : state["stored"]],
                        "cpu_ms": store[0][2, : state["stored"]],
                        "dropped": state["dropped"],
                        "samples": samples,
                        "final_clients": final_clients,
                        "fps": app.fps,
                        "gc": gc_stats,
                    },
                )
            )
            # viser's stop() waits seconds for connected browsers: the parent closes them first
            conn.poll(60)
        app.stop()
        conn.close()


# --------------------------------------------------------------------------- the benchmark
def default_client_cpus() -> tuple[int, ...] | None:
    """The CPUs the browsers may use by default: the last one this process may run on, when
    there are at least two (the server keeps the others); ``None`` (no limit) otherwise."""
    try:
        cpus = sorted(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return None
    return (cpus[-1],) if len(cpus) >= 2 else None


def _client_wrapper(
    exe: str, nice: int | None, cpus: tuple[int, ...] | None, folder: str
) -> tuple[str, dict]:
    """An executable script that starts Chromium with its CPU affinity limited to ``cpus`` and
    at niceness ``nice``; returns its path and what was applied.

    On a small machine the software-rendering browsers (SwiftShader draws WebGL on the CPU)
    would otherwise take the CPU the server needs, which real clients on their own machines
    never do. The affinity is what holds: running as root, Chromium raises its GPU process to
    niceness -8 itself, but it never widens its CPU set, and every process it starts inherits it.
    """
    applied: dict = {"nice": None, "cpus": None}
    prefix = []
    if cpus:
        taskset = shutil.which("taskset")
        if taskset:
            prefix += [taskset, "-c", ",".join(str(c) for c in cpus)]
            applied["cpus"] = list(cpus)
    if nice is not None:
        prefix += [shutil.which("nice") or "nice", "-n", str(int(nice))]
        applied["nice"] = int(nice)
    path = os.path.join(folder, "chromium")
    with open(path, "w") as f:
        f.write(f'#!/bin/sh\nexec {shlex.join([*prefix, exe])} "$@"\n')
    os.chmod(path, 0o755)
    return path, applied


def _page_sim_time(page) -> float | None:
    """The simulated time the visible exhibit's readout shows (``t = 12.34 s``)."""
    try:
        text = page.evaluate("() => document.body.innerText")
    except Exception:  # a crashed or closed page
        return None
    m = _SIM_TIME.search(text or "")
    return float(m.group(1)) if m else None


def _check_pages(pages, wait_s: float = 1.0) -> list[dict]:
    """For each page: still "Connected", and its simulated time advances over ``wait_s``."""
    connected = []
    for page in pages:
        try:
            connected.append(bool(page.get_by_text("Connected", exact=True).first.is_visible()))
        except Exception:
            connected.append(False)
    before = [_page_sim_time(p) for p in pages]
    time.sleep(wait_s)
    after = [_page_sim_time(p) for p in pages]
    return [
        {"connected": c, "sim_time": [a, b], "advancing": a is not None and b is not None and b > a}
        for c, a, b in zip(connected, before, after, strict=True)
    ]


def run_endurance(
    seconds: float = 600.0,
    clients: int = 3,
    port: int = 0,
    *,
    out: str | Path | None = DEFAULT_OUT,
    window_s: float = 10.0,
    rss_every_s: float = 2.0,
    settle_s: float = 10.0,
    viewport: tuple[int, int] = (800, 600),
    environment_map: bool = False,
    client_nice: int | None = 19,
    client_cpus: tuple[int, ...] | str | None = "auto",
    check_s: float = 1.0,
    warm: bool = True,
    progress=None,
) -> dict:
    """Run the live viewer for ``seconds`` with ``clients`` headless Chromium pages connected.

    Returns the results (see the module docstring) and writes them to ``out`` (``None``: not
    written). ``port=0`` lets the OS pick a free port.

    - ``window_s``: length of the frame-rate windows; ``rss_every_s``: memory sampling period;
      ``settle_s``: wait after every page shows "Connected" before measuring.
    - ``viewport``, ``environment_map``: the pages' size and the viewer's environment lighting.
    - ``client_cpus`` (``"auto"``: the last CPU when there are two or more; ``None``: no limit)
      and ``client_nice``: where and how nicely the browsers run; the server process then
      keeps to the other CPUs (see :func:`_client_wrapper`). Both are recorded in the result.
    - ``check_s``: how long the final check watches each page's simulated time advance.
    - ``warm``: compile the default kernels before serving, as ``mechviz view`` does.
    - ``progress(text)`` is called with a line now and then (the CLI prints them).

    Raises :class:`EnduranceUnavailable` if Chromium or playwright is missing, ``RuntimeError``
    if the server or a page does not come up.
    """
    import multiprocessing

    if not (seconds > 0 and math.isfinite(seconds)):
        raise ValueError(f"seconds must be positive, got {seconds!r}")
    if int(clients) < 1:
        raise ValueError(f"clients must be at least 1, got {clients!r}")
    clients = int(clients)
    exe = check_browser()
    say = progress or (lambda _text: None)
    from playwright.sync_api import sync_playwright

    t_begin = time.time()
    load_before = os.getloadavg()
    profiles: list[str] = []
    wrapper_dir = tempfile.mkdtemp(prefix="mechviz-endurance-bin-")
    if client_cpus == "auto":
        client_cpus = default_client_cpus()
    exe, client_limits = _client_wrapper(exe, client_nice, client_cpus, wrapper_dir)
    server_cpus = None  # the server keeps to the CPUs the browsers may not use
    if client_limits["cpus"]:
        with contextlib.suppress(AttributeError, OSError):
            rest = sorted(os.sched_getaffinity(0) - set(client_limits["cpus"]))
            server_cpus = tuple(rest) or None
    client_limits["server_cpus"] = list(server_cpus) if server_cpus else None
    ctx = multiprocessing.get_context("spawn")  # no fork of a process holding threads
    parent_conn, child_conn = ctx.Pipe()
    proc = ctx.Process(
        target=_serve,
        args=(
            child_conn,
            port,
            environment_map,
            rss_every_s,
            server_cpus,
            warm,
            settle_s + seconds,
        ),
        name="mechviz-endurance-server",
        daemon=True,
    )
    proc.start()
    child_conn.close()
    data: dict[str, Any] | None = None
    page_checks: list[dict] = []
    try:
        with sync_playwright() as pw:
            # Chromium starts while the server compiles its kernels.
            contexts = []
            for _ in range(clients):
                profile = tempfile.mkdtemp(prefix="mechviz-endurance-")
                profiles.append(profile)
                contexts.append(launch(pw, profile, exe, *viewport))
            if not parent_conn.poll(300):
                raise RuntimeError("the viewer process did not start within 300 s")
            kind, value = parent_conn.recv()
            if kind != "ready":
                raise RuntimeError(f"the viewer process failed: {value}")
            url = f"http://127.0.0.1:{value}/"
            say(f"viewer at {url}; connecting {clients} Chromium client(s)")
            pages = []
            for c in contexts:
                page = first_page(c)
                page.goto(url)
                pages.append(page)
            for page in pages:
                page.get_by_text("Connected", exact=True).wait_for(timeout=60_000)
            if settle_s > 0:
                say(f"all connected; settling {settle_s:g} s")
                time.sleep(settle_s)
            parent_conn.send("mark")
            _, first_frame, t0, n_clients0 = parent_conn.recv()
            say(f"measuring {seconds:g} s with {n_clients0} viser client(s)")
            deadline = time.monotonic() + seconds
            next_note = time.monotonic() + 60.0
            while (left := deadline - time.monotonic()) > 0:
                time.sleep(min(left, 1.0))
                if time.monotonic() >= next_note and left > 1.0:
                    next_note += 60.0
                    parent_conn.send("clients")
                    _, n, sim_t = parent_conn.recv()
                    say(f"{seconds - left:.0f} s: {n} client(s), simulated t = {sim_t:.1f} s")
            parent_conn.send("mark")
            _, last_frame, t1, n_clients1 = parent_conn.recv()
            # the checks come after the measured span (reading pages costs nothing server-side)
            page_checks = _check_pages(pages, check_s)
            say("stopping")
            parent_conn.send("stop")
            if not parent_conn.poll(60):
                raise RuntimeError("the viewer process did not report its data")
            _, data = parent_conn.recv()
            say("closing the browsers")
            for c in contexts:
                with contextlib.suppress(Exception):
                    c.close()
    finally:
        with contextlib.suppress(Exception):
            if proc.is_alive() and data is None:  # failed half-way: stop it, discard its data
                parent_conn.send("stop")
                if parent_conn.poll(30):
                    parent_conn.recv()
            parent_conn.send("exit")  # the browsers are closed: the server may stop now
        proc.join(timeout=30)
        if proc.is_alive():
            proc.terminate()
            proc.join(timeout=5)
        for profile in profiles:
            shutil.rmtree(profile, ignore_errors=True)
        shutil.rmtree(wrapper_dir, ignore_errors=True)

    result = _summarize(
        data,
        t0=t0,
        t1=t1,
        frames=(first_frame, last_frame),
        seconds=seconds,
        clients=clients,
        clients_seen=(n_clients0, n_clients1),
        page_checks=page_checks,
        window_s=window_s,
        rss_every_s=rss_every_s,
        settle_s=settle_s,
        viewport=viewport,
        environment_map=environment_map,
        client_limits=client_limits,
        load=(load_before, os.getloadavg()),
        wall_s=time.time() - t_begin,
        started=t_begin,
    )
    if out is not None:
        write_json_atomically(out, result, indent=1)
        result["written_to"] = str(out)
    return result
