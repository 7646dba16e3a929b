"""``mechviz video``: a recording (``.viser``, or a recorded ``.html`` page such as the live
viewer's downloaded session) filmed into an MP4 or a GIF; and the ``--video`` options of
``mechviz record``. The options that say how a clip is shown (camera, words, part) are shared
with ``mechviz still`` (:mod:`mechviz.viz.cli.still`).

Registered on the ``mechviz`` parser by :mod:`mechviz.viz.cli`; playwright and the encoders are
imported only when a video is made. Bad input exits with status 2 and one line naming the
flag; a failure with status 1; Ctrl-C with 130. No half-written video is ever left behind.
"""

from __future__ import annotations

import argparse
import logging
import os
import signal
import sys
import threading
from collections.abc import Callable
from pathlib import Path

from .. import framing, video
from ..interrupts import exit_status
from ..printable import printable
from ..video_input import read_clip
from .errors import CliError, command, number, whole

# ValueError prefixes from mechviz.viz.video and mechviz.viz.framing -> the flag that set the value
FLAGS = {
    "size": "--size",
    "fps": "--fps",
    "camera": "--camera",
    "start": "--start",
    "end": "--end",
    "at": "--at",
}


def size_type(text: str) -> tuple[int, int]:
    """argparse type for ``--size WxH``."""
    try:
        return video.size_arg(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def camera_type(text: str) -> framing.Request:
    """argparse type for ``--camera``."""
    try:
        return framing.parse_camera(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def text_type(text: str) -> str:
    """argparse type for ``--title`` and ``--caption``: one line of printable text."""
    if any(ord(c) < 32 for c in text) or len(text) > 300:
        raise argparse.ArgumentTypeError("one line of at most 300 printable characters")
    return text


def add_look_options(p: argparse.ArgumentParser, *, part: bool = True) -> None:
    """``--camera``, ``--title``, ``--caption``, ``--no-overlay`` (and ``--start``/``--end``)."""
    presets = "; ".join(f"{k}: {v}" for k, v in framing.PRESETS.items())
    p.add_argument(
        "--camera",
        type=camera_type,
        metavar="VIEW",
        help=f"a preset ({presets}) or a position X,Y,Z in metres looking at the exhibit's "
        "centre, or X,Y,Z:LX,LY,LZ looking at LX,LY,LZ (default: exhibit for a demo, recorded "
        "for a live session)",
    )
    p.add_argument(
        "--title", type=text_type, help="the title drawn at the top (default: the demo's)"
    )
    p.add_argument(
        "--caption", type=text_type, help="the caption under the title (default: the demo's)"
    )
    p.add_argument(
        "--no-overlay",
        dest="overlay",
        action="store_false",
        help="no words at all: only the scene",
    )
    if part:
        p.add_argument(
            "--start",
            type=number,
            metavar="S",
            help="from this second of the recording (default 0)",
        )
        p.add_argument(
            "--end",
            type=number,
            metavar="S",
            help="to this second of the recording (default its end)",
        )


def look_of(args: argparse.Namespace) -> video.Look:
    return video.Look(
        camera=args.camera, title=args.title, caption=args.caption, overlay=args.overlay
    )


ABOUT = """\
film a recording (.viser or recorded .html) into an MP4 or a GIF

Draw every frame of a recording in headless Chromium (viser's own player) and encode it as H.264
MP4 (yuv420p: browsers, PowerPoint, Keynote) or GIF, framed on the exhibit, with the title,
caption and the measured-against-predicted figures true at each moment drawn in. A demo manifest
beside the file (FILE.json, as mechviz record writes it) gives the duration, fps, words and
framing, once every file it lists is checked against it (a folder holding files of two
recordings is refused, naming the file); a live session's page its title and the viewer's
camera. The video is written
atomically. Needs Chromium and pip install 'mechviz-lab[video]'.
"""


def add_commands(sub) -> None:
    p = command(sub, "video", ABOUT)
    p.add_argument("file", help="a .viser recording or a recorded .html page")
    p.add_argument(
        "--out", metavar="PATH", help="the video file (default: FILE with .mp4 or .gif, beside it)"
    )
    p.add_argument(
        "--format", choices=video.FORMATS, help="mp4 or gif (default: from --out, else mp4)"
    )
    p.add_argument(
        "--size",
        type=size_type,
        metavar="WxH",
        help=f"frame size in pixels, even numbers (default {video.DEFAULT_SIZE[0]}x{video.DEFAULT_SIZE[1]})",
    )
    p.add_argument(
        "--fps",
        type=whole,
        metavar="N",
        help=f"frames per second, up to {video.MAX_FPS} (default: the demo's, else 30)",
    )
    add_look_options(p)
    from ..progress import add_option

    add_option(p)
    p.set_defaults(func=run_video)


def flag_error(exc: ValueError, flags: dict[str, str] = FLAGS) -> CliError:
    """A ``ValueError`` whose message starts ``key: ...`` as a one-line error naming the flag."""
    msg = str(exc)
    key, _, rest = msg.partition(": ")
    if key in flags:
        return CliError(f"{flags[key]}: {rest}")
    return CliError(msg)


def _progress(label: str):
    from ..progress import ProgressBar

    return ProgressBar(label)


def interruptible(path: Path, make: Callable[[], object]) -> tuple[int, object]:
    """Run ``make()`` (which writes ``path``): ``(0, its result)``, or ``(status, None)`` after
    one line on stderr for a failure (1) or Ctrl-C / SIGTERM (130, 128 + signal)."""
    # Ctrl-C reaches Chromium and playwright's driver too (one process group), which may fail
    # before Python sees the KeyboardInterrupt: remember it, so either way it reads as one.
    interrupted = threading.Event()

    def on_sigint(signum, frame):
        interrupted.set()
        signal.default_int_handler(signum, frame)

    previous = signal.signal(signal.SIGINT, on_sigint)
    try:
        return 0, make()
    except (video.VideoError, KeyboardInterrupt) as exc:
        _end_line()
        if interrupted.is_set() or isinstance(exc, KeyboardInterrupt):
            logging.getLogger("asyncio").setLevel(logging.CRITICAL)  # the driver's closed pipe
            print(f"mechviz: interrupted; {path} was not written", file=sys.stderr)
            return (exit_status(exc) if isinstance(exc, KeyboardInterrupt) else 130), None
        print(f"mechviz: error: {exc}; {path} was not written", file=sys.stderr)
        return 1, None
    finally:
        signal.signal(signal.SIGINT, previous)


def _film(clip: video.Clip, path: Path, fmt: str, size, look: video.Look, flags) -> int:
    try:
        video.check_request(fmt, size, clip.fps)
        video.camera_for(clip, look, size, None)  # a camera that cannot be had: before Chromium
        video.require_chromium()
    except video.NoChromium as exc:
        raise CliError(str(exc)) from None
    except ValueError as exc:
        raise flag_error(exc, flags) from None
    status, res = interruptible(
        path,
        lambda: video.write_video(
            clip, path, fmt=fmt, size=size, look=look, progress=_progress(path.name)
        ),
    )
    if status:
        return status
    print(
        f"{path}: {res.frames} frames, {res.fps} fps, {res.frames / res.fps:g} s, "
        f"{res.size[0]}x{res.size[1]}, {res.bytes / 1e6:.2f} MB (page loaded in "
        f"{res.load_seconds:.1f} s, then {res.ms_per_frame:.0f} ms per frame: "
        f"{res.real_time_ratio:.2f}x real time)"
    )
    return 0


def _end_line() -> None:
    if sys.stderr.isatty():
        sys.stderr.write("\n")


def check_out(out: Path) -> None:
    """``CliError`` naming ``--out`` for a target that cannot be written."""
    try:
        if out.is_dir():
            raise CliError(f"--out: {printable(str(out))} is a folder; give a file name")
        os.lstat(out.parent / f".{out.name}.{os.getpid()}.partial")  # the name the writer makes
    except FileNotFoundError:
        pass
    except OSError as exc:  # a name too long for the file system, a folder we may not read
        raise CliError(f"--out: {exc.strerror or exc}") from None


def run_video(args: argparse.Namespace) -> int:
    src = Path(args.file)
    if args.fps is not None and not 1 <= args.fps <= video.MAX_FPS:
        raise CliError(f"--fps: must be a whole number from 1 to {video.MAX_FPS}, got {args.fps}")
    try:
        clip = read_clip(src, fps=args.fps)
    except ValueError as exc:
        raise CliError(str(exc)) from None
    try:
        clip = video.window(clip, args.start, args.end)
    except ValueError as exc:
        raise flag_error(exc) from None
    if args.out:
        out = Path(args.out)
        suffix = out.suffix.lstrip(".").lower()
        if args.format is None and suffix not in video.FORMATS:
            raise CliError(
                f"--out: end the name in .mp4 or .gif (or give --format), got {printable(out.name)}"
            )
        fmt = args.format or suffix
    else:
        fmt = args.format or "mp4"
        out = src.with_suffix(f".{fmt}")
    check_out(out)
    flags = {**FLAGS, "video": "--format"}
    return _film(clip, out, fmt, args.size or video.DEFAULT_SIZE, look_of(args), flags)


# =========================================================================== mechviz record
def add_record_options(p: argparse.ArgumentParser) -> None:
    """``--video``, ``--size`` and the look of the video on ``mechviz record``."""
    p.add_argument(
        "--video",
        choices=video.FORMATS,
        help="also film the recording into DEMO.mp4 or DEMO.gif (headless Chromium; pip install "
        "'mechviz-lab[video]')",
    )
    p.add_argument(
        "--size",
        type=size_type,
        metavar="WxH",
        help=f"video frame size (default {video.DEFAULT_SIZE[0]}x{video.DEFAULT_SIZE[1]})",
    )
    add_look_options(p)


_LOOK = ("size", "camera", "title", "caption", "start", "end")


def check_record_options(args: argparse.Namespace, demos) -> None:
    """Before anything is recorded: ``CliError`` for a video that cannot be made."""
    if not args.video:
        for name in (*_LOOK, "overlay"):
            value = getattr(args, name)
            if (name == "overlay" and value is False) or (name != "overlay" and value is not None):
                flag = "--no-overlay" if name == "overlay" else f"--{name}"
                raise CliError(f"{flag}: only with --video mp4 or --video gif")
        return
    flags = {**FLAGS, "video": "--video"}
    try:
        for demo in demos:
            video.check_request(args.video, args.size or video.DEFAULT_SIZE, demo.fps)
            for key in ("start", "end"):
                value = getattr(args, key)
                if value is not None and not 0 <= value <= demo.duration:
                    raise ValueError(
                        f"{key}: must be from 0 to the demo's {demo.duration:g} s, got {value:g}"
                    )
        if args.start is not None and args.end is not None and args.end <= args.start:
            raise ValueError(f"end: must be after the start ({args.start:g} s), got {args.end:g}")
        video.require_chromium()
    except video.NoChromium as exc:
        raise CliError(str(exc)) from None
    except ValueError as exc:
        raise flag_error(exc, flags) from None


def film_record(res, args: argparse.Namespace) -> int:
    """Film a finished recording (:class:`mechviz.viz.record.RecordResult`) into DEMO.mp4 / DEMO.gif
    beside its other files; the exit status (0 when done)."""
    clip = video.clip_from_manifest(res.paths[".html"].read_bytes(), res.manifest)
    flags = {**FLAGS, "video": "--video"}
    try:
        clip = video.window(clip, args.start, args.end)
    except ValueError as exc:
        raise flag_error(exc, flags) from None
    out = res.paths[".html"].with_suffix(f".{args.video}")
    return _film(clip, out, args.video, args.size or video.DEFAULT_SIZE, look_of(args), flags)
