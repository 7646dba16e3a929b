"""``mechviz bench --video``: how fast videos are made, as a ratio to real time, with today's
path (:mod:`mechviz.viz.player`: two copies of the page drawing the frames side by side, each frame a
seek, one render without the default lights' shadow maps and a JPEG copied from the canvas; the
words and the encoder on a worker thread) beside the same with one page, and with one page and the
shadow maps; on request also an older path (the player playing on a faked clock at 0.5x, four
animation frames and a PNG screenshot per frame, kept here only to be measured).

The target: a video made at least as fast as real time (ratio >= 1) at 960x540 and 30 fps. Page
load (starting Chromium, the first frame of a lit scene in software WebGL) is reported apart and
not counted. The machine's load average is reported beside the figures: on a shared machine
they are lower bounds.
"""

from __future__ import annotations

import base64
import contextlib
import io
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

from mechviz.viz.chromium import find_chromium, first_page, launch

LOAD_TIMEOUT_S = 180.0
TARGET_RATIO = 1.0


def _drawn(img: np.ndarray) -> bool:
    return len(np.unique(img[::4, ::4].reshape(-1, 3), axis=0)) > 40


# ------------------------------------------------------------------ the path it replaced
def frame_clock_ms(k: int, fps: int) -> tuple[float, float]:
    """``(playback speed, clock time [ms] after play)`` at which frame ``k`` is captured.

    Measured in the player: a recorded frame reaches the canvas within two animation frames
    (the fake clock runs them every 16 ms) of about 20 ms after its time, so it is on screen,
    complete, from about 38 ms after its time until the next one arrives. Frames are captured
    in the middle of that window; above 15 fps the player runs at 0.5x so the window stays
    over 30 ms wide (which caps videos at 30 fps)."""
    speed = 1.0 if fps <= 15 else 0.5
    period = 1000.0 / (fps * speed)
    return speed, k * period + 38.0 + (period - 30.0) / 2


def render_frames(
    page_html: bytes, *, fps: int, frames: int, size: tuple[int, int] = (960, 540)
) -> Iterator[np.ndarray]:
    """Yield ``frames`` images ``(H, W, 3)`` uint8 of the player page: frame ``k`` is the
    recording as it stands at playback time ``k / fps``.

    One headless Chromium, the page's clock faked: load, wait for the first drawn frame, seek
    to 0 and play, then advance the clock to each frame's capture time
    (:func:`frame_clock_ms`) before its screenshot."""
    from playwright.sync_api import Error as PlaywrightError
    from playwright.sync_api import sync_playwright

    exe = find_chromium()
    W, H = size
    tmp = tempfile.mkdtemp(prefix="mechviz-video-")
    try:
        html_path = Path(tmp) / "recording.html"
        html_path.write_bytes(page_html)
        with sync_playwright() as pw:
            context = launch(pw, str(Path(tmp) / "profile"), exe, W, H)
            try:
                page = first_page(context)
                speed = frame_clock_ms(0, fps)[0]
                clip = _open_player(page, html_path, W, H, speed)
                cdp = context.new_cdp_session(page)
                clip["scale"] = 1
                ms = [round(frame_clock_ms(k, fps)[1]) for k in range(frames)]
                prev = 0
                for k in range(frames):
                    page.clock.run_for(ms[k] - prev)
                    prev = ms[k]
                    shot = cdp.send("Page.captureScreenshot", {"format": "png", "clip": clip})
                    yield _decode_png(base64.b64decode(shot["data"]), W, H)
            except PlaywrightError as exc:
                raise RuntimeError(f"Chromium failed while drawing the frames: {exc}") from None
            finally:
                with contextlib.suppress(Exception):
                    context.close()
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _open_player(page, html_path: Path, W: int, H: int, speed: float) -> dict[str, float]:
    """Load the player with a fake clock, size its canvas to W x H, wait until the scene is
    drawn, set the playback ``speed``, seek to 0 and play with the clock paused. Returns the
    canvas's clip rectangle."""
    page.clock.install(time=0)
    # fixedDpr: the client would otherwise lower its resolution when frames are slow.
    page.goto(html_path.as_uri() + "?fixedDpr=1")
    # Overlays that are not part of the scene: the software-WebGL notice, notifications.
    page.add_style_tag(
        content="[role=alert], .mantine-Notifications-root {display: none !important;}"
    )
    canvas = page.locator('canvas[data-engine^="three.js"]')
    time_box = page.get_by_role("textbox")
    deadline = time.monotonic() + LOAD_TIMEOUT_S
    while not (canvas.count() and time_box.count()):
        if time.monotonic() > deadline:
            raise RuntimeError("the recording's page did not load in Chromium (no player)")
        page.clock.run_for(100)
    # The playback bar sits below the canvas: grow the window so the canvas is exactly W x H.
    for _ in range(3):
        box = canvas.bounding_box()
        if box is not None and round(box["height"]) == H and round(box["width"]) == W:
            break
        vp = page.viewport_size
        page.set_viewport_size(
            {"width": W, "height": vp["height"] + H - round(box["height"] if box else H)}
        )
        page.clock.run_for(100)
    box = canvas.bounding_box()
    rect = {"x": box["x"], "y": box["y"], "width": float(W), "height": float(H)}
    page.clock.pause_at(page.evaluate("() => Date.now()") + 100)
    while not _drawn(_decode_png(page.screenshot(clip=rect), W, H)):
        if time.monotonic() > deadline:
            raise RuntimeError("the recording's scene was never drawn in Chromium")
        page.clock.run_for(100)
    if speed != 1.0:
        page.get_by_role("combobox").first.click()
        page.clock.run_for(300)  # the menu opens on timers of the faked clock
        page.get_by_role("option", name=f"{speed:g}x").click()
        page.clock.run_for(300)
    # Seeking through the time box pauses playback at t = 0; the play button resumes it.
    time_box.first.fill("0")
    time_box.first.press("Enter")
    play = page.locator("button.mantine-ActionIcon-root").first
    play.click()
    page.mouse.move(W / 2, H / 2)
    with contextlib.suppress(Exception):
        time_box.first.blur()
    return rect


def _decode_png(png: bytes, W: int, H: int) -> np.ndarray:
    from PIL import Image

    img = Image.open(io.BytesIO(png)).convert("RGB")
    if img.size != (W, H):
        img = img.resize((W, H))
    return np.asarray(img)


def _baseline(clip, size: tuple[int, int], cpu) -> dict[str, Any]:
    """The replaced path: frames drawn and encoded (overlay and H.264, as before)."""
    from mechviz.viz.encoders import Mp4Writer
    from mechviz.viz.overlay import Overlay

    times = [clip.simulated(t) for t in clip.playback_times()]
    overlay = Overlay(
        title=clip.title, caption=clip.caption, figures=clip.figures, size=size, times=times
    )
    with tempfile.TemporaryDirectory(prefix="mechviz-bench-") as tmp:
        writer = Mp4Writer(Path(tmp) / "old.mp4", size, clip.fps)
        t0 = time.perf_counter()
        load = None
        frames = render_frames(clip.page, fps=clip.fps, frames=clip.frames, size=size)
        try:
            for k, frame in enumerate(frames):
                if k == 0:
                    load = time.perf_counter() - t0
                    t1 = time.perf_counter()
                    cpu.mark()
                writer.add(overlay.apply(frame, times[k]))
        finally:
            frames.close()
        writer.close()
        work = time.perf_counter() - t1
    return _figures(clip, load or 0.0, work, skipped_first=True)


def _figures(clip, load: float, work: float, *, skipped_first: bool = False) -> dict[str, Any]:
    frames = clip.frames - (1 if skipped_first else 0)
    return {
        "frames": clip.frames,
        "load_s": round(load, 2),
        "ms_per_frame": round(1000 * work / frames, 1),
        "real_time_ratio": round((frames / clip.fps) / work, 3),
    }


class _TreeCpu:
    """CPU seconds of this process and every process below it (Chromium's, playwright's driver,
    ffmpeg), sampled from /proc every 0.2 s while it runs: a figure that depends less on the
    machine's load than the wall clock. A process's last 0.2 s before it ends may be missed."""

    def __init__(self) -> None:
        import threading

        self.seen: dict[int, float] = {}
        self.start = self._sample()
        self.stop_flag = threading.Event()
        self.thread = threading.Thread(target=self._run, daemon=True)
        self.thread.start()

    @staticmethod
    def _sample() -> dict[int, float]:
        tick = os.sysconf("SC_CLK_TCK")
        parent: dict[int, int] = {}
        cpu: dict[int, float] = {}
        for name in os.listdir("/proc"):
            if not name.isdigit():
                continue
            with contextlib.suppress(OSError, IndexError, ValueError):
                fields = Path(f"/proc/{name}/stat").read_text().rsplit(")", 1)[1].split()
                parent[int(name)] = int(fields[1])
                cpu[int(name)] = (int(fields[11]) + int(fields[12])) / tick
        me = os.getpid()
        out = {}
        for pid in cpu:
            p, hops = pid, 0
            while p not in (me, 0, 1) and hops < 64:
                p, hops = parent.get(p, 0), hops + 1
            if p == me:
                out[pid] = cpu[pid]
        return out

    def _run(self) -> None:
        while not self.stop_flag.wait(0.2):
            self.seen.update(self._sample())

    def mark(self) -> None:
        """Count from now on (after the page loaded)."""
        self.start = self._sample()
        self.own0 = time.process_time()

    def stop(self) -> float:
        self.stop_flag.set()
        self.thread.join()
        self.seen.update(self._sample())
        used = sum(v - self.start.get(pid, 0.0) for pid, v in self.seen.items())
        return used + time.process_time() - self.own0

    def __enter__(self):
        self.own0 = time.process_time()
        return self

    def __exit__(self, *exc) -> None:
        self.total = self.stop()


# The ways of drawing a video's frames measured, as ``write_video`` keyword arguments: as videos
# are made, then one change taken back at a time.
PATHS: dict[str, dict[str, Any]] = {
    "today": {},
    "two_pages": {"pages": 2},
    "one_page": {"pages": 1},
    "one_page_shadows": {"pages": 1, "shadows": True},
    "one_page_environment": {"pages": 1, "environment": True},
}
LABELS = {
    "today": "today's path (as mechviz video: pages by length, no shadow maps, sky light)",
    "two_pages": "two pages, no shadow maps, sky light",
    "one_page": "one page, no shadow maps, sky light",
    "one_page_shadows": "one page, with the shadow maps, sky light",
    "one_page_environment": "one page, no shadow maps, environment map",
    "replaced": "the replaced path (faked clock, PNG)",
}


def measure_video_speed(
    demo: str = "helix",
    duration: float = 10.0,
    fps: int = 30,
    size: tuple[int, int] = (960, 540),
    *,
    baseline: bool = False,
) -> dict[str, Any]:
    """Record ``demo`` for ``duration`` s at ``fps`` and film it at ``size`` as MP4 in each way
    of :data:`PATHS` (today's first) and, with ``baseline``, by the replaced path: per path the
    page load [s], ms per frame after it, the ratio to real time without the page load and with
    it (``end_to_end_ratio``), and the CPU seconds per frame of this process and its children
    (Chromium, ffmpeg), which depend less on the machine's load; whether the target (today's
    path: ratio >= 1) is met, beside the load averages before and after."""
    from mechviz.viz import record as rec
    from mechviz.viz import video

    if find_chromium() is None:
        raise RuntimeError("no Chromium (apt-get install chromium)")
    out: dict[str, Any] = {
        "demo": demo,
        "duration_s": duration,
        "fps": fps,
        "size": f"{size[0]}x{size[1]}",
        "cores": os.cpu_count(),
        "load_average_before": [round(x, 2) for x in os.getloadavg()],
    }
    with tempfile.TemporaryDirectory(prefix="mechviz-bench-") as tmp:
        res = rec.record(rec.load_demo(demo).with_overrides(duration=duration, fps=fps), tmp)
        clip = video.clip_from_manifest(res.paths[".html"].read_bytes(), res.manifest)
        for key, how in PATHS.items():
            with _TreeCpu() as cpu:
                v = video.write_video(
                    clip,
                    Path(tmp) / f"{key}.mp4",
                    size=size,
                    progress=lambda done, total, cpu=cpu: cpu.mark() if done == 1 else None,
                    **how,
                )
            out[key] = {
                "frames": v.frames,
                "load_s": round(v.load_seconds, 2),
                "ms_per_frame": round(v.ms_per_frame, 1),
                "real_time_ratio": round(v.real_time_ratio, 3),
                "end_to_end_ratio": round(
                    v.frames / v.fps / (v.load_seconds + v.render_seconds), 3
                ),
                "cpu_ms_per_frame": round(1000 * cpu.total / (v.frames - 1), 1),
            }
        if baseline:
            with _TreeCpu() as cpu:
                out["replaced"] = _baseline(clip, size, cpu)
            out["replaced"]["cpu_ms_per_frame"] = round(1000 * cpu.total / (clip.frames - 1), 1)
    out["load_average_after"] = [round(x, 2) for x in os.getloadavg()]
    out["targets"] = {
        "real_time_ratio_min": TARGET_RATIO,
        "met": out["today"]["real_time_ratio"] >= TARGET_RATIO,
    }
    return out


def format_video_speed(r: dict[str, Any]) -> str:
    """The figures as a few lines of text."""
    lines = [
        f"video of {r['demo']}: {r['duration_s']:g} s at {r['fps']} fps, {r['size']} "
        f"({r.get('cores', '?')} cores, load average {r['load_average_before']} -> "
        f"{r['load_average_after']})"
    ]
    for key, label in LABELS.items():
        if key in r:
            v = r[key]
            end = f", {v['end_to_end_ratio']:.2f}x with it" if "end_to_end_ratio" in v else ""
            lines.append(
                f"  {label:42s} {v['real_time_ratio']:.2f}x real time ({v['ms_per_frame']:.0f} ms "
                f"a frame, {v['cpu_ms_per_frame']:.0f} ms CPU a frame; page load "
                f"{v['load_s']:.1f} s{end})"
            )
    met = r["targets"]["met"]
    lines.append(
        f"  target (today's path at least as fast as real time, page load apart): "
        f"{'met' if met else 'MISSED'}"
    )
    return "\n".join(lines)
