"""Videos and stills of a recording: every picture drawn by viser's own client, with the words a
slide needs.

A recording's self-contained page (``DEMO.html``, a live session's download, or a page built
around a ``DEMO.viser``) is opened in headless Chromium (:mod:`mechviz.viz.player`) and *seeked* to each
frame's playback time, so frame ``k`` is the recording exactly as it stands at
``start + k / fps``, one WebGL render per frame, whatever the machine's speed. Frames cross to
Python as JPEGs, get the title, caption and the figures true at that moment drawn in
(:mod:`mechviz.viz.overlay`) on a worker thread while the browser draws the next one, and go to the
encoder (:mod:`mechviz.viz.encoders`: H.264 MP4 or GIF). A still is one lossless picture (PNG).

The camera (:mod:`mechviz.viz.framing`): a demo's recording is framed on its exhibit (the exhibit's
bounding box fills most of the height the words leave free), from the exhibit's own view or a
preset, or from a given position; a live session is filmed from the camera the viewer had when
recording started. A video of ``duration`` seconds at ``fps`` has ``round(duration * fps)``
frames, the first at ``t = start``. Files are written to a temporary name beside the target and
renamed into place, so an interruption or a failure leaves no half-written file.
"""

from __future__ import annotations

import base64
import contextlib
import json
import math
import os
import queue
import re
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from . import framing
from .chromium import find_chromium
from .encoders import GifWriter, Mp4Writer, gif_delays_ms
from .overlay import Overlay
from .player import Player, PlayerError, decode
from .printable import has_control_characters
from .recording_edit import page_for_video, recording_of_page

FORMATS = ("mp4", "gif")
DEFAULT_SIZE = (960, 540)
STILL_SIZE = (1920, 1080)
MAX_SIDE = 3840
MAX_FPS = 60
# Multisampling doubles the cost of a frame in software WebGL: videos go without it (at 960x540
# and above the lines stay clean enough), stills have it.
ANTIALIAS = False
# Copies of the page drawing a video's frames side by side: while one copies and encodes its
# picture, the other's frame is drawn (software WebGL spreads one frame over the cores, but not
# the page's own work). Measured on two idle cores at 960x540: two pages make a frame in 30-31
# ms against 36 ms, but their second browser adds about 1.5 s to the page load, which the
# quicker frames repay from about 260 frames on. Hence two pages from TWO_PAGES_FRAMES frames (9
# s at 30 fps) on, and never on one core, where there is nothing to overlap.
TWO_PAGES_FRAMES = 270


def pages_for(frames: int) -> int:
    """How many copies of the page draw a video of ``frames`` frames (see TWO_PAGES_FRAMES)."""
    return 2 if frames >= TWO_PAGES_FRAMES and (os.cpu_count() or 1) > 1 else 1


ProgressFn = Callable[[int, int], None]


class VideoError(RuntimeError):
    """A video that could not be made; the message says why (nothing was written)."""


class NoChromium(VideoError):
    """No Chromium (or no playwright) to draw the frames with."""


@dataclass
class Clip:
    """What to film: a recording's page and the words drawn on its frames.

    ``page`` is the self-contained HTML of viser's player with the recording embedded;
    ``frames`` frames are taken at ``fps`` from playback time ``start`` [s]; ``speed`` is
    simulated seconds per second of playback (for the time shown and the figures' times);
    ``figures`` are the manifest's measured-against-predicted figures; ``scene`` the exhibit's
    ``bounds`` and ``view`` (from a demo's manifest) and ``camera`` the recording's own camera
    (a live session's), for framing; ``length`` the recording's playback length [s]."""

    page: bytes
    fps: int
    frames: int
    title: str = ""
    caption: str = ""
    figures: list[dict[str, Any]] = field(default_factory=list)
    speed: float = 1.0
    start: float = 0.0
    scene: dict[str, Any] | None = None
    camera: framing.Camera | None = None
    length: float | None = None

    @property
    def duration(self) -> float:
        return self.frames / self.fps

    def playback_times(self) -> list[float]:
        """Playback time [s] of each frame."""
        return [self.start + k / self.fps for k in range(self.frames)]

    def simulated(self, playback: float) -> float:
        return playback * self.speed


@dataclass(frozen=True)
class Look:
    """How a clip is shown: ``camera`` (a ``--camera`` request; ``None``: the default),
    ``title``/``caption`` (``None``: the clip's own), ``overlay`` (the words at all)."""

    camera: framing.Request | None = None
    title: str | None = None
    caption: str | None = None
    overlay: bool = True


# =========================================================================== sources
_SESSION = re.compile(
    rb'<script type="application/json" id="mechviz-recording">(.*?)</script>', re.DOTALL
)


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


def with_session_info(page: bytes, info: dict[str, Any]) -> bytes:
    """``page`` carrying ``info`` (title, caption, camera, bounds of a live session) for videos
    made from it later (a JSON script block in its head; the player ignores it)."""
    text = json.dumps(info, ensure_ascii=True).replace("</", "<\\/").encode("ascii")
    block = b'<script type="application/json" id="mechviz-recording">' + text + b"</script>"
    i = page.find(b"</head>")
    return page[:i] + block + page[i:] if i >= 0 else block + page


def session_info(page: bytes) -> dict[str, Any] | None:
    """What :func:`with_session_info` put in ``page`` (``None`` if nothing or not readable)."""
    m = _SESSION.search(page[:65536]) or _SESSION.search(page)
    if m is None:
        return None
    with contextlib.suppress(ValueError):
        data = json.loads(m.group(1).replace(b"<\\/", b"</"))
        if isinstance(data, dict):
            return data
    return None


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


def clip_from_manifest(page: bytes, manifest: dict[str, Any]) -> Clip:
    """The clip of a demo recording: its duration and fps, title, description and figures, and
    the exhibit's bounds and view for framing."""
    fps = int(manifest["fps"])
    scene = manifest.get("scene")
    return Clip(
        page=page,
        fps=fps,
        frames=max(1, round(float(manifest["duration"]) * fps)),
        title=str(manifest.get("title", "")),
        caption=str(manifest.get("description", "")),
        figures=list(manifest.get("figures", [])),
        speed=float(manifest.get("speed", 1.0)),
        scene=scene if isinstance(scene, dict) else None,
        length=float(manifest["duration"]),
    )


def clip_from_file(path: Path, *, fps: int | None = None) -> Clip:
    """The clip of a ``.viser`` recording or a player page (``.html``, such as the live viewer's
    downloaded session). A demo manifest beside it (same name, ``.json``) gives the duration,
    fps, title, caption, figures and framing; a live session's page carries its title and the
    viewer's camera; otherwise the whole recording is filmed, titled with the file's name.
    ``ValueError`` names the problem, and the file that does not belong when the manifest lists
    a set that the folder holds only in part (:func:`mechviz.dynamics.fileset.check_beside`)."""
    from mechviz.dynamics import fileset

    if not path.is_file():
        raise ValueError(f"{path}: no such file")
    with fileset.reading(path.parent):  # a recording written meanwhile waits for the check
        data = path.read_bytes()
        checked = fileset.check_beside(path, data)
    if path.suffix == ".viser":
        viser_bytes, page = data, page_for_recording(data)
    elif path.suffix in (".html", ".htm"):
        viser_bytes, page = recording_of_page(data), data
    else:
        raise ValueError(f"{path}: not a .viser recording or a recorded .html page")
    duration = recording_duration(viser_bytes)
    manifest = checked if _is_demo_manifest(checked) else _manifest_beside(path)
    if manifest is not None:
        clip = clip_from_manifest(page, manifest)
        if fps is not None:
            clip.frames = max(1, round(clip.duration * fps))
            clip.fps = fps
        return clip
    fps = fps or 30
    clip = Clip(
        page=page, fps=fps, frames=max(1, round(duration * fps)), title=path.stem, length=duration
    )
    info = session_info(page) if path.suffix != ".viser" else None
    if info is not None:
        clip.title = str(info.get("title") or clip.title)
        clip.caption = str(info.get("caption") or "")
        with contextlib.suppress(TypeError, ValueError, KeyError):
            cam = info["camera"]
            clip.camera = framing.Camera(
                tuple(cam["position"]), tuple(cam["look_at"]), cam.get("fov")
            )
        if isinstance(info.get("scene"), dict):
            clip.scene = info["scene"]
    return clip


def _is_demo_manifest(data: Any) -> bool:
    return isinstance(data, dict) and {"fps", "duration", "title"} <= data.keys()


def _manifest_beside(path: Path) -> dict[str, Any] | None:
    """The demo manifest beside ``path`` (same name, ``.json``), checked; None if there is none.
    One that is there but broken is refused (``ValueError`` naming it and what is wrong), not
    passed over: filming the recording without the duration, frame rate and title it was
    recorded with would be a different video, made without a word."""
    m = path.with_suffix(".json")
    if not m.is_file():
        return None
    where = f"the manifest beside it ({m.name})"

    def no_constant(word: str):
        raise ValueError(f"{where} holds {word}, not a number")

    try:
        data = json.loads(m.read_text(encoding="utf-8"), parse_constant=no_constant)
    except UnicodeDecodeError:
        raise ValueError(f"{where} is not UTF-8 text") from None
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where} is not JSON ({exc.msg}, line {exc.lineno})") from None
    if not isinstance(data, dict):
        raise ValueError(f"{where} is not a JSON object")
    missing = [k for k in ("fps", "duration", "title") if k not in data]
    if missing:
        raise ValueError(f"{where} lacks {', '.join(missing)}")
    fps, duration = data["fps"], data["duration"]
    if not (isinstance(fps, int) and not isinstance(fps, bool)):
        raise ValueError(f"{where}: fps must be a whole number, got {str(fps)[:40]}")
    if not (
        isinstance(duration, int | float)
        and not isinstance(duration, bool)
        and math.isfinite(duration)
        and duration > 0
    ):
        raise ValueError(f"{where}: duration must be a positive number, got {str(duration)[:40]}")
    for key in ("title", "description"):
        text = data.get(key, "")
        if not isinstance(text, str) or has_control_characters(text):
            raise ValueError(f"{where}: {key} must be text without control characters")
    return data


def window(clip: Clip, start: float | None, end: float | None) -> Clip:
    """The part of ``clip`` from playback time ``start`` to ``end`` [s] (``None``: its own
    ends). ``ValueError`` naming ``start`` or ``end`` if they are not inside the recording."""
    length = clip.length if clip.length is not None else clip.start + clip.duration
    s = clip.start if start is None else float(start)
    e = clip.start + clip.duration if end is None else float(end)
    if not (math.isfinite(s) and 0.0 <= s < length):
        raise ValueError(f"start: must be from 0 to below the recording's {length:g} s, got {s:g}")
    if not (math.isfinite(e) and s < e <= length + 1e-9):
        raise ValueError(
            f"end: must be after the start ({s:g} s) and at most the recording's {length:g} s, "
            f"got {e:g}"
        )
    return replace(clip, start=s, frames=max(1, round((e - s) * clip.fps)))


# =========================================================================== checks
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
            "the Python package playwright is needed to drive Chromium: pip install "
            "'mechviz-lab[video]' (never playwright install; the system's Chromium is used)"
        ) from None
    return path


def check_size(size: tuple[int, int]) -> None:
    W, H = size
    if not (16 <= W <= MAX_SIDE and 16 <= H <= MAX_SIDE) or W % 2 or H % 2:
        raise ValueError(
            f"size: width and height must be even numbers from 16 to {MAX_SIDE}, got {W}x{H}"
        )


def check_request(fmt: str, size: tuple[int, int], fps: int) -> None:
    """``ValueError`` naming the option if a video of this format, size and fps cannot be made."""
    if fmt not in FORMATS:
        raise ValueError(f"video: choose one of {', '.join(FORMATS)}, got {fmt!r}")
    check_size(size)
    if fps > MAX_FPS:
        raise ValueError(f"fps: videos are made at up to {MAX_FPS} frames per second, got {fps}")


def size_arg(text: str) -> tuple[int, int]:
    """``WxH`` as two ints (``ValueError`` with an example otherwise)."""
    m = re.fullmatch(r"\s*(\d+)\s*[xX×]\s*(\d+)\s*", text)
    if m is None:
        raise ValueError(f"expected WIDTHxHEIGHT such as 1280x720, got {text!r}")
    return int(m.group(1)), int(m.group(2))


# =========================================================================== set-up
def _overlay(clip: Clip, look: Look, size, times_sim) -> Overlay | None:
    if not look.overlay:
        return None
    return Overlay(
        title=clip.title if look.title is None else look.title,
        caption=clip.caption if look.caption is None else look.caption,
        figures=clip.figures,
        size=size,
        times=times_sim,
    )


def camera_for(clip: Clip, look: Look, size, overlay: Overlay | None) -> framing.Camera:
    """The camera the clip is filmed from (``ValueError`` naming ``camera`` if the request
    cannot be met)."""
    scene = clip.scene or {}
    bounds, view = scene.get("bounds"), scene.get("view")
    try:
        return framing.resolve(
            look.camera,
            bounds=bounds,
            view=tuple(view) if view else None,
            recorded=clip.camera,
            aspect=size[0] / size[1],
            band=overlay.band if overlay is not None else (0.0, 0.0),
        )
    except ValueError as exc:
        raise ValueError(f"camera: {exc}") from None


@dataclass
class VideoResult:
    path: Path
    frames: int
    fps: int
    size: tuple[int, int]
    bytes: int
    load_seconds: float  # starting Chromium, loading the page, drawing the first frame
    render_seconds: float  # drawing and encoding the frames, after the page loaded

    @property
    def ms_per_frame(self) -> float:
        """Drawing, overlay and encoding per frame, page load not included."""
        return 1000 * self.render_seconds / self.frames

    @property
    def real_time_ratio(self) -> float:
        """Seconds of video made per second of work (page load not included)."""
        return (self.frames / self.fps) / max(self.render_seconds, 1e-9)


# =========================================================================== video
def write_video(
    clip: Clip,
    path: str | os.PathLike,
    *,
    fmt: str | None = None,
    size: tuple[int, int] = DEFAULT_SIZE,
    look: Look = Look(),
    progress: ProgressFn | None = None,
    antialias: bool = ANTIALIAS,
    pages: int | None = None,
    shadows: bool = False,
    environment: bool = False,
) -> VideoResult:
    """Film ``clip`` into ``path`` (format from ``fmt`` or the suffix), atomically.

    ``antialias``, ``pages`` (:class:`mechviz.viz.player.Player`; default :func:`pages_for` the video's
    frames), ``shadows`` (the default lights' shadow maps) and ``environment`` (the viewer's default
    environment map, otherwise a hemisphere light; :mod:`mechviz.viz.recording_edit`) say how the frames
    are drawn; the defaults are the fastest way that gives nearly the same picture.

    Raises ``ValueError`` for a request that cannot be met (:func:`check_request`, the camera),
    :class:`NoChromium` without a browser, :class:`VideoError` if drawing or encoding fails;
    ``KeyboardInterrupt`` passes through. In every failure the target is left as it was."""
    path = Path(path)
    fmt = fmt or path.suffix.lstrip(".").lower()
    check_request(fmt, size, clip.fps)
    times = clip.playback_times()
    overlay = _overlay(clip, look, size, [clip.simulated(t) for t in times])
    camera = camera_for(clip, look, size, overlay)
    page = page_for_video(clip.page, shadows=shadows, environment=environment)
    require_chromium()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.parent / f".{path.name}.{os.getpid()}.partial"
    writer = None
    post = None
    try:
        writer = (Mp4Writer if fmt == "mp4" else GifWriter)(tmp, size, clip.fps)
        pages = pages_for(len(times)) if pages is None else pages
        with Player(page, size, camera=camera, antialias=antialias, pages=pages) as player:
            t0 = time.perf_counter()
            post = _Finisher(writer, overlay, clip, times, progress)
            # a little past each frame's time: its messages are in, the next frame's are not
            seek = [t + min(1e-6, 0.25 / clip.fps) for t in times]
            for k, jpeg in enumerate(player.jpegs(seek)):
                post.put(k, jpeg)
            post.finish()
            post = None
            writer.close()
            writer = None
            with open(tmp, "rb+") as fh:
                os.fsync(fh.fileno())
            render = time.perf_counter() - t0
            load = player.load_seconds
        os.replace(tmp, path)
    except PlayerError as exc:
        raise VideoError(str(exc)) from None
    except OSError as exc:
        raise VideoError(f"could not write {path}: {exc.strerror or exc}") from None
    except RuntimeError as exc:
        if isinstance(exc, VideoError):
            raise
        raise VideoError(f"encoding {path.name} failed: {exc}") from None
    finally:
        if post is not None:
            post.abort()
        if writer is not None:
            writer.abort()
        with contextlib.suppress(OSError):
            tmp.unlink()
    return VideoResult(path, clip.frames, clip.fps, size, path.stat().st_size, load, render)


class _Finisher:
    """Decodes each frame, draws the words on it and hands it to the encoder, on a thread of its
    own so that the browser draws frame ``k + 1`` meanwhile. Frames arrive in order; a bounded
    queue keeps at most a few in memory. The first failure is raised in the caller's thread."""

    def __init__(self, writer, overlay, clip: Clip, times, progress) -> None:
        self.writer, self.overlay, self.clip, self.times = writer, overlay, clip, times
        self.progress = progress
        self.q: queue.Queue = queue.Queue(maxsize=4)
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, name="mechviz-video-frames", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while True:
            item = self.q.get()
            if item is None:
                return
            if self.error is not None:
                continue
            k, jpeg = item
            try:
                frame = decode(jpeg)
                if self.overlay is not None:
                    frame = self.overlay.apply(frame, self.clip.simulated(self.times[k]))
                self.writer.add(frame)
            except BaseException as exc:  # handed to the caller's thread
                self.error = exc

    def _raise(self) -> None:
        if self.error is not None:
            raise self.error

    def put(self, k: int, jpeg: bytes) -> None:
        self._raise()
        self.q.put((k, jpeg))
        if self.progress is not None:
            self.progress(k + 1, self.clip.frames)

    def finish(self) -> None:
        self.q.put(None)
        self.thread.join()
        self._raise()

    def abort(self) -> None:
        self.error = self.error or RuntimeError("aborted")
        with contextlib.suppress(queue.Empty):
            while True:
                self.q.get_nowait()
        with contextlib.suppress(queue.Full):
            self.q.put_nowait(None)
        self.thread.join(timeout=10)


# =========================================================================== still
def write_still(
    clip: Clip,
    path: str | os.PathLike,
    at: float,
    *,
    size: tuple[int, int] = STILL_SIZE,
    look: Look = Look(),
) -> Path:
    """A PNG of ``clip`` at playback time ``at`` [s], seen as ``look`` says, written atomically
    to ``path``. Errors as :func:`write_video`."""
    from PIL import Image

    path = Path(path)
    check_size(size)
    length = clip.length if clip.length is not None else clip.duration
    if not (math.isfinite(at) and 0.0 <= at <= length + 1e-9):
        raise ValueError(f"at: must be from 0 to the recording's {length:g} s, got {at:g}")
    overlay = _overlay(clip, look, size, [clip.simulated(at)])
    camera = camera_for(clip, look, size, overlay)
    require_chromium()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.parent / f".{path.name}.{os.getpid()}.partial"
    try:
        with Player(clip.page, size, camera=camera, antialias=True) as player:
            frame = decode(player.png(min(at + 1e-6, length)))
        if overlay is not None:
            frame = overlay.apply(frame, clip.simulated(at))
        with open(tmp, "wb") as fh:
            Image.fromarray(frame).save(fh, format="PNG")
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except PlayerError as exc:
        raise VideoError(str(exc)) from None
    except OSError as exc:
        raise VideoError(f"could not write {path}: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()
    return path


__all__ = [
    "DEFAULT_SIZE",
    "FORMATS",
    "STILL_SIZE",
    "Clip",
    "Look",
    "NoChromium",
    "VideoError",
    "VideoResult",
    "check_request",
    "check_size",
    "clip_from_file",
    "clip_from_manifest",
    "gif_delays_ms",
    "page_for_recording",
    "recording_duration",
    "session_info",
    "size_arg",
    "window",
    "with_session_info",
    "write_still",
    "write_video",
]
