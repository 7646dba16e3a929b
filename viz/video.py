"""Video of a recording: every frame drawn by viser's own client, with the words a slide needs.

A recording's self-contained page (``DEMO.html``, a live session's download, or a page built
around a ``DEMO.viser``) is opened in headless Chromium with the page's clock faked: the player
advances its playback with ``Date.now()``, so advancing the fake clock to each frame's capture
time before its screenshot gives the recording as it stands at ``t = k / fps`` of playback,
deterministically and without waiting for real time (at most 30 fps; :func:`frame_clock_ms`).
Each frame gets the title, the caption and the key readouts (measured against predicted, from
the recording's manifest) drawn in with Pillow, and goes to the encoder:

- ``mp4``: H.264, yuv420p, ``+faststart`` (plays in browsers, PowerPoint and Keynote), encoded by
  the ffmpeg that ships in ``imageio-ffmpeg``, streamed frame by frame;
- ``gif``: Pillow, one 256-colour palette for all frames (half from the first frame, half a
  colour cube), looping; GIF delays are whole centiseconds, so they alternate (30 fps: 30, 40,
  30 ms, ...) to keep the exact duration.

A video of ``duration`` seconds at ``fps`` has ``round(duration * fps)`` frames, the first at
``t = 0``. The file is written to a temporary name beside the target and renamed into place, so
an interruption or a failure leaves no half-written video.
"""

from __future__ import annotations

import base64
import contextlib
import io
import itertools
import json
import logging
import os
import re
import shutil
import tempfile
import time
import zlib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .chromium import find_chromium, first_page, launch
from .overlay import Overlay

FORMATS = ("mp4", "gif")
DEFAULT_SIZE = (960, 540)
MAX_SIDE = 3840
MAX_FPS = 30  # see render_frames: the player needs about 40 ms of clock per frame
LOAD_TIMEOUT_S = 180.0  # first frame of a lit scene in software WebGL, on a loaded machine

ProgressFn = Callable[[int, int], None]


class VideoError(RuntimeError):
    """A video that could not be made; the message says why (nothing was written)."""


class NoChromium(VideoError):
    """No Chromium (or no playwright) to draw the frames with."""


@dataclass
class Clip:
    """What to film: a recording's page and the words drawn on every frame.

    ``page`` is the self-contained HTML of viser's player with the recording embedded;
    ``frames`` frames are taken at ``fps``; ``speed`` is simulated seconds per second of
    playback (for the time shown); ``readouts`` are short lines (measured against predicted)."""

    page: bytes
    fps: int
    frames: int
    title: str = ""
    caption: str = ""
    readouts: list[str] = field(default_factory=list)
    speed: float = 1.0

    @property
    def duration(self) -> float:
        return self.frames / self.fps


# =========================================================================== sources
_EMBED = re.compile(rb'window\.__VISER_EMBED_DATA__="([A-Za-z0-9+/=]*)"')


def page_for_recording(viser_bytes: bytes) -> bytes:
    """viser's self-contained player page around a ``.viser`` recording (what viser's own
    ``as_html`` builds from the client that ships in the wheel)."""
    import viser

    client = (Path(viser.__file__).parent / "client" / "build" / "index.html").read_text()
    b64 = base64.b64encode(viser_bytes).decode("ascii")
    script = (
        f'<script>window.__VISER_EMBED_DATA__="{b64}";'
        "window.__VISER_EMBED_CONFIG__={darkMode:false};</script>"
    )
    head_end = client.index("</head>")
    return (client[:head_end] + script + client[head_end:]).encode("utf-8")


def recording_of_page(page: bytes) -> bytes:
    """The ``.viser`` bytes embedded in a player page (``ValueError`` if there are none)."""
    m = _EMBED.search(page)
    if m is None:
        raise ValueError("not a viser recording page (no embedded scene data)")
    return base64.b64decode(m.group(1))


def recording_duration(viser_bytes: bytes) -> float:
    """Seconds of playback in a ``.viser`` recording (``ValueError`` if it is not one)."""
    import msgspec
    import zstandard

    try:
        size = int.from_bytes(viser_bytes[:8], "little")
        inner = zstandard.ZstdDecompressor().decompress(viser_bytes[8:], max_output_size=size)
        n = int.from_bytes(inner[:8], "little")
        head = msgspec.msgpack.decode(inner[8 : 8 + n])
        return float(head["durationSeconds"])
    except Exception as exc:  # zstd, msgpack or a missing key: the file is not a recording
        raise ValueError(f"not a viser recording ({type(exc).__name__})") from None


def readout_lines(figures: list[dict[str, Any]], limit: int = 4) -> list[str]:
    """The manifest's measured-against-predicted figures as short lines."""
    lines = []
    for f in figures:
        if f.get("measured") is None:
            continue
        unit = f" {f['unit']}" if f.get("unit") else ""
        line = f"{f['name']}: {f['measured']:.6g}{unit}"
        if f.get("predicted") is not None:
            line += f"   (theory {f['predicted']:.6g})"
        lines.append(line)
    return lines[:limit]


def clip_from_manifest(page: bytes, manifest: dict[str, Any]) -> Clip:
    """The clip of a demo recording: its duration and fps, title, description and figures."""
    fps = int(manifest["fps"])
    return Clip(
        page=page,
        fps=fps,
        frames=max(1, round(float(manifest["duration"]) * fps)),
        title=str(manifest.get("title", "")),
        caption=str(manifest.get("description", "")),
        readouts=readout_lines(manifest.get("figures", [])),
        speed=float(manifest.get("speed", 1.0)),
    )


def clip_from_file(path: Path, *, fps: int | None = None) -> Clip:
    """The clip of a ``.viser`` recording or a player page (``.html``, such as the live viewer's
    downloaded session). A demo manifest beside it (same name, ``.json``) gives the duration,
    fps, title, caption and readouts; otherwise the whole recording is filmed, titled with the
    file's name. ``ValueError`` names the problem."""
    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    data = path.read_bytes()
    if path.suffix == ".viser":
        viser_bytes, page = data, page_for_recording(data)
    elif path.suffix in (".html", ".htm"):
        viser_bytes, page = recording_of_page(data), data
    else:
        raise ValueError(f"{path}: not a .viser recording or a recorded .html page")
    duration = recording_duration(viser_bytes)
    manifest = _manifest_beside(path)
    if manifest is not None:
        clip = clip_from_manifest(page, manifest)
        if fps is not None:
            clip.frames = max(1, round(clip.duration * fps))
            clip.fps = fps
        return clip
    fps = fps or 30
    return Clip(page=page, fps=fps, frames=max(1, round(duration * fps)), title=path.stem)


def _manifest_beside(path: Path) -> dict[str, Any] | None:
    m = path.with_suffix(".json")
    with contextlib.suppress(OSError, ValueError):
        data = json.loads(m.read_text())
        if isinstance(data, dict) and {"fps", "duration", "title"} <= data.keys():
            return data
    return None


# =========================================================================== frames
def require_chromium() -> str:
    """Chromium's path; :class:`NoChromium` saying how to get it otherwise."""
    path = find_chromium()
    if path is None:
        raise NoChromium(
            "no Chromium found to draw the frames: install it (apt-get install chromium) or set "
            "MECHVIZ_CHROMIUM to its path"
        )
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        raise NoChromium(
            "the Python package playwright is needed to drive Chromium: pip install playwright "
            "(never playwright install; the system's Chromium is used)"
        ) from None
    return path


def _drawn(img: np.ndarray) -> bool:
    """More than a blank background."""
    return len(np.unique(img[::4, ::4].reshape(-1, 3), axis=0)) > 40


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
    page_html: bytes, *, fps: int, frames: int, size: tuple[int, int] = DEFAULT_SIZE
) -> Iterator[np.ndarray]:
    """Yield ``frames`` images ``(H, W, 3)`` uint8 of the player page: frame ``k`` is the
    recording as it stands at playback time ``k / fps``.

    One headless Chromium, the page's clock faked: load, wait for the first drawn frame, seek
    to 0 and play, then advance the clock to each frame's capture time
    (:func:`frame_clock_ms`) before its screenshot."""
    from playwright.sync_api import Error as PlaywrightError
    from playwright.sync_api import sync_playwright

    exe = require_chromium()
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
                raise VideoError(f"Chromium failed while drawing the frames: {exc}") from None
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
            raise VideoError("the recording's page did not load in Chromium (no player)")
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
            raise VideoError("the recording's scene was never drawn in Chromium")
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


# =========================================================================== encoding
def gif_delays_ms(frames: int, fps: int) -> list[int]:
    """Per-frame GIF delays (whole centiseconds) that add up to ``frames / fps`` seconds."""
    edges = [round(k * 100 / fps) * 10 for k in range(frames + 1)]
    return [b - a for a, b in itertools.pairwise(edges)]


class _Mp4Writer:
    def __init__(self, path: Path, size: tuple[int, int], fps: int):
        import imageio_ffmpeg

        self.gen = imageio_ffmpeg.write_frames(
            str(path),
            size,
            fps=fps,
            codec="libx264",
            pix_fmt_in="rgb24",
            pix_fmt_out="yuv420p",
            quality=None,
            macro_block_size=2,
            ffmpeg_log_level="error",
            output_params=[
                "-crf",
                "20",
                "-preset",
                "medium",
                "-movflags",
                "+faststart",
                "-f",
                "mp4",
            ],
        )
        self.gen.send(None)

    def add(self, frame: np.ndarray) -> None:
        self.gen.send(np.ascontiguousarray(frame))

    def close(self) -> None:
        self.gen.close()

    def abort(self) -> None:
        log = logging.getLogger("imageio_ffmpeg")
        level = log.level
        log.setLevel(logging.ERROR)  # "no frames have been written": we know, and remove it
        try:
            with contextlib.suppress(Exception):
                self.gen.close()  # ffmpeg exits; the caller removes the partial file
        finally:
            log.setLevel(level)


class _GifWriter:
    """Frames share one palette (half from the first frame, half a uniform colour cube), so
    Pillow stores only the part of each frame that changed. Until the file is written, frames
    are kept as compressed palette indices (a 960x540 frame of a mostly blank scene: ~10 kB);
    Pillow's writer then holds every frame uncompressed (W x H bytes each) until it is done."""

    def __init__(self, path: Path, size: tuple[int, int], fps: int):
        self.path, self.size, self.fps = path, size, fps
        self.frames: list[bytes] = []
        self.palette = None

    def add(self, frame: np.ndarray) -> None:
        from PIL import Image

        img = Image.fromarray(frame)
        if self.palette is None:
            first = img.quantize(131, method=Image.Quantize.FASTOCTREE).getpalette()[: 131 * 3]
            cube = [
                c
                for r in range(5)
                for g in range(5)
                for b in range(5)
                for c in (r * 63, g * 63, b * 63)
            ]
            self.palette = Image.new("P", (1, 1))
            self.palette.putpalette(first + cube)
        indices = img.quantize(palette=self.palette, dither=Image.Dither.NONE).tobytes()
        self.frames.append(zlib.compress(indices, 1))

    def _images(self) -> Iterator:
        from PIL import Image

        colours = self.palette.getpalette()
        for data in self.frames:
            img = Image.frombytes("P", self.size, zlib.decompress(data))
            img.putpalette(colours)
            yield img

    def abort(self) -> None:
        self.frames.clear()

    def close(self) -> None:
        images = self._images()
        first = next(images)
        first.save(
            self.path,
            format="GIF",
            save_all=True,
            append_images=images,
            loop=0,
            duration=gif_delays_ms(len(self.frames), self.fps),
            optimize=False,
        )


@dataclass
class VideoResult:
    path: Path
    frames: int
    fps: int
    size: tuple[int, int]
    bytes: int
    load_seconds: float  # starting Chromium, loading the page, drawing the first frame
    render_seconds: float  # drawing the other frames
    encode_seconds: float  # overlay and encoder (includes writing the file)

    @property
    def ms_per_frame(self) -> float:
        """Drawing, overlay and encoding per frame, page load not included."""
        return 1000 * (self.render_seconds + self.encode_seconds) / self.frames


def check_request(fmt: str, size: tuple[int, int], fps: int) -> None:
    """``ValueError`` naming the option if a video of this format, size and fps cannot be made."""
    if fmt not in FORMATS:
        raise ValueError(f"video: choose one of {', '.join(FORMATS)}, got {fmt!r}")
    W, H = size
    if not (16 <= W <= MAX_SIDE and 16 <= H <= MAX_SIDE) or W % 2 or H % 2:
        raise ValueError(
            f"size: width and height must be even numbers from 16 to {MAX_SIDE}, got {W}x{H}"
        )
    if fps > MAX_FPS:
        raise ValueError(f"fps: videos are made at up to {MAX_FPS} frames per second, got {fps}")


def write_video(
    clip: Clip,
    path: str | os.PathLike,
    *,
    fmt: str | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    progress: ProgressFn | None = None,
) -> VideoResult:
    """Film ``clip`` into ``path`` (format from ``fmt`` or the suffix), atomically.

    Raises ``ValueError`` for a request that cannot be met (:func:`check_request`),
    :class:`NoChromium` without a browser, :class:`VideoError` if drawing or encoding fails;
    ``KeyboardInterrupt`` passes through. In every failure the target is left as it was."""
    path = Path(path)
    fmt = fmt or path.suffix.lstrip(".").lower()
    check_request(fmt, size, clip.fps)
    require_chromium()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.parent / f".{path.name}.{os.getpid()}.partial"
    overlay = Overlay(clip, size)
    load = render = encode = 0.0
    writer = None
    try:
        writer = (_Mp4Writer if fmt == "mp4" else _GifWriter)(tmp, size, clip.fps)
        t0 = time.perf_counter()
        frames = render_frames(clip.page, fps=clip.fps, frames=clip.frames, size=size)
        try:
            for k, frame in enumerate(frames):
                t1 = time.perf_counter()
                if k == 0:
                    load = t1 - t0
                else:
                    render += t1 - t0
                writer.add(overlay.apply(frame, k, clip.fps))
                t0 = time.perf_counter()
                encode += t0 - t1
                if progress is not None:
                    progress(k + 1, clip.frames)
        finally:
            frames.close()
        t1 = time.perf_counter()
        writer.close()
        writer = None
        with open(tmp, "rb+") as fh:
            os.fsync(fh.fileno())
        encode += time.perf_counter() - t1
        os.replace(tmp, path)
    except OSError as exc:
        raise VideoError(f"could not write {path}: {exc.strerror or exc}") from None
    except RuntimeError as exc:
        if isinstance(exc, VideoError):
            raise
        raise VideoError(f"encoding {path.name} failed: {exc}") from None
    finally:
        if writer is not None:
            writer.abort()
        with contextlib.suppress(OSError):
            tmp.unlink()
    return VideoResult(path, clip.frames, clip.fps, size, path.stat().st_size, load, render, encode)


def measure(
    demo: str = "helix", duration: float = 4.0, fps: int = 30, size: tuple[int, int] = (640, 360)
) -> dict[str, Any]:
    """Record ``demo`` for ``duration`` s and film it as MP4 and GIF in a temporary folder:
    seconds to load the page, ms per frame (drawing; overlay + encoding), file sizes."""
    from . import record as rec

    out: dict[str, Any] = {"demo": demo, "duration_s": duration, "fps": fps, "size": list(size)}
    with tempfile.TemporaryDirectory() as tmp:
        res = rec.record(rec.load_demo(demo).with_overrides(duration=duration, fps=fps), tmp)
        clip = clip_from_manifest(res.paths[".html"].read_bytes(), res.manifest)
        for fmt in FORMATS:
            v = write_video(clip, Path(tmp) / f"{demo}.{fmt}", size=size)
            out[fmt] = {
                "frames": v.frames,
                "load_s": round(v.load_seconds, 2),
                "render_ms_per_frame": round(1000 * v.render_seconds / (v.frames - 1), 1),
                "encode_ms_per_frame": round(1000 * v.encode_seconds / v.frames, 1),
                "mb": round(v.bytes / 1e6, 3),
            }
    return out


def size_arg(text: str) -> tuple[int, int]:
    """``WxH`` as two ints (``ValueError`` with an example otherwise)."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if m is None:
        raise ValueError(f"expected WIDTHxHEIGHT such as 1280x720, got {text!r}")
    return int(m.group(1)), int(m.group(2))


__all__ = [
    "DEFAULT_SIZE",
    "FORMATS",
    "Clip",
    "NoChromium",
    "Overlay",
    "VideoError",
    "VideoResult",
    "check_request",
    "clip_from_file",
    "clip_from_manifest",
    "gif_delays_ms",
    "page_for_recording",
    "readout_lines",
    "recording_duration",
    "render_frames",
    "size_arg",
    "write_video",
]
