"""SIGTERM mid-run: `bench`, `record`, `video` and `still` end, and leave no process and no temporary
folder behind (their compile workers, viser servers, Chromium and its profile included).

Each command runs with a temporary directory of its own (``TMPDIR``); its processes are the
descendants it has when the signal is sent, and each must be gone soon after. The signal is
sent once the command is at work (a condition, never a fixed sleep).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from waiting import alive, descendants, scaled, wait_until

from mechviz.viz.chromium import find_chromium

pytestmark = pytest.mark.slow
needs_chromium = pytest.mark.skipif(
    find_chromium() is None, reason="no Chromium (apt-get install chromium)"
)


def cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def start(args: list[str], tmp: Path, **env) -> subprocess.Popen:
    tmp.mkdir(exist_ok=True)
    return subprocess.Popen(
        [sys.executable, "-m", "mechviz.viz.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
        env={**os.environ, "TMPDIR": str(tmp), **env},
    )


def terminate_and_check(proc: subprocess.Popen, tmp: Path) -> str:
    children = descendants(proc.pid)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=scaled(60))
    assert proc.returncode == 128 + signal.SIGTERM, err[-2000:]
    assert "Traceback" not in err, err[-2000:]
    wait_until(lambda: not alive(children), 20, f"the command's processes to end: {children}")
    assert [p.name for p in tmp.iterdir()] == []
    return err


def start_drawing(args: list[str], tmp: Path, within: float) -> subprocess.Popen:
    """``mechviz ARGS`` (a command that draws in Chromium), once Chromium runs and the
    command's temporary folder exists."""
    proc = start(args, tmp)
    wait_until(
        lambda: (
            any("chrom" in name.lower() for name in descendants(proc.pid).values())
            and any(p.name.startswith("mechviz-video-") for p in tmp.iterdir())
        ),
        within,
        "Chromium to start drawing",
    )
    return proc


def test_sigterm_ends_bench_while_its_workers_compile(tmp_path):
    cache = tmp_path / "cache"
    proc = start(
        ["bench", "--quick", "--out", str(tmp_path / "out")],
        tmp_path / "tmp",
        NUMBA_CACHE_DIR=str(cache),
    )
    wait_until(
        lambda: len(descendants(proc.pid)) >= 2 and cache.exists(), 120, "the compile workers"
    )
    terminate_and_check(proc, tmp_path / "tmp")
    assert not (tmp_path / "out").exists()


def test_sigterm_ends_record_at_work(tmp_path):
    out = tmp_path / "out"
    proc = start(["record", "helix", "--out", str(out), "--duration", "20"], tmp_path / "tmp")
    wait_until(lambda: cpu_seconds(proc.pid) > 2.0, 120, "the recording to be at work")
    terminate_and_check(proc, tmp_path / "tmp")
    assert not out.exists() or list(out.iterdir()) == []


@needs_chromium
def test_sigterm_ends_video_while_chromium_draws(tmp_path):
    rec = tmp_path / "rec"
    record = ["record", "helix", "--out", str(rec), "--duration", "10", "--fps", "10"]
    subprocess.run(
        [sys.executable, "-m", "mechviz.viz.cli", *record],
        check=True,
        capture_output=True,
        timeout=scaled(300),
    )
    tmp = tmp_path / "tmp"
    video = tmp_path / "helix.mp4"
    proc = start_drawing(["video", str(rec / "helix.viser"), "--out", str(video)], tmp, 120)
    terminate_and_check(proc, tmp)
    assert not video.exists()


@needs_chromium
def test_sigterm_ends_still_while_chromium_draws(tmp_path):
    tmp = tmp_path / "tmp"
    still = tmp_path / "helix.png"
    args = ["still", "helix", "--at", "2", "--size", "1920x1080", "--out", str(still)]
    proc = start_drawing(args, tmp, 180)
    terminate_and_check(proc, tmp)
    assert not still.exists()


def _long_atlas(tmp_path: Path, workers: int) -> tuple[subprocess.Popen, Path, Path]:
    """``mechviz atlas`` of one chunk of about ten minutes (32 x 32 starts and their twins,
    30000 s at 0.01 s) on ``workers`` local workers: the process, its output folder and its
    temporary folder."""
    pytest.importorskip("distributed")
    out = tmp_path / "out"
    args = ["atlas", "chaos", "--theta1=-3:3:32", "--theta2=-3:3:32", "--duration", "30000"]
    args += ["--chunk", "32x32", "--workers", str(workers), "--no-progress", "--out", str(out)]
    tmp = tmp_path / "tmp"
    return start(args, tmp), out, tmp


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP])
def test_a_signal_inside_a_long_atlas_chunk_ends_it_within_two_seconds(tmp_path, signum):
    """One chunk of about ten minutes (:func:`_long_atlas`): the run ends within two seconds of
    the signal (scaled by the load), its Dask workers gone and nothing left in its temporary
    folder (no dask-scratch-space)."""
    import time

    proc, out, tmp = _long_atlas(tmp_path, workers=1)
    try:
        # at work: a worker process (not the command itself) has spent CPU beyond its start-up
        wait_until(
            lambda: any(_cpu(p) > 3.0 for p in descendants(proc.pid)),
            180,
            "a worker computing the chunk",
        )
        children = descendants(proc.pid)
        t0 = time.monotonic()
        if signum == signal.SIGINT:
            os.killpg(proc.pid, signum)  # as a terminal's Ctrl-C: the whole group
        else:
            proc.send_signal(signum)
        _, err = proc.communicate(timeout=scaled(60))
        took = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 128 + signum, err[-2000:]
    assert took < scaled(2.0), f"{took:.2f} s"
    assert "Traceback" not in err and "--resume" in err, err[-2000:]
    wait_until(lambda: not alive(children), 10, f"the command's processes to end: {children}")
    assert [p.name for p in tmp.iterdir()] == []
    assert not (out / "atlas.zarr").with_name("atlas.zarr.partial").exists()


def test_ctrl_c_while_the_atlas_cluster_starts_ends_the_run_within_a_second(tmp_path):
    """A terminal's Ctrl-C the moment the first worker process is spawned (the cluster still
    starting, which takes seconds): the start is cut short and the run ends within about a
    second (scaled by the load), with the usual message and exit status, no traceback from a
    worker, every process it spawned gone and nothing left behind."""
    import time

    proc, _, tmp = _long_atlas(tmp_path, workers=2)
    try:
        seen = wait_until(lambda: descendants(proc.pid), 180, "the first worker process")
        t0 = time.monotonic()
        os.killpg(proc.pid, signal.SIGINT)  # as a terminal's Ctrl-C: the whole group

        def ended() -> bool:
            seen.update(descendants(proc.pid))  # the workers started after the signal too
            return proc.poll() is not None

        wait_until(ended, 60, "the run to end", poll_s=0.01)
        took = time.monotonic() - t0
        _, err = proc.communicate()
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert proc.returncode == 128 + signal.SIGINT, err[-2000:]
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err[-2000:]
    assert "interrupted" in err and "--resume" in err, err[-2000:]
    # not the cluster's start (two interpreters importing numpy and Dask: seconds)
    assert took < scaled(1.5), f"{took:.2f} s"
    print(f"Ctrl-C while the cluster starts: ended in {took:.2f} s")
    wait_until(lambda: not alive(seen), 10, f"the command's processes to end: {seen}")
    assert [p.name for p in tmp.iterdir()] == []


def _cpu(pid: int) -> float:
    try:
        return cpu_seconds(pid)
    except OSError:  # gone meanwhile
        return 0.0


def test_a_finished_atlas_leaves_no_process_and_nothing_in_its_temporary_folder(tmp_path):
    pytest.importorskip("distributed")
    out = tmp_path / "out"
    args = ["atlas", "chaos", "--theta1=-3:3:4", "--theta2=-3:3:4", "--duration", "1"]
    args += ["--chunk", "2x4", "--workers", "2", "--no-progress", "--out", str(out)]
    tmp = tmp_path / "tmp"
    proc = start(args, tmp)
    seen: dict[int, str] = {}

    def finished() -> bool:
        seen.update(descendants(proc.pid))
        return proc.poll() is not None

    wait_until(finished, 180, "the atlas to finish")
    _, err = proc.communicate()
    assert proc.returncode == 0, err[-2000:]
    assert (out / "chaos.png").is_file()
    wait_until(lambda: not alive(seen), 10, f"the command's processes to end: {seen}")
    assert [p.name for p in tmp.iterdir()] == []


def _sigint_disposition(queue) -> None:
    handler = signal.getsignal(signal.SIGINT)
    queue.put("ignored" if handler is signal.SIG_IGN else "handled")


def _spawned_sigint(inside: bool, folder: Path) -> str:
    import contextlib
    import multiprocessing

    from mechviz.dynamics._spawn import spawned_workers_ignore_ctrl_c

    context = multiprocessing.get_context("spawn")
    queue = context.Queue()
    block = spawned_workers_ignore_ctrl_c(folder) if inside else contextlib.nullcontext()
    with block:
        proc = context.Process(target=_sigint_disposition, args=(queue,))
        proc.start()
    try:
        return queue.get(timeout=scaled(60))
    finally:
        proc.join()


def test_a_worker_spawned_for_a_run_ignores_ctrl_c_from_its_start_and_this_process_does_not(
    tmp_path,
):
    """The bench's compile workers and the atlas's cluster are spawned this way: a spawned
    interpreter that handled SIGINT itself would print "Fatal Python error" or a traceback if a
    terminal's Ctrl-C came while it imports. Python keeps an ignored SIGINT ignored, so the
    worker's first Python code already sees it ignored; this process still handles Ctrl-C, and
    the spawn executable is put back (a worker spawned after the block handles it again)."""
    assert _spawned_sigint(True, tmp_path) == "ignored"
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert _spawned_sigint(False, tmp_path) == "handled"
